"""Inverse kinematics of a fitted hand: per-frame TBS angles (twist, bend, splay) that put its bones along
the recorded bones, within the anatomical limits (`semantics.anatomy`).

Closed form, batched over every frame, down each finger: a joint placed by its (already solved) parent
aims its bone from where the solved chain has put the joint at the recorded child joint, ``b``, and sees it
as ``v = F^T b``, with ``F = G_parent C_parent^T C_joint``; ``Ry(bend) Rz(splay)``
takes the twist axis x onto ``v = (cos bend cos splay, sin splay, -sin bend cos splay)``. Twist is 0
(the anatomical prior, and keypoints cannot see it); a hinge (PIP, DIP, thumb MCP and IP) keeps only its
bend, the knuckles their bend and splay, each clamped into its limits before the joints below it are solved,
so they make up what the limits took from their parent where they can.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.rotations import tbs_euler_to_quat
from s2h_viewer.semantics.anatomy import BEND_HIGH, BEND_LOW, SPLAY_LIMIT

#: bends stop this far inside 90 deg, where the XYZ angles lock (as `motions.fitting.clamp_to_limits`)
BEND_MARGIN = math.radians(1.0)


class _FingerWalk:
    """Down one finger from its fixed knuckle, what `solve` and `_chain_points` share: each joint placed by its
    solved parent (``F = G_parent C_parent^T C_joint``), then turned and its bone laid along the turned twist
    axis from where the chain has got to."""

    def __init__(self, hand: HandModel, finger: int, n_frames: int):
        self.canonical = hand.canonical_frames
        self.lengths = np.linalg.norm(hand.offsets, axis=-1)
        self.finger = finger
        self.parent_global = np.broadcast_to(np.eye(3), (n_frames, 3, 3))
        self.parent_canonical = np.eye(3)
        self.at = np.broadcast_to(hand.rest_positions[1 + 4 * finger], (n_frames, 3))  # the joint reached

    def placed(self, level: int) -> np.ndarray:
        """(T, 3, 3) the joint at ``level``'s frame as its parent places it, before its own turn."""
        return self.parent_global @ (self.parent_canonical.T @ self.canonical[3 * self.finger + level])

    def turn(self, level: int, placed: np.ndarray, bend: np.ndarray, splay: np.ndarray) -> np.ndarray:
        """Turn the placed joint by ``Ry(bend) Rz(splay)``; (T, 3) where its child joint lands."""
        self.parent_global = placed @ _bend_splay_matrix(bend, splay)
        self.parent_canonical = self.canonical[3 * self.finger + level]
        self.at = self.at + self.lengths[2 + 4 * self.finger + level] * self.parent_global[:, :, 0]
        return self.at


def solve(hand: HandModel, positions: np.ndarray, hinges: bool = True) -> np.ndarray:
    """(T, 15, 3) radians for (T, 21, 3) keypoints in ``hand``'s space (see the module docstring);
    ``hinges=False`` leaves the hinges their sideways bend (to measure how much of it the data has)."""
    n = len(positions)
    angles = np.zeros((n, topo.N_ARTICULATED, 3))
    low, high, splay_limit = BEND_LOW.numpy(), BEND_HIGH.numpy() - BEND_MARGIN, SPLAY_LIMIT.numpy()
    for f in range(topo.N_FINGERS):
        walk = _FingerWalk(hand, f, n)
        for level in range(3):
            a, joint = 3 * f + level, 1 + 4 * f + level
            placed = walk.placed(level)
            bone = positions[:, joint + 1] - walk.at
            bone = bone / np.linalg.norm(bone, axis=-1, keepdims=True).clip(1e-12)
            v = np.einsum("tca,tc->ta", placed, bone)
            splay = np.arcsin(np.clip(v[:, 1], -1.0, 1.0))
            bend = np.arctan2(-v[:, 2], v[:, 0])
            if topo.ARTICULATED_IS_KNUCKLE[a]:
                splay = np.clip(splay, -splay_limit[a], splay_limit[a])
            elif hinges:
                splay = np.zeros(n)
            angles[:, a, 1], angles[:, a, 2] = np.clip(bend, low[a], high[a]), splay
            walk.turn(level, placed, angles[:, a, 1], angles[:, a, 2])
    return angles


#: Gauss-Newton refinement of each finger: weights of its three child joints' errors (tips count most: they
#: make the contacts), iterations, and the finite-difference step (radians)
CHAIN_WEIGHTS = np.array([0.25, 0.5, 4.0])
CHAIN_ITERATIONS = 6
_STEP = 1e-5


