"""A seeded procedural family of right hands with ground-truth TBS frames and varied rig conventions.

Hand space is canonical: x toward the fingers, y toward the thumb, z out of the back of the hand,
metres. Each finger is a chain of bones whose frames *are* the TBS frames (x along the bone,
y across it, z toward its back), so ground truth is exact. What varies between hands: length,
palm width and length, finger lengths and phalanx ratios, knuckle arc and spread, thumb base,
abduction and pronation, thickness, rest curl, and the rig's own bone-axis convention (so that
rig-local rotations, i.e. Copy, differ between hands as they do between real rigs).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel

#: metres, wrist crease to middle fingertip of an average adult hand: absolute sizes are tuned for it.
REFERENCE_HAND_LENGTH = 0.185

#: rig conventions: the rig's joint frame is ``M_rest @ AXES[c] @ roll``, roll about the rig's bone axis.
RIG_CONVENTIONS: dict[str, tuple[np.ndarray, str]] = {
    "tbs": (np.eye(3), "x"),  # bone along x, like the TBS frame itself
    "y_along_bone": (Rotation.from_euler("z", -90, degrees=True).as_matrix(), "y"),  # Blender-style
    "z_along_bone": (Rotation.from_euler("y", 90, degrees=True).as_matrix(), "z"),
    "neg_x_along_bone": (Rotation.from_euler("z", 180, degrees=True).as_matrix(), "x"),  # mirrored-side rigs
}


def _rot(axis: str, degrees: float) -> np.ndarray:
    return Rotation.from_euler(axis, degrees, degrees=True).as_matrix()


@dataclass(frozen=True)
class HandParams:
    """Everything that tells one generated hand from another (lengths in metres, angles in degrees)."""

    seed: int
    hand_length: float
    middle_ratio: float  # middle finger length (MCP to tip) / hand length
    finger_scale: tuple[float, float, float, float]  # index, middle, ring, pinky length / middle
    phalanx_ratios: tuple[tuple[float, float, float], ...]  # per finger, proximal/middle/distal fractions
    knuckle_spacing: float  # / hand length
    knuckle_arc: tuple[float, float, float, float]  # knuckle x / palm length, index..pinky
    fan: tuple[float, float, float, float]  # rest splay of index..pinky about z
    rest_curl: float  # rest flexion at each finger joint
    thumb_base: tuple[float, float, float]  # CMC position / palm length (x), / hand length (y, z)
    thumb_lengths: tuple[float, float, float]  # metacarpal, proximal, distal / hand length
    thumb_abduction: float
    thumb_drop: float
    thumb_pronation: float
    thickness: float  # scales every radius
    rig_convention: str
    rig_roll: float  # base roll of rig frames about the bone axis
    rig_roll_jitter: float  # per-joint extra roll, uniform in +-this


def sample_params(seed: int, rig_convention: str | None = None) -> HandParams:
    """Draw plausible, varied hand proportions from a seed (same seed -> same hand)."""
    rng = np.random.default_rng(seed)
    u = rng.uniform

    def ratios(base):
        r = np.asarray(base) + u(-0.03, 0.03, 3)
        return tuple(float(x) for x in r / r.sum())

    return HandParams(
        seed=seed,
        hand_length=float(u(0.150, 0.215)),
        middle_ratio=float(u(0.43, 0.47)),
        finger_scale=(float(u(0.86, 0.95)), 1.0, float(u(0.90, 0.98)), float(u(0.70, 0.81))),
        phalanx_ratios=tuple(ratios(b) for b in [(0.42, 0.31, 0.27)] + [(0.47, 0.29, 0.24)] * 4),
        knuckle_spacing=float(u(0.100, 0.125)),
        knuckle_arc=(float(u(0.94, 0.99)), 1.0, float(u(0.94, 0.99)), float(u(0.84, 0.91))),
        fan=(float(u(3, 8)), 0.0, float(u(-6, -2)), float(u(-13, -7))),
        rest_curl=float(u(5, 15)),
        thumb_base=(float(u(0.12, 0.22)), float(u(0.10, 0.13)), float(u(-0.06, -0.035))),
        thumb_lengths=(float(u(0.22, 0.26)), float(u(0.15, 0.18)), float(u(0.135, 0.16))),
        thumb_abduction=float(u(35, 50)),
        thumb_drop=float(u(25, 40)),
        thumb_pronation=float(u(60, 80)),
        thickness=float(u(0.88, 1.15)),
        rig_convention=rig_convention or str(rng.choice(sorted(RIG_CONVENTIONS))),
        rig_roll=float(u(-180, 180)),
        rig_roll_jitter=float(u(0, 25)),
    )


def build_skeleton(p: HandParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rest offsets (21, 3), ground-truth TBS frames (15, 3, 3) and radii (21,) of a parameter set."""
    length = p.hand_length
    palm_length = length * (1.0 - p.middle_ratio)
    middle_length = length * p.middle_ratio
    scale = length / REFERENCE_HAND_LENGTH * p.thickness
    spacing = p.knuckle_spacing * length
    knuckle_y = np.array([spacing, 0.0, -spacing, -2.0 * spacing])
    knuckle_z = np.array([0.0, 0.002, 0.0, -0.004]) * scale

    positions = np.zeros((topo.N_JOINTS, 3))
    frames = np.zeros((topo.N_ARTICULATED, 3, 3))
    radii = np.zeros(topo.N_JOINTS)
    radii[0] = 0.015 * scale

    # thumb: CMC on the palm's radial, palmar side; frame = abduct (z), drop palmar (y), pronate (x)
    tb = p.thumb_base
    thumb_frame = _rot("z", p.thumb_abduction) @ _rot("y", p.thumb_drop) @ _rot("x", -p.thumb_pronation)
    chains = [(np.array([tb[0] * palm_length, tb[1] * length, tb[2] * length]), thumb_frame,
               np.array(p.thumb_lengths) * length, np.array([0.0135, 0.0115, 0.0105, 0.0090]) * scale,
               [0.0, p.rest_curl * 0.5, p.rest_curl * 0.5])]
    base_radius = np.array([0.0093, 0.0097, 0.0091, 0.0080]) * scale
    for i in range(4):
        finger_length = middle_length * p.finger_scale[i]
        chains.append((np.array([p.knuckle_arc[i] * palm_length, knuckle_y[i], knuckle_z[i]]),
                       _rot("z", p.fan[i]), np.array(p.phalanx_ratios[i + 1]) * finger_length,
                       base_radius[i] * np.array([1.0, 0.90, 0.80, 0.70]), [p.rest_curl] * 3))

    for f, (base, frame, bones, rad, curl) in enumerate(chains):
        joint = 1 + 4 * f
        positions[joint] = base
        radii[joint:joint + 4] = rad
        for level in range(3):
            frame = frame @ _rot("y", curl[level])
            frames[3 * f + level] = frame
            positions[joint + level + 1] = positions[joint + level] + bones[level] * frame[:, 0]
    offsets = positions - positions[np.maximum(topo.PARENTS, 0)]
    offsets[0] = 0.0
    return offsets, frames, radii


