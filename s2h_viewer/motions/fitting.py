"""Fit gesture key poses to one hand: adjust bends and knuckle splays until the labelled contacts hold.

One batched Adam optimisation over all requested gestures: labelled pairs are pulled to a gap
just inside touching (-0.6 to -0.1 of the tolerance, so tremor added later keeps them in contact), unlabelled pairs are kept apart, the angles
stay near the authored ones and inside the anatomical limits (hard-clamped at the end).
"""

from __future__ import annotations

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.rotations import tbs_euler_to_quat
from s2h_viewer.motions.gestures import Gesture
from s2h_viewer.semantics.anatomy import SPLAY_LIMIT, clamp_bends
from s2h_viewer.semantics.contacts import CONTACT_PAIRS, CONTACT_TOLERANCE, contact_gaps, pair_index


def clamp_to_limits(angles: torch.Tensor) -> torch.Tensor:
    """(..., 15, 3) radians (twist, bend, splay) with twist zeroed and bend and splay clamped into the
    anatomical limits (non-knuckle splay to 0; bends 1 deg inside 90, where the XYZ angles lock)."""
    limit = SPLAY_LIMIT.to(angles.dtype)
    splay = torch.maximum(torch.minimum(angles[..., 2], limit), -limit)
    return torch.stack([torch.zeros_like(splay), clamp_bends(angles)[..., 1], splay], -1)


THUMB_STARTS_DEG = (0.0, 15.0, -10.0)  # offsets of the thumb's bends: one batched multi-start


def fit_gesture_angles(hand: HandModel, gestures: list[Gesture], steps: int = 300, lr: float = 0.03
                       ) -> np.ndarray:
    """(K, 15, 3) radians: the gestures' angles adjusted so that, on this hand, their contacts hold.

    The thumb's reach depends strongly on the hand, so each gesture is fitted from a few thumb
    starts at once (one batch) and the start with the lowest final loss wins.
    """
    authored = torch.as_tensor(np.stack([np.radians(g.angles_deg) for g in gestures]), dtype=torch.float64)
    n = len(gestures)
    starts = authored.repeat(len(THUMB_STARTS_DEG), 1, 1)
    for i, offset in enumerate(THUMB_STARTS_DEG):
        starts[i * n:(i + 1) * n, 0:3, 1] += np.radians(offset)
    base = clamp_to_limits(starts)
    want = torch.as_tensor(np.stack([g.contact_vector() for g in gestures])).repeat(len(THUMB_STARTS_DEG), 1)
    free = torch.zeros_like(base)
    free[..., 1] = 1.0
    free[..., 2] = torch.as_tensor(topo.ARTICULATED_IS_KNUCKLE, dtype=base.dtype)
    delta = torch.zeros_like(base, requires_grad=True)
    optimiser = torch.optim.Adam([delta], lr=lr)
    tol = CONTACT_TOLERANCE
    # the thumb sweeps past the palm on its way to a fingertip: keeping it off the palm is secondary
    apart_weight = torch.full((len(CONTACT_PAIRS),), 0.1, dtype=base.dtype)
    apart_weight[pair_index("thumb", "palm")] = 0.01

    def losses(d: torch.Tensor) -> torch.Tensor:
        angles = base + d * free
        gaps = contact_gaps(hand, forward_kinematics(hand, tbs_euler_to_quat(angles)),  # the labels' pads
                            thumb_tips=False) / hand.hand_length
        touch = torch.relu(gaps + 0.1 * tol).square() + torch.relu(-gaps - 0.6 * tol).square()
        apart = torch.relu(1.5 * tol - gaps).square() * apart_weight
        limits = (angles - clamp_to_limits(angles)).square().sum((-1, -2))
        drift = (angles - authored.repeat(len(THUMB_STARTS_DEG), 1, 1)).square().sum((-1, -2))
        return torch.where(want, touch, apart).sum(-1) * 1e4 + 1e-2 * drift + limits

    for _ in range(steps):
        loss = losses(delta).sum()
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
    with torch.no_grad():
        final = losses(delta).reshape(len(THUMB_STARTS_DEG), n)
        best = final.argmin(0)
        fitted = clamp_to_limits(base + delta * free).reshape(len(THUMB_STARTS_DEG), n, *base.shape[1:])
        return fitted[best, torch.arange(n)].numpy()


