"""The anatomical canonical pose that TBS rotations are measured from (DESIGN.md section 2).

As in the official code (utils/armatures.py ``build_finger_frame``): the palm plane passes through the
wrist and the index and pinky knuckles (normal out of the back of a right hand); finger by finger,
joint by joint, each bone of the rest skeleton is turned into that plane, and the four fingers' bones
are then turned parallel to the wrist -> middle-knuckle direction (projected); the thumb's bones are
only flattened into the plane. Each turn is the smallest rotation taking one direction to the other,
applied to the joint's global rotation, so it carries the bones below it along.

Where we deliberately differ from the official code: angles come from ``atan2(|a x b|, a . b)`` (the
official ``asin(|a x b|)`` is wrong beyond 90 deg), and a bone already in place is left alone (the
official code divides 0 by 0 there and returns NaN).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.hand import topology as topo

_PARALLEL_EPS = 1e-12


def palm_normal(positions: np.ndarray) -> np.ndarray:
    """Unit normal of the plane (wrist, index MCP, pinky MCP), out of the back of a right hand."""
    wrist = positions[0]
    index = positions[topo.joint_index("index_mcp")] - wrist
    pinky = positions[topo.joint_index("pinky_mcp")] - wrist
    n = np.cross(pinky, index)
    return n / np.linalg.norm(n)


def turn_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(3, 3) the smallest rotation taking direction ``a`` to direction ``b`` (identity if parallel)."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    axis = np.cross(a, b)
    sin = np.linalg.norm(axis)
    if sin < _PARALLEL_EPS:
        return np.eye(3)
    angle = np.arctan2(sin, float(a @ b))
    return Rotation.from_rotvec(axis / sin * angle).as_matrix()


def _in_plane(v: np.ndarray, normal: np.ndarray) -> np.ndarray:
    v = v - (v @ normal) * normal
    return v / np.linalg.norm(v)


def canonical_turns(offsets: np.ndarray) -> np.ndarray:
    """(15, 3, 3) per articulated joint, the global rotation taking its rest bone to the canonical pose.

    ``offsets`` are the (21, 3) parent-relative rest offsets in hand space. The canonical global frame
    of joint ``j`` is ``turns[j] @ rest_frame[j]``; knuckle positions do not move.
    """
    positions = np.zeros((topo.N_JOINTS, 3))
    for j in range(1, topo.N_JOINTS):
        positions[j] = positions[topo.PARENTS[j]] + offsets[j]
    normal = palm_normal(positions)
    middle = _in_plane(positions[topo.joint_index("middle_mcp")] - positions[0], normal)
    turns = np.empty((topo.N_ARTICULATED, 3, 3))
    for f, finger in enumerate(topo.FINGERS):
        parent_turn = np.eye(3)
        for level in range(3):
            child = 1 + 4 * f + level + 1
            bone = parent_turn @ offsets[child]  # the bone as the turns of the joints above left it
            flat = _in_plane(bone, normal)
            turn = turn_between(bone, flat)
            if finger != "thumb":
                turn = turn_between(flat, middle) @ turn
            parent_turn = turn @ parent_turn
            turns[3 * f + level] = parent_turn
    return turns
