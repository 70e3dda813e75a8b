"""BVH: finger motion with its skeleton, in and out.

A BVH skeleton has every joint's rest orientation equal to the world axes, so its rig frames are the
identity; it has no mesh, so a hand read from BVH takes TBS frames from an annotation sidecar if there
is one, else from the palm plane. `save_bvh` writes that sidecar beside the file with the hand's own
frames: TBS rotations are measured in them, and frames guessed from the palm plane (the thumb's some
50 deg off) would read the same joint positions back as other TBS rotations. Rotation channels may
come in any order; positions are read but only the hand's rotations are used (the wrist stays where it
is). Written files use ZXY rotation channels, the order Blender and MotionBuilder expect, and the
project's joint names.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.errors import InputFileError, reading, require_readable_file
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.annotation import hand_side, refuse_foreign_sidecar, save_hand_frames
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.hand.mirror import reflection
from s2h_viewer.io.rig import (MIRROR_NORMAL, RigMapping, RigSkeleton, build_hand, motion_from_world_rotations,
                               recognise, world_rotations_from_motion)

WRITE_ORDER = "ZXY"


@dataclass
class BvhClip:
    """A parsed BVH file: joints (End Sites included, with no channels) and their channel data."""

    names: list[str]
    parents: np.ndarray  # (N,)
    offsets: np.ndarray  # (N, 3)
    channels: list[list[str]]  # per joint, e.g. ["Xposition", ..., "Zrotation"]
    frames: np.ndarray  # (T, total channels)
    frame_time: float


#: bounds a BVH file must stay within (checked before its motion data is parsed)
MAX_BVH_BYTES = 1024 ** 3
MAX_JOINTS = 10_000
MAX_FRAMES = 5_000_000
MAX_VALUE = 1e6  # degrees or file units (centimetres): anything larger is damage, not motion
MAX_FPS = 1000.0
_CHANNELS = {f"{a}{k}" for a in "XYZ" for k in ("position", "rotation")}


def _text(path: Path) -> str:
    require_readable_file(path, MAX_BVH_BYTES)
    try:
        return path.read_text(errors="strict")
    except UnicodeDecodeError:
        raise InputFileError(path, "not a BVH file (binary data)") from None


def _hierarchy(path: Path, tokens: list[str]) -> tuple[list[str], list[int], list[np.ndarray], list[list[str]]]:
    """Joint names, parents, offsets and channels of the HIERARCHY section's tokens."""
    names, parents, offsets, channels = [], [], [], []
    stack: list[int] = []
    i = 1
    while i < len(tokens):
        token = tokens[i]
        if token in ("ROOT", "JOINT", "End"):
            if token != "ROOT" and not stack:
                raise ValueError(f"{token} outside any joint")
            name = tokens[i + 1] if token != "End" else f"{names[stack[-1]]}_end"
            names.append(name)
            parents.append(stack[-1] if stack else -1)
            offsets.append(np.zeros(3))
            channels.append([])
            if len(names) > MAX_JOINTS:
                raise InputFileError(path, f"more than {MAX_JOINTS} joints")
            i += 2
        elif token == "{":
            if not names:
                raise ValueError("'{' before any joint")
            stack.append(len(names) - 1)
            i += 1
        elif token == "}":
            stack.pop()
            i += 1
        elif token == "OFFSET":
            offset = np.array(tokens[i + 1:i + 4], dtype=np.float64)
            if offset.shape != (3,) or not np.all(np.abs(offset) <= MAX_VALUE):
                raise ValueError(f"OFFSET of {names[stack[-1]] if stack else '?'} is not 3 finite numbers")
            offsets[-1 if not stack else stack[-1]] = offset
            i += 4
        elif token == "CHANNELS":
            n = int(tokens[i + 1])
            if not 0 <= n <= 6 or not stack:
                raise ValueError(f"CHANNELS {n}")
            chans = tokens[i + 2:i + 2 + n]
            unknown = set(chans) - _CHANNELS
            if unknown or len(chans) != n:
                raise InputFileError(path, f"unknown channels {', '.join(sorted(unknown)) or '(too few)'}")
            channels[stack[-1]] = chans
            i += 2 + n
        else:
            raise ValueError(f"unexpected token {token!r}")
    if stack or not names:
        raise InputFileError(path, "malformed BVH (unbalanced braces in the hierarchy)")
    return names, parents, offsets, channels


