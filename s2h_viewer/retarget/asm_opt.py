"""ASM-Opt: per-sequence gradient optimisation of the target's TBS rotations (DESIGN.md section 6).

Variables: per-frame, per-joint TBS Euler angles (twist, splay, bend), warm-started from TBS Copy.
Long clips go in overlapping chunks, cross-faded at the seams (`retarget.windows`).
Loss: -L_sem (match the source's ASM) + L_ana (stay anatomical) + temporal smoothness (no jitter)
+ a contact term that goes beyond the paper: pairs touching in the source are pulled to touch on
the target and pairs apart are kept apart, gaps measured in each hand's own length. No training.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rotations import quat_to_tbs_euler, tbs_euler_to_quat
from s2h_viewer.retarget.methods import on_target, register
from s2h_viewer.retarget.windows import Progress, stream_windows
from s2h_viewer.semantics.anatomy import anatomical_loss
from s2h_viewer.semantics.asm import semantic_matrix
from s2h_viewer.semantics.contacts import CONTACT_TOLERANCE, contact_gaps
from s2h_viewer.semantics.similarity import semantic_similarity


@dataclass(frozen=True)
class AsmOptConfig:
    steps: int = 150
    learning_rate: float = 0.01
    semantic_weight: float = 5.0
    anatomy_weight: float = 10.0
    smoothness_weight: float = 20.0
    contact_weight: float = 2e3
    prior_weight: float = 0.01  # pull toward the warm start (TBS Copy), keeps the unconstrained DOF put
    chunk: int = 512  # frames optimised together; a longer clip goes in chunks (memory of one chunk)
    chunk_overlap: int = 64  # frames two chunks share, cross-faded so there is no seam


def optimise_asm(source_q: np.ndarray, source_hand: HandModel, target_hand: HandModel,
                 initial_q: np.ndarray | None = None, config: AsmOptConfig = AsmOptConfig(),
                 progress: Progress | None = None) -> np.ndarray:
    """(T, 15, 4) target TBS rotations whose ASM matches the source's: each chunk of `AsmOptConfig.chunk`
    frames optimised on its own (batched over its frames), chunks cross-faded over ``chunk_overlap``
    frames, so memory stays that of one chunk however long the clip."""
    source_q = np.asarray(source_q, dtype=np.float32)
    initial_q = source_q if initial_q is None else np.asarray(initial_q, dtype=np.float32)
    n_frames = len(source_q)
    chunk = min(config.chunk, n_frames)
    out = np.empty_like(source_q)

    def run(starts: list[int], first: int, end: int) -> np.ndarray:
        return np.stack([_optimise_chunk(source_q[s:s + chunk], source_hand, target_hand, initial_q[s:s + chunk],
                                         config) for s in starts])

    def finish(first: int, end: int, angles: np.ndarray) -> None:
        out[first:end] = tbs_euler_to_quat(torch.as_tensor(angles, dtype=torch.float32)).numpy()

    stream_windows(n_frames, chunk, min(config.chunk_overlap, chunk - 1), run, finish, windows_per_batch=1,
                   progress=progress)
    return out


def _optimise_chunk(source_q: np.ndarray, source_hand: HandModel, target_hand: HandModel, initial_q: np.ndarray,
                    config: AsmOptConfig) -> np.ndarray:
    """(T, 15, 3) optimised TBS Euler angles of one chunk, warm-started from ``initial_q``."""
    with torch.no_grad():
        src_pose = forward_kinematics(source_hand, torch.as_tensor(source_q, dtype=torch.float32))
        d_source = semantic_matrix(src_pose)
        src_gaps = contact_gaps(source_hand, src_pose) / source_hand.hand_length
        touching = src_gaps < CONTACT_TOLERANCE
        start = quat_to_tbs_euler(torch.as_tensor(initial_q, dtype=torch.float32))
    angles = start.clone().requires_grad_(True)
    optimiser = torch.optim.Adam([angles], lr=config.learning_rate)
    tol = CONTACT_TOLERANCE
    for _ in range(config.steps):
        q = tbs_euler_to_quat(angles)
        pose = forward_kinematics(target_hand, q)
        sem = semantic_similarity(d_source, semantic_matrix(pose), source_hand.hand_length)
        gaps = contact_gaps(target_hand, pose) / target_hand.hand_length
        contact = torch.where(touching, torch.relu(gaps - 0.5 * tol), torch.relu(1.2 * tol - gaps)).square()
        smooth = (angles[2:] - 2 * angles[1:-1] + angles[:-2]).square().sum((-1, -2)).mean() if len(angles) > 2 \
            else angles.new_zeros(())
        loss = (-config.semantic_weight * sem + config.anatomy_weight * anatomical_loss(q)
                + config.smoothness_weight * smooth + config.contact_weight * contact.sum(-1).mean()
                + config.prior_weight * (angles - start).square().sum((-1, -2)).mean())
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
    return angles.detach().numpy()


@register("asm_opt", "ASM-Opt", "optimise the target pose per clip to match the source's semantics (no training)")
def retarget_asm_opt(motion: Motion, source_hand: HandModel, target_hand: HandModel,
                     progress: Progress | None = None) -> Motion:
    q = optimise_asm(motion.q_tbs, source_hand, target_hand, progress=progress)
    return on_target(motion, target_hand, q, "asm_opt")
