"""What the networks see: per-frame source features and the target hand's static description.

Source, per frame: the ASM in palm lengths (ASRN, 1740 values) or the distance matrix (DM, 580),
plus the source's TBS rotations (60), since the network predicts a residual rotation on top of TBS
Copy. Target, static: the shape parameter H as (20, 3) and the canonical-pose TBS frames in the palm
frame as (15, 6) (first two columns): independent of the rig's axes and of the pose it was bound in.
"""

from __future__ import annotations

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import HandPose, forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.semantics.asm import distance_matrix, semantic_matrix

KINDS = ("asrn", "dm")
SEMANTIC_SIZE = {"asrn": topo.N_FINGER_JOINTS * topo.N_ASM_COLUMNS * 3, "dm": topo.N_FINGER_JOINTS * topo.N_ASM_COLUMNS}


def feature_size(kind: str) -> int:
    return SEMANTIC_SIZE[kind] + topo.N_ARTICULATED * 4


def semantic_features(kind: str, pose: HandPose) -> torch.Tensor:
    """(T, 1740) ASM or (T, 580) distance matrix, both in palm lengths."""
    if kind == "asrn":
        return semantic_matrix(pose).reshape(len(pose.positions), -1)
    if kind == "dm":
        return distance_matrix(pose).reshape(len(pose.positions), -1)
    raise ValueError(f"unknown network kind {kind!r}; choose from {', '.join(KINDS)}")


def source_features(kind: str, hand: HandModel, q_tbs: np.ndarray | torch.Tensor) -> torch.Tensor:
    """(T, feature_size) float32 for a source motion on its hand."""
    q = torch.as_tensor(np.asarray(q_tbs), dtype=torch.float32)
    with torch.no_grad():
        pose = forward_kinematics(hand, q)
        return torch.cat([semantic_features(kind, pose), q.reshape(len(q), -1)], -1)


def target_static(hand: HandModel) -> tuple[torch.Tensor, torch.Tensor]:
    """(20, 3) shape parameter H and (15, 6) canonical TBS frames in the palm frame, float32."""
    frames = hand.palm_frame.T @ hand.canonical_frames
    six_d = frames[:, :, :2].transpose(0, 2, 1).reshape(topo.N_ARTICULATED, 6)
    return (torch.as_tensor(hand.shape_vector.reshape(topo.N_FINGER_JOINTS, 3), dtype=torch.float32),
            torch.as_tensor(six_d, dtype=torch.float32))
