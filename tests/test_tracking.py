"""Tracked hands as a motion source: the readers (WebXR/OpenXR, MediaPipe, keypoint arrays), the fitter
against the truth it was recorded from, a real WebXR recording, and every command that takes a motion."""

from __future__ import annotations

import json

import numpy as np
import pytest

from s2h_viewer.cli import main
from s2h_viewer.errors import InputFileError
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.io.files import load_hand_file, load_motion_file
from s2h_viewer.io.mediapipe_hand import save_mediapipe_hand
from s2h_viewer.io.recordings import read_recording
from s2h_viewer.io.webxr_hand import OPENXR_JOINTS, WEBXR_JOINTS, save_webxr_hand
from s2h_viewer.retarget import retarget
from s2h_viewer.samples import ASSETS_DIR, load_sample_motions
from s2h_viewer.semantics.contacts import CONTACT_PAIRS, detect_contacts, pair_index
from s2h_viewer.tracking.accuracy import compare_with_truth
from s2h_viewer.tracking.fitter import fit_recording
from s2h_viewer.tracking.synthetic import synthetic_recording

REAL_WEBXR = ASSETS_DIR / "recordings" / "webxr_hand_poses_right.json"
REAL_WEBXR_LEFT = ASSETS_DIR / "recordings" / "webxr_hand_poses_left.json"
GODOT = str(ASSETS_DIR / "hands" / "real" / "godot_hand_r.gltf")


@pytest.fixture(scope="module")
def gestures():
    return load_sample_motions()[0]


@pytest.mark.parametrize("name, seed", [("iris", 0), ("gorse", 1), ("kale", 2)])
def test_noise_free_keypoints_give_back_the_joints_and_the_finger_angles(sample_hands, gestures, name, seed):
    """Truth known: a shipped motion on a procedural hand, recorded as keypoints (gorse: the worst of the 12)."""
    hand = sample_hands[name]
    fit = fit_recording(synthetic_recording(hand, gestures, seed=seed), mesh=False)
    accuracy = compare_with_truth(fit, hand, gestures, seed)
    assert accuracy.position_mm_mean < 0.5 and accuracy.position_mm_max < 4.0
    assert accuracy.finger_deg_mean < 2.0 and accuracy.finger_deg_max < 5.0
    assert 0.7 < accuracy.jitter_ratio < 1.05
    assert not fit.filled.any() and np.nanmax(fit.residual_mm) < 3.0


def test_noisy_keypoints_are_smoothed_without_losing_the_motion(sample_hands, gestures):
    """3 mm of noise (RMS, 3D) on every keypoint: joints within 5 mm, jitter within 1.5 x the truth's."""
    hand = sample_hands["laurel"]
    clean = compare_with_truth(fit_recording(synthetic_recording(hand, gestures, seed=4), mesh=False), hand,
                               gestures, 4)
    fit = fit_recording(synthetic_recording(hand, gestures, noise_mm=3.0, seed=4), mesh=False)
    noisy = compare_with_truth(fit, hand, gestures, 4)
    assert noisy.position_mm_mean < 5.0 and noisy.jitter_ratio < 1.5
    assert noisy.position_mm_mean > clean.position_mm_mean  # the noise is there (the check can fail)
    assert 1.2 < fit.noise_mm < 2.3  # per coordinate: 3 / sqrt(3) = 1.73


def test_lost_frames_and_spikes_are_filled_and_marked(sample_hands, gestures):
    hand = sample_hands["iris"]
    recording = synthetic_recording(hand, gestures, noise_mm=2.0, lost=0.08, seed=5)
    lost = ~recording.valid
    tracked = np.flatnonzero(~lost[:-1] & ~lost[1:] & ~np.roll(lost, 1)[:-1])[1::30]  # away from the gaps
    for i, frame in enumerate(tracked):  # a keypoint thrown 3-5 cm for one frame, as trackers do
        recording.positions[frame, 1 + i % 20] += np.array([0.03, -0.02, 0.02]) * (1 + i % 3) / 2
    fit = fit_recording(recording, mesh=False)
    assert lost.sum() >= 0.08 * len(lost) and np.array_equal(fit.lost, lost)
    assert len(tracked) >= 8 and set(np.flatnonzero(fit.filled & ~lost)) == set(tracked)
    assert np.isnan(fit.residual_mm[fit.filled]).all() and np.isfinite(fit.residual_mm[~fit.filled]).all()
    accuracy = compare_with_truth(fit, hand, gestures, 5)
    assert accuracy.position_mm_mean < 5.0  # filled frames too: the motion runs on through the gaps
    assert np.isfinite(fit.motion.q_tbs).all() and fit.motion.n_frames == len(lost)


