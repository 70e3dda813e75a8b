"""Mirroring between left and right hands (DESIGN.md section 1: left hands become right on load).

A reflection ``S`` (across the plane with the given normal) maps positions and bone directions;
the TBS frame keeps twist and splay and flips bend so that it stays right-handed:
``M' = S M D`` with ``D = diag(1, -1, 1)``. Hence a TBS rotation becomes ``D R D``: bend is
unchanged, twist and splay change sign (quaternion ``(w, -x, y, -z)``), and spreading stays
spreading. Rig frames are conjugated (``S B S``) to stay proper rotations. Mirroring twice is
the identity.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from s2h_viewer.hand.model import HandModel, SkinnedMesh
from s2h_viewer.hand.motion import Motion

_FLIP_BEND = np.diag([1.0, -1.0, 1.0])
_TBS_QUAT_SIGNS = np.array([1.0, -1.0, 1.0, -1.0], dtype=np.float32)


def reflection(normal: np.ndarray | tuple[float, float, float] = (1.0, 0.0, 0.0)) -> np.ndarray:
    """(3, 3) reflection across the plane through the origin with this normal."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    return np.eye(3) - 2.0 * np.outer(n, n)


def mirror_hand(hand: HandModel, normal=(1.0, 0.0, 0.0), name: str | None = None) -> HandModel:
    """The mirror image of a hand (left <-> right), with its mesh's winding kept outward."""
    s = reflection(normal)
    mesh = None
    if hand.mesh is not None:
        mesh = SkinnedMesh(
            vertices=(hand.mesh.vertices @ s.T).astype(np.float32),
            faces=hand.mesh.faces[:, ::-1].copy(),
            weights=hand.mesh.weights.copy(),
        )
    return dataclasses.replace(
        hand,
        name=name if name is not None else hand.name,
        offsets=hand.offsets @ s.T,
        rest_frames=s @ hand.rest_frames @ _FLIP_BEND,
        rig_frames=s @ hand.rig_frames @ s,
        mesh=mesh,
    )


def mirror_motion(motion: Motion) -> Motion:
    """The same motion on the mirrored hand (TBS quaternions ``(w, -x, y, -z)``)."""
    return dataclasses.replace(motion, q_tbs=motion.q_tbs * _TBS_QUAT_SIGNS)
