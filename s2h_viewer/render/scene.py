"""Scene pieces shared by the CLI and the app: posed meshes, skeletons, frame arrows, all as pyvista data.

Geometry is turned into the hand's canonical palm frame (fingers up the screen's y after the
camera below), so every hand, whatever its rig's wrist orientation, is shown the same way.
"""

from __future__ import annotations

import dataclasses
import weakref

import numpy as np
import pyvista as pv
import torch
from scipy.spatial import cKDTree

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import HandPose, forward_kinematics
from s2h_viewer.hand.model import HandModel, SkinnedMesh
from s2h_viewer.hand.skinning import skin_vertices

SKIN_COLOUR = "#e0ac8c"
BONE_COLOUR = "#30343f"
#: twist, bend, splay arrow colours (x, y, z as in most 3D tools).
AXIS_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")
#: camera directions in view space (x = fingers, y = thumb side, z = back of the hand) and up vectors: from the
#: palm and the thumb's side, the palm, the back, the thumb's side (where a pinch's touch shows)
CAMERA_DIRECTIONS = {
    "three_quarter": ((0.15, 0.45, -0.85), (1.0, 0.0, 0.0)),
    "palm": ((0.0, 0.0, -1.0), (1.0, 0.0, 0.0)),
    "back": ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0)),
    "side": ((0.0, 1.0, 0.0), (1.0, 0.0, 0.0)),
}


def pose_frame(hand: HandModel, q_tbs: np.ndarray) -> HandPose:
    """FK of a single pose (15, 4) as a one-frame `HandPose`."""
    return forward_kinematics(hand, torch.as_tensor(np.asarray(q_tbs, dtype=np.float64)[None]))


def to_view(hand: HandModel, points: np.ndarray) -> np.ndarray:
    """Hand-space points -> view space (canonical palm frame)."""
    return points @ hand.palm_frame


def surface(hand: HandModel, vertices: np.ndarray) -> pv.PolyData:
    """The hand's mesh triangles over the given (V, 3) vertices (rest, posed, in any space)."""
    faces = np.hstack([np.full((len(hand.mesh.faces), 1), 3), hand.mesh.faces]).astype(np.int64)
    return pv.PolyData(np.asarray(vertices, dtype=np.float64), faces)


def posed_mesh(hand: HandModel, pose: HandPose, frame: int = 0) -> pv.PolyData:
    """The skinned mesh at one frame, in view space, with normals for smooth shading."""
    mesh = surface(hand, to_view(hand, skin_vertices(hand, pose, frame)))
    return mesh.compute_normals(auto_orient_normals=False, split_vertices=False)


def skeleton(hand: HandModel, pose: HandPose, frame: int = 0) -> pv.PolyData:
    """Bones as line segments and joints as points, in view space."""
    points = to_view(hand, pose.positions[frame].detach().cpu().numpy().astype(np.float64))
    children = np.arange(1, topo.N_JOINTS)
    lines = np.column_stack([np.full(len(children), 2), topo.PARENTS[children], children]).ravel()
    return pv.PolyData(points, lines=lines)


#: the palm of a hand drawn without a skin: the wrist and the finger knuckles, fanned
_PALM_FAN = np.array([[3, 0, topo.joint_index(a), topo.joint_index(b)]
                      for a, b in (("index_mcp", "middle_mcp"), ("middle_mcp", "ring_mcp"), ("ring_mcp", "pinky_mcp"))])
#: its colour and opacity: the skin's, see-through, so the bones show through it
PALM_OPACITY = 0.45


def palm_fan(hand: HandModel, pose: HandPose, frame: int = 0) -> pv.PolyData:
    """The palm of a hand drawn as bones (no skin: a VRM robot, a BVH), in view space: triangles from the wrist to
    the knuckles, so its front, back and fingers' fan read (its metacarpals alone all start at one point)."""
    points = to_view(hand, pose.positions[frame].detach().cpu().numpy().astype(np.float64))
    return pv.PolyData(points, faces=_PALM_FAN.ravel())


def frame_arrows(hand: HandModel, pose: HandPose, frame: int = 0, scale: float | None = None) -> list[pv.PolyData]:
    """Three glyph sets (twist, bend, splay) of arrows at the 15 articulated joints."""
    scale = scale or 0.11 * hand.hand_length
    origins = to_view(hand, pose.positions[frame, topo.ARTICULATED_JOINTS].detach().cpu().numpy().astype(np.float64))
    frames = pose.frames[frame, topo.ARTICULATED_JOINTS].detach().cpu().numpy().astype(np.float64)
    out = []
    for axis in range(3):
        cloud = pv.PolyData(origins)
        cloud["vectors"] = to_view(hand, frames[:, :, axis])
        out.append(cloud.glyph(orient="vectors", scale=False, factor=scale, geom=pv.Arrow(shaft_radius=0.04,
                                                                                            tip_radius=0.1)))
    return out


#: each mesh's lighter versions, by face count: the grid is built again for every change (a method ticked, a clip
#: opened), and decimating its skins again was half of the second it froze for when 12 retargets came in
_LIGHTER: weakref.WeakKeyDictionary[SkinnedMesh, dict[int, SkinnedMesh]] = weakref.WeakKeyDictionary()


def display_hand(hand: HandModel, max_faces: int = 8000) -> HandModel:
    """``hand`` with a lighter mesh for interactive views (software OpenGL draws triangles slowly).

    vtkDecimatePro removes vertices but never moves the ones it keeps, so each kept vertex takes the
    skin weights of the original vertex at its position.
    """
    if hand.mesh is None or len(hand.mesh.faces) <= max_faces:
        return hand
    lighter = _LIGHTER.setdefault(hand.mesh, {})
    if max_faces not in lighter:
        light = surface(hand, hand.mesh.vertices).decimate_pro(1.0 - max_faces / len(hand.mesh.faces),
                                                                preserve_topology=True, splitting=False).clean()
        _, nearest = cKDTree(hand.mesh.vertices).query(np.asarray(light.points))
        lighter[max_faces] = SkinnedMesh(np.asarray(light.points, dtype=np.float32),
                                         light.regular_faces.astype(np.int32), hand.mesh.weights[nearest])
    return dataclasses.replace(hand, mesh=lighter[max_faces])
