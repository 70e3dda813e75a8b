"""From a rig read out of any file format (named bones with rest transforms, an optional skinned mesh,
bone rotations over time) to a `HandModel` and a `Motion`, and back to per-bone rotations.

Hand space is the rig's wrist bone frame (rotation only, origin at the wrist, metres); a left hand
is mirrored to a right one (`hand.mirror`) and its motion with it. TBS frames come from the
annotation sidecar when the file has one, else from the ray solver, else (no mesh) from the palm
plane; ``hand.meta["annotation"]`` says which.
Torch and the ray solver are imported where a hand is built or a motion converted, not with the module:
recognising a rig (`s2h rig`) needs neither.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.errors import InputFileError, InvalidHandError, InvalidMotionError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.mirror import mirror_hand, reflection
from s2h_viewer.hand.model import HandModel, SkinnedMesh
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rig_mapping import RigMapping
from s2h_viewer.hand.rig_recognition import Skeleton, recognise_rig
from s2h_viewer.io.annotation import hand_side, legacy_sidecar_path, load_annotation
from s2h_viewer.io.units import UNIT_NAMES, UNITS, UnitChoice, choose_unit

#: a tip missing from the rig is put this far beyond its DIP, as a fraction of the DIP bone
TIP_EXTRAPOLATION = 0.8
#: the farthest a hand's skin may be from its wrist, in metres (beyond is damage, not a hand)
MAX_VERTEX_DISTANCE = 2.0
MIRROR_NORMAL = (0.0, 1.0, 0.0)  # a left hand is reflected across its wrist frame's x-z plane


@dataclass
class RigSkeleton:
    """Bones of a rig as a file stores them (any hierarchy; only the mapped ones matter)."""

    names: list[str]
    world: np.ndarray  # (N, 4, 4) rest world matrices
    parents: np.ndarray  # (N,) node parent index, -1 for roots (used to turn world rotations into locals)


@dataclass
class RigMesh:
    """A skinned mesh in world space at rest; weights over the skeleton's bones, K influences a vertex."""

    vertices: np.ndarray  # (V, 3)
    faces: np.ndarray  # (F, 3)
    bone_index: np.ndarray  # (V, K) int, into RigSkeleton.names
    bone_weight: np.ndarray  # (V, K)


def rotation_part(matrices: np.ndarray) -> np.ndarray:
    """(..., 3, 3) nearest rotations to the upper-left blocks of (..., 4, 4) matrices (scale removed)."""
    u, _, vt = np.linalg.svd(matrices[..., :3, :3])
    r = u @ vt
    flip = np.linalg.det(r) < 0
    if np.any(flip):
        u[flip, :, -1] *= -1
        r = u @ vt
    return r


def recognise(skeleton: RigSkeleton, source: str | Path, side: str | None = None, scheme: str | None = None,
              joint_map: dict[str, str] | None = None, humanoid: dict[str, dict[str, str]] | None = None
              ) -> RigMapping:
    """The hand of a rig read from any format (see `rig_recognition.recognise_rig`)."""
    return recognise_rig(Skeleton(skeleton.names, skeleton.parents, skeleton.world[:, :3, 3]), source, side, scheme,
                         joint_map, humanoid)


def bone_indices(names: list[str], hand: HandModel, source: str | Path) -> list[int]:
    """Index in ``names`` of the hand's 16 rotating bones (by the names the hand was loaded with)."""
    lookup = {n: i for i, n in enumerate(names)}
    bones = [hand.meta["rig_joints"][topo.JOINT_NAMES[j]] for j in topo.ROTATING_JOINTS]
    absent = [b for b in bones if b not in lookup]
    if absent:
        shown = names[:4] + (["..."] if len(names) > 4 else [])
        raise InputFileError(source, f"has no bones {', '.join(absent)} of the hand {hand.name!r} "
                                     f"(loaded from {hand.source}): its own are {', '.join(shown)}; the rig it "
                                     f"was made for has bones of those names")
    return [lookup[b] for b in bones]


def _bone_index(skeleton: RigSkeleton, mapping: RigMapping) -> np.ndarray:
    """(21,) skeleton index of each canonical joint, -1 for a tip the rig lacks."""
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    return np.array([lookup.get(mapping.joints.get(name, ""), -1) for name in topo.JOINT_NAMES])


