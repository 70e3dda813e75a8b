"""The 21-joint hand topology every module shares (DESIGN.md section 1).

Joint 0 is the wrist; then 5 fingers (thumb, index, middle, ring, pinky) of 4 joints each, the
last a dummy tip. Three index spaces are used and named consistently everywhere:

- *joint* (21): wrist + 20 finger joints, ``JOINT_NAMES`` order.
- *finger joint* (20): the ASM rows, ``joint - 1``; finger ``f`` joint ``j`` is ``4 * f + j``.
- *articulated* (15): finger joints that carry a rotation (no tips); finger ``f`` level ``j`` is
  ``3 * f + j``. ``Q_tbs`` and ``M_rest`` are indexed this way.
- *rotating* (16): wrist + the 15 articulated joints; skin-weight columns and rig frames.
"""

from __future__ import annotations

import numpy as np

FINGERS: tuple[str, ...] = ("thumb", "index", "middle", "ring", "pinky")
FINGER_LEVELS: dict[str, tuple[str, ...]] = {
    "thumb": ("cmc", "mcp", "ip", "tip"),
    **{f: ("mcp", "pip", "dip", "tip") for f in FINGERS[1:]},
}

N_FINGERS = 5
N_JOINTS = 21
N_FINGER_JOINTS = 20
N_ARTICULATED = 15
N_ROTATING = 16
N_ANCHORS = 9
N_ASM_COLUMNS = N_FINGER_JOINTS + N_ANCHORS

JOINT_NAMES: tuple[str, ...] = ("wrist",) + tuple(f"{f}_{lv}" for f in FINGERS for lv in FINGER_LEVELS[f])
FINGER_JOINT_NAMES: tuple[str, ...] = JOINT_NAMES[1:]

#: joint -> parent joint (21), -1 for the wrist.
PARENTS = np.array([-1] + [0 if j == 0 else 1 + 4 * f + j - 1 for f in range(5) for j in range(4)])
#: articulated index (15) -> joint index (21).
ARTICULATED_JOINTS = np.array([1 + 4 * f + j for f in range(5) for j in range(3)])
ARTICULATED_NAMES: tuple[str, ...] = tuple(JOINT_NAMES[j] for j in ARTICULATED_JOINTS)
#: joint index (21) -> articulated index (15), -1 for the wrist and the tips.
ARTICULATED_OF_JOINT = np.full(N_JOINTS, -1)
ARTICULATED_OF_JOINT[ARTICULATED_JOINTS] = np.arange(N_ARTICULATED)
#: rotating index (16) -> joint index (21): wrist first.
ROTATING_JOINTS = np.concatenate([[0], ARTICULATED_JOINTS])
#: tip joints (21-space) and knuckles (first joint of each finger).
TIP_JOINTS = np.array([4 + 4 * f for f in range(5)])
KNUCKLE_JOINTS = np.array([1 + 4 * f for f in range(5)])
#: articulated index -> True for a knuckle (thumb CMC, finger MCPs): their splay is limited.
ARTICULATED_IS_KNUCKLE = np.array([j == 0 for f in range(5) for j in range(3)])
#: articulated index -> rotating index of its parent (0 = wrist).
ARTICULATED_PARENT_ROTATING = np.array([0 if j == 0 else 1 + 3 * f + j - 1 for f in range(5) for j in range(3)])


def joint_index(name: str) -> int:
    """Index (21-space) of a joint given its canonical name, e.g. ``"index_pip"``."""
    try:
        return JOINT_NAMES.index(name)
    except ValueError:
        raise KeyError(f"unknown joint {name!r}; expected one of {', '.join(JOINT_NAMES)}") from None


def joint_label(name: str) -> str:
    """'index_pip' -> 'index PIP', 'thumb_ip' -> 'thumb IP': how every message names a joint ('wrist' stays)."""
    finger, _, level = name.partition("_")
    return f"{finger} {level.upper()}" if level else name
