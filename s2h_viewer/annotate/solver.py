"""The TBS annotation solver (DESIGN.md section 3, the paper's appendix A): frames from rays cast at the mesh.

For each articulated joint the twist axis follows the bone. Around it, ``N_ANGLES`` candidate splay
directions are tried; for each, one ray goes along the splay axis and one along the bend axis
(``bend = splay x twist``, so ``splay = twist x bend``). The loss
``-n_splay.m_splay - n_bend.m_bend + |p_splay - o| / |p_bend - o|`` prefers rays leaving the
surface squarely, with the splay ray along the finger's thinner (pad-to-back) section.

The loss cannot tell the back of a finger from its pad (a section is nearly symmetric), so the sign
is fixed afterwards by one rule: a finger's splay axis points out of the back of the hand (the palm
normal), the thumb's toward the back of the hand and the thumb side together. All 15 x N_ANGLES x 2
rays go into one ray query (embree through trimesh when installed). The thumb CMC, inside the thenar pad
with no section of its own, takes its frame from the palm (`thumb_cmc_frame`), on every hand alike.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh

from s2h_viewer.errors import InvalidHandError
from s2h_viewer.geometry import distance_to_segments
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
#: how far one joint's splay axis may turn from its finger's common fit, and what turning that far costs
MAX_CORRECTION_DEGREES = 8.0
CORRECTION_PENALTY = 0.02
#: priors on a finger's common bend axis (loss units): across the palm, and normal to its curl plane
PALM_PRIOR = 0.3
CURL_PRIOR = 0.3
FULL_CURL_DEGREES = 20.0
#: a fit within this of the rays' own choice, or of the curl plane's normal, counts as agreeing with it
AGREE_DEGREES = 20.0
#: a finger whose fit follows the palm plane is that sure of it without other evidence
PALM_EVIDENCE = 0.6
#: rays decide a finger's bend axes only this sure (all its joints), and, but for the thumb, within
#: `AGREE_DEGREES` of the palm plane or of the rig's own bone axis: on nearly round sections the rays'
#: minimum wanders 60-90 deg from the true hinge while still scoring well (issue 26)
TRUST_RAYS = 0.8
#: a rig's own bone axis nearest the palm-plane bend axis (the rays' for the thumb) counts as the hinge
#: the rig was authored with when it is this close for every joint of the finger: an authored hinge lies within
#: 7 deg of the palm plane's (a Mixamo hand); at 25 deg the RPM avatar's index bones rolled 30 deg otherwise
#: (another exporter's roll, `tests/wild_rigs.rerolled_glb`) were still taken, and its frames followed the roll
RIG_AXIS_DEGREES = 12.0
#: sure rays give way to the rig's bone axes where, at some joint of the finger, they lie this much further from
#: both the bones' axis and the palm plane's than those two lie from each other, and the bones agree with the palm
#: plane (`RIG_AXIS_DEGREES`) at every joint: two readings against one (the Godot pinky DIPs: 10.4 and 11.4 deg)
ODD_ONE_OUT_DEGREES = 8.0
#: sure rays also stay where the finger is curled at rest this much (`_curl_bend_axes`' strength, 1 at
#: `FULL_CURL_DEGREES`) and its curl plane's normal lies within `RIG_AXIS_DEGREES` of them at every joint: two
#: readings of the mesh, neither a rig's roll (the Ready Player Me pinky, curled 20+ deg at rest: rays 6-9 deg
#: from its curl plane's normal, 27-30 from the palm plane's; re-rolled by another exporter, its bones no longer
#: vouched for the rays and a fist about the palm plane's axes bent it 33 deg sideways)
CURL_EVIDENCE = 0.8
#: a finger's PIP or DIP section measured wider, side to side, than this fraction of the way to the nearest
#: neighbouring finger's bone is not the finger's own: the mesh does not part the fingers (a low-poly mitten,
#: cryptovoxels.vrm: 0.81-1.35), so its rays and widths say nothing of the finger. Separate fingers read
#: 0.17-0.34 (human-female, Godot, WebXR); knuckles, joined by the webbing, are left out (up to 1.37 there)
PARTED_FRACTION = 0.6
#: the thumb CMC's bend axis in the palm axes (`palm_axes`: x to the middle knuckle, y toward the thumb, z out of
#: the back), made perpendicular to the metacarpal: a convention, as the CMC's rays read the thenar pad. Taken
#: from the thumb's rays or a rig's bone axis, its roll about the metacarpal lay 15-45 deg apart between real
#: rigs (WebXR, Meta), so one TBS rotation turned the metacarpal another way on each hand: TBS Copy of the
#: authored poses onto the Meta hand followed their thumb across the palm at 0.24. The direction is the
#: procedural hands' (least squares over the 12; each hand's own within 0.5-8 deg of it).
THUMB_CMC_BEND = (-0.133, 0.159, -0.978)
#: `TbsSolution.basis` of the thumb CMC, framed by `thumb_cmc_frame`
THUMB_CONVENTION = "thumb CMC convention"


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
    #: (15,) what decided each bend axis: "rays", "rig bone axis" (the rays could not tell), "palm plane",
    #: `THUMB_CONVENTION` (the thumb CMC)
    basis: list[str] = field(default_factory=lambda: ["rays"] * topo.N_ARTICULATED)
    #: fingers the mesh does not part from their neighbours (a mitten): its skin cannot show what they do
    unparted: tuple[str, ...] = ()

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
    frames = np.stack([twist, np.cross(z, twist), z], axis=2)
    frames[0] = thumb_cmc_frame(positions)
    return frames


def thumb_cmc_frame(positions: np.ndarray) -> np.ndarray:
    """(3, 3) the thumb CMC's TBS frame from a right hand's (21, 3) rest joint positions (wrist at the origin):
    twist along the metacarpal, bend `THUMB_CMC_BEND` in the palm axes made perpendicular to it."""
    cmc = topo.joint_index("thumb_cmc")
    twist = positions[cmc + 1] - positions[cmc]
    twist = twist / np.linalg.norm(twist)
    bend = palm_axes(positions) @ np.asarray(THUMB_CMC_BEND)
    bend -= twist * (bend @ twist)
    bend /= np.linalg.norm(bend)
    return np.stack([twist, bend, np.cross(twist, bend)], axis=1)


def _ray_intersector(mesh: trimesh.Trimesh):
    try:
        from trimesh.ray.ray_pyembree import RayMeshIntersector
        return RayMeshIntersector(mesh)
    except (ImportError, ValueError):  # embreex not installed: trimesh's pure-Python intersector
        return trimesh.ray.ray_triangle.RayMeshIntersector(mesh)


def _exit_hits(mesh: trimesh.Trimesh, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance to and normal-along-ray of each ray's first hit where it LEAVES a surface (normal along the
    ray): a ray from inside a finger crossing a nail or another overlapping primitive from outside first
    (an entering hit) goes on to the surface it leaves. Inf / 0 for rays leaving nothing."""
    locations, ray_index, tri_index = _ray_intersector(mesh).intersects_location(origins, directions,
                                                                               multiple_hits=True)
    dist = np.full(len(directions), np.inf)
    normal_dot = np.zeros(len(directions))
    if len(ray_index):
        along = np.einsum("ij,ij->i", mesh.face_normals[tri_index], directions[ray_index])
        d = np.linalg.norm(locations - origins[ray_index], axis=1)
        leaving = along > 0.0
        d, along, rays = d[leaving], along[leaving], ray_index[leaving]
        order = np.lexsort((d, rays))  # per ray, nearest leaving hit first
        rays, d, along = rays[order], d[order], along[order]
        first = np.r_[True, rays[1:] != rays[:-1]]
        dist[rays[first]], normal_dot[rays[first]] = d[first], along[first]
    return dist, normal_dot


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angles (radians) wrapped to [-pi/2, pi/2): the loss repeats every half turn (rays go both ways)."""
    return (angle + np.pi / 2) % np.pi - np.pi / 2


def _curl_bend_axes(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per finger (5, 3) the normal of the plane its bones curl in, and how much they curl (0-1, full at
    ``FULL_CURL_DEGREES``): where a finger is bent at rest, anatomy puts its bend axes along that normal."""
    axes, strength = np.zeros((topo.N_FINGERS, 3)), np.zeros(topo.N_FINGERS)
    for f in range(topo.N_FINGERS):
        chain = positions[1 + 4 * f: 5 + 4 * f]
        bones = np.diff(chain, axis=0)
        bones /= np.linalg.norm(bones, axis=1, keepdims=True)
        normal = np.cross(bones[:-1], bones[1:]).sum(0)
        size = np.linalg.norm(normal)
        if size > 1e-9:
            axes[f] = normal / size
            strength[f] = min(np.degrees(np.arcsin(min(size / 2.0, 1.0))) / FULL_CURL_DEGREES, 1.0)
    return axes, strength