def file_unit(skeleton: RigSkeleton, mapping: RigMapping, source: str | Path, unit: str | None = None,
              declared: str | None = "m") -> UnitChoice:
    """The length unit of a mapped rig (`io.units.choose_unit`); an `InputFileError` where no unit (or not the
    user's) makes it a plausible hand."""
    return _unit(skeleton, _bone_index(skeleton, mapping), Path(source), unit, declared)


def _unit(skeleton: RigSkeleton, index: np.ndarray, source: Path, unit: str | None, declared: str | None
          ) -> UnitChoice:
    if not np.isfinite(skeleton.world).all():
        raise InputFileError(source, "bone transforms contain NaN or infinite values")
    length = _length(skeleton, index)
    choice = choose_unit(length, unit, declared)
    if choice is None and unit is not None:
        raise InputFileError(source, f"wrist to middle DIP is {length:.4g} file units: in {UNIT_NAMES[unit]} "
                                     f"(--unit {unit}) a hand of {length * UNITS[unit]:.4g} m, not a plausible one")
    if choice is None:
        raise InputFileError(source, f"wrist to middle DIP is {length:.4g} file units, not a plausible hand in "
                                     f"{', '.join(UNIT_NAMES.values())}"
                                     + ("; is the hand collapsed (a bone scaled to 0)?" if length < 1e-9 else ""))
    return choice


def build_hand(source: str | Path, skeleton: RigSkeleton, mapping: RigMapping, mesh: RigMesh | None,
               name: str | None = None, unit: str | None = None, declared: str | None = "m",
               hinge_evidence: str | Path | None = None) -> HandModel:
    """The `HandModel` of a mapped rig, annotated (sidecar, solver or palm plane) and mirrored if left; lengths
    in ``unit`` (None: the ``declared`` unit of the format where the hand is plausible in it, else a guess).
    ``hinge_evidence``: a motion file on this skeleton (the rig's own, or a pose file) whose animations the
    solver's frames are checked against (`annotate.hinges`)."""
    from s2h_viewer.annotate.solver import palm_plane_frames

    source = Path(source)
    side = mapping.side
    index = _bone_index(skeleton, mapping)
    _refuse_collapsed(skeleton, mapping, index, source)
    unit_choice = _unit(skeleton, index, source, unit, declared)
    wrist_rot, wrist_origin = rotation_part(skeleton.world[index[0]]), skeleton.world[index[0], :3, 3]
    to_metres = unit_choice.to_metres
    length = _length(skeleton, index)
    unit_note = unit_choice.note(length)
    unit_guess = None if unit_note is None else {"unit": unit_choice.unit, "sure": unit_choice.sure,
                                                  "alternatives": unit_choice.alternatives(length)}
    positions = np.zeros((topo.N_JOINTS, 3))
    present = index >= 0
    positions[present] = (skeleton.world[index[present], :3, 3] - wrist_origin) @ wrist_rot * to_metres
    for tip in np.flatnonzero(~present):
        positions[tip] = positions[tip - 1] + TIP_EXTRAPOLATION * (positions[tip - 1] - positions[tip - 2])
    offsets = positions - positions[topo.PARENTS.clip(0)]
    offsets[0] = 0.0
    rig_frames = wrist_rot.T @ rotation_part(skeleton.world[index[topo.ROTATING_JOINTS]])
    rig_frames[0] = np.eye(3)

    skinned = None
    if mesh is not None:
        _check_mesh(mesh, skeleton, source)
        skinned = _hand_mesh(mesh, skeleton, mapping, index, wrist_rot, wrist_origin, to_metres, source)
    try:
        hand = HandModel(name=name or source.stem, offsets=offsets, rest_frames=palm_plane_frames(positions),
                         rig_frames=rig_frames, radii=np.full(topo.N_JOINTS, 0.01), mesh=skinned,
                         source=str(source),
                         meta={"side": side, "side_from": mapping.side_from, "rig_scheme": mapping.scheme,
                               "rig_joints": mapping.joints, "rig_confidence": mapping.confidence,
                               "rig_notes": mapping.notes, "palm_bones": mapping.palm_bones,
                               "both_hands": mapping.both_hands,
                               "extrapolated_tips": mapping.missing_tips, "to_metres": to_metres,
                               "unit": unit_choice.unit, "unit_note": unit_note, "unit_guess": unit_guess})
        if side == "left":
            hand = mirror_hand(hand, MIRROR_NORMAL)
            hand.rest_frames = palm_plane_frames(hand.rest_positions)  # the guess, made for the right hand
        return annotate(hand, source, None if hinge_evidence is None else Path(hinge_evidence), skeleton)
    except InvalidHandError as exc:
        raise InputFileError(source, str(exc)) from None


