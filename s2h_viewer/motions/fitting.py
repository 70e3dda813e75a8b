"""Fit gesture key poses to one hand: adjust bends and knuckle splays until the labelled contacts hold.

One batched Adam optimisation over all requested gestures: labelled pairs are pulled to a gap
within the contact tolerance (without sinking in), unlabelled pairs are kept apart, the angles
stay near the authored ones and inside the anatomical limits (hard-clamped at the end).
"""

from __future__ import annotations

import math

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.rotations import tbs_euler_to_quat
from s2h_viewer.motions.gestures import Gesture
from s2h_viewer.semantics.anatomy import BEND_LIMIT, KNUCKLE_SPLAY_LIMIT
from s2h_viewer.semantics.contacts import CONTACT_PAIRS, CONTACT_TOLERANCE, contact_gaps, pair_index


def clamp_to_limits(angles: torch.Tensor) -> torch.Tensor:
    """(..., 15, 3) radians with twist and non-knuckle splay zeroed, knuckle splay and bend clamped."""
    knuckle = torch.as_tensor(topo.ARTICULATED_IS_KNUCKLE)
    splay = torch.where(knuckle, angles[..., 1].clamp(-KNUCKLE_SPLAY_LIMIT, KNUCKLE_SPLAY_LIMIT),
                        torch.zeros_like(angles[..., 1]))
    bend = angles[..., 2].clamp(0.0, BEND_LIMIT)
    return torch.stack([torch.zeros_like(bend), splay, bend], -1)


def fit_gesture_angles(hand: HandModel, gestures: list[Gesture], steps: int = 300, lr: float = 0.03
                       ) -> np.ndarray:
    """(K, 15, 3) radians: the gestures' angles adjusted so that, on this hand, their contacts hold."""
    base = torch.as_tensor(np.stack([np.radians(g.angles_deg) for g in gestures]), dtype=torch.float64)
    want = torch.as_tensor(np.stack([g.contact_vector() for g in gestures]))
    free = torch.zeros_like(base)
    free[..., 2] = 1.0
    free[..., 1] = torch.as_tensor(topo.ARTICULATED_IS_KNUCKLE, dtype=base.dtype)
    delta = torch.zeros_like(base, requires_grad=True)
    optimiser = torch.optim.Adam([delta], lr=lr)
    tol = CONTACT_TOLERANCE
    # the thumb sweeps past the palm on its way to a fingertip: keeping it off the palm is secondary
    apart_weight = torch.full((len(CONTACT_PAIRS),), 0.1, dtype=base.dtype)
    apart_weight[pair_index("thumb", "palm")] = 0.01
    for _ in range(steps):
        angles = base + delta * free
        gaps = contact_gaps(hand, forward_kinematics(hand, tbs_euler_to_quat(angles))) / hand.hand_length
        touch = torch.relu(gaps - 0.3 * tol).square() + torch.relu(-gaps - 0.5 * tol).square()
        apart = torch.relu(1.5 * tol - gaps).square() * apart_weight
        limits = (angles - clamp_to_limits(angles)).square().sum((-1, -2))
        loss = (torch.where(want, touch, apart).sum(-1) * 1e4
                + 1e-2 * (delta * free).square().sum((-1, -2)) + limits).sum()
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
    with torch.no_grad():
        return clamp_to_limits(base + delta * free).numpy()


def degrees_to_radians(angles_deg: np.ndarray) -> np.ndarray:
    return np.asarray(angles_deg, dtype=np.float64) * (math.pi / 180.0)