def read_bvh(path: str | Path) -> BvhClip:
    """Parse a BVH file; an `InputFileError` naming the file and what is wrong with it."""
    path = Path(path)
    text = _text(path)
    head, marker, motion = text.partition("MOTION")
    tokens = head.split()
    if not tokens or tokens[0] != "HIERARCHY":
        raise InputFileError(path, "not a BVH file (no HIERARCHY header)")
    if not marker:
        raise InputFileError(path, "malformed BVH (no MOTION section)")
    try:
        names, parents, offsets, channels = _hierarchy(path, tokens)
        frames_line, time_line, numbers = (motion.lstrip().split("\n", 2) + ["", ""])[:3]
        frames_key, n_frames = frames_line.split(":")
        time_key, frame_time = time_line.split(":")
        if frames_key.strip() != "Frames" or time_key.strip() != "Frame Time":
            raise ValueError("MOTION must start with 'Frames:' and 'Frame Time:' lines")
        n_frames, frame_time = int(n_frames), float(frame_time)
    except (IndexError, ValueError) as exc:
        raise InputFileError(path, f"malformed BVH ({exc})") from None
    width = sum(len(c) for c in channels)
    if not 1 <= n_frames <= MAX_FRAMES:
        raise InputFileError(path, f"declares {n_frames} frames; this program reads 1 to {MAX_FRAMES}")
    if not np.isfinite(frame_time) or not 1.0 / MAX_FPS <= frame_time:
        raise InputFileError(path, f"frame time {frame_time} is not a positive number of at least {1 / MAX_FPS} s")
    if width == 0 or len(numbers) < n_frames * width:  # each number takes at least one character
        raise InputFileError(path, f"MOTION is too short for {n_frames} frames x {width} channels")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # text-mode fromstring: the parse is checked below
        values = np.fromstring(numbers, dtype=np.float64, sep=" ")
    if len(values) != n_frames * width:
        raise InputFileError(path, f"MOTION holds {len(values)} numbers, expected {n_frames} frames x {width} "
                                   f"channels")
    frames = values.reshape(n_frames, width)
    for problem, bad_frames in (("NaN or infinite", ~np.isfinite(frames).all(axis=1)),
                                (f"absurd (beyond {MAX_VALUE:g})", ~(np.abs(frames) <= MAX_VALUE).all(axis=1))):
        if bad_frames.any():
            raise InputFileError(path, f"{problem} values in {int(bad_frames.sum())} frames "
                                       f"(first at frame {int(np.flatnonzero(bad_frames)[0])})")
    return BvhClip(names, np.array(parents), np.array(offsets), channels, frames, frame_time)


def _local_rotations(clip: BvhClip) -> np.ndarray:
    """(T, N, 3, 3) each joint's rotation channels as matrices (identity for End Sites)."""
    out = np.tile(np.eye(3), (len(clip.frames), len(clip.names), 1, 1))
    column = 0
    for j, chans in enumerate(clip.channels):
        rot = [(c[0], column + k) for k, c in enumerate(chans) if c.endswith("rotation")]
        if rot:
            order = "".join(axis for axis, _ in rot)
            angles = clip.frames[:, [col for _, col in rot]]
            out[:, j] = Rotation.from_euler(order.upper(), angles, degrees=True).as_matrix()
        column += len(chans)
    return out


def _world(clip: BvhClip, local: np.ndarray) -> np.ndarray:
    """(T, N, 3, 3) world rotations over time (from rest: BVH rest frames are the world axes)."""
    world = local.copy()
    for j, p in enumerate(clip.parents):  # BVH lists parents before children
        if p >= 0:
            world[:, j] = world[:, p] @ local[:, j]
    return world


