"""Linear-blend skinning of a `SkinnedMesh` from an FK pose, vectorised (the viewer calls it per frame)."""

from __future__ import annotations

import numpy as np

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import HandPose
from s2h_viewer.hand.model import HandModel


def skinning_transforms(hand: HandModel, pose: HandPose, frame: int = 0) -> np.ndarray:
    """(16, 3, 4) affine maps rest -> posed for the wrist and the 15 articulated joints of one frame.

    Joint ``j`` moves its rest geometry by ``A_j = M_j(t) M_rest_j^T`` about its own joint position.
    """
    frames = pose.frames[frame, topo.ARTICULATED_JOINTS].detach().cpu().numpy().astype(np.float64)
    positions = pose.positions[frame, topo.ARTICULATED_JOINTS].detach().cpu().numpy().astype(np.float64)
    rot = frames @ hand.rest_frames.transpose(0, 2, 1)
    rest = hand.rest_positions[topo.ARTICULATED_JOINTS]
    trans = positions - np.einsum("jab,jb->ja", rot, rest)
    out = np.zeros((topo.N_ROTATING, 3, 4))
    out[0, :, :3] = np.eye(3)
    out[1:, :, :3] = rot
    out[1:, :, 3] = trans
    return out


def skin_vertices(hand: HandModel, pose: HandPose, frame: int = 0) -> np.ndarray:
    """(V, 3) posed vertices: one (V, 16) x (16, 12) product blends the joints' affine maps per vertex."""
    if hand.mesh is None:
        raise ValueError(f"hand {hand.name!r} has no mesh to skin")
    mesh = hand.mesh
    blended = (mesh.weights @ skinning_transforms(hand, pose, frame).reshape(topo.N_ROTATING, 12)).reshape(-1, 3, 4)
    v = mesh.vertices.astype(np.float64)
    return np.einsum("vab,vb->va", blended[:, :, :3], v) + blended[:, :, 3]