def test_a_left_hand_recording_is_fitted_as_its_mirror(sample_hands, gestures):
    hand = sample_hands["kale"]
    right = fit_recording(synthetic_recording(hand, gestures, seed=6), mesh=False)
    left_recording = synthetic_recording(hand, gestures, side="left", seed=6)
    left = fit_recording(left_recording, mesh=False)
    assert left.motion.meta["tracked"]["side"] == "left"
    np.testing.assert_allclose(left.motion.q_tbs, right.motion.q_tbs, atol=2e-3)


@pytest.mark.parametrize("writer", ["webxr", "mediapipe"])
def test_files_read_back_as_written_and_the_side_comes_from_the_geometry(tmp_path, sample_hands, gestures, writer):
    hand = sample_hands["iris"]
    for side in ("right", "left"):
        recording = synthetic_recording(hand, gestures, lost=0.05, side=side, seed=7)
        path = tmp_path / f"{side}.json"
        if writer == "webxr":
            save_webxr_hand(path, recording)
        else:  # MediaPipe labels a hand as if the image were mirrored: the label says the other side
            save_mediapipe_hand(path, recording, handedness="Left" if side == "right" else "Right")
        back = read_recording(path)
        assert back.side == side and back.n_frames == recording.n_frames
        np.testing.assert_allclose(back.positions, recording.positions, atol=1e-5)
        assert np.array_equal(back.valid, recording.valid)
        if writer == "webxr":
            np.testing.assert_allclose(back.orientations[back.valid][:, 1:4], recording.orientations[
                recording.valid][:, 1:4], atol=1e-5)


def test_openxr_joint_names_with_the_palm_are_read(tmp_path, sample_hands, gestures):
    recording = synthetic_recording(sample_hands["iris"], gestures, seed=8)
    webxr = json.loads(save_webxr_hand(tmp_path / "w.json", recording).read_text())
    palm = np.eye(4).T.ravel().tolist()
    webxr["joints"] = list(OPENXR_JOINTS)
    webxr["frames"] = [None if f is None else palm + f for f in webxr["frames"]]
    (tmp_path / "o.json").write_text(json.dumps(webxr))
    back = read_recording(tmp_path / "o.json")
    assert back.format == "openxr-hand" and len(OPENXR_JOINTS) == 26 and len(WEBXR_JOINTS) == 25
    np.testing.assert_allclose(back.positions, recording.positions, atol=1e-5)


def test_keypoint_arrays_need_their_frame_rate_or_assume_30(tmp_path, sample_hands, gestures):
    recording = synthetic_recording(sample_hands["iris"], gestures, lost=0.05, seed=9)
    np.save(tmp_path / "k.npy", recording.positions)
    np.savez(tmp_path / "k.npz", keypoints=recording.positions, fps=60.0)
    from_npy = read_recording(tmp_path / "k.npy")
    assert from_npy.fps == 30.0 and any("assumed" in n for n in from_npy.notes)
    assert read_recording(tmp_path / "k.npy", fps=24.0).fps == 24.0
    assert read_recording(tmp_path / "k.npz").fps == 60.0
    with pytest.raises(InputFileError, match="--fps is 0"):
        read_recording(tmp_path / "k.npy", fps=0.0)
    assert np.array_equal(read_recording(tmp_path / "k.npz").valid, recording.valid)


def _bad_files(tmp_path, recording) -> dict[str, tuple[str, str]]:
    """name -> (file, what the one line must say)."""
    good = json.loads(save_mediapipe_hand(tmp_path / "good.json", recording).read_text())
    files = {"truncated": ('{"format": "mediapipe-hand", "fps": 30, "frames": [[[0.1, 0.2', "truncated"),
             "wrong joint count": (dict(good, frames=[good["frames"][0][:20]]), "20 landmarks, not 21"),
             "nan": (json.dumps(dict(good, frames=[good["frames"][0], [[float("nan")] * 3] * 21])), "NaN"),
             "all frames null": (dict(good, frames=[None, None, None]), "all 3 frames are null"),
             "fps 0": (dict(good, fps=0), '"fps" is 0'),
             "no format": (dict(good, format="leap-motion"), '"format" is'),
             "not a hand in metres": (dict(good, frames=[(np.array(f) * 1000).tolist() for f in good["frames"]
                                                         if f]), "not a hand in metres"),
             "webxr joints missing": ({"format": "webxr-hand", "fps": 30, "joints": list(WEBXR_JOINTS[:24]),
                                       "frames": [[0.0] * 16 * 24]}, "lacks pinky-finger-tip")}
    webxr = json.loads(save_webxr_hand(tmp_path / "webxr.json", recording).read_text())
    files["handedness against the axes"] = (dict(webxr, handedness="left"), "joint axes form a right hand")
    out = {}
    for name, (content, says) in files.items():
        path = tmp_path / (name.replace(" ", "_") + ".json")
        path.write_text(content if isinstance(content, str) else json.dumps(content))
        out[name] = (str(path), says)
    np.save(tmp_path / "shape.npy", np.zeros((4, 20, 3)))
    out["array shape"] = (str(tmp_path / "shape.npy"), "expected (frames, 21, 3)")
    np.save(tmp_path / "long.npy", recording.positions[:10])
    with open(tmp_path / "long.npy", "ab") as stream:  # bytes after the data its header declares
        stream.write(b"\0" * 100)
    out["array bytes"] = (str(tmp_path / "long.npy"), "the file holds")
    return out


