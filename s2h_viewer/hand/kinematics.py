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

import weakref
from dataclasses import dataclass

import numpy as np
import torch
from scipy.spatial.transform import Rotation

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.rotations import canonical_quat, matrix_to_quat, quat_conjugate, quat_multiply


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


def _quat_product_table() -> np.ndarray:
    """(4, 16) ``P`` with ``a * b = P @ outer(a, b).ravel()`` for (w, x, y, z) quaternions (Hamilton)."""
    table = np.zeros((4, 4, 4))  # (out, a, b)
    for out, terms in enumerate((
            ((0, 0, 1), (1, 1, -1), (2, 2, -1), (3, 3, -1)),
            ((0, 1, 1), (1, 0, 1), (2, 3, 1), (3, 2, -1)),
            ((0, 2, 1), (1, 3, -1), (2, 0, 1), (3, 1, 1)),
            ((0, 3, 1), (1, 2, 1), (2, 1, -1), (3, 0, 1)))):
        for a, b, sign in terms:
            table[out, a, b] = sign
    return table.reshape(4, 16)


def _quat_matrix_table() -> np.ndarray:
    """(9, 16) ``P`` with ``R(q).ravel() = P @ outer(q, q).ravel()`` for a unit (w, x, y, z) quaternion."""
    w, x, y, z = range(4)
    table = np.zeros((3, 3, 4, 4))
    for row, squares in enumerate(((1, 1, -1, -1), (1, -1, 1, -1), (1, -1, -1, 1))):
        for i, sign in enumerate(squares):
            table[row, row, i, i] = sign
    for row, col, (i, j), (k, l), sign in ((0, 1, (x, y), (w, z), -1), (1, 0, (x, y), (w, z), 1),
                                           (0, 2, (x, z), (w, y), 1), (2, 0, (x, z), (w, y), -1),
                                           (1, 2, (y, z), (w, x), -1), (2, 1, (y, z), (w, x), 1)):
        table[row, col, [i, j], [j, i]] = 1.0  # 2 x y as x y + y x
        table[row, col, [k, l], [l, k]] = sign
    return table.reshape(9, 16)


_QUAT_PRODUCT = _quat_product_table()
_QUAT_MATRIX = _quat_matrix_table()


@dataclass(frozen=True)
class _Chain:
    """A hand's FK constants in one dtype, batched over the 15 (finger, level) joints (see `forward_kinematics`)."""

    left_products: torch.Tensor  # (15, 4, 4): ``C_p^T C_j`` as a quaternion's left-product matrix
    frame_and_bone: torch.Tensor  # (15, 12, 16): ``outer(g, g)`` -> the frame ``R(g)`` (9) and ``R(g) offset`` (3)
    first: torch.Tensor  # (5, 3, 1): each finger's first joint (MCP/CMC) offset from the wrist
    quat_product: torch.Tensor  # (4, 16) `_quat_product_table`


#: per hand: (the geometry the constants were made from, {dtype: _Chain}); a re-annotated hand is rebuilt
_CHAINS: weakref.WeakKeyDictionary[HandModel, tuple[bytes, dict[torch.dtype, _Chain]]] = weakref.WeakKeyDictionary()


def _chain(hand: HandModel, dtype: torch.dtype) -> _Chain:
    """The FK constants of ``hand`` (cached per hand and dtype, so no call converts numpy arrays)."""
    key = hand.offsets.tobytes() + hand.rest_frames.tobytes()
    cached = _CHAINS.get(hand)
    if cached is None or cached[0] != key:
        cached = _CHAINS[hand] = (key, {})
    if dtype not in cached[1]:
        canonical = hand.canonical_frames
        parent_frames = np.concatenate([np.eye(3)[None], canonical])[topo.ARTICULATED_PARENT_ROTATING]
        local = Rotation.from_matrix(parent_frames.transpose(0, 2, 1) @ canonical).as_quat(scalar_first=True)
        left = np.einsum("ja,oab->job", local, _QUAT_PRODUCT.reshape(4, 4, 4))  # (l * r) = left @ r
        offsets = hand.offsets[1:].reshape(5, 4, 3).copy()  # (finger, level, 3)
        # each child's offset in its parent's TBS rest frame, so that x_child = x_parent + M_parent @ offset
        children = np.einsum("flba,flb->fla", hand.rest_frames.reshape(5, 3, 3, 3), offsets[:, 1:])
        matrix = _QUAT_MATRIX.reshape(3, 3, 16)
        bone = np.einsum("abp,flb->flap", matrix, children).reshape(15, 3, 16)
        frame_and_bone = np.concatenate([np.broadcast_to(_QUAT_MATRIX, (15, 9, 16)), bone], 1)
        cached[1][dtype] = _Chain(*(torch.as_tensor(np.ascontiguousarray(a), dtype=dtype) for a in (
            left, frame_and_bone, offsets[:, 0, :, None], _QUAT_PRODUCT)))
    return cached[1][dtype]


