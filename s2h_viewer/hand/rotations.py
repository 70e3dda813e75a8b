"""Rotation conversions on torch tensors, quaternions as (w, x, y, z) (DESIGN.md section 2).

roma does the work (it uses (x, y, z, w)); these wrappers fix the project's scalar-first
convention and ``w >= 0`` on output in one place. `slerp` works on numpy arrays of whole clips.

TBS Euler angles, the official code's order (DESIGN.md section 2): intrinsic twist (x), then bend (y),
then splay (z), i.e. ``R = Rx(twist) @ Ry(bend) @ Rz(splay)``, angles ordered (twist, bend, splay); a
positive bend about the bend axis (y) flexes the finger toward its pad side (-z).
"""

from __future__ import annotations

import numpy as np
import roma
import torch
from scipy.spatial.transform import Rotation

_WXYZ_TO_XYZW = [1, 2, 3, 0]
_XYZW_TO_WXYZ = [3, 0, 1, 2]


def canonical_quat(q: torch.Tensor) -> torch.Tensor:
    """Unit quaternion (w, x, y, z) with ``w >= 0`` (the double cover resolved)."""
    q = q / q.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    return torch.where(q[..., :1] < 0, -q, q)


def quat_to_matrix(q: torch.Tensor) -> torch.Tensor:
    """(..., 4) quaternions (w, x, y, z), normalised here -> (..., 3, 3) rotation matrices."""
    q = q / q.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    return roma.unitquat_to_rotmat(q[..., _WXYZ_TO_XYZW])


def matrix_to_quat(r: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) rotation matrices -> (..., 4) unit quaternions (w, x, y, z), ``w >= 0``."""
    return canonical_quat(roma.rotmat_to_unitquat(r)[..., _XYZW_TO_WXYZ])


def quat_multiply(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product ``a * b`` of (w, x, y, z) quaternions (rotation b first, then a)."""
    return roma.quat_product(a[..., _WXYZ_TO_XYZW], b[..., _WXYZ_TO_XYZW])[..., _XYZW_TO_WXYZ]


def quat_conjugate(q: torch.Tensor) -> torch.Tensor:
    """Inverse of a unit quaternion (w, x, y, z)."""
    return q * q.new_tensor([1.0, -1.0, -1.0, -1.0])


def quat_angle(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Angle in radians of the rotation taking ``b`` to ``a`` (geodesic distance)."""
    dot = (a * b).sum(-1).abs() / (a.norm(dim=-1) * b.norm(dim=-1)).clamp_min(1e-12)
    return 2.0 * torch.acos(dot.clamp(max=1.0))


def random_quats(shape: tuple[int, ...], generator: torch.Generator | None = None,
                 dtype: torch.dtype = torch.float64) -> torch.Tensor:
    """Uniformly random unit quaternions (w, x, y, z), ``w >= 0``."""
    return canonical_quat(torch.randn(*shape, 4, generator=generator, dtype=dtype))


def tbs_euler_to_matrix(twist: torch.Tensor, bend: torch.Tensor, splay: torch.Tensor) -> torch.Tensor:
    """Rotation ``Rx(twist) @ Ry(bend) @ Rz(splay)`` (radians) as (..., 3, 3)."""
    zero = torch.zeros_like(twist)
    x = torch.stack([twist, zero, zero], -1)
    y = torch.stack([zero, bend, zero], -1)
    z = torch.stack([zero, zero, splay], -1)
    return roma.rotvec_to_rotmat(x) @ roma.rotvec_to_rotmat(y) @ roma.rotvec_to_rotmat(z)


def matrix_to_tbs_euler(r: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) -> (..., 3) angles (twist, bend, splay) in radians; differentiable.

    From ``R = Rx(a) Ry(b) Rz(c)``: ``R02 = sin b``, ``(-R12, R22) ~ (sin a, cos a)``,
    ``(-R01, R00) ~ (sin c, cos c)``. Bend comes from ``atan2`` over the full column norm, not the
    official code's clamped ``asin`` (which saturates at 39.5 deg), so it reaches +-90 deg.
    """
    bend = torch.atan2(r[..., 0, 2], torch.sqrt(r[..., 0, 0] ** 2 + r[..., 0, 1] ** 2 + 1e-12))
    twist = torch.atan2(-r[..., 1, 2], r[..., 2, 2])
    splay = torch.atan2(-r[..., 0, 1], r[..., 0, 0])
    return torch.stack([twist, bend, splay], -1)


def tbs_euler_to_quat(angles: torch.Tensor) -> torch.Tensor:
    """(..., 3) angles (twist, bend, splay) in radians -> (..., 4) quaternions (w, x, y, z), ``w >= 0``.

    The product ``qx(twist) qy(bend) qz(splay)`` in closed form: a handful of elementwise ops (ASM-Opt
    calls it at every step, through autograd), not a matrix built and decomposed again.
    """
    c, s = torch.cos(0.5 * angles).unbind(-1), torch.sin(0.5 * angles).unbind(-1)
    q = torch.stack([c[0] * c[1] * c[2] - s[0] * s[1] * s[2], s[0] * c[1] * c[2] + c[0] * s[1] * s[2],
                     c[0] * s[1] * c[2] - s[0] * c[1] * s[2], c[0] * c[1] * s[2] + s[0] * s[1] * c[2]], -1)
    return torch.where(q[..., :1] < 0, -q, q)


def quat_to_tbs_euler(q: torch.Tensor) -> torch.Tensor:
    """(..., 4) quaternions (w, x, y, z) -> (..., 3) angles (twist, bend, splay) in radians."""
    return matrix_to_tbs_euler(quat_to_matrix(q))


def quat_to_tbs_euler_past_lock(q: torch.Tensor) -> torch.Tensor:
    """(..., 4) quaternions -> (..., 3) TBS angles with the twist within +-90 deg and the bend free to pass
    +-90 deg. `quat_to_tbs_euler` keeps the bend within +-90, so a joint bent to 103 deg reads (twist 158,
    bend 77, splay -159): the same rotation, but an optimiser stepping its "splay" there twists the finger.
    ``Rx(a + pi) Ry(pi - b) Rz(c + pi) = Rx(a) Ry(b) Rz(c)`` gives the other reading."""
    twist, bend, splay = quat_to_tbs_euler(q).unbind(-1)
    flip = twist.abs() > torch.pi / 2
    half_turn = torch.full_like(twist, torch.pi)
    twist = torch.where(flip, twist - torch.copysign(half_turn, twist), twist)
    bend = torch.where(flip, torch.copysign(half_turn, bend) - bend, bend)
    splay = torch.where(flip, splay - torch.copysign(half_turn, splay), splay)
    return torch.stack([twist, bend, splay], -1)


def slerp(a: np.ndarray, b: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """(T, J, 4) per-joint slerp from ``a`` to ``b`` (T, J, 4; w, x, y, z) by ``weight`` (T,), float32."""
    start = Rotation.from_quat(a.reshape(-1, 4).astype(np.float64), scalar_first=True)
    end = Rotation.from_quat(b.reshape(-1, 4).astype(np.float64), scalar_first=True)
    step = (start.inv() * end).as_rotvec() * np.repeat(weight, a.shape[-2])[:, None]
    return (start * Rotation.from_rotvec(step)).as_quat(scalar_first=True).reshape(a.shape).astype(np.float32)
