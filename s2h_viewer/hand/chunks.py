"""A clip's frames a bounded chunk at a time, so the temporaries of a whole-clip operation (checks,
conversions) stay the size of one chunk however long the clip is."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

#: frames handled at once: (16384, 15, 4) float32 rotations are 3.75 MiB
FRAMES_PER_CHUNK = 16384


def frame_chunks(n_frames: int, size: int = FRAMES_PER_CHUNK) -> Iterator[tuple[int, int]]:
    """(first, end) of consecutive chunks of at most ``size`` frames covering ``n_frames``."""
    for first in range(0, n_frames, size):
        yield first, min(first + size, n_frames)


def nonfinite_frames(values: np.ndarray) -> tuple[int, int]:
    """(how many, first) frames (rows of ``values``) holding a NaN or an infinity; (0, -1) when none."""
    count, first = 0, -1
    for lo, hi in frame_chunks(len(values)):
        bad = ~np.isfinite(values[lo:hi].reshape(hi - lo, -1)).all(axis=1)
        found = int(bad.sum())
        if found and first < 0:
            first = lo + int(np.argmax(bad))
        count += found
    return count, first
