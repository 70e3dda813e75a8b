"""The TBS annotation solver (DESIGN.md section 3, the paper's appendix A): frames from rays cast at the mesh.

For each articulated joint the twist axis follows the bone. Around it, ``N_ANGLES`` candidate splay
directions are tried; for each, one ray goes along the splay axis and one along the bend axis
(``bend = splay x twist``, so ``splay = twist x bend``). The loss
``-n_splay.m_splay - n_bend.m_bend + |p_splay - o| / |p_bend - o|`` prefers rays leaving the
surface squarely, with the splay ray along the finger's thinner (pad-to-back) section.

The loss cannot tell the back of a finger from its pad (a section is nearly symmetric), so the sign
is fixed afterwards by one rule: a finger's splay axis points out of the back of the hand (the palm
normal), the thumb's toward the back of the hand and the thumb side together. All 15 x N_ANGLES x 2
rays go into one ray query (embree through trimesh when installed).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh

from s2h_viewer.errors import InvalidHandError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel, palm_axes

N_ANGLES = 360
#: rays start at these fractions along the bone, not at the joint: there the section is a round
#: blend of two bones, along the bone it has the phalanx's own (elliptical) shape
STATIONS_ALONG_BONE = (0.35, 0.5, 0.65)
SMOOTHING_DEGREES = 25.0
#: a loss contrast (loss 90 deg away minus the best) this large or more counts as full confidence;
#: 0.3 is what a section 0.84 as deep as it is wide gives
FULL_CONTRAST = 0.3
LOW_CONFIDENCE = 0.3


@dataclass
class TbsSolution:
    """Solver output: frames (15, 3, 3) in hand space, and how sure it is of each."""

    frames: np.ndarray
    confidence: np.ndarray  # (15,) in [0, 1]
    hit_fraction: np.ndarray  # (15,) share of candidate directions whose two rays both hit the mesh
    thickness: np.ndarray  # (15,) pad-to-back half thickness of the bone's section (splay rays), metres
    width: np.ndarray  # (15,) side-to-side half width (bend rays), metres
    fallback: np.ndarray  # (15,) bool: no candidate hit, the frame comes from the palm plane
    diagnostics: list[str] = field(default_factory=list)

    @property
    def needs_review(self) -> np.ndarray:
        """(15,) bool: joints a person should look at (fallback or low confidence)."""
        return self.fallback | (self.confidence < LOW_CONFIDENCE)


def _plane_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (J, 3) spanning the plane normal to each unit ``axis`` (J, 3)."""
    helper = np.where(np.abs(axis[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u, np.cross(axis, u)


def _circular_smooth(loss: np.ndarray, half_width: float) -> np.ndarray:
    """Mean of each (J, A) row over a window of +-half_width samples, wrapping around; a window with a
    miss stays infinite. Averages out the facet noise of the hit normals (a few hundredths) that
    otherwise moves a shallow optimum by 10 degrees or more."""
    k = max(int(round(half_width)), 0)
    if k == 0:
        return loss
    padded = np.concatenate([loss[:, -k:], loss, loss[:, :k]], axis=1)
    kernel = np.ones(2 * k + 1) / (2 * k + 1)
    return np.stack([np.convolve(row, kernel, mode="valid") for row in padded])


def back_directions(positions: np.ndarray) -> np.ndarray:
    """(15, 3) the direction each joint's splay axis should lean toward (see the module docstring),
    from a right hand's (21, 3) rest joint positions."""
    palm = palm_axes(positions)
    thumb_back = palm[:, 1] + palm[:, 2]
    back = np.tile(palm[:, 2], (topo.N_ARTICULATED, 1))
    back[:3] = thumb_back / np.linalg.norm(thumb_back)
    return back


def palm_plane_frames(positions: np.ndarray) -> np.ndarray:
    """(15, 3, 3) frames without a mesh: twist along each bone, splay leaning out of the back of the hand.
    The fallback for a joint the rays cannot see, and for rigs that come without a mesh (BVH)."""
    twist = positions[topo.ARTICULATED_JOINTS + 1] - positions[topo.ARTICULATED_JOINTS]
    twist /= np.linalg.norm(twist, axis=1, keepdims=True)
    back = back_directions(positions)
    z = back - twist * np.einsum("ij,ij->i", back, twist)[:, None]
    z /= np.linalg.norm(z, axis=1, keepdims=True)
    return np.stack([twist, np.cross(z, twist), z], axis=2)


def _ray_intersector(mesh: trimesh.Trimesh):
    try:
        from trimesh.ray.ray_pyembree import RayMeshIntersector
        return RayMeshIntersector(mesh)
    except (ImportError, ValueError):  # embreex not installed: trimesh's pure-Python intersector
        return trimesh.ray.ray_triangle.RayMeshIntersector(mesh)


def solve_tbs_frames(hand: HandModel, n_angles: int = N_ANGLES) -> TbsSolution:
    """TBS rest frames for ``hand`` found from its mesh (``hand.rest_frames`` is not read)."""
    if hand.mesh is None:
        raise InvalidHandError(f"hand {hand.name!r}: has no mesh; the TBS solver casts rays at the mesh")
    mesh = trimesh.Trimesh(hand.mesh.vertices, hand.mesh.faces, process=False)
    positions = hand.rest_positions
    joints, children = positions[topo.ARTICULATED_JOINTS], positions[topo.ARTICULATED_JOINTS + 1]
    twist = children - joints
    twist /= np.linalg.norm(twist, axis=1, keepdims=True)
    u, v = _plane_basis(twist)
    theta = np.linspace(0.0, 2 * np.pi, n_angles, endpoint=False)
    splay = np.cos(theta)[None, :, None] * u[:, None] + np.sin(theta)[None, :, None] * v[:, None]  # (J, A, 3)
    bend = np.cross(splay, twist[:, None])
    n_joints = len(joints)

    # rays both ways along each axis (widths through the bone, free of where the bone sits in its
    # section), from a few stations along the bone, all in one query
    stations = joints[None] + np.asarray(STATIONS_ALONG_BONE)[:, None, None] * (children - joints)[None]
    directions = np.concatenate([splay, bend, -splay, -bend], axis=1)  # (J, 4A, 3)
    ray_directions = np.broadcast_to(directions, (len(stations), *directions.shape)).reshape(-1, 3)
    ray_origins = np.repeat(stations.reshape(-1, 3), 4 * n_angles, axis=0)
    locations, ray_index, tri_index = _ray_intersector(mesh).intersects_location(
        ray_origins, ray_directions, multiple_hits=False)
    dist = np.full(len(ray_directions), np.inf)
    normal_dot = np.zeros(len(ray_directions))
    dist[ray_index] = np.linalg.norm(locations - ray_origins[ray_index], axis=1)
    normal_dot[ray_index] = np.einsum("ij,ij->i", mesh.face_normals[tri_index], ray_directions[ray_index])
    dist = dist.reshape(len(stations), n_joints, 4, n_angles)
    normal_dot = normal_dot.reshape(len(stations), n_joints, 4, n_angles)

    hit = np.isfinite(dist).all(axis=(0, 2))  # (J, A)
    with np.errstate(invalid="ignore"):
        loss = (-normal_dot.mean(axis=2) * 2.0 + (dist[:, :, 0] + dist[:, :, 2]) / (dist[:, :, 1] + dist[:, :, 3]))
    loss = loss.mean(axis=0)
    loss[~hit] = np.inf
    loss = _circular_smooth(loss, SMOOTHING_DEGREES * n_angles / 360.0)
    half_thickness = 0.5 * (dist[:, :, 0] + dist[:, :, 2]).mean(axis=0)  # (J, A)
    half_width = 0.5 * (dist[:, :, 1] + dist[:, :, 3]).mean(axis=0)

    frames = np.empty((n_joints, 3, 3))
    confidence = np.zeros(n_joints)
    thickness = np.full(n_joints, np.nan)
    width = np.full(n_joints, np.nan)
    fallback = ~np.isfinite(loss).any(axis=1)  # no direction whose whole smoothing window hit
    diagnostics = []
    back = back_directions(positions)
    guess = palm_plane_frames(positions)
    for j in range(n_joints):
        name = topo.ARTICULATED_NAMES[j]
        if fallback[j]:
            z = guess[j][:, 2]
            diagnostics.append(f"{name}: no ray hit the mesh (is the joint outside it?); frame taken from the "
                               f"palm plane, review it")
        else:
            best = int(np.argmin(loss[j]))
            z = splay[j, best]
            thickness[j], width[j] = half_thickness[j, best], half_width[j, best]
            quarter = loss[j, [(best + n_angles // 4) % n_angles, (best - n_angles // 4) % n_angles]]
            contrast = np.min(quarter) - loss[j, best]
            confidence[j] = float(np.clip(contrast / FULL_CONTRAST, 0.0, 1.0)) * hit[j].mean()
            if confidence[j] < LOW_CONFIDENCE:
                diagnostics.append(f"{name}: low confidence {confidence[j]:.2f} (round section or rays "
                                   f"missing: {hit[j].mean():.0%} hit); review the frame")
            if z @ back[j] < 0:
                z = -z
        frames[j] = np.stack([twist[j], np.cross(z, twist[j]), z], axis=1)
    # the thumb's CMC sits inside the thenar pad, where no section belongs to its bone: its bend axis
    # is taken from the thumb MCP (the thumb's joints flex about nearly parallel axes)
    cmc, mcp = topo.ARTICULATED_NAMES.index("thumb_cmc"), topo.ARTICULATED_NAMES.index("thumb_mcp")
    if not fallback[mcp]:
        y = frames[mcp][:, 1] - twist[cmc] * (frames[mcp][:, 1] @ twist[cmc])
        y /= np.linalg.norm(y)
        frames[cmc] = np.stack([twist[cmc], y, np.cross(twist[cmc], y)], axis=1)
        confidence[cmc] = confidence[mcp]
    return TbsSolution(frames, confidence, hit.mean(axis=1), thickness, width, fallback, diagnostics)


def frame_angle_errors(frames: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """(15,) degrees of the rotation between each solved frame and its reference frame."""
    relative = reference.transpose(0, 2, 1) @ frames
    cos = np.clip((np.trace(relative, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    return np.degrees(np.arccos(cos))


#: per joint (21) radius over hand length, the mean of the procedural hands: for rigs without a mesh
DEFAULT_RADIUS_FRACTIONS = np.array([0.0817, 0.0735, 0.0626, 0.0572, 0.049, 0.0506, 0.0456, 0.0405, 0.0355, 0.0528,
                                     0.0475, 0.0423, 0.037, 0.0496, 0.0446, 0.0396, 0.0347, 0.0436, 0.0392, 0.0349,
                                     0.0305])


def estimate_radii(hand: HandModel, solution: TbsSolution | None) -> np.ndarray:
    """(21,) finger radii for contact tests: the mean of the solver's measured half thickness and half
    width where it has them
    (a tip takes 85% of its DIP's), the procedural hands' proportions elsewhere."""
    radii = DEFAULT_RADIUS_FRACTIONS * hand.hand_length
    if solution is not None:
        measured = np.isfinite(solution.thickness) & ~solution.fallback
        measured[0] = False  # the thumb CMC's rays measure the thenar pad, not a finger
        radii[topo.ARTICULATED_JOINTS[measured]] = 0.5 * (solution.thickness + solution.width)[measured]
        for tip in topo.TIP_JOINTS:
            if measured[topo.ARTICULATED_OF_JOINT[tip - 1]]:
                radii[tip] = 0.85 * radii[tip - 1]
    return radii
