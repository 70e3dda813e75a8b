"""DM, ASRN (shipped checkpoints), ASM-Opt, windowed inference, and training itself."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand.rotations import quat_angle
from s2h_viewer.motions.synthesis import synthesize
from s2h_viewer.retarget import METHODS, retarget
from s2h_viewer.io.files import load_hand_file
from s2h_viewer.retarget.asm_opt import contact_keyframes, keyframes
from s2h_viewer.retarget.evaluation import EvaluationRow, format_markdown, summarise, write_results
from s2h_viewer.samples import ASSETS_DIR, hand_names, load_sample_motions
from s2h_viewer.retarget.asrn.dataset import build_training_set, sample_batch
from s2h_viewer.retarget.asrn.inference import MODELS_DIR, load_network, run_network
from s2h_viewer.retarget.windows import blend_weights, window_starts
from s2h_viewer.retarget.asrn.training import (GRADIENT_CLIP, TrainConfig, batch_loss, build_model, default_config,
                                               load_checkpoint, stored_config, train)
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.semantics.contacts import CONTACT_TOLERANCE, PAD_PAIRS, contact_gaps
from s2h_viewer.semantics.metrics import RetargetScores, score_retarget


def test_registry_lists_the_paper_table_in_order():
    assert list(METHODS)[:5] == ["copy", "tbs_copy", "dm", "asrn", "asm_opt"]


@pytest.mark.parametrize("method,name", [("dm", "gorse"), ("asrn", "gorse"), ("asm_opt", "juniper")])
def test_retargeting_a_hand_onto_itself_keeps_its_semantics(sample_hands, method, name):
    # the networks on a (stylised) training hand; on held-out stylised hands they keep 0.981-0.988 (issue note)
    hand = sample_hands[name]
    motion = synthesize(["fist", "ok", "letter_w"], hand, seed=2)
    result = retarget(motion, hand, hand, method)
    scores = score_retarget(hand, motion.q_tbs, hand, result.q_tbs)
    assert scores.s_finger >= 0.99 and scores.s_palm >= 0.99
    assert result.n_frames == motion.n_frames and result.hand_name == name


def test_asm_opt_restores_the_contacts_tbs_copy_loses(sample_hands):
    source, target = sample_hands["birch"], sample_hands["laurel"]  # realistic -> small stylised hand
    motion = synthesize(["ok", "pinch", "fist", "letter_o"], source, seed=3)
    scores = {m: score_retarget(source, motion.q_tbs, target, retarget(motion, source, target, m).q_tbs)
              for m in ("tbs_copy", "asm_opt")}
    assert scores["tbs_copy"].contact_recall < 0.9
    assert scores["asm_opt"].contact_recall > scores["tbs_copy"].contact_recall + 0.1
    assert scores["asm_opt"].s_finger > scores["tbs_copy"].s_finger
    assert scores["asm_opt"].violation_rate < 0.02


def test_every_change_in_the_source_contacts_is_keyed_and_a_long_hold_only_on_the_grid():
    touching = np.zeros((20, 15), bool)
    touching[7, 3] = True  # a one-frame touch between the keyframes 6 and 9
    touching[13:15, 14] = True
    touching[1:19, 0] = True  # a long hold: keyed where it starts and ends, on the grid in between
    keys = contact_keyframes(touching, 3)
    changes = {0, 1, 6, 7, 8, 12, 13, 14, 15, 18, 19}  # the frames either side of each start and end
    assert set(keys) == set(keyframes(20, 3)) | changes
    assert np.all(np.diff(keys) > 0)
    assert set(contact_keyframes(touching[:, :1], 3)) == set(keyframes(20, 3)) | {1}  # 0, 18, 19 on the grid


@pytest.mark.parametrize("rig", ["real/godot_hand_r.gltf", "webxr/generic-hand-left.glb"])
def test_asm_opt_keeps_the_short_source_contacts_on_a_real_hand(sample_hands, rig):
    """The counting clip touches for a few frames at a time: touches shorter than the keyframe step fell
    between keyframes and were lost (contact recall 0.5 on both hands before contact changes became keys);
    keying every contact frame instead kept them but made false ones (precision 0.53 on the WebXR hand)."""
    motion = next(m for m in load_sample_motions() if m.name == "counting")
    source = sample_hands[motion.hand_name]
    target = load_hand_file(ASSETS_DIR / "hands" / rig)
    result = retarget(motion, source, target, "asm_opt")
    scores = score_retarget(source, motion.q_tbs, target, result.q_tbs)
    assert scores.contact_recall >= 0.95
    assert scores.contact_precision >= 0.8
    assert scores.violation_rate < 0.02


def test_asm_opt_keeps_a_long_hold_whose_frames_between_keys_drift_apart(sample_hands):
    """Inside a long hold only every third frame is a key: on the Godot hand two frames of the
    fingerspelling clip's thumb-middle hold came out 1.7% of the hand apart between touching keys
    (recall 0.987) until frames that lose a source contact became keys of a repair pass."""
    motion = next(m for m in load_sample_motions() if m.name == "fingerspelling")
    source = sample_hands[motion.hand_name]
    target = load_hand_file(ASSETS_DIR / "hands" / "real" / "godot_hand_r.gltf")
    scores = score_retarget(source, motion.q_tbs, target, retarget(motion, source, target, "asm_opt").q_tbs)
    assert scores.contact_recall == 1.0
    assert scores.contact_precision >= 0.95 and scores.violation_rate < 0.02


def test_window_layout_covers_every_frame_with_weights_summing_to_one():
    for n in (8, 9, 20, 1000):
        starts = window_starts(n, 8, 2)
        weights = blend_weights(starts, 8)
        total = np.zeros(max(n, 8))
        for s, w in zip(starts, weights):
            total[s:s + 8] += w
        np.testing.assert_allclose(total[:n], 1.0)
        assert starts[-1] + 8 == max(n, 8)


def test_windowed_inference_matches_each_window_inside_and_has_no_seams(sample_hands):
    source, target = sample_hands["birch"], sample_hands["kale"]
    motion = synthesize(["fist", "ok", "point", "letter_y", "spread", "count_3", "pinch", "v_sign", "rock",
                         "letter_c", "claw", "thumbs_up", "letter_b", "count_4", "flat"], source, seed=9)
    q_src = motion.q_tbs[:1000]
    model, config = load_network(str(MODELS_DIR / "asrn.pt"))
    out = run_network(model, "asrn", source, q_src, target)
    assert out.shape == q_src.shape and len(q_src) >= 400
    starts = window_starts(len(q_src), 8, 2)
    for start in starts[1:-1:7]:  # interior frames of a window equal that window run on its own
        alone = run_network(model, "asrn", source, q_src[start:start + 8], target)
        np.testing.assert_allclose(out[start + 2:start + 6], alone[2:6], atol=1e-5)
    # no seam: frame-to-frame rotation change of the output follows the source's, at borders as inside
    step_out = quat_angle(torch.as_tensor(out[1:]), torch.as_tensor(out[:-1])).numpy()
    step_src = quat_angle(torch.as_tensor(q_src[1:]), torch.as_tensor(q_src[:-1])).numpy()
    excess = np.abs(step_out - step_src).max(-1)
    borders = np.array([s - 1 for s in starts[1:]] + [s + 1 for s in starts[1:]])
    inside = np.setdiff1d(np.arange(len(excess)), borders)
    assert excess[borders].max() <= max(2 * excess[inside].max(), np.radians(0.5))


def test_shipped_checkpoints_load_and_say_how_they_were_trained():
    for kind in ("asrn", "dm"):
        state = load_checkpoint(MODELS_DIR / f"{kind}.pt")
        assert state["config"]["kind"] == kind and state["step"] == state["config"]["steps"]
        assert set(hand_names("train")) <= set(state["train_hands"])
        assert not set(hand_names("test")) & set(state["train_hands"])
        assert len(state["train_hands"]) == 8 + state["config"]["extra_hands"]
        assert state["history"][-1]["loss"] < state["history"][0]["loss"]


def test_damaged_checkpoint_gives_a_clear_error(tmp_path):
    bad = tmp_path / "asrn.pt"
    bad.write_bytes(b"not a checkpoint")
    with pytest.raises(InputFileError, match="asrn.pt: not a readable checkpoint"):
        load_checkpoint(bad)


def test_shipped_dm_is_the_baseline_without_a_contact_term():
    assert stored_config(load_checkpoint(MODELS_DIR / "dm.pt")).contact_weight == 0.0
    assert default_config("dm").contact_weight == 0.0 and default_config("asrn").contact_weight > 0


def test_contact_term_sees_each_windows_own_source_contacts(sample_hands):
    # an untrained network is TBS Copy: on a same-hand batch its pose is the source's, so the gaps the loss
    # measures on the target equal the gaps stored with the windows (window and source hand line up)
    hands = [sample_hands["birch"], sample_hands["laurel"]]
    data = build_training_set("asrn", hands, scripts_per_hand=1, gestures_per_script=6, seed=1)
    config = default_config("asrn")
    model = build_model(config)
    same = sample_batch(data, np.random.default_rng(3), 4, 16, p_same=1.0)
    pose = forward_kinematics(hands[same.target], same.q_source.reshape(-1, 15, 4))
    gaps = contact_gaps(hands[same.target], pose, thumb_tips=False) / hands[same.target].hand_length  # its data's
    torch.testing.assert_close(gaps.float(), same.source_gaps.reshape(gaps.shape), atol=1e-5, rtol=0)
    # across hands the copied pose misses pad contacts the source makes, and the loss says so and pulls on them
    batches = [sample_batch(data, np.random.default_rng(s), 8, 16, p_same=0.0) for s in range(8)]
    cross = max(batches, key=lambda b: int((b.source_gaps[..., PAD_PAIRS] < CONTACT_TOLERANCE).sum()))
    assert (cross.source_gaps[..., PAD_PAIRS] < CONTACT_TOLERANCE).any()
    loss, parts = batch_loss(model, data, cross, config)
    assert parts["contact"] > 0
    loss.backward()
    assert model.head.weight.grad.abs().sum() > 0


def test_training_lowers_the_loss_on_batches_it_never_saw(sample_hands):
    # An untrained network is TBS Copy, whose loss sits next to its floor (-0.98 of a floor near -0.99): a drop
    # there is decided by kernel rounding. So the network starts knocked off its zero start (a random head, as
    # after a bad step): its residual breaks the anatomical limits (L_ana ~2) on every window. Thirty clipped
    # Adam steps on one set of scripts must bring the loss down by far more than rounding (measured: -0.78 ->
    # -0.99, L_ana 2.06 -> 0.04) on windows of other scripts, cross-hand and same-hand alike; with the
    # parameters frozen nothing moves and the test fails.
    hands = [sample_hands["birch"], sample_hands["cedar"]]
    config = TrainConfig(kind="asrn", batch_size=16, learning_rate=1e-3, p_same=0.5)
    seen = build_training_set("asrn", hands, scripts_per_hand=1, gestures_per_script=6, seed=1)
    unseen = build_training_set("asrn", hands, scripts_per_hand=1, gestures_per_script=6, seed=2)
    torch.manual_seed(0)
    model = build_model(config)
    with torch.no_grad():
        model.head.weight.normal_(0.0, 0.05)
    probe = [sample_batch(unseen, np.random.default_rng(100 + i), 16, 8, p_same) for i in range(4) for p_same in (0, 1)]

    def probe_loss() -> tuple[float, float]:
        with torch.no_grad():
            parts = [batch_loss(model, unseen, batch, config)[1] for batch in probe]
        return float(np.mean([p["loss"] for p in parts])), float(np.mean([p["anatomy"] for p in parts]))

    loss_before, anatomy_before = probe_loss()
    assert anatomy_before > 1.0  # the start is far from the floor
    optimiser = torch.optim.Adam(model.parameters(), lr=config.learning_rate)
    rng = np.random.default_rng(0)
    for _ in range(30):
        loss, _ = batch_loss(model, seen, sample_batch(seen, rng, 16, 8, config.p_same), config)
        optimiser.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), GRADIENT_CLIP)
        optimiser.step()
    loss_after, anatomy_after = probe_loss()
    assert loss_after < loss_before - 0.1
    assert anatomy_after < 0.1 * anatomy_before


def test_train_is_seeded_and_resumes(sample_hands, tmp_path):
    hands = [sample_hands["birch"], sample_hands["cedar"]]
    # 20 steps and no extra hands: each train() call fits the gesture library to its hands (3 s a hand), which
    # is what the four calls below spend their time on
    config = TrainConfig(kind="dm", steps=20, checkpoint_every=10, scripts_per_hand=1, batch_size=8, extra_hands=0)
    train(config, hands, tmp_path / "a.pt", show_progress=False)
    train(config, hands, tmp_path / "b.pt", show_progress=False)
    a, b = load_checkpoint(tmp_path / "a.pt"), load_checkpoint(tmp_path / "b.pt")
    for key in a["model"]:
        assert torch.equal(a["model"][key], b["model"][key])
    # stop half way, then resume: the same weights as training straight through
    train(config, hands, tmp_path / "c.pt", show_progress=False, stop_at=10)
    assert load_checkpoint(tmp_path / "c.pt")["step"] == 10
    train(config, hands, tmp_path / "c.pt", resume=True, show_progress=False)
    c = load_checkpoint(tmp_path / "c.pt")
    assert c["step"] == 20
    for key in a["model"]:
        torch.testing.assert_close(c["model"][key], a["model"][key])


def test_a_clip_without_target_contacts_has_no_precision_and_the_means_skip_it(sample_hands, tmp_path):
    hand = sample_hands["iris"]
    motion = synthesize(["pinch", "ok"], sample_hands["birch"], seed=3)  # pad contacts in the source
    flat = np.zeros_like(motion.q_tbs)
    flat[..., 0] = 1.0  # the canonical flat hand on every frame: no pad ever touches another
    untouched = score_retarget(sample_hands["birch"], motion.q_tbs, hand, flat)
    assert np.isnan(untouched.contact_precision) and untouched.contact_recall == 0.0  # undefined, not 1.000

    def row(method: str, precision: float) -> EvaluationRow:
        scores = RetargetScores(s_palm=1.0, s_finger=1.0, s_finger_paper=0.9, contact_precision=precision,
                                contact_recall=0.5, palm_contact_recall=0.5, violation_rate=0.0, jitter=0.0)
        return EvaluationRow(method, "clip", "birch", "iris", "same", scores)

    rows = [row("copy", float("nan")), row("tbs_copy", 0.6), row("tbs_copy", float("nan")), row("tbs_copy", 0.8)]
    summary = summarise(rows)
    assert np.isnan(summary["copy"]["Contact P"]) and summary["tbs_copy"]["Contact P"] == pytest.approx(0.7)
    table = format_markdown(summary).splitlines()
    assert "| n/a | 0.500 |" in table[2] and "| 0.700 | 0.500 |" in table[3]  # Contact P, Contact R
    csv_path = write_results(rows, summary, tmp_path)[0]
    assert csv_path.read_text().splitlines()[1].split(",")[9] == ""  # contact_precision: no score, no "nan"
