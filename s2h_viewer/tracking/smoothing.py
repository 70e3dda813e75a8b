"""Tracking noise taken out of keypoint trajectories, gaps filled: a weighted Whittaker smoother.

Each coordinate's trajectory ``x`` minimises ``sum_t w_t (x_t - y_t)^2 + lambda sum_t (D2 x)_t^2``. The
noise ``sigma`` is estimated from the recording itself (third differences of white noise have variance
20 sigma^2; a median of them, so a smooth motion's own third differences barely count), and ``lambda`` is
the one whose fit leaves residuals of that size (the discrepancy principle): a clean recording passes
almost untouched, a noisy one is smoothed as much as its noise asks. One lambda for a whole clip would
flatten its fast moves (a finger snapping shut) as much as its still stretches, so `follow_fast_moves`
then raises each joint's data weight wherever its fit stays off by more than the noise for several frames
running (a bias, not noise), and solves again. Frames with weight 0
(lost or outlying) are filled by the smoother's curve between their neighbours; before the first and
after the last tracked frame the nearest tracked frame is held.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solveh_banded


MIN_LAMBDA, MAX_LAMBDA = 1e-3, 1e6


def _runs(valid: np.ndarray) -> list[tuple[int, int]]:
    """(first, end) of each run of consecutive True frames."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], valid.astype(np.int8), [0]])))
    return list(zip(edges[::2], edges[1::2]))


def estimate_noise(series: np.ndarray, valid: np.ndarray) -> float:
    """Per-coordinate noise (same unit as ``series``) of (T, K) trajectories, from their runs of valid frames."""
    third = [np.diff(series[first:end], 3, axis=0).ravel() for first, end in _runs(valid) if end - first >= 4]
    if not third:
        return 0.0
    return 1.4826 * float(np.median(np.abs(np.concatenate(third)))) / np.sqrt(20.0)


def choose_smoothing(series: np.ndarray, weights: np.ndarray, sigma: float, steps: int = 12) -> float:
    """The lambda whose smoothed trajectories differ from ``series`` by ``sigma`` RMS on the weighted frames
    (bisection in log lambda; the residual grows with lambda)."""
    used = weights > 0
    if sigma <= 0 or used.sum() < 4:
        return MIN_LAMBDA
    low, high = np.log10(MIN_LAMBDA), np.log10(MAX_LAMBDA)
    for _ in range(steps):
        mid = 0.5 * (low + high)
        residual = np.sqrt(np.mean((smooth(series, weights, 10 ** mid)[used] - series[used]) ** 2))
        low, high = (mid, high) if residual < sigma else (low, mid)
    return float(10 ** low)


def _banded_system(weights: np.ndarray, lam: float) -> np.ndarray:
    """Upper bands (3, n) of ``W + lam D2^T D2`` for `scipy.linalg.solveh_banded`."""
    n = len(weights)
    ab = np.zeros((3, n))
    rows = np.ones(n - 2)  # each row of D2 is (1, -2, 1): its products land on three bands
    diag, off1 = np.convolve(rows, [1.0, 4.0, 1.0]), np.convolve(rows, [-2.0, -2.0])
    ab[2] = weights + lam * diag
    ab[1, 1:] = lam * off1
    ab[0, 2:] = lam * rows
    return ab


def smooth(series: np.ndarray, weights: np.ndarray, lam: float) -> np.ndarray:
    """(T, K) trajectories smoothed and filled (see the module docstring); ``weights`` (T,) 0 or 1."""
    tracked = np.flatnonzero(weights > 0)
    out = np.empty_like(series)
    first, last = int(tracked[0]), int(tracked[-1])
    if last - first < 2:
        out[:] = series[tracked].mean(0)
        return out
    span = slice(first, last + 1)
    y = np.where(weights[span, None] > 0, series[span], 0.0)
    out[span] = solveh_banded(_banded_system(weights[span].astype(np.float64), max(lam, 1e-9)),
                              weights[span, None] * y, check_finite=False)
    out[:first], out[last + 1:] = out[first], out[last]
    return out


#: `follow_fast_moves`: frames a joint's residual is pooled over, rounds, and the largest data weight
BIAS_WINDOW = 5
BIAS_ROUNDS = 2
MAX_WEIGHT = 1e4
BIAS_SIGMAS = 2.0  # a residual this many times the noise, held over the window, is a bias


def follow_fast_moves(series: np.ndarray, weights: np.ndarray, lam: float, sigma: float, group: int = 3
                      ) -> np.ndarray:
    """(T, K) `smooth` with each group of ``group`` coordinates (a joint's x, y, z) weighted up where its
    residual, averaged over `BIAS_WINDOW` frames, exceeds the noise ``sigma`` (weight (residual / sigma)^2)."""
    out = smooth(series, weights, lam)
    if sigma <= 0:
        return out
    used = weights > 0
    kernel = np.ones(BIAS_WINDOW) / BIAS_WINDOW
    boost = np.ones((len(series), series.shape[1] // group))
    for _ in range(BIAS_ROUNDS):  # a weight once raised stays (else the next round, fitting well, drops it again)
        squared = ((out - series) ** 2 * used[:, None]).reshape(len(series), -1, group).mean(-1)  # (T, joints)
        local = np.stack([np.convolve(column, kernel, mode="same") for column in squared.T], axis=1)
        boost = np.clip(boost * np.maximum(local / (BIAS_SIGMAS * sigma) ** 2, 1.0), 1.0, MAX_WEIGHT)
        for joint in range(boost.shape[1]):
            columns = slice(joint * group, (joint + 1) * group)
            out[:, columns] = smooth(series[:, columns], weights * boost[:, joint], lam)
    return out