@dataclass
class FoldedJoints:
    """A clip's joints with each run of zero-length bones folded into one: optical finger mocap writes a joint
    per degree of freedom (``INDEX_MCP_FE`` then ``INDEX_MCP_AA`` at the same point) and zero-length End Sites.
    ``kept`` are the joints that stay (each run's first, which carries the offset and the name), ``last`` the
    run's last joint of each, whose world rotation is the run's rotation; ``parents`` index into ``kept``."""

    kept: np.ndarray  # (K,) clip joint indices
    last: np.ndarray  # (K,) clip joint index of each kept joint's run end
    parents: np.ndarray  # (K,)


def fold_zero_length(clip: BvhClip) -> FoldedJoints:
    """Fold every joint at its parent's point (an offset under a millionth of the skeleton's bones), where it
    is its parent's only child, into the parent (`FoldedJoints`)."""
    lengths = np.linalg.norm(clip.offsets, axis=1)
    scale = float(np.median(lengths[lengths > 0])) if np.any(lengths > 0) else 1.0
    children = np.bincount(clip.parents[clip.parents >= 0], minlength=len(clip.names))
    folded = np.array([p >= 0 and lengths[j] <= 1e-6 * scale and children[p] == 1
                       for j, p in enumerate(clip.parents)])
    head = np.arange(len(clip.names))
    for j, p in enumerate(clip.parents):  # parents come first: a folded joint joins its parent's run
        if folded[j]:
            head[j] = head[p]
    kept = np.flatnonzero(~folded)
    last = kept.copy()
    for j in np.flatnonzero(folded):
        last[np.searchsorted(kept, head[j])] = j  # deeper joints of a run come later
    position = {int(k): i for i, k in enumerate(kept)}
    parents = np.array([position[int(head[clip.parents[k]])] if clip.parents[k] >= 0 else -1 for k in kept])
    return FoldedJoints(kept, last, parents)


def bvh_skeleton(clip: BvhClip) -> RigSkeleton:
    """The clip's skeleton at rest: BVH rest frames are the world axes, so only positions vary."""
    rest = np.zeros((len(clip.names), 3))
    for j, p in enumerate(clip.parents):  # BVH lists parents before children
        if p >= 0:
            rest[j] = rest[p] + clip.offsets[j]
    matrices = np.tile(np.eye(4), (len(clip.names), 1, 1))
    matrices[:, :3, 3] = rest
    return RigSkeleton(clip.names, matrices, clip.parents)


def load_bvh(path: str | Path, side: str | None = None, scheme: str | None = None,
             joint_map: dict[str, str] | None = None, name: str | None = None, unit: str | None = None
             ) -> tuple[HandModel, Motion]:
    """The hand skeleton of a BVH file and its finger motion (a hand alone or one hand of a body)."""
    path = Path(path)
    with reading(path, "a BVH rig and motion"):
        return _load_bvh(path, read_bvh(path), side, scheme, joint_map, name, unit)


def folded_skeleton(clip: BvhClip) -> tuple[RigSkeleton, FoldedJoints]:
    """The clip's skeleton at rest with its zero-length bones folded (`fold_zero_length`): what is recognised."""
    full = bvh_skeleton(clip)
    folds = fold_zero_length(clip)
    return RigSkeleton([clip.names[k] for k in folds.kept], full.world[folds.kept], folds.parents), folds


