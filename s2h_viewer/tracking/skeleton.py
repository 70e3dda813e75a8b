"""A hand model fitted to a recording: the palm as one rigid body, bone lengths robust over frames, and a
skeleton built in its anatomical canonical pose (DESIGN.md section 2: flat, fingers straight along the
wrist -> middle-knuckle direction), so that a fitted rotation of 0 means the same posture as on any rig.

What keypoints cannot say, and is therefore a convention here: the thumb's rest direction in the palm plane
(`THUMB_ANGLE_DEG`, near the shipped real rigs' canonical thumbs). How far each finger is rolled about its
bone (its hinge axes) is what the recording shows: the fitter picks the roll that makes the finger's PIP and
DIP (thumb: MCP and IP) bend as hinges, or reads it off the recorded joint axes.
"""

from __future__ import annotations

import numpy as np

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.canonical import palm_normal
from s2h_viewer.hand.model import HandModel, palm_axes

#: the thumb's canonical direction: this far from the fingers' direction, toward the thumb, in the palm plane
THUMB_ANGLE_DEG = 35.0
#: the thumb's default roll about its bone (its bend axis tilted this far toward the palm), before fitting
THUMB_ROLL_DEG = 78.0
#: the rigid palm: wrist and the five knuckles (the thumb CMC moves least of the thumb; weighted down)
PALM_JOINTS = np.array([0, *topo.KNUCKLE_JOINTS])
PALM_WEIGHTS = np.array([2.0, 0.5, 1.0, 1.0, 1.0, 1.0])
#: finger joint radii of a 0.18 m hand (the procedural family's reference; joint order), scaled by hand length
_REFERENCE_RADII = np.concatenate([[0.015], [0.0135, 0.0115, 0.0105, 0.0090], *(
    r * np.array([1.0, 0.90, 0.80, 0.70]) for r in (0.0093, 0.0097, 0.0091, 0.0080))])
_REFERENCE_LENGTH = 0.18


def palm_template(positions: np.ndarray) -> np.ndarray:
    """(6, 3) wrist and knuckles in the palm's own axes: per coordinate, the median over the frames given."""
    from_wrist = positions - positions[:, :1]
    local = np.einsum("tca,tjc->tja", palm_axes(from_wrist), from_wrist[:, PALM_JOINTS])
    return np.median(local, axis=0)


def align_palm(positions: np.ndarray, template: np.ndarray) -> np.ndarray:
    """(T, 3, 3) per frame the rotation R (hand space -> recording) best taking the template's knuckles onto
    the frame's, about the wrist (weighted Kabsch): a point is ``wrist + R x``."""
    observed = positions[:, PALM_JOINTS] - positions[:, :1]
    cov = np.einsum("j,tjc,jd->tcd", PALM_WEIGHTS, observed, template)
    u, _, vt = np.linalg.svd(cov)
    fix = np.ones((len(cov), 3))
    fix[:, 2] = np.sign(np.linalg.det(u @ vt))
    return (u * fix[:, None, :]) @ vt


def bone_lengths(hand_space: np.ndarray) -> np.ndarray:
    """(21,) each joint's distance from its parent per frame, median over frames; [knuckles] from the palm."""
    parents = np.maximum(topo.PARENTS, 0)
    return np.median(np.linalg.norm(hand_space - hand_space[:, parents], axis=-1), axis=0)


def rolled_frame(direction: np.ndarray, normal: np.ndarray, roll_deg: float) -> np.ndarray:
    """(3, 3) TBS frame along ``direction`` in the palm plane, its bend axis turned ``roll_deg`` about the bone
    from across the palm toward the palm (0: the splay axis is the palm's normal)."""
    y0, z0 = np.cross(normal, direction), normal
    roll = np.radians(roll_deg)
    y = np.cos(roll) * y0 - np.sin(roll) * z0
    return np.stack([direction, y, np.cross(direction, y)], axis=1)


DEFAULT_ROLLS_DEG = (THUMB_ROLL_DEG, 0.0, 0.0, 0.0, 0.0)


def build_hand(template: np.ndarray, lengths: np.ndarray, name: str, rolls_deg=DEFAULT_ROLLS_DEG,
               radii: np.ndarray | None = None, source: str = "") -> HandModel:
    """The fitted hand in its canonical pose: knuckles from ``template`` (`palm_template`), every finger
    bone of ``lengths`` (`bone_lengths`) straight along its canonical direction, each finger's frames
    rolled about it by ``rolls_deg``: (5,) per finger (thumb first) or (5, 3) per joint."""
    rolls = np.asarray(rolls_deg, dtype=np.float64)
    rolls = np.repeat(rolls[:, None], 3, axis=1) if rolls.ndim == 1 else rolls
    positions = np.zeros((topo.N_JOINTS, 3))
    positions[PALM_JOINTS] = template - template[0]
    normal = palm_normal(positions)
    middle = positions[topo.joint_index("middle_mcp")] - (positions[topo.joint_index("middle_mcp")] @ normal) * normal
    middle /= np.linalg.norm(middle)
    across = np.cross(normal, middle)  # toward the thumb
    angle = np.radians(THUMB_ANGLE_DEG)
    thumb = np.cos(angle) * middle + np.sin(angle) * across
    rest_frames = np.empty((topo.N_ARTICULATED, 3, 3))
    for f in range(topo.N_FINGERS):
        direction = thumb if f == 0 else middle
        for level in range(3):
            joint = 1 + 4 * f + level
            positions[joint + 1] = positions[joint] + lengths[joint + 1] * direction
            rest_frames[3 * f + level] = rolled_frame(direction, normal, rolls[f, level])
    offsets = positions - positions[np.maximum(topo.PARENTS, 0)]
    offsets[0] = 0.0
    hand_length = float(np.linalg.norm(positions[topo.joint_index("middle_tip")]))
    return HandModel(name=name, offsets=offsets, rest_frames=rest_frames,
                     rig_frames=np.concatenate([np.eye(3)[None], rest_frames]),
                     radii=radii if radii is not None else _REFERENCE_RADII * hand_length / _REFERENCE_LENGTH,
                     source=source, meta={"fitted_to_keypoints": True})
