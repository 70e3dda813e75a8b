"""Run a trained network on a clip of any length: sliding windows, cross-faded where they overlap
(`retarget.windows`), streamed a batch of windows at a time so a long clip needs no more working
memory than a short one: the features of one batch are made, run and blended, and the finished frames
written into the output before the next batch starts. Window length and overlap are the model's.
Progress and cancellation go through `retarget.progress` (after every batch).
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
from s2h_viewer.retarget.asrn.training import TrainConfig, build_model, load_checkpoint, stored_config
from s2h_viewer.retarget.contact_fit import fit_contacts
from s2h_viewer.retarget.guard import guarded
from s2h_viewer.retarget.methods import on_target, register
from s2h_viewer.retarget.progress import report, stage
from s2h_viewer.retarget.windows import stream_windows
from s2h_viewer.semantics.anatomy import within_source_limits

MODELS_DIR = Path(__file__).resolve().parents[3] / "assets" / "models"
#: source frames whose features are made and run at once: sets the working memory, not the result
FRAMES_PER_BATCH = 2048


def run_network(model: RetargetNet, kind: str, source_hand: HandModel, source_q: np.ndarray,
                target_hand: HandModel, window: int = 8, overlap: int = 2) -> np.ndarray:
    """(T, 15, 4) target TBS rotations for a whole clip (a clip shorter than ``window`` is padded by
    holding its last frame)."""
    q = np.asarray(source_q, dtype=np.float32)
    n_frames = len(q)
    out = np.empty_like(q)
    shape, frames = target_static(target_hand)

    def run(starts: list[int], first: int, end: int) -> np.ndarray:
        held = np.minimum(np.arange(first, end), n_frames - 1)  # frames past the clip hold its last
        features = source_features(kind, source_hand, q[held])
        windows = torch.stack([features[s - first:s - first + window] for s in starts])
        with torch.no_grad():
            return model(windows, shape.expand(len(starts), *shape.shape),
                         frames.expand(len(starts), *frames.shape)).numpy()

    def finish(first: int, end: int, rotvec: np.ndarray) -> None:
        end = min(end, n_frames)
        if end > first:
            out[first:end] = apply_residual(torch.as_tensor(q[first:end]),
                                            torch.as_tensor(rotvec[:end - first], dtype=torch.float32)).numpy()

    stream_windows(max(n_frames, window), window, overlap, run, finish,
                   windows_per_batch=max(1, FRAMES_PER_BATCH // max(window - overlap, 1)))
    return out


@lru_cache(maxsize=4)
def load_network(path: str) -> tuple[RetargetNet, TrainConfig]:
    """A trained network from its checkpoint, in eval mode (cached per path)."""
    state = load_checkpoint(path)
    config = stored_config(state)
    model = build_model(config)
    model.load_state_dict(state["model"])
    return model.eval(), config


def network_retarget(kind: str, source_q: np.ndarray, source_hand: HandModel, target_hand: HandModel) -> np.ndarray:
    """(T, 15, 4) target TBS rotations from the shipped network ``kind`` ("asrn" or "dm") alone."""
    model, config = load_network(str(MODELS_DIR / f"{kind}.pt"))
    return run_network(model, kind, source_hand, source_q, target_hand, window=config.window,
                       overlap=config.window // 4)


def guarded_pipeline(kind: str, motion: Motion, source_hand: HandModel, target_hand: HandModel) -> np.ndarray:
    """(T, 15, 4) target TBS rotations from the shipped network ``kind`` kept within the anatomical limits, its
    fingertip contacts fitted to the source's and guarded frame by frame by TBS Copy: the one pipeline both
    networks run, so DM and ASRN differ only in what their network reads (DESIGN section 6)."""
    with stage(0.0, 0.1, "network"):
        # the network's angles within the anatomical limits the source keeps (L_ana trains toward them, not to them)
        network = within_source_limits(motion.q_tbs, network_retarget(kind, motion.q_tbs, source_hand, target_hand))
    with stage(0.1, 0.85, "contact fit"):
        q = fit_contacts(motion.q_tbs, source_hand, target_hand, network.copy())
    with stage(0.85, 1.0, "guard"):
        # the fit may not invent a contact the network's frame did not make, and no frame may lose what
        # TBS Copy (the source's own TBS rotations) keeps (`retarget.guard`)
        q, _ = guarded(source_hand, motion.q_tbs, target_hand, q, network)
        q, _ = guarded(source_hand, motion.q_tbs, target_hand, q, motion.q_tbs)
        report(1.0)
    return q


@register("dm", "DM", "the paper's baseline: a network trained on distance matrices (Zhang et al. 2023) instead of "
                      "the ASM, in ASRN's pipeline (contacts fitted, guarded by TBS Copy)")
def retarget_dm(motion: Motion, source_hand: HandModel, target_hand: HandModel) -> Motion:
    return on_target(motion, target_hand, guarded_pipeline("dm", motion, source_hand, target_hand), "dm")


@register("asrn", "ASRN", "the anatomy-based semantic retargeting network (trained, shipped), its fingertip "
                          "contacts then fitted to the source's, guarded frame by frame by TBS Copy")
def retarget_asrn(motion: Motion, source_hand: HandModel, target_hand: HandModel) -> Motion:
    return on_target(motion, target_hand, guarded_pipeline("asrn", motion, source_hand, target_hand), "asrn")
