"""Long clips in bounded memory: checks and conversions a chunk of frames at a time still see every frame,
labels cost a reference per frame, and every streamed retarget reports its progress through
`retarget.progress` up to 1.0 and stops where a cancel is raised."""

from __future__ import annotations

import math

import numpy as np
import pytest

from s2h_viewer import cli, samples
from s2h_viewer.errors import InputFileError, InvalidMotionError
from s2h_viewer.hand.chunks import FRAMES_PER_CHUNK
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.npz import READ_CHUNK_BYTES, load_motion, save_motion
from s2h_viewer.retarget import retarget
from s2h_viewer.retarget.asm_opt import AsmOptConfig, optimise_asm
from s2h_viewer.retarget.asrn import inference
from s2h_viewer.retarget.progress import Cancelled, reporting
from s2h_viewer.retarget.windows import stream_windows

#: frames of a clip that spans several chunks of every chunked pass (checks, npz reads)
LONG = max(3 * FRAMES_PER_CHUNK, 3 * READ_CHUNK_BYTES // (15 * 4 * 4)) + 5


@pytest.fixture(scope="module")
def gestures() -> Motion:
    return next(m for m in samples.load_sample_motions() if m.name == "gestures")


def tiled(motion: Motion, n_frames: int) -> Motion:
    """``motion`` repeated to ``n_frames`` (rotations and labels)."""
    reps = -(-n_frames // motion.n_frames)
    return Motion(q_tbs=np.tile(motion.q_tbs, (reps, 1, 1))[:n_frames], fps=motion.fps, name=f"{motion.name}_long",
                  hand_name=motion.hand_name, labels=np.tile(motion.labels, reps)[:n_frames])


def identity_clip(n_frames: int) -> np.ndarray:
    q = np.zeros((n_frames, 15, 4), dtype=np.float32)
    q[..., 0] = 1.0
    return q


def test_checks_in_chunks_still_find_a_nan_at_the_last_frame_and_count_every_bad_frame():
    q = identity_clip(LONG)
    q[-1, 14, 3] = np.nan
    with pytest.raises(InvalidMotionError, match=rf"in 1 frames \(first at frame {LONG - 1}\)"):
        Motion(q_tbs=q, name="long")
    q[FRAMES_PER_CHUNK, 0, 0] = np.inf  # the first frame of the second chunk
    q[5, 3, 1] = -np.inf
    with pytest.raises(InvalidMotionError, match=r"in 3 frames \(first at frame 5\)"):
        Motion(q_tbs=q, name="long")


def test_checks_in_chunks_find_a_quaternion_off_unit_in_the_last_chunk_only():
    q = identity_clip(LONG)
    q[-2, 7] = [0.1, 0.0, 0.0, 0.0]
    with pytest.raises(InvalidMotionError, match="norms from 0.1 to 1"):
        Motion(q_tbs=q, name="long")


def test_reading_in_chunks_finds_a_nan_in_the_last_frame_of_a_long_file(tmp_path, gestures):
    clip = tiled(gestures, LONG)
    q = clip.q_tbs.astype(np.float64)  # stored as float64: converted to float32 chunk by chunk
    q[-1, 0, 0] = np.nan
    path = tmp_path / "nan_at_the_end.npz"
    np.savez_compressed(path, schema="s2h-motion", schema_version=2, q_tbs=q, fps=30.0, name="long",
                        hand_name=clip.hand_name, labels=clip.labels.astype(str), meta_json="{}")
    with pytest.raises(InputFileError, match=rf"q_tbs has NaN or infinite values in 1 frames \(first at frame "
                                             rf"{LONG - 1}\)"):
        load_motion(path)


def test_an_older_schema_2_file_loads_converted_with_one_string_object_per_label(tmp_path, gestures):
    """Files written by ``np.savez_compressed`` (float64 rotations, text labels) read as before."""
    clip = tiled(gestures, LONG)
    path = tmp_path / "older.npz"
    np.savez_compressed(path, schema="s2h-motion", schema_version=2, q_tbs=clip.q_tbs.astype(np.float64), fps=24.0,
                        name="older", hand_name=clip.hand_name, labels=clip.labels.astype(str), meta_json='{"a": 1}')
    back = load_motion(path)
    assert back.q_tbs.dtype == np.float32 and back.fps == 24.0 and back.meta == {"a": 1}
    np.testing.assert_array_equal(back.q_tbs, clip.q_tbs)
    assert back.labels.tolist() == clip.labels.tolist()
    assert len({id(label) for label in back.labels}) == len(set(back.labels.tolist())) == len(set(gestures.labels))


def test_a_saved_long_motion_is_a_plain_npz_that_reads_back_the_same(tmp_path, gestures):
    clip = tiled(gestures, LONG)
    path = save_motion(clip, tmp_path / "long.npz")
    with np.load(path, allow_pickle=False) as plain:  # what any numpy reads: text labels, float32 rotations
        assert plain["labels"].dtype.kind == "U" and plain["labels"].tolist() == clip.labels.tolist()
        np.testing.assert_array_equal(plain["q_tbs"], clip.q_tbs)
    back = load_motion(path)
    np.testing.assert_array_equal(back.q_tbs, clip.q_tbs)
    assert back.labels.tolist() == clip.labels.tolist() and back.name == clip.name


def test_text_labels_become_one_string_object_per_distinct_label(gestures):
    clip = Motion(q_tbs=gestures.q_tbs, labels=gestures.labels.astype(str))
    assert clip.labels.dtype == object and clip.labels.tolist() == gestures.labels.tolist()
    assert len({id(label) for label in clip.labels}) == len(set(gestures.labels))


@pytest.mark.parametrize("method", ["copy", "tbs_copy", "asrn", "dm"])
def test_a_streamed_retarget_reports_rising_progress_up_to_one(method, sample_hands, gestures, monkeypatch):
    monkeypatch.setattr(inference, "FRAMES_PER_BATCH", 512)  # several batches from a short clip
    clip = tiled(gestures, 3000)
    reported = []
    with reporting(lambda fraction, what: reported.append(fraction)):
        moved = retarget(clip, sample_hands[clip.hand_name], sample_hands["juniper"], method)
    assert moved.n_frames == clip.n_frames
    assert reported[-1] == 1.0 and all(a <= b for a, b in zip(reported, reported[1:]))
    if method in ("asrn", "dm"):
        assert len({f for f in reported if 0 < f < 1}) >= 4  # after every batch, not only at the end


@pytest.mark.parametrize("method", ["asrn", "dm"])
def test_a_cancel_stops_a_streamed_retarget_part_way(method, sample_hands, gestures, monkeypatch):
    monkeypatch.setattr(inference, "FRAMES_PER_BATCH", 512)
    clip = tiled(gestures, 3000)
    reported = []

    def cancel_past_a_third(fraction: float, what: str) -> None:
        reported.append(fraction)
        if fraction > 1 / 3:
            raise Cancelled()

    with pytest.raises(Cancelled), reporting(cancel_past_a_third):
        retarget(clip, sample_hands[clip.hand_name], sample_hands["juniper"], method)
    assert 1 / 3 < reported[-1] < 1.0 and all(f <= 1 / 3 for f in reported[:-1])


def test_no_window_runs_after_the_hook_cancels():
    batches = []

    def run(starts, first, end):
        batches.append(first)
        return np.zeros((len(starts), 10, 3))

    def cancel_at_half(fraction: float, what: str) -> None:
        if fraction >= 0.5:
            raise Cancelled()

    with pytest.raises(Cancelled), reporting(cancel_at_half):
        stream_windows(1000, 10, 2, run, lambda first, end, values: None, windows_per_batch=5)
    frames_per_batch = 5 * (10 - 2)
    assert len(batches) == math.ceil(500 / frames_per_batch)  # stopped after the batch that passed half way


def test_asm_opt_steps_move_one_bar_across_chunks_and_a_cancel_stops_inside_a_chunk(sample_hands, gestures):
    config = AsmOptConfig(steps=4, chunk=48, chunk_overlap=12)
    source, target = sample_hands[gestures.hand_name], sample_hands["juniper"]
    q = gestures.q_tbs[:150]
    reported = []
    with reporting(lambda fraction, what: reported.append(fraction)):
        optimise_asm(q, source, target, config=config)
    assert reported[-1] == 1.0 and all(a <= b for a, b in zip(reported, reported[1:]))
    assert len(reported) > 4 * config.steps  # every step of every chunk, placed within that chunk's share

    steps_seen = []

    def cancel_in_the_second_chunk(fraction: float, what: str) -> None:
        steps_seen.append(fraction)
        if len(steps_seen) == config.steps + 3:  # a chunk's steps and its end, then two steps into the next
            raise Cancelled()

    with pytest.raises(Cancelled), reporting(cancel_in_the_second_chunk):
        optimise_asm(q, source, target, config=config)
    assert 0 < steps_seen[-1] < 0.6


def test_the_cli_progress_bar_follows_a_retarget_to_the_end(sample_hands, gestures, capsys):
    clip = tiled(gestures, 3000)
    with cli._progress_bar("retarget (asrn)", clip.n_frames, "frame", disable=False):
        retarget(clip, sample_hands[clip.hand_name], sample_hands["juniper"], "asrn")
    bar = capsys.readouterr().err.replace("\r", "\n").strip().splitlines()[-1]
    assert "100%" in bar and "3.00k/3.00k" in bar