def rig_frames_for(p: HandParams, rest_frames: np.ndarray) -> np.ndarray:
    """(16, 3, 3) the rig's own joint orientations under its convention, with per-joint roll."""
    rng = np.random.default_rng(p.seed + 7919)
    axes, bone_axis = RIG_CONVENTIONS[p.rig_convention]
    rolls = p.rig_roll + rng.uniform(-p.rig_roll_jitter, p.rig_roll_jitter, topo.N_ROTATING)
    wrist = Rotation.from_rotvec(rng.normal(size=3) * 0.6).as_matrix()  # the rig's wrist bone is tilted too
    frames = np.concatenate([wrist[None], rest_frames])
    return np.stack([frames[j] @ axes @ _rot(bone_axis, rolls[j]) for j in range(topo.N_ROTATING)])


def generate_hand(seed: int, name: str | None = None, rig_convention: str | None = None,
                  with_mesh: bool = True) -> HandModel:
    """One procedural right hand: skeleton, ground-truth TBS frames, rig frames and a skinned mesh."""
    from s2h_viewer.hand.hand_mesh import build_hand_mesh  # heavy (marching cubes); only when asked

    params = sample_params(seed, rig_convention)
    offsets, rest_frames, radii = build_skeleton(params)
    hand = HandModel(
        name=name or f"procedural_{seed}",
        offsets=offsets,
        rest_frames=rest_frames,
        rig_frames=rig_frames_for(params, rest_frames),
        radii=radii,
        source=f"procedural:{seed}",
        meta={"params": asdict(params)},
    )
    if with_mesh:
        hand.mesh = build_hand_mesh(hand)
        hand.validate()
    return hand