def _length(skeleton: RigSkeleton, index: np.ndarray) -> float:
    """Wrist to middle DIP in file units."""
    return float(np.linalg.norm(skeleton.world[index[topo.joint_index("middle_dip")], :3, 3]
                                - skeleton.world[index[0], :3, 3]))


def _refuse_collapsed(skeleton: RigSkeleton, mapping: RigMapping, index: np.ndarray, source: Path) -> None:
    """An `InputFileError` for a hand bone whose transform collapses space (a scale of 0 on it or above it):
    its fingers sit on one point, not a hand to retarget."""
    present = np.flatnonzero(index >= 0)  # canonical joints the rig has
    scale = np.abs(np.linalg.det(skeleton.world[index[present], :3, :3])) ** (1.0 / 3.0)
    flat = np.flatnonzero(~(scale > 1e-6 * max(float(scale.max()), 1e-300)))  # all of them where every scale is 0
    if len(flat):
        bone = mapping.joints[topo.JOINT_NAMES[int(present[flat[0]])]]
        raise InputFileError(source, f"bone {bone!r} is scaled to 0 (or a node above it is): the hand collapses to "
                                     f"a point; fix the scale in the authoring tool")


def _check_mesh(mesh: RigMesh, skeleton: RigSkeleton, source: Path) -> None:
    """Refuse a mesh with non-finite values or indices past its tables (before anything indexes them)."""
    if not (np.isfinite(mesh.vertices).all() and np.isfinite(mesh.bone_weight).all()):
        raise InputFileError(source, "mesh vertices or skin weights contain NaN or infinite values")
    if len(mesh.faces) and (mesh.faces.min() < 0 or mesh.faces.max() >= len(mesh.vertices)):
        raise InputFileError(source, f"a mesh triangle uses a vertex past the {len(mesh.vertices)} there are")
    if mesh.bone_index.size and (mesh.bone_index.min() < 0 or mesh.bone_index.max() >= len(skeleton.names)):
        raise InputFileError(source, f"mesh is skinned to a bone past the {len(skeleton.names)} there are")


def annotate(hand: HandModel, source: Path, hinge_evidence: Path | None = None,
             skeleton: RigSkeleton | None = None) -> HandModel:
    """Set ``hand``'s TBS frames and radii: the sidecar of ``source``, else the solver (checked against the
    hinges of ``hinge_evidence``'s animations, if given; ``skeleton``: ``source``'s, which another file's is
    compared with), else the palm plane."""
    from s2h_viewer.annotate import trust
    from s2h_viewer.annotate.hinges import LABEL as HINGE_LABEL
    from s2h_viewer.annotate.solver import estimate_radii, solve_tbs_frames
    from s2h_viewer.semantics.rest_pose import posed_rest_note

    side = hand_side(hand)
    annotation = load_annotation(source, side) if source.exists() else None
    solution = solve_tbs_frames(hand) if hand.mesh is not None else None
    refused, diagnostics = None, []
    if annotation is not None and annotation.side is None and not _frames_fit(hand, annotation.frames):
        refused = (f"{legacy_sidecar_path(source).name} (an older sidecar that does not say its hand) does not fit "
                   f"the {side} hand: not used; annotate this hand and save to write its own sidecar")
        annotation = None
    if annotation is not None:
        hand.rest_frames, how = annotation.frames, "sidecar"
        set_by, confidence = annotation.set_by, annotation.confidence
    elif solution is not None:
        if hinge_evidence is not None:
            solution = _with_animation_hinges(hand, solution, hinge_evidence, source, skeleton)
        hand.rest_frames, how = solution.frames, "solver"
        set_by = [basis if basis in (trust.GUESS, HINGE_LABEL) else "solver" for basis in solution.basis]
        confidence = solution.confidence
    else:
        how = "palm plane (no mesh)"
        set_by, confidence = [trust.GUESS] * topo.N_ARTICULATED, np.full(topo.N_ARTICULATED, np.nan)
        if hinge_evidence is not None:  # a skeleton with animations: its one-axis joints bend as they do there
            hinged = _with_animation_hinges(hand, _palm_plane_solution(hand.rest_frames), hinge_evidence, source,
                                            skeleton)
            hand.rest_frames, set_by, confidence = hinged.frames, hinged.basis, hinged.confidence
            if HINGE_LABEL in set_by:
                how = "palm plane (no mesh), animation hinges"
            diagnostics = hinged.diagnostics
    trust.record(hand, set_by, confidence)
    hand.radii = estimate_radii(hand, solution)
    hand.meta["annotation"] = how
    if solution is not None:
        diagnostics = solution.diagnostics
        hand.meta["unparted_fingers"] = list(solution.unparted)
    if solution is not None or diagnostics or refused:
        hand.meta["solver_diagnostics"] = ([refused] if refused else []) + diagnostics
    hand.validate()
    hand.meta["rest_note"] = posed_rest_note(hand)
    return hand


