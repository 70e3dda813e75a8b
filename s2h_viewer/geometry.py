"""Plain geometry shared by the core and the window (numpy only): distances to line segments."""
from __future__ import annotations

import numpy as np


def distance_to_segments(points: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Distances from ``points`` to the segments ``starts`` -> ``ends``, all (..., D) and broadcast against each
    other (D = 3 in the scene, 2 on screen): the point's projection clamped to the segment (a segment of length 0
    is its start)."""
    along = ends - starts
    share = ((points - starts) * along).sum(-1) / np.maximum((along * along).sum(-1), np.finfo(float).tiny)
    nearest = starts + np.clip(share, 0.0, 1.0)[..., None] * along
    return np.linalg.norm(points - nearest, axis=-1)
