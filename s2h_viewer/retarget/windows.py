"""Overlapping windows over a clip, cross-faded where they overlap, processed as a stream.

Windows of ``window`` frames start every ``window - overlap`` frames (the last one is aligned to the
clip's end). A frame covered by one window takes that window's value unchanged; in an overlap the
two windows' values are cross-faded linearly, so there is no seam at window borders. `stream_windows`
runs a few windows at a time and hands out each stretch of frames as soon as no later window can
touch it, so working memory depends on the window and batch sizes, never on the clip's length. It
reports its progress (`retarget.progress`) after every batch, and each batch runs as a stage of it, so
a method reporting inside a window (ASM-Opt's steps) moves the same bar and can be cancelled there.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from s2h_viewer.retarget.progress import report, stage

#: run(window starts, first frame, end frame) -> (len(starts), window, ...) values of those windows
RunWindows = Callable[[list[int], int, int], np.ndarray]
#: finish(first frame, end frame, blended values (end - first, ...)) for frames no later window touches
FinishFrames = Callable[[int, int, np.ndarray], None]


def window_starts(n_frames: int, window: int, overlap: int) -> list[int]:
    """Start frames of the sliding windows covering ``n_frames`` (at least one window)."""
    if not 0 <= overlap < window:
        raise ValueError(f"window overlap {overlap} must be from 0 to below the window length {window}")
    if n_frames <= window:
        return [0]
    starts = list(range(0, n_frames - window + 1, window - overlap))
    if starts[-1] + window < n_frames:
        starts.append(n_frames - window)
    return starts


def blend_weights(starts: list[int], window: int) -> np.ndarray:
    """(n_windows, window) cross-fade weights; at every frame the covering windows' weights sum to 1."""
    weights = np.ones((len(starts), window))
    pos = np.arange(window)
    for i, start in enumerate(starts):
        ramp_in = starts[i - 1] + window - start if i > 0 else 0
        ramp_out = start + window - starts[i + 1] if i + 1 < len(starts) else 0
        if ramp_in > 0:
            weights[i] = np.minimum(weights[i], np.where(pos < ramp_in, (pos + 1) / (ramp_in + 1), 1.0))
        if ramp_out > 0:
            weights[i] = np.minimum(weights[i], np.where(pos >= window - ramp_out,
                                                         (window - pos) / (ramp_out + 1), 1.0))
    return weights


def stream_windows(n_frames: int, window: int, overlap: int, run: RunWindows, finish: FinishFrames,
                   windows_per_batch: int) -> None:
    """Cover ``n_frames`` (at least ``window``) with windows, ``windows_per_batch`` at a time through ``run``,
    and pass every frame's cross-faded value to ``finish`` exactly once, in order; reports the share of
    frames finished (a ``Cancelled`` from the hook stops it between batches)."""
    starts = window_starts(n_frames, window, overlap)
    pending = None  # blended values of frames [pending_start, ...) that later windows may still touch
    pending_start = 0
    for lo in range(0, len(starts), windows_per_batch):
        hi = min(lo + windows_per_batch, len(starts))
        batch = starts[lo:hi]
        first, end = batch[0], batch[-1] + window
        done = starts[hi] if hi < len(starts) else end  # frames before the next window are final
        with stage(pending_start / n_frames, min(done, n_frames) / n_frames):
            values = np.asarray(run(batch, first, end))
        with_neighbours = starts[max(lo - 1, 0):hi + 1]
        weights = blend_weights(with_neighbours, window)[(1 if lo > 0 else 0):][:len(batch)]
        grown = np.zeros((end - pending_start, *values.shape[2:]))
        if pending is not None:
            grown[:len(pending)] = pending
        for start, w, value in zip(batch, weights, values):
            grown[start - pending_start:start - pending_start + window] += w.reshape(-1, *[1] * (value.ndim - 1)) * value
        finish(pending_start, done, grown[:done - pending_start])
        pending, pending_start = grown[done - pending_start:], done
        report(min(done, n_frames) / n_frames)