def _frame_positions(clip: BvhClip, world: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """(F, N, 3) every joint's position at ``frames`` (root translation left out: hand shape is what matters)."""
    out = np.zeros((len(frames), len(clip.names), 3))
    for j, p in enumerate(clip.parents):
        if p >= 0:
            out[:, j] = out[:, p] + world[frames, p] @ clip.offsets[j]
    return out


def _side_of_pose(skeleton: RigSkeleton, positions: np.ndarray, mapping: RigMapping) -> tuple[str, float]:
    """Geometry's call (`rig_recognition.detect_side`) on the mapped hand with its bones at ``positions``."""
    from s2h_viewer.hand.rig_recognition import Skeleton, canonical_positions, detect_side
    return detect_side(canonical_positions(Skeleton(skeleton.names, skeleton.parents, positions), mapping.joints))


def _side_from_frames(clip: BvhClip, world: np.ndarray, skeleton: RigSkeleton, folds: FoldedJoints,
                      mapping: RigMapping) -> tuple[str, float]:
    """The side the clip's own poses say (a zero pose of per-DOF mocap is no hand pose): geometry's call on
    up to 50 frames, summed with its confidence as weight."""
    frames = np.unique(np.linspace(0, len(clip.frames) - 1, min(50, len(clip.frames))).astype(int))
    score = 0.0
    for pose in _frame_positions(clip, world, frames)[:, folds.kept]:
        side, sure = _side_of_pose(skeleton, pose, mapping)
        score += sure if side == "right" else -sure
    return ("right" if score >= 0 else "left"), min(abs(score) / len(frames), 1.0)


def recognise_bvh(path: Path, clip: BvhClip, side: str | None = None, scheme: str | None = None,
                  joint_map: dict[str, str] | None = None) -> tuple[RigSkeleton, FoldedJoints, RigMapping, np.ndarray]:
    """The hand of a BVH clip: recognised on its folded skeleton (`folded_skeleton`), its side, where geometry
    decides it, from the clip's poses; with the skeleton, the folds and every joint's world rotations (T, N)."""
    from s2h_viewer.hand.rig_recognition import SURE
    full = _world(clip, _local_rotations(clip))
    skeleton, folds = folded_skeleton(clip)
    mapping = recognise(skeleton, path, side, scheme, joint_map)
    if mapping.side_from.startswith("geometry"):  # the poses decide; a rest pose that agrees adds its certainty
        at_rest, rest_sure = _side_of_pose(skeleton, skeleton.world[:, :3, 3], mapping)
        mapping.side, sure = _side_from_frames(clip, full, skeleton, folds, mapping)
        sure = max(sure, rest_sure) if at_rest == mapping.side else sure
        mapping.side_from = f"geometry of the clip's poses (confidence {sure:.2f})"
        mapping.notes = [n for n in mapping.notes if not n.startswith("the side is a guess")] + (
            [f"the side is a guess ({mapping.side}, confidence {sure:.2f}): check it, or pass --side"]
            if sure < SURE else [])
        if mapping.scheme != "topology":  # names settled the joints; the side is all geometry decided
            mapping.confidence = sure
    return skeleton, folds, mapping, full


def _load_bvh(path: Path, clip: BvhClip, side: str | None, scheme: str | None, joint_map: dict[str, str] | None,
              name: str | None, unit: str | None = None) -> tuple[HandModel, Motion]:
    skeleton, folds, mapping, full = recognise_bvh(path, clip, side, scheme, joint_map)
    for tip in mapping.missing_tips:  # a finger's End Site is its tip (unless of zero length: folded away)
        end_site = f"{mapping.joints[topo.JOINT_NAMES[topo.joint_index(tip) - 1]]}_end"
        if end_site in skeleton.names:
            mapping.joints[tip] = end_site
    world = full[:, folds.last]  # a folded run turns as its last joint
    hand = build_hand(path, skeleton, mapping, None, name, unit, declared=None)  # BVH says no unit
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    rotating = [lookup[mapping.joints[topo.JOINT_NAMES[j]]] for j in topo.ROTATING_JOINTS]
    fps = 1.0 / clip.frame_time
    fps = float(round(fps)) if abs(fps - round(fps)) < 1e-3 else fps  # "Frame Time: 0.0333333" is 30 fps
    motion = motion_from_world_rotations(hand, world[:, rotating], fps, path)
    return hand, motion


def save_bvh(path: str | Path, motion: Motion, hand: HandModel) -> Path:
    """Write ``motion`` on ``hand`` as BVH, atomically: with the rig's own bone names, hierarchy (under the
    wrist) and rest offsets (file units) when the hand was read from a rig file, so it re-imports onto the
    avatar; else with the project's joint names (centimetres, the wrist as root). The hand's TBS frames
    go beside it as its annotation sidecar, so that it reads back with the same TBS rotations."""
    path = Path(path)
    refuse_foreign_sidecar(path, hand_side(hand))
    if "rig_joints" in hand.meta and Path(hand.source).exists():
        from s2h_viewer.io.files import read_rig_skeleton
        return _save_rig_bvh(path, motion, hand, read_rig_skeleton(hand.source))
    return save_hand_frames(_write_hand_bvh(path, motion, hand), hand, np.eye(3))


def _write_hand_bvh(path: Path, motion: Motion, hand: HandModel) -> Path:
    """BVH of ``motion`` on ``hand``'s own skeleton, in hand space (see `save_bvh`)."""
    rotations = world_rotations_from_motion(hand, motion)  # (T, 16, 3, 3) the rig's frames over time
    rig, positions = hand.rig_frames, hand.rest_positions * 100.0
    if hand.meta.get("side") == "left":  # written as the left hand it was loaded from
        s = reflection(MIRROR_NORMAL)
        rig, positions = s @ rig @ s, positions @ s
    world = rotations @ rig.transpose(0, 2, 1)  # rotation from rest: BVH's rest frames are the world axes
    rotating_of_joint = topo.ARTICULATED_OF_JOINT + 1
    lines = ["HIERARCHY"]
    columns = []

    def joint(j: int, depth: int) -> None:
        pad = "  " * depth
        parent = topo.PARENTS[j]
        offset = positions[j] - (positions[parent] if parent >= 0 else 0.0)
        if j in topo.TIP_JOINTS:
            lines.extend([f"{pad}End Site", f"{pad}{{", f"{pad}  OFFSET {offset[0]:.6f} {offset[1]:.6f} "
                                                        f"{offset[2]:.6f}", f"{pad}}}"])
            return
        keyword = "ROOT" if parent < 0 else "JOINT"
        chans = ["Xposition", "Yposition", "Zposition"] if parent < 0 else []
        chans += [f"{a}rotation" for a in WRITE_ORDER]
        lines.extend([f"{pad}{keyword} {topo.JOINT_NAMES[j]}", f"{pad}{{",
                      f"{pad}  OFFSET {offset[0]:.6f} {offset[1]:.6f} {offset[2]:.6f}",
                      f"{pad}  CHANNELS {len(chans)} {' '.join(chans)}"])
        columns.append(j)
        for child in np.flatnonzero(topo.PARENTS == j):
            joint(int(child), depth + 1)
        lines.append(f"{pad}}}")

    joint(0, 0)
    data = []
    for j in columns:
        r = rotating_of_joint[j]
        parent = topo.PARENTS[j]
        local = world[:, r] if parent < 0 else world[:, rotating_of_joint[parent]].transpose(0, 2, 1) @ world[:, r]
        euler = Rotation.from_matrix(local).as_euler(WRITE_ORDER, degrees=True)
        data.append(np.concatenate([np.tile(positions[0], (len(local), 1)), euler], 1) if parent < 0 else euler)
    return _write_bvh(path, lines, motion, data)



def _rig_tree(skeleton: RigSkeleton, hand: HandModel) -> tuple[list[int], np.ndarray]:
    """The bones to write (the wrist, everything under it, the mapped and palm bones) parents first, and
    each one's parent among them (-1 for the wrist). A bone whose file parent is outside (a flat
    hierarchy, as in WebXR) hangs from its finger's previous joint, a palm bone from the wrist."""
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    joints = hand.meta["rig_joints"]
    wrist = lookup[joints["wrist"]]
    chosen = {wrist} | {lookup[b] for b in joints.values()} | {lookup[b] for b in hand.meta.get("palm_bones", [])}
    for bone in range(len(skeleton.names)):
        node = skeleton.parents[bone]
        while node >= 0 and node != wrist:
            node = skeleton.parents[node]
        if node == wrist:
            chosen.add(bone)
    canonical_parent = {lookup[b]: lookup[joints[topo.JOINT_NAMES[topo.PARENTS[topo.joint_index(j)]]]]
                        for j, b in joints.items() if j != "wrist"}
    parent = np.full(len(skeleton.names), -1)
    for bone in chosen - {wrist}:
        node = skeleton.parents[bone]
        while node >= 0 and node not in chosen:
            node = skeleton.parents[node]
        parent[bone] = node if node >= 0 else canonical_parent.get(bone, wrist)
    order, placed = [wrist], {wrist}
    while len(order) < len(chosen):
        for bone in sorted(chosen - placed):
            if parent[bone] in placed:
                order.append(bone)
                placed.add(bone)
    return order, parent


def _save_rig_bvh(path: Path, motion: Motion, hand: HandModel, skeleton: RigSkeleton) -> Path:
    """BVH of ``motion`` on the rig ``skeleton`` the hand was read from (see `save_bvh`)."""
    from s2h_viewer.io.rig import rotation_part

    order, parent = _rig_tree(skeleton, hand)
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    rest_rot = rotation_part(skeleton.world)
    rest_pos = skeleton.world[:, :3, 3]
    wrist = order[0]
    hand_rot = world_rotations_from_motion(hand, motion)  # (T, 16, 3, 3) in the rig's wrist frame
    delta = {wrist: np.broadcast_to(np.eye(3), (motion.n_frames, 3, 3))}  # world rotation from rest, per bone
    rotating = {lookup[hand.meta["rig_joints"][topo.JOINT_NAMES[j]]]: r for r, j in enumerate(topo.ROTATING_JOINTS)}
    for bone in order[1:]:
        if bone in rotating:
            delta[bone] = rest_rot[wrist] @ hand_rot[:, rotating[bone]] @ rest_rot[bone].T
        else:  # unmapped bones (palm, tips, twist bones) follow their parent rigidly
            delta[bone] = delta[parent[bone]]
    children = {b: [c for c in order if parent[c] == b] for b in order}
    lines, data = ["HIERARCHY"], []

    def write(bone: int, depth: int) -> None:
        pad = "  " * depth
        offset = rest_pos[bone] - (rest_pos[parent[bone]] if parent[bone] >= 0 else 0.0)
        root = parent[bone] < 0
        chans = (["Xposition", "Yposition", "Zposition"] if root else []) + [f"{a}rotation" for a in WRITE_ORDER]
        lines.extend([f"{pad}{'ROOT' if root else 'JOINT'} {skeleton.names[bone]}", f"{pad}{{",
                      f"{pad}  OFFSET {offset[0]:.9f} {offset[1]:.9f} {offset[2]:.9f}",  # file units: metres too
                      f"{pad}  CHANNELS {len(chans)} {' '.join(chans)}"])
        local = delta[bone] if root else delta[parent[bone]].transpose(0, 2, 1) @ delta[bone]
        euler = Rotation.from_matrix(local).as_euler(WRITE_ORDER, degrees=True)
        data.append(np.concatenate([np.tile(rest_pos[bone], (motion.n_frames, 1)), euler], 1) if root else euler)
        for child in children[bone]:
            write(child, depth + 1)
        if not children[bone]:  # an end site half a bone beyond a leaf bone, along it
            tail = 0.5 * offset
            lines.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET {tail[0]:.9f} {tail[1]:.9f} "
                                                          f"{tail[2]:.9f}", f"{pad}  }}"])
        lines.append(f"{pad}}}")

    write(wrist, 0)
    to_file = rest_rot[wrist]  # hand space -> the written file's (a BVH hand's space is its world axes)
    if hand.meta.get("side") == "left":  # both hands mirrored to right ones on load
        s = reflection(MIRROR_NORMAL)
        to_file = s @ to_file @ s
    return save_hand_frames(_write_bvh(path, lines, motion, data), hand, to_file)


def _write_bvh(path: Path, hierarchy: list[str], motion: Motion, channels: list[np.ndarray]) -> Path:
    """The HIERARCHY lines, then the MOTION section of per-joint channel columns, written atomically."""
    values = np.concatenate(channels, axis=1)
    lines = hierarchy + ["MOTION", f"Frames: {motion.n_frames}", f"Frame Time: {1.0 / motion.fps:.8f}"]
    lines += [" ".join(f"{v:.6f}" for v in row) for row in values]
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    return path
