"""Batched, differentiable forward kinematics and rig-local <-> TBS rotation conversion.

Conventions (DESIGN.md section 2), with ``p`` the parent of articulated joint ``j`` and ``C`` the
canonical-pose TBS frames (``HandModel.canonical_frames``; wrist = I):

- global TBS frame: ``M_j(t) = M_p(t) @ (C_p^T C_j) @ R_tbs_j(t)``, so identity rotations give the
  canonical (flat, straight) pose and ``HandModel.rest_tbs`` gives the rig's rest pose;
- position: ``x_j(t) = x_p(t) + M_p(t) @ (M_rest_p^T offset_j)`` (a bone is rigid in its parent's frame);
- rig-local rotation (what a glTF/FBX/BVH rig stores, relative to rest, in the parent's rest rig frame):
  ``Q_j = K_j (R_rest_j^T R_tbs_j) K_j^T`` with ``R_rest_j`` the rest pose's TBS rotation and
  ``K_j = B_p^T M_rest_j`` the rest TBS frame seen from the parent's rig frame ``B_p``; the node's full
  local rotation is then ``Q_j @ (B_p^T B_j)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.rotations import canonical_quat, matrix_to_quat, quat_conjugate, quat_multiply, quat_to_matrix


@dataclass
class HandPose:
    """FK output for T frames, in hand space."""

    positions: torch.Tensor  # (T, 21, 3): wrist (origin) + 20 finger joints
    frames: torch.Tensor  # (T, 21, 3, 3): global TBS frames; wrist = I, a tip takes its parent's frame

    @property
    def finger_positions(self) -> torch.Tensor:
        """(T, 20, 3): the ASM's joints."""
        return self.positions[:, 1:]

    @property
    def finger_frames(self) -> torch.Tensor:
        """(T, 20, 3, 3)."""
        return self.frames[:, 1:]


def _as_tensor(x: np.ndarray | torch.Tensor, dtype: torch.dtype) -> torch.Tensor:
    return x if isinstance(x, torch.Tensor) else torch.as_tensor(np.asarray(x), dtype=dtype)


def _chain_rest(hand: HandModel) -> tuple[np.ndarray, np.ndarray]:
    """Per finger and level: the canonical TBS frame relative to the parent's (5, 3, 3, 3) and each
    joint's offset in its parent's TBS rest frame (5, 4, 3); the wrist frame is I."""
    canonical = hand.canonical_frames
    parent_frames = np.concatenate([np.eye(3)[None], canonical])[topo.ARTICULATED_PARENT_ROTATING]
    local_rot = parent_frames.transpose(0, 2, 1) @ canonical
    offsets = hand.offsets[1:].reshape(5, 4, 3)
    finger_frames = hand.rest_frames.reshape(5, 3, 3, 3)
    local_off = offsets.copy()
    local_off[:, 1:] = np.einsum("flba,flb->fla", finger_frames, offsets[:, 1:])
    return local_rot.reshape(5, 3, 3, 3), local_off


def forward_kinematics(hand: HandModel, q_tbs: torch.Tensor | np.ndarray) -> HandPose:
    """(T, 15, 4) TBS quaternions (w, x, y, z) -> joint positions and global TBS frames.

    Vectorised over frames and fingers; loops only over the 4 levels of a finger chain.
    Differentiable in ``q_tbs``; dtype follows ``q_tbs`` (float32 for numpy input).
    """
    q = _as_tensor(q_tbs, torch.float32)
    if q.ndim != 3 or q.shape[1:] != (topo.N_ARTICULATED, 4):
        raise ValueError(f"q_tbs must have shape (T, 15, 4), got {tuple(q.shape)}")
    n_frames = q.shape[0]
    local_rot_np, local_off_np = _chain_rest(hand)
    local_rot = torch.as_tensor(local_rot_np, dtype=q.dtype)
    local_off = torch.as_tensor(local_off_np, dtype=q.dtype)
    rot = quat_to_matrix(q).reshape(n_frames, 5, 3, 3, 3)

    frame = torch.eye(3, dtype=q.dtype).expand(n_frames, 5, 3, 3)
    pos = q.new_zeros(n_frames, 5, 3)
    positions, frames = [], []
    for level in range(3):
        pos = pos + (frame @ local_off[:, level, :, None])[..., 0]
        frame = frame @ local_rot[:, level] @ rot[:, :, level]
        positions.append(pos)
        frames.append(frame)
    positions.append(pos + (frame @ local_off[:, 3, :, None])[..., 0])
    frames.append(frame)

    finger_pos = torch.stack(positions, 2).reshape(n_frames, topo.N_FINGER_JOINTS, 3)
    finger_frames = torch.stack(frames, 2).reshape(n_frames, topo.N_FINGER_JOINTS, 3, 3)
    wrist_frame = torch.eye(3, dtype=q.dtype).expand(n_frames, 1, 3, 3)
    return HandPose(
        positions=torch.cat([q.new_zeros(n_frames, 1, 3), finger_pos], 1),
        frames=torch.cat([wrist_frame, finger_frames], 1),
    )


def _tbs_in_parent_rig_frame(hand: HandModel, dtype: torch.dtype) -> torch.Tensor:
    """(15, 4) quaternions of ``K_j = B_p^T M_rest_j``."""
    parent_rig = hand.rig_frames[topo.ARTICULATED_PARENT_ROTATING]
    k = parent_rig.transpose(0, 2, 1) @ hand.rest_frames
    return matrix_to_quat(torch.as_tensor(k, dtype=dtype))


def tbs_to_rig_local(hand: HandModel, q_tbs: torch.Tensor | np.ndarray) -> torch.Tensor:
    """TBS rotations (T, 15, 4) -> the rig's local rotations relative to rest (``Q = K R_rest^T R_tbs K^T``)."""
    q = _as_tensor(q_tbs, torch.float32)
    k = _tbs_in_parent_rig_frame(hand, q.dtype)
    from_rest = quat_multiply(quat_conjugate(torch.as_tensor(hand.rest_tbs, dtype=q.dtype)), q)
    return canonical_quat(quat_multiply(quat_multiply(k, from_rest), quat_conjugate(k)))


def rig_local_to_tbs(hand: HandModel, q_local: torch.Tensor | np.ndarray) -> torch.Tensor:
    """The rig's local rotations relative to rest (T, 15, 4) -> TBS rotations (``R_tbs = R_rest K^T Q K``)."""
    q = _as_tensor(q_local, torch.float32)
    k = _tbs_in_parent_rig_frame(hand, q.dtype)
    from_rest = quat_multiply(quat_multiply(quat_conjugate(k), q), k)
    return canonical_quat(quat_multiply(torch.as_tensor(hand.rest_tbs, dtype=q.dtype), from_rest))


def rest_motion(hand: HandModel, n_frames: int, dtype: torch.dtype = torch.float32) -> torch.Tensor:
    """(T, 15, 4) the rig's rest pose held for ``n_frames``."""
    return torch.as_tensor(hand.rest_tbs, dtype=dtype).expand(n_frames, -1, -1).clone()


def identity_motion(n_frames: int, dtype: torch.dtype = torch.float32) -> torch.Tensor:
    """(T, 15, 4) identity rotations: the canonical (flat, straight) pose."""
    q = torch.zeros(n_frames, topo.N_ARTICULATED, 4, dtype=dtype)
    q[..., 0] = 1.0
    return q
