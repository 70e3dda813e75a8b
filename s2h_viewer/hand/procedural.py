"""A seeded procedural family of right hands with ground-truth TBS frames and varied rig conventions.

Hand space is canonical: x toward the fingers, y toward the thumb, z out of the back of the hand,
metres. Each finger is a chain of bones whose frames *are* the TBS frames (x along the bone,
y across it, z toward its back), so ground truth is exact. What varies between hands: length,
palm width and length, finger lengths and phalanx ratios, knuckle arc and spread, thumb base,
abduction and pronation, thickness, the rest pose the rig is bound in (flat to strongly curled and
fanned, as game and XR hands are), mesh density (low-poly avatars too), and the rig's own bone-axis
convention (so that rig-local rotations, i.e. Copy, differ between hands as they do between real rigs).
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
    style: str  # a key of STYLES
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
    mesh_detail: float  # marching-cubes grid steps per hand length (82: ~25k faces; ~30: low-poly)
    rig_convention: str
    rig_roll: float  # base roll of rig frames about the bone axis
    rig_roll_jitter: float  # per-joint extra roll, uniform in +-this


#: sampling ranges (low, high) per style. "realistic": adult human hands, bound flat to mildly
#: curled. "stylised": the wider proportions of game and cartoon avatars: short thick or long slender
#: (anime) fingers, big thumbs, wide palms, rests from flat to strongly curled and fanned, low-poly
#: meshes now and then (``LOW_POLY_SHARE``).
STYLES: dict[str, dict[str, tuple[float, float]]] = {
    "realistic": dict(
        hand_length=(0.150, 0.215), middle_ratio=(0.43, 0.47), index_scale=(0.86, 0.95), ring_scale=(0.90, 0.98),
        pinky_scale=(0.70, 0.81), phalanx_jitter=(-0.03, 0.03), knuckle_spacing=(0.100, 0.125),
        index_arc=(0.94, 0.99), ring_arc=(0.94, 0.99), pinky_arc=(0.84, 0.91), index_fan=(3, 8),
        ring_fan=(-6, -2), pinky_fan=(-13, -7), rest_curl=(0, 20), thumb_x=(0.12, 0.22), thumb_y=(0.10, 0.13),
        thumb_z=(-0.06, -0.035), thumb_scale=(0.95, 1.05), thumb_abduction=(35, 50), thumb_drop=(25, 40),
        thumb_pronation=(60, 80), thickness=(0.88, 1.15)),
    "stylised": dict(
        hand_length=(0.130, 0.250), middle_ratio=(0.34, 0.54), index_scale=(0.80, 1.0), ring_scale=(0.85, 1.0),
        pinky_scale=(0.62, 0.88), phalanx_jitter=(-0.06, 0.06), knuckle_spacing=(0.12, 0.19),
        index_arc=(0.90, 1.0), ring_arc=(0.90, 1.0), pinky_arc=(0.78, 0.95), index_fan=(0, 18),
        ring_fan=(-12, 0), pinky_fan=(-26, -4), rest_curl=(0, 45), thumb_x=(0.08, 0.30), thumb_y=(0.09, 0.15),
        thumb_z=(-0.08, -0.02), thumb_scale=(0.80, 1.35), thumb_abduction=(25, 60), thumb_drop=(15, 45),
        thumb_pronation=(60, 85), thickness=(0.9, 1.8)),
}
#: share of stylised hands with a low-poly mesh, and their grid steps per hand length
LOW_POLY_SHARE = 0.35
LOW_POLY_DETAIL = (28.0, 40.0)
FULL_DETAIL = 82.0
#: finger diameter at the knuckle may fill at most this share of the knuckle spacing (fingers never fuse).
MAX_FINGER_FILL = 0.85


def sample_params(seed: int, rig_convention: str | None = None, style: str = "realistic") -> HandParams:
    """Draw plausible, varied hand proportions from a seed (same seed and style -> same hand)."""
    if style not in STYLES:
        raise ValueError(f"unknown hand style {style!r}; choose from {', '.join(STYLES)}")
    rng = np.random.default_rng(seed)
    ranges = STYLES[style]

    def u(name: str, size: int | None = None):
        return rng.uniform(*ranges[name], size)

    def ratios(base):
        r = np.asarray(base) + u("phalanx_jitter", 3)
        return tuple(float(x) for x in r / r.sum())

    hand_length = float(u("hand_length"))
    spacing = float(u("knuckle_spacing"))
    thumb_scale = float(u("thumb_scale"))
    widest = 2 * 0.0097 * hand_length / REFERENCE_HAND_LENGTH  # middle finger's knuckle diameter at thickness 1
    return HandParams(
        seed=seed,
        style=style,
        hand_length=hand_length,
        middle_ratio=float(u("middle_ratio")),
        finger_scale=(float(u("index_scale")), 1.0, float(u("ring_scale")), float(u("pinky_scale"))),
        phalanx_ratios=tuple(ratios(b) for b in [(0.42, 0.31, 0.27)] + [(0.47, 0.29, 0.24)] * 4),
        knuckle_spacing=spacing,
        knuckle_arc=(float(u("index_arc")), 1.0, float(u("ring_arc")), float(u("pinky_arc"))),
        fan=(float(u("index_fan")), 0.0, float(u("ring_fan")), float(u("pinky_fan"))),
        rest_curl=float(u("rest_curl")),
        thumb_base=(float(u("thumb_x")), float(u("thumb_y")), float(u("thumb_z"))),
        thumb_lengths=tuple(float(x * thumb_scale) for x in (rng.uniform(0.22, 0.26), rng.uniform(0.15, 0.18),
                                                             rng.uniform(0.135, 0.16))),
        thumb_abduction=float(u("thumb_abduction")),
        thumb_drop=float(u("thumb_drop")),
        thumb_pronation=float(u("thumb_pronation")),
        thickness=float(min(u("thickness"), MAX_FINGER_FILL * spacing * hand_length / widest)),
        mesh_detail=float(rng.uniform(*LOW_POLY_DETAIL)) if style == "stylised" and rng.random() < LOW_POLY_SHARE
        else FULL_DETAIL,
        rig_convention=rig_convention or str(rng.choice(sorted(RIG_CONVENTIONS))),
        rig_roll=float(rng.uniform(-180, 180)),
        rig_roll_jitter=float(rng.uniform(0, 25)),
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
                  with_mesh: bool = True, style: str = "realistic") -> HandModel:
    """One procedural right hand: skeleton, ground-truth TBS frames, rig frames and a skinned mesh."""
    from s2h_viewer.hand.hand_mesh import build_hand_mesh  # heavy (marching cubes); only when asked

    params = sample_params(seed, rig_convention, style)
    offsets, rest_frames, radii = build_skeleton(params)
    hand = HandModel(
        name=name or f"procedural_{seed}",
        offsets=offsets,
        rest_frames=rest_frames,
        rig_frames=rig_frames_for(params, rest_frames),
        radii=radii,
        source=f"procedural:{style}:{seed}",
        meta={"params": asdict(params)},
    )
    if with_mesh:
        hand.mesh = build_hand_mesh(hand, params.mesh_detail)
        hand.validate()
    return hand
