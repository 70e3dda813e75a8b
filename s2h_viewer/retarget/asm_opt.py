"""ASM-Opt: per-sequence gradient optimisation of the target's TBS rotations (DESIGN.md section 6).

Variables: per-frame, per-joint TBS Euler angles (twist, splay, bend), warm-started from TBS Copy.
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
from s2h_viewer.retarget.progress import report
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


def optimise_asm(source_q: np.ndarray, source_hand: HandModel, target_hand: HandModel,
                 initial_q: np.ndarray | None = None, config: AsmOptConfig = AsmOptConfig()) -> np.ndarray:
    """(T, 15, 4) target TBS rotations whose ASM matches the source's; batched over all frames."""
    with torch.no_grad():
        src_pose = forward_kinematics(source_hand, torch.as_tensor(source_q, dtype=torch.float32))
        d_source = semantic_matrix(src_pose)
        src_gaps = contact_gaps(source_hand, src_pose) / source_hand.hand_length
        touching = src_gaps < CONTACT_TOLERANCE
        start = quat_to_tbs_euler(torch.as_tensor(source_q if initial_q is None else initial_q, dtype=torch.float32))
    angles = start.clone().requires_grad_(True)
    optimiser = torch.optim.Adam([angles], lr=config.learning_rate)
    tol = CONTACT_TOLERANCE
    for step in range(config.steps):
        report(step / config.steps)  # progress, and where a cancel stops the optimisation
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
    with torch.no_grad():
        return tbs_euler_to_quat(angles).numpy()


@register("asm_opt", "ASM-Opt", "optimise the target pose per clip to match the source's semantics (no training)")
def retarget_asm_opt(motion: Motion, source_hand: HandModel, target_hand: HandModel) -> Motion:
    return on_target(motion, target_hand, optimise_asm(motion.q_tbs, source_hand, target_hand), "asm_opt")
