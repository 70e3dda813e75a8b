"""`HandModel`: one hand's rest skeleton, TBS frames, rig convention and optional skinned mesh.

Everything is in *hand space*: the wrist's rest frame, wrist at the origin, metres, right-hand
convention (left hands are mirrored on load, see ``mirror``). Procedural hands use a canonical
hand space (x toward the fingers, y toward the thumb, z out of the back of the hand); real rigs
keep their wrist bone's frame, and ``palm_frame`` recovers the canonical one when needed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.errors import InvalidHandError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.canonical import canonical_turns


def palm_axes(positions: np.ndarray) -> np.ndarray:
    """(..., 3, 3) palm axes (columns) of a right hand's (..., 21, 3) joint positions (wrist at the origin): x to
    the middle knuckle, z out of the back of the hand, y = z x x (toward the thumb)."""
    x = positions[..., topo.joint_index("middle_mcp"), :]
    z = np.cross(positions[..., topo.joint_index("pinky_mcp"), :], positions[..., topo.joint_index("index_mcp"), :])
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    z = z - x * (z * x).sum(-1, keepdims=True)
    z = z / np.linalg.norm(z, axis=-1, keepdims=True)
    return np.stack([x, np.cross(z, x), z], axis=-1)


@dataclass(eq=False)
class SkinnedMesh:
    """A triangle mesh in rest pose with linear-blend weights over the 16 rotating joints."""

    vertices: np.ndarray  # (V, 3) float32, hand space, rest pose
    faces: np.ndarray  # (F, 3) int32
    weights: np.ndarray  # (V, 16) float32, rows sum to 1; column 0 = wrist, then articulated order


@dataclass(eq=False)
class HandModel:
    """A right hand: rest offsets, ground-truth/annotated TBS frames, the rig's own joint frames.

    TBS rotations are measured from the hand's anatomical canonical pose (``canonical_frames``), not
    from the rest pose the rig was bound in; the rest pose is one pose among others (``rest_tbs``).
    ``offsets`` are fixed once the hand is built (derived geometry is cached); ``rest_frames`` may be
    re-annotated.

    ``rig_frames`` are the rig's rest global orientations (wrist + 15 articulated joints). They are
    what makes rig-local rotations (Copy) differ from TBS rotations (TBS Copy) between rigs whose
    bone axes are oriented differently; identity-aligned rigs have ``rig_frames[1:] == rest_frames``.
    """

    name: str
    offsets: np.ndarray  # (21, 3) parent-relative rest offsets in hand space; offsets[0] = 0
    rest_frames: np.ndarray  # (15, 3, 3) M_rest: columns (twist, bend, splay) in hand space
    rig_frames: np.ndarray  # (16, 3, 3) the rig's rest joint orientations in hand space
    radii: np.ndarray  # (21,) finger thickness (radius) at each joint; [0] = palm half-thickness
    mesh: SkinnedMesh | None = None
    source: str = ""  # file it came from, or "procedural:<seed>"
    meta: dict = field(default_factory=dict)  # free-form provenance (generator parameters, rig names)

    def __post_init__(self) -> None:
        self.offsets = np.asarray(self.offsets, dtype=np.float64)
        self.rest_frames = np.asarray(self.rest_frames, dtype=np.float64)
        self.rig_frames = np.asarray(self.rig_frames, dtype=np.float64)
        self.radii = np.asarray(self.radii, dtype=np.float64)
        self.validate()

    def same_as(self, other: "HandModel") -> bool:
        """The same hand as ``other``: skeleton, TBS frames and mesh all equal (one file loaded twice, or a copy
        renamed to tell it from another target's name, `retarget.comparison.distinct_name`)."""
        meshes = (self.mesh, other.mesh)
        same_mesh = meshes[0] is meshes[1] or (None not in meshes and all(
            np.array_equal(getattr(meshes[0], a), getattr(meshes[1], a)) for a in ("vertices", "faces", "weights")))
        return (same_mesh and np.array_equal(self.offsets, other.offsets)
                and np.array_equal(self.rest_frames, other.rest_frames))

    def validate(self) -> None:
        """Raise `InvalidHandError` naming the hand and the problem if any convention is broken."""
        expected = {"offsets": (21, 3), "rest_frames": (15, 3, 3), "rig_frames": (16, 3, 3), "radii": (21,)}
        for attr, shape in expected.items():
            value = getattr(self, attr)
            if value.shape != shape:
                raise InvalidHandError(f"hand {self.name!r}: {attr} has shape {value.shape}, expected {shape}")
            if not np.all(np.isfinite(value)):
                raise InvalidHandError(f"hand {self.name!r}: {attr} contains NaN or infinite values")
        bone_lengths = np.linalg.norm(self.offsets[1:], axis=1)
        if np.any(bone_lengths < 1e-6):
            bad = [topo.FINGER_JOINT_NAMES[i] for i in np.flatnonzero(bone_lengths < 1e-6)]
            raise InvalidHandError(f"hand {self.name!r}: zero-length bones at {', '.join(bad)}")
        for attr in ("rest_frames", "rig_frames"):
            frames = getattr(self, attr)
            ortho = np.abs(frames.transpose(0, 2, 1) @ frames - np.eye(3)).max()
            if ortho > 1e-4 or np.any(np.linalg.det(frames) < 0):
                raise InvalidHandError(f"hand {self.name!r}: {attr} are not right-handed rotations "
                                       f"(orthonormality error {ortho:.2g})")
        twist = self.rest_frames[:, :, 0]
        child = self.offsets[topo.ARTICULATED_JOINTS + 1]
        cos = np.einsum("ij,ij->i", twist, child) / np.linalg.norm(child, axis=1)
        if np.any(cos < 0.99):
            bad = [topo.ARTICULATED_NAMES[i] for i in np.flatnonzero(cos < 0.99)]
            raise InvalidHandError(f"hand {self.name!r}: twist axis does not follow the bone at {', '.join(bad)}")
        if self.mesh is not None:
            v, f, w = self.mesh.vertices, self.mesh.faces, self.mesh.weights
            if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3 or w.shape != (len(v), 16):
                raise InvalidHandError(f"hand {self.name!r}: mesh arrays have inconsistent shapes "
                                       f"(vertices {v.shape}, faces {f.shape}, weights {w.shape})")
            if len(f) and (f.min() < 0 or f.max() >= len(v)):
                raise InvalidHandError(f"hand {self.name!r}: mesh faces index missing vertices")
            if np.abs(w.sum(axis=1) - 1).max() > 1e-3:
                raise InvalidHandError(f"hand {self.name!r}: skin weights do not sum to 1 per vertex")

    @cached_property
    def rest_positions(self) -> np.ndarray:
        """(21, 3) rest joint positions in hand space (wrist at the origin)."""
        pos = np.zeros((topo.N_JOINTS, 3))
        for j in range(1, topo.N_JOINTS):
            pos[j] = pos[topo.PARENTS[j]] + self.offsets[j]
        return pos

    @cached_property
    def canonical_turns(self) -> np.ndarray:
        """(15, 3, 3) global rotations taking each rest bone to the canonical pose (see `canonical`)."""
        return canonical_turns(self.offsets)

    @property
    def canonical_frames(self) -> np.ndarray:
        """(15, 3, 3) global TBS frames in the canonical pose: the frames identity ``Q_tbs`` gives."""
        return self.canonical_turns @ self.rest_frames

    @property
    def rest_tbs(self) -> np.ndarray:
        """(15, 4) the rig's rest pose as TBS quaternions (w, x, y, z) measured from the canonical pose."""
        canonical = np.concatenate([np.eye(3)[None], self.canonical_frames])
        rest = np.concatenate([np.eye(3)[None], self.rest_frames])
        parent = topo.ARTICULATED_PARENT_ROTATING
        local_canonical = canonical[parent].transpose(0, 2, 1) @ canonical[1:]
        local_rest = rest[parent].transpose(0, 2, 1) @ rest[1:]
        q = Rotation.from_matrix(local_canonical.transpose(0, 2, 1) @ local_rest).as_quat(scalar_first=True)
        return np.where(q[:, :1] < 0, -q, q)

    @cached_property
    def palm_length(self) -> float:
        """Wrist to middle knuckle: the official unit of ASM magnitudes (fixed under any finger pose)."""
        return float(np.linalg.norm(self.rest_positions[topo.joint_index("middle_mcp")]))

    @cached_property
    def hand_length(self) -> float:
        """Wrist to middle-finger tip at rest: the unit that makes different hands comparable."""
        return float(np.linalg.norm(self.rest_positions[topo.joint_index("middle_tip")]))

    @cached_property
    def palm_frame(self) -> np.ndarray:
        """(3, 3) canonical palm axes in hand space (see `palm_axes`)."""
        return palm_axes(self.rest_positions)

    @cached_property
    def shape_vector(self) -> np.ndarray:
        """The shape parameter H (60,): each finger joint's rest offset in its parent's frame / hand length.

        Knuckle offsets are taken in the canonical palm frame, the others in the parent's TBS frame,
        so H does not depend on how a rig orients its bones: one network can serve every rig.
        """
        local = np.empty((topo.N_FINGER_JOINTS, 3))
        for j in range(1, topo.N_JOINTS):
            parent = topo.PARENTS[j]
            if parent == 0:
                frame = self.palm_frame
            else:
                frame = self.rest_frames[topo.ARTICULATED_OF_JOINT[parent]]
            local[j - 1] = frame.T @ self.offsets[j]
        return (local / self.hand_length).reshape(-1)
