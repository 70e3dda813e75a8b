"""Plain per-frame numpy FK and ASM: the readable definition of DESIGN.md section 4.

Slow on purpose (Python loops over frames and joints): tests check the batched torch code
against it, and the benchmark uses it as its baseline.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.semantics.asm import ANCHORS


def fk_frame(hand: HandModel, q_tbs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One frame (15, 4) -> positions (21, 3) and global TBS frames (21, 3, 3), joint by joint."""
    rot = Rotation.from_quat(q_tbs, scalar_first=True).as_matrix()
    rest = {int(j): hand.rest_frames[a] for a, j in enumerate(topo.ARTICULATED_JOINTS)}
    canonical = {int(j): hand.canonical_frames[a] for a, j in enumerate(topo.ARTICULATED_JOINTS)}
    rest[0] = canonical[0] = np.eye(3)
    positions = np.zeros((topo.N_JOINTS, 3))
    frames = np.zeros((topo.N_JOINTS, 3, 3))
    frames[0] = np.eye(3)
    for j in range(1, topo.N_JOINTS):
        p = topo.PARENTS[j]
        positions[j] = positions[p] + frames[p] @ rest[p].T @ hand.offsets[j]
        if j in rest:
            frames[j] = frames[p] @ canonical[p].T @ canonical[j] @ rot[topo.ARTICULATED_OF_JOINT[j]]
        else:
            frames[j] = frames[p]
    return positions, frames


def asm_frame(positions: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """One frame's ASM (20, 29, 3) from FK output, in units of the wrist -> middle-knuckle distance."""
    anchors = [positions[0] + f * (positions[k] - positions[0]) for k, f in ANCHORS]
    columns = np.concatenate([positions[1:], np.array(anchors)])
    unit = np.linalg.norm(positions[topo.joint_index("middle_mcp")] - positions[0])
    out = np.zeros((topo.N_FINGER_JOINTS, topo.N_ASM_COLUMNS, 3))
    for k in range(topo.N_FINGER_JOINTS):
        out[k] = (columns - positions[k + 1]) @ frames[k + 1] / unit
    return out


def asm_sequence(hand: HandModel, q_tbs: np.ndarray) -> np.ndarray:
    """(T, 15, 4) -> (T, 20, 29, 3), one frame at a time."""
    return np.stack([asm_frame(*fk_frame(hand, q)) for q in q_tbs])