SAME_ROLL_DEGREES = 30.0  # a finger bone rolled further than this about itself in another file: another skeleton


def _roll_difference(own: RigSkeleton, other: RigSkeleton, joints: dict[str, str]
                     ) -> tuple[list[tuple[float, str]], list[str]]:
    """``other``'s finger bones rolled unlike ``own``'s, as (degrees, bone), and those it lacks; both empty for
    the same skeleton. Each mapped finger bone's rest rotation relative to its parent is compared, and only its
    turn about the bone itself counts: a pose file's nodes may rest in a pose (bent, not rolled), while bones
    rolled otherwise (another export of the rig) make the same animation keys turn about other axes. The thumb
    is left out (opposition rolls it)."""
    lookup = [{n: i for i, n in enumerate(s.names)} for s in (own, other)]
    missing, rolled = [], []
    for joint, bone in joints.items():
        child_bone = None if joint.endswith("_tip") or joint == "wrist" else joints.get(_child_joint(joint))
        if joint.startswith("thumb") or not bone or bone not in lookup[0] or child_bone not in lookup[0]:
            continue
        if bone not in lookup[1]:
            missing.append(bone)
            continue
        local = []
        for skeleton, index in zip((own, other), lookup):
            i = index[bone]
            world = rotation_part(skeleton.world[i])
            parent = skeleton.parents[i]
            local.append(world if parent < 0 else rotation_part(skeleton.world[parent]).T @ world)
        child = own.world[lookup[0][child_bone], :3, 3] - own.world[lookup[0][bone], :3, 3]
        along = rotation_part(own.world[lookup[0][bone]]).T @ child  # the bone's direction in its own axes
        quat = Rotation.from_matrix(local[0].T @ local[1]).as_quat()  # x, y, z, w
        roll = 2.0 * np.arctan2(abs(quat[:3] @ along) / max(np.linalg.norm(along), 1e-12), abs(quat[3]))
        if np.degrees(roll) > SAME_ROLL_DEGREES:
            rolled.append((float(np.degrees(roll)), bone))
    return sorted(rolled, reverse=True), missing


def _child_joint(joint: str) -> str:
    """'index_mcp' -> 'index_pip': the next joint down a finger (a finger's DIP -> its tip)."""
    return topo.JOINT_NAMES[topo.JOINT_NAMES.index(joint) + 1]


def _palm_plane_solution(frames: np.ndarray):
    """A `TbsSolution` of palm-plane frames (a rig without a mesh), for the animation hinges to check."""
    from s2h_viewer.annotate import trust
    from s2h_viewer.annotate.solver import TbsSolution

    unknown = np.full(topo.N_ARTICULATED, np.nan)
    return TbsSolution(frames.copy(), unknown, np.zeros(topo.N_ARTICULATED), unknown, unknown,
                       np.ones(topo.N_ARTICULATED, dtype=bool), [], [trust.GUESS] * topo.N_ARTICULATED)


