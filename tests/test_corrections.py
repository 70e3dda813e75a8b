"""Corrections of a retarget (`retarget.corrections`, `io.corrections`, ``s2h retarget --corrections``): the offset
curve's keys, ranges and eases; a turn about a joint's own axis moves that joint's chain and nothing else; the
sidecar's round trip and its refusals of hostile files; the command line applying a sidecar as the viewer does."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from fuzzing import Tally, classify, mutate_json
from s2h_viewer.cli import main
from s2h_viewer.errors import InputFileError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.io.corrections import (CorrectionsFile, load_corrections, save_corrections, sidecar_path)
from s2h_viewer.io.files import load_motion_file
from s2h_viewer.io.npz import save_motion
from s2h_viewer.motions.synthesis import synthesize
from s2h_viewer.retarget.comparison import compute_result, corrected_result, source_semantics
from s2h_viewer.retarget.corrections import AXES, Corrections, key_span, smoothstep, turn_about
from s2h_viewer.retarget.methods import retarget

INDEX_PIP = topo.ARTICULATED_NAMES.index("index_pip")


def degrees(corrections: Corrections, joint: int, n_frames: int) -> np.ndarray:
    return np.degrees(corrections.of(joint).offsets(n_frames).magnitude())


def test_a_key_holds_its_turn_at_its_frame_and_eases_to_nothing_at_its_range_ends():
    fixes = Corrections().with_turn(INDEX_PIP, 40, turn_about("bend", 30.0), 20, 70)
    curve = degrees(fixes, INDEX_PIP, 100)
    assert curve[40] == pytest.approx(30.0, abs=1e-9)
    assert np.all(curve[:21] < 1e-9) and np.all(curve[70:] < 1e-9)  # nothing at and outside the range's ends
    rising, falling = np.diff(curve[20:41]), np.diff(curve[40:71])
    assert np.all(rising > 0) and np.all(falling < 0)  # eases in, then out
    assert rising[0] < rising[10] and rising[-1] < rising[10]  # flat at both ends of the ease (a smoothstep)
    np.testing.assert_allclose(curve[20:41], 30.0 * smoothstep(np.arange(21) / 20), atol=1e-9)
    np.testing.assert_allclose(curve[40:71], 30.0 * smoothstep(np.arange(30, -1, -1) / 30), atol=1e-9)
    axis = fixes.of(INDEX_PIP).offsets(100)[30].as_rotvec()
    np.testing.assert_allclose(axis / np.linalg.norm(axis), [0.0, 1.0, 0.0], atol=1e-12)  # about its bend axis


def test_a_key_on_a_held_pose_holds_over_the_pose_and_eases_only_between_poses():
    """The authored poses read as one clip (`--animation all`) hold each pose 12 frames, 8 between: a fix on one
    frame of a pose faded across the pose itself and, at the default ease of 10, into the poses either side. A
    new key on a held pose now holds its whole turn over the pose and eases over the frames between poses; one
    between poses eases within them; a clip with no poses keeps the ease frames."""
    labels = np.array(["Cup"] * 12 + [""] * 8 + ["OK"] * 12 + [""] * 8 + ["Peace"] * 12, dtype=object)
    assert key_span(labels, 25, 10, 10) == (12, 39, (20, 31))  # anywhere in OK: all of OK, eased up to Cup, Peace
    assert key_span(labels, 20, 3, 3) == (17, 34, (20, 31))  # eased over 3 frames
    assert key_span(labels, 14, 10, 10) == (12, 19, None)  # between poses: within the frames between
    assert key_span(np.full(100, "", dtype=object), 50, 10, 5) == (40, 55, None)  # no poses: the ease frames
    assert key_span(labels, 0, 10, 10) == (0, 19, (0, 11))
    start, end, hold = key_span(labels, 25, 10, 10)
    fixes = Corrections().with_turn(INDEX_PIP, 25, turn_about("bend", 30.0), start, end, hold)
    curve = degrees(fixes, INDEX_PIP, len(labels))
    np.testing.assert_allclose(curve[20:32], 30.0, atol=1e-9)  # the whole OK fixed alike
    assert np.all(curve[labels == "Cup"] < 1e-9) and np.all(curve[labels == "Peace"] < 1e-9)
    assert np.all(np.diff(curve[12:21]) >= 0) and np.all(np.diff(curve[31:40]) <= 0)  # eased between
    (key,) = fixes.of(INDEX_PIP).keys
    assert key.hold == (20, 31) and "frame 25 (held over 20-31, blended over 12-39)" in fixes.describe()
    again = fixes.with_turn(INDEX_PIP, 25, turn_about("bend", 10.0), 0, 43, None)  # its frames kept
    np.testing.assert_allclose(degrees(again, INDEX_PIP, len(labels))[20:32], 40.0, atol=1e-6)
    narrower = fixes.with_range(INDEX_PIP, 25, 22, 28)  # a marked range within the pose: the hold within it
    assert narrower.of(INDEX_PIP).keys[0].hold == (22, 28)


def test_a_second_key_changes_only_its_own_range_and_deleting_it_gives_back_the_first(sample_hands):
    first = Corrections().with_turn(INDEX_PIP, 40, turn_about("bend", 30.0), 20, 60)
    assert degrees(first, INDEX_PIP, 100)[50] == pytest.approx(15.0, abs=1e-6)  # half way down the ease out
    both = first.with_turn(INDEX_PIP, 50, turn_about("bend", 10.0), 45, 55)
    curve, alone = degrees(both, INDEX_PIP, 100), degrees(first, INDEX_PIP, 100)
    assert curve[50] == pytest.approx(25.0, abs=1e-6)  # the 15 there turned 10 more, as dragged
    np.testing.assert_allclose(curve[:46], alone[:46], atol=1e-9)  # outside the new key's range: as before
    np.testing.assert_allclose(curve[55:], alone[55:], atol=1e-9)
    assert [(k.frame, k.start, k.end) for k in both.of(INDEX_PIP).keys] == [(40, 20, 60), (50, 45, 55)]
    assert both.without_key(INDEX_PIP, 50) == first  # deleting a key gives back exactly what was there without it
    far = both.with_turn(INDEX_PIP, 80, turn_about("splay", -5.0), 75, 90)
    np.testing.assert_allclose(degrees(far, INDEX_PIP, 100)[:75], curve[:75], atol=1e-9)  # no widened range
    assert far.n_keys == 3 and list(far.frames()) == [40, 50, 80]
    again = far.with_turn(INDEX_PIP, 50, turn_about("bend", 5.0), 0, 99)  # a key there: turned further, range kept
    assert again.of(INDEX_PIP).key_at(50).start == 45 and degrees(again, INDEX_PIP, 100)[50] == pytest.approx(30.0)
    assert not far.without_key(INDEX_PIP, 40).without_key(INDEX_PIP, 50).without_key(INDEX_PIP, 80)
    narrowed = both.with_range(INDEX_PIP, 50, 52, 52)  # a range keeps its key's frame inside it
    assert (narrowed.of(INDEX_PIP).key_at(50).start, narrowed.of(INDEX_PIP).key_at(50).end) == (50, 52)
    assert both.with_range(INDEX_PIP, 41, 0, 99) == both  # no key at that frame: nothing changes
    assert both.without_joint(INDEX_PIP) == Corrections()


def test_overlapping_keys_about_different_axes_still_hold_each_drag_at_its_frame():
    """Keys whose ranges overlap compose; each drag turns the joint by what was dragged at its own frame."""
    first = Corrections().with_turn(INDEX_PIP, 40, turn_about("bend", 30.0), 20, 60)
    second = first.with_turn(INDEX_PIP, 45, turn_about("splay", 20.0), 35, 55)
    want = first.offset_at(INDEX_PIP, 45) * turn_about("splay", 20.0)
    got = second.offset_at(INDEX_PIP, 45)
    assert np.degrees((got.inv() * want).magnitude()) < 1e-6
    third = second.with_turn(INDEX_PIP, 40, turn_about("twist", -15.0), 0, 99)  # the first key turned further
    want = second.offset_at(INDEX_PIP, 40) * turn_about("twist", -15.0)
    assert np.degrees((third.offset_at(INDEX_PIP, 40).inv() * want).magnitude()) < 1e-6


def test_a_turn_about_a_joints_bend_axis_moves_its_chain_by_that_much_and_nothing_else(sample_hands):
    hand = sample_hands["iris"]
    motion = synthesize(["fist", "ok"], sample_hands["birch"], seed=3, name="clip")
    q = retarget(motion, sample_hands["birch"], hand, "tbs_copy").q_tbs
    frame = 30
    fixes = Corrections().with_turn(INDEX_PIP, frame, turn_about("bend", 25.0), 20, 40)
    before, after = forward_kinematics(hand, q), forward_kinematics(hand, fixes.apply(q))
    pip, dip, tip = (topo.JOINT_NAMES.index(f"index_{level}") for level in ("pip", "dip", "tip"))
    moved = {dip, tip}
    still = [j for j in range(topo.N_JOINTS) if j not in moved]
    np.testing.assert_allclose(after.positions[:, still], before.positions[:, still], atol=1e-5)
    assert torch.linalg.norm(after.positions[frame, tip] - before.positions[frame, tip]) > 0.1 * hand.hand_length / 4
    outside = [f for f in range(motion.n_frames) if not 20 <= f <= 40]
    np.testing.assert_allclose(after.positions[outside], before.positions[outside], atol=1e-6)
    # the PIP's frame turned 25 deg about its own bend axis at the key's frame: bone directions say so
    bone_before = before.positions[frame, dip] - before.positions[frame, pip]
    bone_after = after.positions[frame, dip] - after.positions[frame, pip]
    cosine = torch.dot(bone_before, bone_after) / (bone_before.norm() * bone_after.norm())
    assert np.degrees(np.arccos(float(cosine.clamp(-1, 1)))) == pytest.approx(25.0, abs=0.05)
    axis = before.frames[frame, pip][:, AXES.index("bend")]
    np.testing.assert_allclose(float(torch.dot(axis, bone_after)), 0.0, atol=1e-5)  # turned in its bend plane


def test_a_corrected_retarget_is_measured_again_and_no_corrections_give_the_methods_own(sample_hands):
    source, target = sample_hands["birch"], sample_hands["iris"]
    motion = synthesize(["fist", "ok", "v_sign"], source, seed=4, name="clip")
    _, source_asm = source_semantics(motion, source)
    result = compute_result(motion, source, source_asm, target, "tbs_copy")
    fixes = Corrections().with_turn(INDEX_PIP, 40, turn_about("bend", -60.0), 20, 60)
    fixed = corrected_result(result, fixes, motion, source, source_asm)
    assert fixed.base is result and fixed.uncorrected is result and fixed.corrections == fixes
    np.testing.assert_allclose(fixed.motion.q_tbs, fixes.apply(result.motion.q_tbs))
    assert fixed.frame_error[40] > result.frame_error[40] + 0.01  # a finger turned off: its error shows there
    np.testing.assert_allclose(fixed.frame_error[:20], result.frame_error[:20], atol=1e-6)
    assert fixed.scores.s_finger < result.scores.s_finger
    again = corrected_result(fixed, fixes.with_turn(INDEX_PIP, 40, turn_about("bend", 60.0), 20, 60), motion,
                             source, source_asm)  # measured from the method's retarget, not the corrected one
    assert again.base is result
    assert corrected_result(fixed, Corrections(), motion, source, source_asm) is result


def sample_file(tmp_path) -> tuple[CorrectionsFile, object]:
    fixes = (Corrections().with_turn(INDEX_PIP, 40, turn_about("bend", 30.0), 20, 60)
             .with_turn(INDEX_PIP, 50, turn_about("splay", 10.0), 45, 55)
             .with_turn(topo.ARTICULATED_NAMES.index("thumb_ip"), 10, turn_about("twist", -20.0), 0, 30, (5, 15)))
    file = CorrectionsFile(fixes, "clip", 100, 30.0, "birch", "iris", "tbs_copy")
    return file, save_corrections(tmp_path / "take.glb.corrections.json", file)


def test_the_sidecar_reads_back_what_was_written_and_sits_beside_its_motion(tmp_path):
    file, path = sample_file(tmp_path)
    read = load_corrections(path)
    assert (read.clip, read.frames, read.fps, read.source, read.target, read.method) == (
        "clip", 100, 30.0, "birch", "iris", "tbs_copy")
    q = np.zeros((100, 15, 4), np.float32)
    q[..., 0] = 1.0
    np.testing.assert_allclose(read.corrections.apply(q), file.corrections.apply(q), atol=1e-6)
    assert [c.name for c in read.corrections.joints] == ["thumb_ip", "index_pip"]
    assert read.corrections.joints[0].keys[0].hold == (5, 15) and read.corrections.joints[1].keys[0].hold is None
    assert sidecar_path(tmp_path / "take.glb") == path
    assert read.mismatch(100) is None and "100 frames" in read.mismatch(90)


@pytest.mark.parametrize("change, problem", [
    (lambda d: d.update(format="other"), 'no "format"'),
    (lambda d: d.update(version=2), "version 2"),
    (lambda d: d.update(frames=-3), "frames"),
    (lambda d: d["joints"][0].update(joint="index_pipp"), "'index_pipp' is not one of"),
    (lambda d: d["joints"].append(dict(d["joints"][0])), "corrected twice"),
    (lambda d: d["joints"][0]["keys"][0].update(end=500), "end is 500, outside"),
    (lambda d: d["joints"][1]["keys"][0].update(frame=500), "frame is 500, outside 0..99"),
    (lambda d: d["joints"][1]["keys"][0].update(start=45), "start is 45, outside 0..40"),
    (lambda d: d["joints"][1]["keys"][0].update(start=True), "start is True, not a whole number"),
    (lambda d: d["joints"][1]["keys"].reverse(), "does not follow"),
    (lambda d: d["joints"][1]["keys"][0].update(rotation_deg=[float("nan"), 0, 0]), "not three finite numbers"),
    (lambda d: d["joints"][1]["keys"][0].update(rotation_deg=[0, 1, "2"]), "not three finite numbers"),
    (lambda d: d["joints"][1]["keys"][0].update(rotation_deg=[900, 0, 0]), "a turn of 900 deg"),
    (lambda d: d["joints"][1].update(keys=[]), "has no keys"),
    (lambda d: d["joints"][0]["keys"][0].update(hold=[12, 5]), "hold's first frame is 12, outside 0..10"),
    (lambda d: d["joints"][0]["keys"][0].update(hold=[5, 31]), "hold's last frame is 31, outside 10..30"),
    (lambda d: d["joints"][0]["keys"][0].update(hold=5), '"hold" is 5, not [first, last]'),
])
def test_a_hostile_sidecar_is_refused_naming_the_file_and_the_problem(tmp_path, change, problem):
    _, path = sample_file(tmp_path)
    document = json.loads(path.read_text())
    change(document)
    path.write_text(json.dumps(document))  # Python's json writes NaN as NaN: a reader must check, not trust
    with pytest.raises(InputFileError) as caught:
        load_corrections(path)
    assert path.name in str(caught.value) and problem in str(caught.value) and "\n" not in str(caught.value)


def test_damaged_sidecars_never_give_a_traceback(tmp_path):
    _, path = sample_file(tmp_path)
    data, rng, tally = path.read_bytes(), np.random.default_rng(11), Tally()
    for n in range(60):
        what, damaged = mutate_json(data, rng)
        bad = tmp_path / f"bad{n}.corrections.json"
        bad.write_bytes(damaged)
        tally.add("corrections", what, *classify(lambda: load_corrections(bad), bad))
    assert tally.bad() == 0, tally.table()


def test_s2h_retarget_applies_a_sidecar_and_records_it_beside_its_output(tmp_path, sample_hands, capsys):
    motion = synthesize(["fist", "ok"], sample_hands["birch"], seed=3, name="clip")
    clip = save_motion(motion, tmp_path / "clip.npz")
    fixes = Corrections().with_turn(INDEX_PIP, 30, turn_about("bend", 40.0), 10, 50)
    sidecar = save_corrections(tmp_path / "fix.corrections.json", CorrectionsFile(
        fixes, "clip", motion.n_frames, motion.fps, "birch", "laurel", "dm"))
    args = ["retarget", "--motion", str(clip), "--source", "birch", "--target", "iris", "--method", "tbs_copy",
            "--quiet"]
    assert main(args + ["--out", str(tmp_path / "plain.npz")]) == 0
    assert main(args + ["--out", str(tmp_path / "fixed.npz"), "--corrections", str(sidecar)]) == 0
    said = capsys.readouterr().out
    assert "made on dm -> laurel; applied to tbs_copy -> iris" in said
    plain, _ = load_motion_file(tmp_path / "plain.npz")
    fixed, _ = load_motion_file(tmp_path / "fixed.npz")
    np.testing.assert_allclose(fixed.q_tbs, fixes.apply(plain.q_tbs), atol=1e-6)
    record = load_corrections(tmp_path / "fixed.npz.corrections.json")
    assert (record.target, record.method) == ("iris", "tbs_copy") and record.corrections.n_keys == 1
    assert not list(tmp_path.glob("plain*.corrections.json"))
    # written again without corrections: the earlier export's sidecar is kept, and said to be not this motion's
    assert main(args + ["--out", str(tmp_path / "fixed.npz")]) == 0
    said = capsys.readouterr().out
    assert "fixed.npz.corrections.json beside it is an earlier export's corrections, left as it was" in said
    assert load_corrections(tmp_path / "fixed.npz.corrections.json").corrections.n_keys == 1
    short = save_corrections(tmp_path / "short.corrections.json", CorrectionsFile(
        fixes, "clip", motion.n_frames + 5, motion.fps, "birch", "iris", "tbs_copy"))
    assert main(args + ["--out", str(tmp_path / "never.npz"), "--corrections", str(short)]) != 0
    err = capsys.readouterr().err
    assert "short.corrections.json" in err and f"this one has {motion.n_frames}" in err and "Traceback" not in err
    assert not (tmp_path / "never.npz").exists()
    # an output whose folder's name is a file's: one line naming it (a fresh-eyes user got a traceback)
    assert main(args + ["--out", str(tmp_path / "plain.npz" / "x.glb"), "--corrections", str(sidecar)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "plain.npz: could not write (Not a directory)" in err, err


def test_every_message_names_a_joint_one_way():
    """'thumb IP', 'index PIP': the fixing's bar and undo texts, the viewer's and the batch report's sideways line
    (which said 'thumb ip' where the others said 'thumb IP')."""
    from s2h_viewer.batch.report import sideways_note
    from s2h_viewer.semantics.flexion import SidewaysPeak
    assert [topo.joint_label(n) for n in ("thumb_ip", "index_pip", "pinky_mcp", "wrist")] == [
        "thumb IP", "index PIP", "pinky MCP", "wrist"]
    assert SidewaysPeak(40.0, "thumb_ip", 3).describe() == "thumb IP bends 40 deg sideways at frame 3"
    assert sideways_note({"sideways_at": "thumb_ip@3", "sideways_deg": 40.0}) == SidewaysPeak(
        40.0, "thumb_ip", 3).describe()
    fixes = Corrections().with_turn(topo.ARTICULATED_NAMES.index("thumb_ip"), 5, turn_about("bend", 10.0), 0, 9)
    assert fixes.describe() == "thumb IP: key at frame 5 (blended over 0-9)"