def _quat_products(table: torch.Tensor, a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton products ``a * b`` of (..., 4, T) component-first quaternions, as ``table @ outer(a, b)``."""
    return table @ (a[..., :, None, :] * b[..., None, :, :]).flatten(-3, -2)


def _global_turns(hand: HandModel, q_tbs: torch.Tensor | np.ndarray) -> tuple[torch.Tensor, torch.Tensor, _Chain]:
    """(q (T, 15, 4), the joints' global turns ``outer(g, g)`` (15, 16, T), the hand's FK constants)."""
    q = _as_tensor(q_tbs, torch.float32)
    if q.ndim != 3 or q.shape[1:] != (topo.N_ARTICULATED, 4):
        raise ValueError(f"q_tbs must have shape (T, 15, 4), got {tuple(q.shape)}")
    n_frames = q.shape[0]
    chain = _chain(hand, q.dtype)
    rot = q.permute(1, 2, 0).contiguous()  # (joint, 4, T)
    rot = rot / (rot * rot).sum(1, keepdim=True).sqrt().clamp_min(1e-12)
    local = torch.bmm(chain.left_products, rot).view(5, 3, 4, n_frames)  # l_j * r_j: (finger, level, 4, T)
    turns = [local[:, 0]]
    for level in (1, 2):
        turns.append(_quat_products(chain.quat_product, turns[-1], local[:, level]))
    turn = torch.stack(turns, 1).view(topo.N_ARTICULATED, 4, n_frames)  # g_j: (joint, 4, T)
    return q, (turn[:, :, None] * turn[:, None]).view(topo.N_ARTICULATED, 16, n_frames), chain


def _positions(q: torch.Tensor, chain: _Chain, bones: torch.Tensor) -> torch.Tensor:
    """(T, 21, 3) joint positions from each joint's child bone ``R(g) offset`` (5, 3, 3, T)."""
    n_frames = q.shape[0]
    positions = q.new_empty(topo.N_JOINTS, 3, n_frames)
    positions[0] = 0.0
    by_finger = positions[1:].view(5, 4, 3, n_frames)
    by_finger[:, 0] = chain.first
    by_finger[:, 1:] = chain.first[:, None] + bones.cumsum(1)  # x_j = x_p + M_p offset_j
    return positions.permute(2, 0, 1).contiguous()


def forward_kinematics(hand: HandModel, q_tbs: torch.Tensor | np.ndarray) -> HandPose:
    """(T, 15, 4) TBS quaternions (w, x, y, z) -> joint positions and global TBS frames.

    Vectorised over frames and joints; loops only over the levels of a finger chain, composing
    quaternions (``g_j = g_p * l_j * r_j``). The work runs with the frames last (``(joint, 4, T)``), so
    every kernel is a small matrix times long contiguous rows: one product per joint turns the
    quaternion's outer product ``g g^T`` into its frame and its child's bone vector at once. The
    rotations are transposed in once and the result out once.
    Differentiable in ``q_tbs``; dtype follows ``q_tbs`` (float32 for numpy input).
    """
    q, outer, chain = _global_turns(hand, q_tbs)
    n_frames = q.shape[0]
    frame_bone = torch.bmm(chain.frame_and_bone, outer).view(5, 3, 12, n_frames)  # (finger, level, 9 + 3, T)
    frames = q.new_empty(topo.N_JOINTS, 9, n_frames)  # every joint's frame, frames last, then transposed once
    frames[0] = torch.eye(3, dtype=q.dtype).view(9, 1)
    by_finger = frames[1:].view(5, 4, 9, n_frames)
    by_finger[:, :3] = frame_bone[:, :, :9]
    by_finger[:, 3] = frame_bone[:, 2, :9]  # a tip takes its parent's frame
    return HandPose(positions=_positions(q, chain, frame_bone[:, :, 9:]),
                    frames=frames.permute(2, 0, 1).contiguous().view(n_frames, topo.N_JOINTS, 3, 3))


def joint_positions(hand: HandModel, q_tbs: torch.Tensor | np.ndarray) -> torch.Tensor:
    """(T, 21, 3) the positions of `forward_kinematics` without its frames: an optimiser that reads only where
    the joints are (the contact fit, at every step) builds a quarter of the products."""
    q, outer, chain = _global_turns(hand, q_tbs)
    bones = torch.matmul(chain.frame_and_bone[:, 9:], outer)  # (15, 3, T)
    return _positions(q, chain, bones.view(5, 3, 3, q.shape[0]))


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