def _with_animation_hinges(hand: HandModel, solution, evidence: Path, source: Path, skeleton: RigSkeleton):
    """``solution`` checked against the hinges every animation of ``evidence`` turns each joint about
    (`annotate.hinges.overrule_with_hinges`). A pose file on another skeleton, or a rig's own animations that
    cannot be read on its hand, leave the solution as it was, with a line saying so; a pose file that cannot be
    read raises its error."""
    from dataclasses import replace

    from s2h_viewer.annotate.hinges import animation_hinges, overrule_with_hinges
    from s2h_viewer.io.files import ALL_ANIMATIONS, RigOptions, load_motion_file

    hand.rest_frames = solution.frames
    if evidence != source:
        from s2h_viewer.io.files import read_rig_skeleton
        rolled, missing = _roll_difference(skeleton, read_rig_skeleton(evidence), hand.meta["rig_joints"])
        if rolled or missing:  # another rig (of several a command reads) or another export of this one
            why = ("its bones are rolled otherwise, so its keys turn them about other axes" if rolled else
                   "its skeleton is not this hand's")
            where = ([f"{bone} rolled {angle:.0f} deg" for angle, bone in rolled[:2]]
                     + [f"no bone {bone}" for bone in missing[:2]])
            return replace(solution, diagnostics=[*solution.diagnostics, (
                f"hinges from {evidence.name} not taken: {why} ({', '.join(where)}); use animations made on this "
                f"skeleton")])
    try:
        motion, _ = load_motion_file(evidence, hand, RigOptions(animation=ALL_ANIMATIONS))
    except InputFileError as exc:
        if evidence != source:
            raise InputFileError(evidence, f"cannot take hinges from it for {source.name}: {exc.problem}") from None
        return replace(solution, diagnostics=[*solution.diagnostics,
                                              f"its animations could not be read for hinges: {exc.problem}"])
    hinges = animation_hinges(motion.q_tbs, solution.frames, evidence.name)
    return overrule_with_hinges(solution, hinges, hand.rest_positions)


def _frames_fit(hand: HandModel, frames: np.ndarray) -> bool:
    """Whether ``frames`` are TBS frames of ``hand`` (each twist axis along its bone), as a side-less sidecar
    made for the other hand of a file is not."""
    try:
        HandModel(hand.name, hand.offsets, frames, hand.rig_frames, hand.radii).validate()
    except InvalidHandError:
        return False
    return True


def _hand_mesh(mesh: RigMesh, skeleton: RigSkeleton, mapping: RigMapping, index: np.ndarray, wrist_rot: np.ndarray,
               wrist_origin: np.ndarray, to_metres: float, source: Path) -> SkinnedMesh:
    """The part of the mesh the hand's bones move, in hand space, weights over the 16 rotating joints."""
    column = np.full(len(skeleton.names) + 1, -1)  # skeleton bone -> rotating column; -1 not the hand
    column[index[0]] = 0
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    for bone in mapping.palm_bones:  # named palm bones (also where the hierarchy is flat, as in WebXR)
        column[lookup[bone]] = 0
    for r, joint in enumerate(topo.ROTATING_JOINTS):
        column[index[joint]] = r
    for tip in topo.TIP_JOINTS:  # the tip bone's skin moves with the DIP
        if index[tip] >= 0:
            column[index[tip]] = column[index[tip - 1]]
    for bone in range(len(skeleton.names)):  # any other bone under the wrist (palm, metacarpal, twist, nail
        node = bone                            # bones) moves with its nearest mapped ancestor
        while column[bone] < 0 and node >= 0:
            node = skeleton.parents[node]
            if node >= 0 and column[node] >= 0:
                column[bone] = column[node]
    cols = column[mesh.bone_index]
    weights = np.zeros((len(mesh.vertices), topo.N_ROTATING))
    on_hand = cols >= 0
    np.add.at(weights, (np.nonzero(on_hand)[0], cols[on_hand]), mesh.bone_weight[on_hand])
    total = mesh.bone_weight.sum(axis=1)
    keep = weights.sum(axis=1) >= 0.5 * np.maximum(total, 1e-12)  # a full body: only the hand's vertices
    if keep.sum() < 100:
        raise InputFileError(source, f"only {int(keep.sum())} vertices are skinned to the hand's bones; "
                                     f"is this the right side?")
    faces = mesh.faces[keep[mesh.faces].all(axis=1)]
    new_index = np.cumsum(keep) - 1
    weights = weights[keep] / weights[keep].sum(axis=1, keepdims=True)
    vertices = (mesh.vertices[keep] - wrist_origin) @ wrist_rot * to_metres
    farthest = float(np.linalg.norm(vertices, axis=1).max(initial=0.0))
    if not farthest <= MAX_VERTEX_DISTANCE:
        raise InputFileError(source, f"hand mesh vertices lie up to {farthest:.3g} m from the wrist, over the "
                                     f"{MAX_VERTEX_DISTANCE} m a hand can span")
    return SkinnedMesh(vertices.astype(np.float32), new_index[faces].astype(np.int32), weights.astype(np.float32))


