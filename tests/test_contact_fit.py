"""The contact fit after a retarget: pad contacts agree with the source's, nothing else moves."""

import numpy as np
import pytest

from s2h_viewer.io.files import load_hand_file
from s2h_viewer.motions.synthesis import synthesize
from s2h_viewer.retarget.contact_fit import _batches, disagreement, fit_contacts, runs_around
from s2h_viewer.retarget.methods import retarget
from s2h_viewer.semantics.metrics import score_retarget
from s2h_viewer.samples import ASSETS_DIR


@pytest.fixture(scope="module")
def webxr_right():
    return load_hand_file(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb")


def test_runs_cover_each_disagreement_with_its_reach_and_merge_when_close():
    differ = np.zeros(30, bool)
    differ[[0, 10, 13, 29]] = True  # at both ends, and two 3 frames apart: their runs merge
    assert runs_around(differ, reach=2) == [(0, 3), (8, 16), (27, 30)]
    assert runs_around(np.zeros(30, bool), reach=2) == []


def test_fit_closes_the_contacts_tbs_copy_loses_on_the_webxr_hand(sample_hands, webxr_right):
    source = sample_hands["birch"]
    motion = synthesize(["ok", "pinch", "letter_o", "fist", "count_2"], source, seed=4)
    copied = retarget(motion, source, webxr_right, "tbs_copy").q_tbs
    fitted = fit_contacts(motion.q_tbs, source, webxr_right, copied.copy())
    before = score_retarget(source, motion.q_tbs, webxr_right, copied)
    after = score_retarget(source, motion.q_tbs, webxr_right, fitted)
    assert before.contact_recall < 0.9  # the proportions differ: a copied pinch does not close
    assert after.contact_recall >= 0.95 and after.contact_precision >= 0.95
    assert after.violation_rate <= 0.01
    assert after.s_finger >= before.s_finger - 0.005  # contacts are bought without losing the rest


def test_frames_far_from_a_disagreement_come_back_bit_for_bit(sample_hands, webxr_right):
    source = sample_hands["birch"]
    motion = synthesize(["relaxed", "pinch", "relaxed", "relaxed"], source, seed=5)
    copied = retarget(motion, source, webxr_right, "tbs_copy").q_tbs
    runs = runs_around(disagreement(source, motion.q_tbs, webxr_right, copied), reach=4)
    assert runs, "the copied pinch should miss on the WebXR hand"
    fitted = fit_contacts(motion.q_tbs, source, webxr_right, copied.copy())
    inside = np.zeros(len(copied), bool)
    for first, end in runs:
        inside[first:end] = True
    assert inside.sum() < len(copied)
    assert np.array_equal(fitted[~inside], copied[~inside])
    assert not np.allclose(fitted[inside], copied[inside])
    # the correction fades in and out: each run's ends move less than half its largest change
    for first, end in runs:
        change = np.abs(fitted[first:end] - copied[first:end]).reshape(end - first, -1).max(-1)
        assert max(change[0], change[-1]) < 0.5 * change.max(), f"frames {first}-{end - 1} jump at an end"


def test_asrn_keeps_the_source_contacts_on_the_godot_hand(sample_hands):
    # the Godot hand's fingers are long and thin beside the procedural ones: TBS Copy keeps 71% of the touches
    # (38% before every hand's thumb CMC was framed alike) and 92% of the frames' signatures (about half while its
    # pinky bent about the rays' axes, pressing on the ring), and the network alone (trained on procedural hands)
    # misses many of them
    godot = load_hand_file(ASSETS_DIR / "hands" / "real" / "godot_hand_r.gltf")
    source = sample_hands["birch"]
    motion = synthesize(["pinch", "ok", "letter_o", "count_3", "fist"], source, seed=6)
    scores = {m: score_retarget(source, motion.q_tbs, godot, retarget(motion, source, godot, m).q_tbs)
              for m in ("tbs_copy", "asrn")}
    assert scores["tbs_copy"].contact_recall < 0.8 and scores["tbs_copy"].signature_kept < 0.95
    asrn = scores["asrn"]
    assert asrn.contact_recall >= 0.9 and asrn.contact_precision >= 0.9 and asrn.violation_rate <= 0.01
    assert asrn.signature_kept >= 0.99
    # the ASRN trained on the wider pose space (issue 26) gives up a little of the ASM on this gesture clip for the
    # real poses it now keeps (350 of 350 over the real rigs, 244 before): S_finger 0.9714 vs TBS Copy's 0.9800,
    # S_palm 0.9802 vs 0.9861 (before the thumb CMC's palm frame: 0.9741 vs 0.9760, 0.9826 vs 0.9848, TBS Copy rising
    # with its thumb where the source's is; the gesture-only network: 0.982 / 0.988); with every angle held within
    # the anatomical limits (the network's twists too: no violation added) 0.9722 vs 0.9823 (0.9734 before), S_palm
    # 0.9812 vs 0.9870: no more than 0.012 below
    assert asrn.s_finger >= scores["tbs_copy"].s_finger - 0.012 and asrn.s_palm >= scores["tbs_copy"].s_palm - 0.012


def test_batches_hold_at_most_their_frames_and_cover_every_run():
    runs = [(0, 5), (10, 30), (40, 41), (50, 120)]
    batches = _batches(runs, 25)
    assert all(sum(b - a for a, b in batch) <= 25 for batch in batches)
    covered = sorted(f for batch in batches for a, b in batch for f in range(a, b))
    assert covered == [f for a, b in runs for f in range(a, b)]


def test_the_fit_keeps_on_the_palm_the_fingertips_the_network_and_the_source_have_there():
    """Closing the thumb's touches in the gestures clip's fists, the fit lifted the ring finger off the palm on the
    VRM robot and the mitten avatar (their ring fingertip-palm recall 1.00 -> 0.52, TBS Copy's 1.00); it may not. And
    where the network lost one that TBS Copy keeps (the mitten's index: 0.42), the fit brings it back."""
    import torch

    from s2h_viewer import samples
    from s2h_viewer.hand.kinematics import joint_positions
    from s2h_viewer.io.files import RigOptions
    from s2h_viewer.retarget.asrn.inference import network_retarget
    from s2h_viewer.semantics.anatomy import within_source_limits
    from s2h_viewer.semantics.contacts import CONTACT_TOLERANCE, palm_gaps

    gestures = next(m for m in samples.load_sample_motions() if m.name.startswith("gestures"))
    source = samples.load_sample_hand(gestures.hand_name)

    def on_palm(hand, q):
        with torch.no_grad():
            gaps = palm_gaps(hand, joint_positions(hand, torch.as_tensor(q, dtype=torch.float32))).numpy()
        return gaps < CONTACT_TOLERANCE * hand.hand_length
    in_source = on_palm(source, gestures.q_tbs)
    for rig in ("cryptovoxels.vrm", "debug_robot.vrm"):
        hand = load_hand_file(ASSETS_DIR / "hands" / "real" / rig, RigOptions(side="right"))
        network = within_source_limits(gestures.q_tbs, network_retarget("asrn", gestures.q_tbs, source, hand))
        held = in_source & on_palm(hand, network)
        fitted = fit_contacts(gestures.q_tbs, source, hand, network.copy())
        assert not np.array_equal(fitted, network)  # the fit did change the clip (its touches)
        lost = held & ~on_palm(hand, fitted)
        assert held.sum() > 300 and lost.sum() <= 0.01 * held.sum(), (rig, lost.sum(), held.sum())
        scores = {method: score_retarget(source, gestures.q_tbs, hand, retarget(gestures, source, hand, method).q_tbs)
                  for method in ("tbs_copy", "asrn")}
        assert scores["asrn"].palm_contact_recall >= scores["tbs_copy"].palm_contact_recall - 0.01, (rig, scores)
