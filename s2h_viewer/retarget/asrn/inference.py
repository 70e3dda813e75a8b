"""Run a trained network on a clip of any length: sliding windows, cross-faded where they overlap.

Windows of ``window`` frames start every ``window - overlap`` frames (the last one is aligned to the
clip's end). Frames covered by one window take that window's output unchanged; in an overlap the
two windows' residual rotations are cross-faded linearly, so there is no seam at window borders.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import torch

from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.retarget.asrn.features import source_features, target_static
from s2h_viewer.retarget.asrn.model import RetargetNet, apply_residual
from s2h_viewer.retarget.asrn.training import TrainConfig, build_model, load_checkpoint
from s2h_viewer.retarget.methods import on_target, register

MODELS_DIR = Path(__file__).resolve().parents[3] / "assets" / "models"


def window_starts(n_frames: int, window: int, overlap: int) -> list[int]:
    """Start frames of the sliding windows covering ``n_frames`` (at least one window)."""
    if n_frames <= window:
        return [0]
    starts = list(range(0, n_frames - window + 1, window - overlap))
    if starts[-1] + window < n_frames:
        starts.append(n_frames - window)
    return starts


def blend_weights(starts: list[int], window: int) -> np.ndarray:
    """(n_windows, window) cross-fade weights; at every frame the covering windows' weights sum to 1."""
    weights = np.ones((len(starts), window))
    for i, start in enumerate(starts):
        ramp_in = starts[i - 1] + window - start if i > 0 else 0
        ramp_out = start + window - starts[i + 1] if i + 1 < len(starts) else 0
        pos = np.arange(window)
        if ramp_in > 0:
            weights[i] = np.minimum(weights[i], np.where(pos < ramp_in, (pos + 1) / (ramp_in + 1), 1.0))
        if ramp_out > 0:
            weights[i] = np.minimum(weights[i], np.where(pos >= window - ramp_out,
                                                         (window - pos) / (ramp_out + 1), 1.0))
    return weights


def run_network(model: RetargetNet, kind: str, source_hand: HandModel, source_q: np.ndarray,
                target_hand: HandModel, window: int = 8, overlap: int = 2) -> np.ndarray:
    """(T, 15, 4) target TBS rotations for a whole clip."""
    q = torch.as_tensor(np.asarray(source_q), dtype=torch.float32)
    n_frames = len(q)
    features = source_features(kind, source_hand, q)
    if n_frames < window:  # pad by holding the last frame
        pad = window - n_frames
        features = torch.cat([features, features[-1:].expand(pad, -1)])
    starts = window_starts(len(features), window, overlap)
    windows = torch.stack([features[s:s + window] for s in starts])
    shape, frames = (s.expand(len(starts), *s.shape) for s in target_static(target_hand))
    with torch.no_grad():
        rotvec = model(windows, shape, frames).numpy()
    weights = blend_weights(starts, window)
    blended = np.zeros((len(features), *rotvec.shape[2:]))
    for start, w, r in zip(starts, weights, rotvec):
        blended[start:start + window] += w[:, None, None] * r
    return apply_residual(q, torch.as_tensor(blended[:n_frames], dtype=torch.float32)).numpy()


@lru_cache(maxsize=4)
def load_network(path: str) -> tuple[RetargetNet, TrainConfig]:
    """A trained network from its checkpoint, in eval mode (cached per path)."""
    state = load_checkpoint(path)
    config = TrainConfig(**state["config"])
    model = build_model(config)
    model.load_state_dict(state["model"])
    return model.eval(), config


def _retarget_with(kind: str, motion: Motion, source_hand: HandModel, target_hand: HandModel) -> Motion:
    model, config = load_network(str(MODELS_DIR / f"{kind}.pt"))
    q = run_network(model, kind, source_hand, motion.q_tbs, target_hand, window=config.window,
                    overlap=config.window // 4)
    return on_target(motion, target_hand, q, kind)


@register("dm", "DM", "the network on distance matrices (Zhang et al. 2023) instead of the ASM")
def retarget_dm(motion: Motion, source_hand: HandModel, target_hand: HandModel) -> Motion:
    return _retarget_with("dm", motion, source_hand, target_hand)


@register("asrn", "ASRN", "the anatomy-based semantic retargeting network (trained, shipped)")
def retarget_asrn(motion: Motion, source_hand: HandModel, target_hand: HandModel) -> Motion:
    return _retarget_with("asrn", motion, source_hand, target_hand)