def _chain_points(hand: HandModel, f: int, params: np.ndarray) -> np.ndarray:
    """(T, 3, 3) finger ``f``'s three child joints for ``params`` (T, 4): knuckle bend and splay, the two
    hinges' bends (no twist, no hinge splay), from its fixed knuckle."""
    walk = _FingerWalk(hand, f, len(params))
    zero = np.zeros(len(params))
    turns = ((params[:, 0], params[:, 1]), (params[:, 2], zero), (params[:, 3], zero))
    return np.stack([walk.turn(level, walk.placed(level), bend, splay) for level, (bend, splay) in enumerate(turns)],
                    axis=1)


def refine_chains(hand: HandModel, positions: np.ndarray, angles: np.ndarray, fingers=range(topo.N_FINGERS)
                  ) -> np.ndarray:
    """(T, 15, 3) ``angles`` (from `solve`) refined finger by finger by Levenberg-Marquardt so its three
    child joints meet the keypoints as a whole (tips weighted most), within the limits: a bone aimed at
    its recorded child from where its parent left it cannot make up for a parent that is off (a thumb whose
    base the tracker moves, say)."""
    low, high, splay_limit = BEND_LOW.numpy(), BEND_HIGH.numpy() - BEND_MARGIN, SPLAY_LIMIT.numpy()
    out = angles.copy()
    weights = np.repeat(CHAIN_WEIGHTS, 3)
    for f in fingers:
        a = 3 * f
        params = np.stack([angles[:, a, 1], angles[:, a, 2], angles[:, a + 1, 1], angles[:, a + 2, 1]], -1)
        lower = np.array([low[a], -splay_limit[a], low[a + 1], low[a + 2]])
        upper = np.array([high[a], splay_limit[a], high[a + 1], high[a + 2]])
        target = positions[:, 2 + 4 * f: 5 + 4 * f].reshape(len(params), 9)
        damping = np.full(len(params), 1e-4)
        residual = (_chain_points(hand, f, params).reshape(-1, 9) - target) * weights
        for _ in range(CHAIN_ITERATIONS):
            base = residual / weights + target
            jacobian = np.stack([(_chain_points(hand, f, params + _STEP * np.eye(4)[k]).reshape(-1, 9) - base)
                                 * weights / _STEP for k in range(4)], -1)  # (T, 9, 4)
            normal = np.einsum("tik,til->tkl", jacobian, jacobian)
            scale = 1e-12 + np.trace(normal, axis1=1, axis2=2)  # damping relative to the system's size
            normal = normal + (damping * scale)[:, None, None] * np.eye(4)
            step = np.linalg.solve(normal, np.einsum("tik,ti->tk", jacobian, residual)[..., None])[..., 0]
            trial = np.clip(params - step, lower, upper)
            trial_residual = (_chain_points(hand, f, trial).reshape(-1, 9) - target) * weights
            better = (trial_residual ** 2).sum(1) < (residual ** 2).sum(1)  # Levenberg-Marquardt: keep what helps
            params = np.where(better[:, None], trial, params)
            residual = np.where(better[:, None], trial_residual, residual)
            damping = np.where(better, damping / 3.0, damping * 4.0)
        out[:, a, 1], out[:, a, 2], out[:, a + 1, 1], out[:, a + 2, 1] = params.T
    return out


def _bend_splay_matrix(bend: np.ndarray, splay: np.ndarray) -> np.ndarray:
    """(T, 3, 3) ``Ry(bend) @ Rz(splay)`` (`rotations.tbs_euler_to_matrix` with no twist), in closed form."""
    cb, sb, cs, ss = np.cos(bend), np.sin(bend), np.cos(splay), np.sin(splay)
    zero = np.zeros_like(bend)
    return np.stack([np.stack([cb * cs, -cb * ss, sb], -1), np.stack([ss, cs, zero], -1),
                     np.stack([-sb * cs, sb * ss, cb], -1)], -2)


def angles_to_quats(angles: np.ndarray) -> np.ndarray:
    """(T, 15, 3) radians -> (T, 15, 4) float32 TBS quaternions (w, x, y, z)."""
    return tbs_euler_to_quat(torch.as_tensor(angles)).numpy().astype(np.float32)


def hinge_errors(angles: np.ndarray) -> np.ndarray:
    """(5, 2) per finger and hinge (PIP, DIP; thumb MCP, IP), the mean |splay| (radians) where it bends: how
    far it bends sideways, which a wrong roll of its frame makes it do (``angles`` from
    ``solve(..., hinges=False)``); NaN for a hinge that never bends."""
    hinges = angles.reshape(len(angles), topo.N_FINGERS, 3, 3)[:, :, 1:]
    bent = np.abs(hinges[..., 1]) > math.radians(10)
    count = bent.sum(0)
    splay = np.where(bent, np.abs(hinges[..., 2]), 0.0).sum(0)
    return np.where(count > 0, splay / np.maximum(count, 1), np.nan)