def solve_tbs_frames(hand: HandModel, n_angles: int = N_ANGLES, bone_axes: np.ndarray | None = None
                     ) -> TbsSolution:
    """TBS rest frames for ``hand`` found from its mesh (``hand.rest_frames`` is not read).

    Per joint, a ray loss over the splay angle; per finger, one common bend direction fitted to the sum
    of its joints' losses (anatomy: a finger's joints bend about nearly parallel axes, as the official
    code's one bend axis per finger), each joint then corrected within ``MAX_CORRECTION_DEGREES`` of it.
    Where rays cannot tell (round sections), the finger's own curl plane and the palm plane decide.
    Then, per finger, rays that are unsure or far from both the palm plane and the rig's own bone axes
    give way to the rig's axes or the palm plane (`_overrule_unsure_rays`). ``bone_axes`` (15, 3, 3) are
    the rig's rest bone frames in hand space; by default a hand read from a rig file's
    (``hand.rig_frames``), none for a procedural hand, whose rig axes carry a deliberate roll.
    """
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
    dist, normal_dot = _exit_hits(mesh, ray_origins, ray_directions)
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

    fallback = ~hit.any(axis=1)
    guess = palm_plane_frames(positions)
    curl_axis, curl_strength = _curl_bend_axes(positions)
    step = 2 * np.pi / n_angles
    frames = guess.copy()
    confidence = np.zeros(n_joints)
    thickness = np.full(n_joints, np.nan)
    width = np.full(n_joints, np.nan)
    diagnostics = []
    for f in range(topo.N_FINGERS):
        fit = _fit_finger(f, loss, u, v, twist, guess, curl_axis[f], curl_strength[f], fallback, step)
        for j, z, conf, note in fit:
            name = topo.ARTICULATED_NAMES[j]
            if fallback[j]:
                diagnostics.append(f"{name}: no ray hit the mesh (is the joint outside it?); frame taken from the "
                                   f"{'palm plane' if z is None else 'rest of its finger'}, review it")
                if z is None:
                    continue
            else:
                a = int(round(np.arctan2(z @ v[j], z @ u[j]) / step)) % n_angles
                thickness[j], width[j] = half_thickness[j, a], half_width[j, a]
                confidence[j] = conf * hit[j].mean()
                if confidence[j] < LOW_CONFIDENCE:
                    diagnostics.append(f"{name}: low confidence {confidence[j]:.2f} ({note}); review the frame")
            frames[j] = np.stack([twist[j], np.cross(z, twist[j]), z], axis=1)
    unparted = _unparted_fingers(positions, width)
    for f, how_wide in unparted:
        members = slice(3 * f, 3 * f + 3)
        confidence[members], thickness[members], width[members] = 0.0, np.nan, np.nan
        diagnostics.append(f"{topo.FINGERS[f]}: the mesh does not part it from its neighbours (its section "
                           f"{how_wide:.0%} of the way to the next finger's bone: a mitten?); its rays and width "
                           f"are not its own, review the frames")
    if bone_axes is None and "rig_scheme" in hand.meta:
        bone_axes = hand.rig_frames[1:]
    basis = ["palm plane" if fallback[j] else "rays" for j in range(n_joints)]
    across = palm_axes(positions)[:, 1]  # toward the thumb: a finger's bend axis when it curls toward the palm
    palm_bend = across - twist * (twist @ across)[:, None]
    palm_bend /= np.linalg.norm(palm_bend, axis=1, keepdims=True)
    curled = np.where((curl_strength >= CURL_EVIDENCE)[:, None], curl_axis, np.nan)
    _overrule_unsure_rays(frames, confidence, basis, diagnostics, palm_bend, guess[:, :, 2], bone_axes, curled,
                          fallback)
    frames[0] = guess[0]  # the thumb CMC: `thumb_cmc_frame`, whatever its rays or its rig read
    if not fallback[0]:
        basis[0] = THUMB_CONVENTION
    return TbsSolution(frames, confidence, hit.mean(axis=1), thickness, width, fallback, diagnostics, basis,
                       tuple(topo.FINGERS[f] for f, _ in unparted))