def motion_from_world_rotations(hand: HandModel, world_rotations: np.ndarray, fps: float, source: str | Path,
                                name: str = "") -> Motion:
    """A `Motion` on ``hand`` from the rig's animated world rotations (T, 16, 3, 3) of the wrist and the
    15 articulated bones (in the file's world axes, before any mirroring)."""
    import torch

    from s2h_viewer.hand.kinematics import rig_local_to_tbs

    source = Path(source)
    if not np.isfinite(world_rotations).all():
        bad = ~np.isfinite(world_rotations).all(axis=(1, 2, 3))
        raise InputFileError(source, f"NaN or infinite rotations in {int(bad.sum())} frames "
                                     f"(first at frame {int(np.flatnonzero(bad)[0])})")
    wrist = world_rotations[:, :1]
    global_hand = wrist.transpose(0, 1, 3, 2) @ world_rotations  # (T, 16, 3, 3) in the animated wrist frame
    rig_frames = hand.rig_frames
    if hand.meta.get("side") == "left":
        s = reflection(MIRROR_NORMAL)
        global_hand = s @ global_hand @ s
    parent = global_hand[:, topo.ARTICULATED_PARENT_ROTATING]
    local = parent.transpose(0, 1, 3, 2) @ global_hand[:, 1:]
    rest = rig_frames[topo.ARTICULATED_PARENT_ROTATING].transpose(0, 2, 1) @ rig_frames[1:]
    q_local = Rotation.from_matrix((local @ rest.transpose(0, 2, 1)).reshape(-1, 3, 3)).as_quat(scalar_first=True)
    q_tbs = rig_local_to_tbs(hand, torch.as_tensor(q_local.reshape(-1, topo.N_ARTICULATED, 4), dtype=torch.float64))
    try:
        return Motion(q_tbs.numpy().astype(np.float32), fps=fps, name=name or source.stem, hand_name=hand.name,
                      meta={"source": str(source)})
    except InvalidMotionError as exc:
        raise InputFileError(source, str(exc)) from None


def world_rotations_from_motion(hand: HandModel, motion: Motion) -> np.ndarray:
    """(T, 16, 3, 3) the rig's bone rotations in hand space (wrist at rest) for ``motion``: what
    exporters write; for a hand loaded as left, mirrored back to the left rig."""
    import torch

    from s2h_viewer.hand.kinematics import tbs_to_rig_local

    q_local = tbs_to_rig_local(hand, torch.as_tensor(motion.q_tbs, dtype=torch.float64)).numpy()
    local = Rotation.from_quat(q_local.reshape(-1, 4), scalar_first=True).as_matrix().reshape(-1, 15, 3, 3)
    rig = hand.rig_frames
    rest = rig[topo.ARTICULATED_PARENT_ROTATING].transpose(0, 2, 1) @ rig[1:]
    out = np.broadcast_to(rig, (motion.n_frames, topo.N_ROTATING, 3, 3)).copy()
    for a in range(topo.N_ARTICULATED):  # parents come before children in articulated order
        out[:, 1 + a] = out[:, topo.ARTICULATED_PARENT_ROTATING[a]] @ local[:, a] @ rest[a]
    if hand.meta.get("side") == "left":
        s = reflection(MIRROR_NORMAL)
        out = s @ out @ s
    return out