def test_bad_recordings_get_one_line_and_exit_2(tmp_path, capsys, sample_hands, gestures):
    recording = synthetic_recording(sample_hands["iris"], gestures, seed=10)
    for name, (path, says) in _bad_files(tmp_path, recording).items():
        with pytest.raises(InputFileError, match=None) as error:
            load_motion_file(path)
        assert says in str(error.value) and path in str(error.value), name
        assert main(["retarget", "--motion", path, "--target", "iris", "--out", str(tmp_path / "o.glb")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and says in err and "Traceback" not in err, (name, err)
    assert not (tmp_path / "o.glb").exists()


def test_the_same_recording_is_read_and_fitted_the_same_way_every_time():
    first = load_motion_file(REAL_WEBXR)[0]
    for _ in range(2):
        again = load_motion_file(REAL_WEBXR)[0]
        assert np.array_equal(again.q_tbs, first.q_tbs)


def _contacts_at(hand, motion, label: str) -> set[tuple[str, str]]:
    frame = int(np.flatnonzero(motion.labels == label)[len(np.flatnonzero(motion.labels == label)) // 2])
    touching = detect_contacts(hand, forward_kinematics(hand, motion.q_tbs[frame:frame + 1]))[0]
    return {CONTACT_PAIRS[i] for i in np.flatnonzero(touching)}


def test_a_real_webxr_recording_keeps_its_pinch_on_the_fitted_hand_and_through_asrn():
    """iwer's recorded poses (Meta, MIT): relaxed, pinch, point. The tracker moves the thumb's base, which the
    fitted skeleton keeps fixed, yet the pinch stays a touch, on the fitted source and retargeted by ASRN."""
    motion, source = load_motion_file(REAL_WEBXR)
    fit = motion.fit
    assert fit.summary["residual_mm_mean"] < 4.0 and not fit.filled.any()
    assert ("thumb", "index") in _contacts_at(source, motion, "pinch")
    assert ("thumb", "index") not in _contacts_at(source, motion, "relaxed") | _contacts_at(source, motion, "point")
    for target in ("iris", GODOT):
        target_hand = load_hand_file(target)
        result = retarget(motion, source, target_hand, "asrn")
        assert ("thumb", "index") in _contacts_at(target_hand, result, "pinch"), target
        assert ("thumb", "index") not in _contacts_at(target_hand, result, "relaxed"), target
    left_motion, _ = load_motion_file(REAL_WEBXR_LEFT)
    assert left_motion.meta["tracked"]["side"] == "left"
    np.testing.assert_allclose(left_motion.q_tbs, motion.q_tbs, atol=2e-3)  # the mirrored twin: one motion
    assert pair_index("thumb", "index") == 0


def test_every_command_that_takes_a_motion_takes_a_recording(tmp_path, capsys, sample_hands, gestures):
    path = save_mediapipe_hand(tmp_path / "rec.json", synthetic_recording(sample_hands["iris"], gestures,
                                                                        noise_mm=2.0, lost=0.03, seed=11))
    out = tmp_path / "rec_on_godot.glb"
    assert main(["retarget", "--motion", str(path), "--target", GODOT, "--method", "tbs_copy", "--out",
                 str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "fitted to" in printed and "residual" in printed and out.stat().st_size > 1000
    retargeted, _ = load_motion_file(out)
    assert retargeted.n_frames == gestures.n_frames
    assert main(["evaluate", "--motion", str(path), "--target", "iris", "--methods", "tbs_copy", "--quiet",
                 "--out", str(tmp_path / "eval")]) == 0
    assert "rec" in (tmp_path / "eval" / "evaluation.csv").read_text()


def test_a_batch_task_retargets_a_recording(tmp_path, sample_hands, gestures):
    """The batch's task runs in-process here (the cluster itself is `test_batch`'s); folders give only the
    JSON files that are recordings, not the sidecars beside them."""
    from s2h_viewer.batch.plan import TaskOptions, plan_batch
    from s2h_viewer.batch.task import run_task
    from s2h_viewer.retarget import METHODS

    folder = tmp_path / "recordings"
    folder.mkdir()
    save_mediapipe_hand(folder / "take.json", synthetic_recording(sample_hands["iris"], gestures, seed=12))
    (folder / "take.tbs.json").write_text('{"schema": "s2h-tbs"}')
    tasks = plan_batch([str(folder)], ["laurel"], ["tbs_copy"], tmp_path / "out", TaskOptions(format="npz",
                       render=False), known_methods=tuple(METHODS))
    assert len(tasks) == 1
    row = run_task(tasks[0])
    assert row["status"] == "ok", row
    assert load_motion_file(row["output"])[0].n_frames == gestures.n_frames