def _unparted_fingers(positions: np.ndarray, width: np.ndarray) -> list[tuple[int, float]]:
    """(finger, width over the gap) of each finger but the thumb whose PIP or DIP half width (15,) reaches
    `PARTED_FRACTION` of the way to a neighbouring finger's bone of the same level."""
    bones = [(positions[j], positions[j + 1]) for j in topo.ARTICULATED_JOINTS]
    unparted = []
    for f in range(1, topo.N_FINGERS):
        ratios = []
        for level in (1, 2):
            j = 3 * f + level
            if not np.isfinite(width[j]):
                continue
            centre = 0.5 * (bones[j][0] + bones[j][1])
            gap = min(float(distance_to_segments(centre, *bones[3 * g + level])) for g in (f - 1, f + 1) if 1 <= g <= 4)
            ratios.append(width[j] / max(gap, 1e-12))
        if ratios and max(ratios) >= PARTED_FRACTION:
            unparted.append((f, max(ratios)))
    return unparted


def _angle_between_lines(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Degrees between the lines of unit vectors ``a`` and ``b`` (..., 3): 0-90, the sign ignored."""
    return np.degrees(np.arccos(np.clip(np.abs((a * b).sum(-1)), 0.0, 1.0)))


def _nearest_bone_axis(bone_frame: np.ndarray, reference: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """The column of ``bone_frame`` (3, 3) nearest the line of ``reference``, made normal to ``twist``."""
    axis = bone_frame[:, int(np.argmax(np.abs(bone_frame.T @ reference)))]
    axis = axis - twist * (axis @ twist)
    return axis / np.linalg.norm(axis)


def _overrule_unsure_rays(frames: np.ndarray, confidence: np.ndarray, basis: list[str], diagnostics: list[str],
                          palm_bend: np.ndarray, back: np.ndarray, bone_axes: np.ndarray | None,
                          curled: np.ndarray, fallback: np.ndarray) -> None:
    """Per finger, in place: the rays' bend axes stay where all its joints are `TRUST_RAYS` sure and (but for
    the thumb, which the palm plane does not predict) within `AGREE_DEGREES` of the palm plane's; else the
    rig's own bone axes where they lie within `RIG_AXIS_DEGREES` of the palm plane's (the thumb: of the
    rays'), the hinge an authored rig bends about; else the palm plane (the thumb keeps its rays). Sure rays
    come first so that a rig with re-rolled bones cannot mislead a hand whose sections the rays can read; and sure
    rays that point away from the palm plane stay where the rig's bone axes agree with them, two readings of the
    hand against a guess (the Ready Player Me pinky, curled and fanned at rest: rays and bones within 5 deg of
    each other, 21-28 deg from the palm plane's axes, about which a fist bent it 31 deg sideways). Where the
    bones agree with the palm plane and the sure rays are the odd one out at a joint (`ODD_ONE_OUT_DEGREES`), the
    bones win, two readings against one (the Godot hand's pinky DIP: rays 12-15 deg from both, bones and palm plane
    2 deg apart; a fist about the rays' axes bent the pinky 27 deg sideways, about the bones' 20). Sure rays a
    finger's curl plane at rest agrees with (``curled`` (5, 3), NaN for a finger not `CURL_EVIDENCE` curled)
    stay as those the bones agree with, whatever the rig's roll.
    A frame the rays did not decide gets confidence `PALM_EVIDENCE` at most and a line saying why."""
    for f in range(topo.N_FINGERS):
        members = [3 * f + level for level in range(3)]
        if fallback[members].all():
            continue
        twist = frames[members][:, :, 0]
        rays = frames[members][:, :, 1]
        reference = rays if f == 0 else palm_bend[members]
        rig, rays_on_bones, outvoted = None, False, False
        rays_off_palm = _angle_between_lines(rays, palm_bend[members])
        if bone_axes is not None:
            # which of the bone's axes is its hinge: the one nearest the rays' (they are 90 deg apart, so even
            # unsure rays pick right), accepted where it agrees with the palm plane (the thumb: the rays)
            rig = np.stack([_nearest_bone_axis(bone_axes[j], rays[k], twist[k]) for k, j in enumerate(members)])
            rays_off_rig, rig_off = _angle_between_lines(rays, rig), _angle_between_lines(rig, reference)
            rays_on_bones = bool((rays_off_rig <= RIG_AXIS_DEGREES).all())
            if not (rig_off <= RIG_AXIS_DEGREES).all():
                rig = None
            elif f != 0:  # bones and palm plane agree: are the rays the odd one out somewhere?
                outvoted = bool((np.minimum(rays_off_palm, rays_off_rig) - rig_off >= ODD_ONE_OUT_DEGREES).any())
        sure = bool((confidence[members] >= TRUST_RAYS).all())
        near = f == 0 or bool((rays_off_palm <= AGREE_DEGREES).all())
        rays_on_curl = bool((_angle_between_lines(rays, curled[f]) <= RIG_AXIS_DEGREES).all())  # False for NaN
        if sure and (near or rays_on_bones or rays_on_curl) and not outvoted:
            continue
        if rig is not None:
            chosen, label = rig, "rig bone axis"
        elif f == 0:
            continue  # the palm plane does not predict the thumb's hinge: its rays stay
        else:
            chosen, label = palm_bend[members], "palm plane"
        why = ("the rays could not tell its bend axis" if not sure else "its rays point away from the palm plane"
               if not near else "its rays disagree with the rig's bone axes and the palm plane, which agree")
        diagnostics.append(f"{topo.FINGERS[f]}: {why} (rays' confidence {confidence[members].min():.2f}); "
                           f"bend axes taken from the {label}, confidence {PALM_EVIDENCE:.1f} at most")
        previous = back[members[0]]
        for k, j in enumerate(members):
            z = np.cross(twist[k], chosen[k])
            z /= np.linalg.norm(z)
            if z @ previous < 0:  # out of the back of the hand at the base, then each joint as its parent
                z = -z
            previous = z
            frames[j] = np.stack([twist[k], np.cross(z, twist[k]), z], axis=1)
            basis[j] = label
            confidence[j] = min(confidence[j], PALM_EVIDENCE)


def _fit_finger(f: int, loss: np.ndarray, u: np.ndarray, v: np.ndarray, twist: np.ndarray, guess: np.ndarray,
                curl_axis: np.ndarray, curl_strength: float, fallback: np.ndarray, step: float
                ) -> list[tuple[int, np.ndarray | None, float, str]]:
    """One finger: (joint, splay axis or None, confidence, why unsure) for its three joints.

    Candidate common bend directions are the MCP's (CMC's) plane sampled at every angle; each joint
    takes that direction projected into its own plane, moved by up to ``MAX_CORRECTION_DEGREES`` where
    its loss is lower (a quadratic penalty on the move). The finger's loss adds the curl and palm priors."""
    members = [3 * f + level for level in range(3)]
    weights = np.array([0.0 if (f == 0 and level == 0) else 1.0 for level in range(3)])  # thumb CMC: thenar pad
    weights[fallback[members]] = 0.0
    if not weights.any():
        return [(j, None, 0.0, "no hits") for j in members]
    n_angles = loss.shape[1]
    ref = members[1] if f == 0 else members[0]
    theta = np.arange(n_angles) * step
    bend_ref = np.cos(theta)[:, None] * np.cross(u[ref], twist[ref]) + np.sin(theta)[:, None] * np.cross(
        v[ref], twist[ref])  # (A, 3) candidate common bend directions
    window = int(round(np.radians(MAX_CORRECTION_DEGREES) / step))
    offsets = np.arange(-window, window + 1)
    penalty = CORRECTION_PENALTY * (offsets / max(window, 1)) ** 2
    total = np.zeros(n_angles)
    chosen = np.zeros((3, n_angles), dtype=int)
    own_best = np.zeros(3, dtype=int)
    for k, j in enumerate(members):
        # the candidate bend projected into joint j's plane -> splay = twist x bend -> its angle index there
        b = bend_ref - np.outer(bend_ref @ twist[j], twist[j])
        z = np.cross(twist[j], b)
        idx = np.round(np.arctan2(z @ v[j], z @ u[j]) / step).astype(int) % n_angles
        options = (idx[:, None] + offsets[None]) % n_angles  # (A, 2w+1)
        row = loss[j] if np.isfinite(loss[j]).any() else np.zeros(n_angles)
        row = np.where(np.isfinite(row), row, np.nanmax(np.where(np.isfinite(row), row, np.nan)) + 1.0)
        scored = row[options] + penalty[None]
        pick = np.argmin(scored, axis=1) if weights[k] else np.full(n_angles, window)  # unweighted: no correction
        chosen[k] = options[np.arange(n_angles), pick]
        total += weights[k] * scored[np.arange(n_angles), pick]
        own_best[k] = int(np.argmin(row))
    total /= weights.sum()
    unit_bend = bend_ref / np.linalg.norm(bend_ref, axis=1, keepdims=True)
    prior = PALM_PRIOR * (1.0 - (unit_bend @ guess[ref][:, 1]) ** 2) if f else np.zeros(n_angles)  # thumb: no
    prior += CURL_PRIOR * curl_strength * (1.0 - (unit_bend @ curl_axis) ** 2)
    best = int(np.argmin(total + prior))
    # evidence for the fit: the rays alone (where they point, how sharply) and the curl plane
    by_rays = int(np.argmin(total))
    ray_contrast = float(np.clip((_quarter_turn_loss(total, by_rays) - total[by_rays]) / FULL_CONTRAST, 0.0, 1.0))
    rays_agree = abs(np.degrees(_wrap((by_rays - best) * step))) <= AGREE_DEGREES
    curl_agree = 1.0 - (unit_bend[best] @ curl_axis) ** 2 <= np.sin(np.radians(AGREE_DEGREES)) ** 2
    palm_agree = f > 0 and 1.0 - (unit_bend[best] @ guess[ref][:, 1]) ** 2 <= np.sin(np.radians(AGREE_DEGREES)) ** 2
    shape_support = max(curl_strength * curl_agree, PALM_EVIDENCE * palm_agree)  # evidence without rays
    finger_confidence = max(ray_contrast * rays_agree, shape_support) * (1.0 - 0.5 * ray_contrast * (not rays_agree))
    finger_why = ("its finger's rays point elsewhere than the palm and curl say" if not rays_agree
                  else "ambiguous rays (round or faceted section) on a straight finger")
    out = []
    back = guess[ref][:, 2]
    sign = 1.0
    for k, j in enumerate(members):
        a = chosen[k, best]
        z = np.cos(a * step) * u[j] + np.sin(a * step) * v[j]
        if k == 0 or (f == 0 and k == 1):
            sign = 1.0 if z @ back >= 0 else -1.0  # the finger's back side, once for all its joints
        z = sign * z
        if f == 0 and k == 0:  # the thumb CMC: no section of its own, it follows the thumb's bend
            out.append((j, z, 0.0, "thenar pad"))
            continue
        own_contrast = float(np.clip((_quarter_turn_loss(loss[j], own_best[k]) - loss[j, own_best[k]])
                                     / FULL_CONTRAST, 0.0, 1.0)) if np.isfinite(loss[j]).any() else 0.0
        off = abs(np.degrees(_wrap((own_best[k] - a) * step)))
        disagree = own_contrast * float(np.clip((off - AGREE_DEGREES) / AGREE_DEGREES, 0.0, 1.0))
        conf = finger_confidence * (1.0 - disagree * (1.0 - shape_support))
        why = f"its own rays point {off:.0f} deg away from its finger's bend axis" if disagree > 0.5 else finger_why
        out.append((j, z, conf, why))
    thumb_mcp = out[1] if f == 0 else None
    if thumb_mcp is not None:  # the CMC's confidence is the thumb's
        out[0] = (out[0][0], out[0][1], thumb_mcp[2], thumb_mcp[3])
    return out


def _quarter_turn_loss(row: np.ndarray, best: int) -> float:
    """The loss a quarter turn from ``best`` (the lower of the two sides): the contrast's reference."""
    n = len(row)
    return float(np.min(row[[(best + n // 4) % n, (best - n // 4) % n]]))


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
