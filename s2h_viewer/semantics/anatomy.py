"""The anatomical loss L_ana and the violation rate built on the same limits (DESIGN.md section 5).

Limits per articulated joint, angles from ``matrix_to_tbs_euler``: twist 0; splay 0 except knuckles
(|splay| <= 10 deg); bend within [0, 90 deg] (no hyperextension, no more than a right angle).
"""

from __future__ import annotations

import math

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.rotations import quat_to_tbs_euler

KNUCKLE_SPLAY_LIMIT = math.pi / 18
BEND_LIMIT = math.pi / 2


def anatomical_excess(q_tbs: torch.Tensor) -> torch.Tensor:
    """(T, 15, 3) how far (radians, >= 0) each joint's twist, splay and bend lie outside their limits."""
    twist, splay, bend = quat_to_tbs_euler(q_tbs).unbind(-1)
    knuckle = torch.as_tensor(topo.ARTICULATED_IS_KNUCKLE)
    splay_excess = torch.where(knuckle, torch.relu(splay.abs() - KNUCKLE_SPLAY_LIMIT), splay.abs())
    bend_excess = torch.relu(bend - BEND_LIMIT) + torch.relu(-bend)
    return torch.stack([twist.abs(), splay_excess, bend_excess], -1)


def anatomical_loss(q_tbs: torch.Tensor) -> torch.Tensor:
    """L_ana: sum over joints of squared excesses, averaged over frames (scalar, radians^2)."""
    return anatomical_excess(q_tbs).square().sum(dim=(-1, -2)).mean()


def violation_rate(q_tbs: torch.Tensor | np.ndarray, tolerance_deg: float = 5.0) -> float:
    """Fraction of (frame, joint) pairs with any angle more than ``tolerance_deg`` outside its limits."""
    q = torch.as_tensor(np.asarray(q_tbs)) if not isinstance(q_tbs, torch.Tensor) else q_tbs
    excess = anatomical_excess(q.to(torch.float64))
    return float((excess > math.radians(tolerance_deg)).any(-1).double().mean())
