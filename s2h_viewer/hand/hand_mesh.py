"""A watertight, skinned hand mesh grown around a skeleton: signed distances, marching cubes, weights.

Shape: each phalanx is a tapered round cone with an elliptical section (thinner pad-to-back than
side-to-side, centred slightly palmar so pads bulge), blended smoothly within its finger; the palm
is four metacarpal cones, a wrist stub and a thenar web blended together; each finger is blended
with the palm on its own and the five results are united with a hard minimum, so neighbouring
fingers never fuse. Skinning: each vertex belongs to the closest part, and blends with the
neighbouring bone across the plane of the joint between them.
"""

from __future__ import annotations

import numpy as np
import trimesh
from skimage.measure import marching_cubes

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel, SkinnedMesh
from s2h_viewer.hand.procedural import REFERENCE_HAND_LENGTH

FLATTEN = 0.84  # section depth / width of a phalanx
PAD_SHIFT = 0.10  # section centre below the bone axis, as a fraction of the radius
PALM_FLATTEN = 0.72


def size_scale(hand: HandModel) -> float:
    """Hand length over `REFERENCE_HAND_LENGTH`: the factor every absolute size is multiplied by."""
    return hand.hand_length / REFERENCE_HAND_LENGTH


def _smin(a: np.ndarray, b: np.ndarray, k: float) -> np.ndarray:
    """Polynomial smooth minimum (blend radius k)."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def _round_cone(points: np.ndarray, start: np.ndarray, frame: np.ndarray, length: float, r1: float, r2: float,
                flatten: float = 1.0, shift: float = 0.0) -> np.ndarray:
    """Approximate signed distance to a round cone along ``frame[:, 0]`` with a flattened section."""
    local = (points - start) @ frame
    axial = local[:, 0]
    radial = np.hypot(local[:, 1], (local[:, 2] + shift) / flatten)
    b = (r1 - r2) / length
    a = np.sqrt(max(1.0 - b * b, 1e-9))
    k = -b * radial + a * axial
    side = a * radial + b * axial - r1
    return np.where(k < 0, np.hypot(radial, axial) - r1,
                    np.where(k > a * length, np.hypot(radial, axial - length) - r2, side))


def _frame_along(direction: np.ndarray, up: np.ndarray = np.array([0.0, 0.0, 1.0])) -> np.ndarray:
    x = direction / np.linalg.norm(direction)
    z = up - x * (up @ x)
    z /= np.linalg.norm(z)
    return np.stack([x, np.cross(z, x), z], 1)


def _stub_start(hand: HandModel) -> np.ndarray:
    """Where the short forearm stub behind the wrist begins (its far end is a round cap)."""
    return hand.palm_frame @ np.array([-0.045 * size_scale(hand), 0.0, 0.0])


def _parts(hand: HandModel, points: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
    """Signed distance of the palm (N,) and of each of the 15 phalanx bones (15 arrays of N)."""
    pos, r, frames = hand.rest_positions, hand.radii, hand.rest_frames
    palm_frame = hand.palm_frame
    up = palm_frame[:, 2]
    scale = size_scale(hand)

    bones = []
    for a, joint in enumerate(topo.ARTICULATED_JOINTS):
        child = joint + 1
        start, end = pos[joint], pos[child]
        r1, r2 = r[joint], r[child]
        if child in topo.TIP_JOINTS:  # the fingertip's rounded cap ends at the tip joint
            end = end - 0.9 * r2 * frames[a][:, 0]
        bones.append(_round_cone(points, start, frames[a], np.linalg.norm(end - start), r1, r2,
                                 FLATTEN, PAD_SHIFT * r1))

    palm_parts = []
    wrist_half_width = 0.026 * scale
    for i, knuckle in enumerate(topo.KNUCKLE_JOINTS[1:]):
        base = palm_frame @ np.array([0.10 * pos[knuckle] @ palm_frame[:, 0],
                                      wrist_half_width * (0.75 - 0.5 * i), 0.0])
        direction = pos[knuckle] - base
        palm_parts.append(_round_cone(points, base, _frame_along(direction, up), np.linalg.norm(direction),
                                      r[0] * 1.25, r[knuckle] * 1.05, PALM_FLATTEN))
    palm_parts.append(_round_cone(points, _stub_start(hand), palm_frame, 0.07 * scale, 0.024 * scale, 0.027 * scale,
                                  0.62))
    thumb_mcp = pos[topo.joint_index("thumb_mcp")]
    web_start = palm_frame @ np.array([0.35 * pos[topo.joint_index("middle_mcp")] @ palm_frame[:, 0], 0.0,
                                       -0.3 * r[0]])
    web_dir = thumb_mcp - web_start
    palm_parts.append(_round_cone(points, web_start, _frame_along(web_dir, up), np.linalg.norm(web_dir),
                                  r[0] * 1.1, r[topo.joint_index("thumb_mcp")] * 0.95, 0.8))
    palm = palm_parts[0]
    for part in palm_parts[1:]:
        palm = _smin(palm, part, 0.012 * scale)
    return palm, bones


def _surface(hand: HandModel, palm: np.ndarray, bones: list[np.ndarray]) -> np.ndarray:
    """Each finger blended with the palm on its own, then united with a hard minimum."""
    scale = size_scale(hand)
    out = None
    for f in range(topo.N_FINGERS):
        finger = _smin(_smin(bones[3 * f], bones[3 * f + 1], 0.004 * scale), bones[3 * f + 2], 0.004 * scale)
        with_palm = _smin(palm, finger, (0.010 if f == 0 else 0.006) * scale)
        out = with_palm if out is None else np.minimum(out, with_palm)
    return out


def _smoothstep(x: np.ndarray) -> np.ndarray:
    t = np.clip(0.5 + 0.5 * x, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def skin_weights(hand: HandModel, vertices: np.ndarray) -> np.ndarray:
    """(V, 16) weights, continuous over the surface so no posed mesh tears.

    A vertex belongs softly to each part (palm or phalanx) by a soft-argmin of the parts' signed
    distances; as a member of a phalanx it blends with the parent bone across the plane of its own
    joint and with the child bone across the next joint's plane; as a member of the palm it blends
    with each knuckle bone past that knuckle's plane, fading with distance from the bone.
    """
    palm, bones = _parts(hand, vertices)
    dist = np.stack([palm] + bones, 1)  # (V, 16), column = rotating index
    member = np.exp(-(dist - dist.min(1, keepdims=True)) / (0.0015 * size_scale(hand)))
    member /= member.sum(1, keepdims=True)

    pos, radii, frames = hand.rest_positions, hand.radii, hand.rest_frames
    ahead = np.stack([_smoothstep(np.einsum("vi,i->v", vertices - pos[j], frames[a][:, 0]) / (0.8 * radii[j]))
                      for a, j in enumerate(topo.ARTICULATED_JOINTS)], 1)  # (V, 15): past joint a's plane

    weights = np.zeros((len(vertices), topo.N_ROTATING))
    for a in range(topo.N_ARTICULATED):
        rot = a + 1
        as_member = np.zeros_like(weights)
        child = ahead[:, a + 1] if a % 3 < 2 else np.zeros(len(vertices))
        as_member[:, topo.ARTICULATED_PARENT_ROTATING[a]] = 1.0 - ahead[:, a]
        as_member[:, rot] = np.clip(ahead[:, a] - child, 0.0, None)
        if a % 3 < 2:
            as_member[:, rot + 1] = child
        weights += member[:, rot:rot + 1] * as_member
    knuckles = 3 * np.arange(topo.N_FINGERS)
    near = np.exp(-np.square(np.clip(dist[:, knuckles + 1] - dist[:, :1], 0.0, None)
                             / (0.5 * radii[topo.KNUCKLE_JOINTS])))
    to_knuckle = ahead[:, knuckles] * near
    palm_member = np.zeros_like(weights)
    palm_member[:, knuckles + 1] = to_knuckle
    palm_member[:, 0] = np.clip(1.0 - to_knuckle.sum(1), 0.0, None)
    palm_member /= palm_member.sum(1, keepdims=True)
    weights += member[:, :1] * palm_member
    return (weights / weights.sum(1, keepdims=True)).astype(np.float32)


def _marching_cubes(hand: HandModel, spacing: float) -> trimesh.Trimesh:
    """The zero set of the hand's signed distance sampled every ``spacing`` metres, outward-facing."""
    points = np.vstack([hand.rest_positions, _stub_start(hand)])
    margin = 0.03 * size_scale(hand) + 3 * spacing  # thicker than any part's radius
    lo = points.min(0) - margin
    hi = points.max(0) + margin
    axes = [np.arange(lo[i], hi[i] + spacing, spacing) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    palm, bones = _parts(hand, grid)
    sdf = _surface(hand, palm, bones).reshape(len(axes[0]), len(axes[1]), len(axes[2]))
    verts, faces, _, _ = marching_cubes(sdf, level=0.0, spacing=(spacing,) * 3)
    mesh = trimesh.Trimesh(verts + lo, faces, process=False)  # merging close vertices would pinch edges
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def build_hand_mesh(hand: HandModel, detail: float = 82.0, max_faces: int = 30_000) -> SkinnedMesh:
    """Marching cubes on the hand's signed distance, Taubin-smoothed (keeps volume), checked
    watertight and at most ``max_faces``, then skinned.

    The grid step is 1/``detail`` of the hand length (82: about 25k faces on a realistic hand; about
    30: a low-poly game hand of 2-4k); a broader or thicker hand that comes out denser than
    ``max_faces`` is sampled again, coarser, aiming at 25k faces.
    """
    spacing = hand.hand_length / detail
    mesh = _marching_cubes(hand, spacing)
    if len(mesh.faces) > max_faces:
        mesh = _marching_cubes(hand, spacing * float(np.sqrt(len(mesh.faces) / 25_000)))
    if not mesh.is_watertight or len(mesh.faces) > max_faces:
        raise RuntimeError(f"hand {hand.name!r}: generated mesh is not watertight or has {len(mesh.faces)} "
                           f"faces (want at most {max_faces})")
    trimesh.smoothing.filter_taubin(mesh, iterations=30)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    return SkinnedMesh(vertices=vertices.astype(np.float32), faces=np.asarray(mesh.faces, dtype=np.int32),
                       weights=skin_weights(hand, vertices))
