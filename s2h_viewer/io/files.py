"""One entry point per direction, by file suffix: hands and motions in, retargeted motion out.

Hands: ``.npz`` (the project's), ``.glb``/``.gltf``, ``.fbx``, ``.bvh`` (skeleton only), or the name
of a shipped sample hand. Motions: ``.npz``, ``.bvh``, ``.glb``/``.gltf`` animation, ``.fbx`` take, and
tracking recordings (WebXR/OpenXR or MediaPipe ``.json``, keypoint ``.npy``/``.npz``: `io.recordings`),
which come with a source hand fitted to them (`tracking.fitter`).
Retargeted motion out: ``.npz``, ``.bvh``, ``.glb``, and ``.fbx`` through Blender (`io.fbx_export`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path

from s2h_viewer.errors import InputFileError, reading, require_readable_file
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rig_mapping import load_user_mapping, sides_named

HAND_SUFFIXES = (".npz", ".glb", ".gltf", ".vrm", ".fbx", ".bvh")
MOTION_SUFFIXES = (".npz", ".bvh", ".glb", ".gltf", ".vrm", ".fbx", ".json", ".npy")
GLTF_FAMILY = (".glb", ".gltf", ".vrm")  # a .vrm is a GLB with a VRM extension
ANIMATED_SUFFIXES = (*GLTF_FAMILY, ".fbx")  # motion files of animations (takes), any number of them
EXPORT_SUFFIXES = (".npz", ".bvh", ".glb", ".fbx")
#: ``RigOptions.animation`` for every animation of a file in turn, as one clip labelled by animation
ALL_ANIMATIONS = "all"


JOINT_MAP_SUFFIX = ".joints.json"
#: a joint-map template `s2h rig` writes for the user to fill: named so that nothing loads it until it is
#: filled in and saved as the sidecar (or passed with --joint-map)
JOINT_MAP_TEMPLATE_SUFFIX = ".joints.template.json"


def joint_map_template_path(hand_file: str | Path) -> Path:
    """``<stem>.joints.template.json`` beside a hand file: where `s2h rig` writes a template to fill."""
    hand_file = Path(hand_file)
    return hand_file.with_name(f"{hand_file.stem}{JOINT_MAP_TEMPLATE_SUFFIX}")


def joint_map_sidecar(hand_file: str | Path, side: str) -> Path:
    """``<stem>.<side>.joints.json`` beside a hand file: the joint map of its ``side`` hand, picked up like the
    TBS sidecar."""
    hand_file = Path(hand_file)
    return hand_file.with_name(f"{hand_file.stem}.{side}{JOINT_MAP_SUFFIX}")


def legacy_joint_map_sidecar(hand_file: str | Path) -> Path:
    """``<stem>.joints.json``: where s2h before per-hand maps saved a file's one joint map."""
    hand_file = Path(hand_file)
    return hand_file.with_name(f"{hand_file.stem}{JOINT_MAP_SUFFIX}")


def saved_joint_map(hand_file: str | Path, side: str | None) -> tuple[dict[str, str], str | None] | None:
    """The joint map saved beside ``hand_file`` for its ``side`` hand (None: the right one's, else the left
    one's) and the side it maps, else the older side-less ``<stem>.joints.json`` (side None) unless its bones'
    names mark the other side, else None."""
    for one in ((side,) if side else ("right", "left")):
        if joint_map_sidecar(hand_file, one).exists():
            return load_user_mapping(joint_map_sidecar(hand_file, one)), one
    legacy = legacy_joint_map_sidecar(hand_file)
    if not legacy.exists():
        return None
    mapping = load_user_mapping(legacy)
    named = sides_named(list(mapping.values()))
    return None if side is not None and named and side not in named else (mapping, None)


def save_joint_map(hand_file: str | Path, mapping: dict[str, str], side: str, path: str | Path | None = None
                   ) -> Path:
    """Write ``mapping`` (of ``hand_file``'s ``side`` hand) atomically to ``path`` (default: that hand's
    sidecar, where loading the hand looks for it); returns the path written."""
    path = joint_map_sidecar(hand_file, side) if path is None else Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(mapping, indent=2) + "\n")
    return path


@dataclass(frozen=True)
class RigOptions:
    """How to read a rig: which hand (None: as names or geometry say), which naming scheme, a user joint
    map (a JSON file or a dict; else the file's own ``<stem>.<side>.joints.json`` if there is one), which
    animation or take; a tracking recording's frame rate where the file has none (keypoint arrays); the
    rig's length unit where the file's is wrong or missing."""

    side: str | None = None
    scheme: str | None = None
    joint_map: str | Path | dict[str, str] | None = None
    animation: str | int | None = None
    fps: float | None = None
    unit: str | None = None  # the rig's length unit (`io.units.UNITS`); None: the format's, else guessed
    #: a motion file on the rig's skeleton whose animations give each joint's hinge (`annotate.hinges`);
    #: None: the rig file's own animations, if it has any
    hinges_from: str | Path | None = None

    def for_file(self, hand_file: str | Path) -> "RigOptions":
        """These options with the joint map to use on ``hand_file`` as a dict: the user's, else the one saved
        beside the file for the side asked (`saved_joint_map`, whose side is then the side), else None
        (recognise the rig)."""
        if isinstance(self.joint_map, dict):
            return replace(self, joint_map=dict(self.joint_map))
        if self.joint_map:
            return replace(self, joint_map=load_user_mapping(self.joint_map))
        saved = saved_joint_map(hand_file, self.side)
        if saved is None:
            return self
        return replace(self, joint_map=saved[0], side=self.side or saved[1])


def _suffix(path: Path, allowed: tuple[str, ...], what: str) -> str:
    suffix = path.suffix.lower()
    if suffix not in allowed:
        raise InputFileError(path, f"cannot read a {what} from a {suffix or 'suffix-less'} file; "
                                   f"use {', '.join(allowed)}")
    return suffix


def load_hand_file(path: str | Path, options: RigOptions = RigOptions()) -> HandModel:
    """A hand from a file (see the module docstring), or a shipped sample hand by name."""
    path = Path(path)
    if path.suffix == "" and not path.exists():
        from s2h_viewer.samples import load_sample_hand
        return load_sample_hand(str(path))
    suffix = _suffix(require_readable_file(path), HAND_SUFFIXES, "hand")
    with reading(path, "a hand"):
        return _load_hand(path, suffix, options)


def _load_hand(path: Path, suffix: str, options: RigOptions) -> HandModel:
    if suffix == ".npz":
        from s2h_viewer.io.npz import load_hand
        return load_hand(path)
    o = options.for_file(path)
    if suffix in GLTF_FAMILY:
        from s2h_viewer.io.gltf import load_gltf_hand
        return load_gltf_hand(path, o.side, o.scheme, o.joint_map, unit=o.unit, hinges_from=o.hinges_from)
    if suffix == ".fbx":
        from s2h_viewer.io.fbx import load_fbx_hand
        return load_fbx_hand(path, o.side, o.scheme, o.joint_map, unit=o.unit, hinges_from=o.hinges_from)
    from s2h_viewer.io.bvh import load_bvh
    return load_bvh(path, o.side, o.scheme, o.joint_map, unit=o.unit)[0]


def load_motion_file(path: str | Path, hand: HandModel | None = None, options: RigOptions = RigOptions()
                     ) -> tuple[Motion, HandModel | None]:
    """A motion and the hand it is performed on: the file's own rig for BVH/glTF/FBX, the hand fitted to a
    tracking recording (the motion's ``fit`` holds the keypoints and residual), None for an npz (its
    ``hand_name`` names a sample hand). ``hand``: the rig it was made for, where the file's skeleton lacks one
    (no mesh, a rest that is a pose): a glTF/FBX animation is read onto its bones, an npz is performed on it; a
    BVH or a recording has its own skeleton, and giving one is an `InputFileError`."""
    path = Path(path)
    suffix = _suffix(require_readable_file(path), MOTION_SUFFIXES, "motion")
    from s2h_viewer.io.recordings import is_recording
    if hand is not None and (suffix == ".bvh" or is_recording(path)):
        what = "a BVH clip carries its own skeleton" if suffix == ".bvh" else "a recording is fitted a hand of its own"
        raise InputFileError(path, f"{what}: a hand to perform it on (--source / --rig {Path(hand.source).name}) "
                                   f"applies only to npz clips and glTF/FBX animations")
    if is_recording(path):
        from s2h_viewer.io.recordings import read_recording
        from s2h_viewer.tracking.fitter import fit_recording
        fit = fit_recording(read_recording(path, options.side, options.fps))
        return fit.motion, fit.hand
    with reading(path, "a motion"):
        return _load_motion(path, suffix, hand, options)


def _load_motion(path: Path, suffix: str, hand: HandModel | None, options: RigOptions
                 ) -> tuple[Motion, HandModel | None]:
    if suffix == ".npz":
        from s2h_viewer.io.npz import load_motion
        return load_motion(path), hand
    if suffix == ".bvh":
        from s2h_viewer.io.bvh import load_bvh
        o = options.for_file(path)
        rig, motion = load_bvh(path, o.side, o.scheme, o.joint_map, unit=o.unit)
        return motion, rig
    rig = hand or _load_hand(path, suffix, options)
    if options.animation == ALL_ANIMATIONS:
        return _every_animation(path, suffix, rig), rig
    if suffix in GLTF_FAMILY:
        from s2h_viewer.io.gltf import load_gltf_motion
        return load_gltf_motion(path, rig, options.animation), rig
    from s2h_viewer.io.fbx import load_fbx_motion
    return load_fbx_motion(path, rig, options.animation), rig


def _every_animation(path: Path, suffix: str, rig: HandModel) -> Motion:
    """Every animation (take) of a glTF/FBX file in turn, one clip labelled by animation (`motions.pose_clip`)."""
    from s2h_viewer.motions.pose_clip import concatenate_clips
    if suffix in GLTF_FAMILY:
        from s2h_viewer.io.gltf import load_every_gltf_animation
        clips = load_every_gltf_animation(path, rig)
    else:
        from s2h_viewer.io.fbx import list_fbx_takes, load_fbx_motion
        clips = [load_fbx_motion(path, rig, k) for k in range(len(list_fbx_takes(path)))]
    if not clips:
        raise InputFileError(path, "has no animations")
    return concatenate_clips(clips, f"{path.stem} (every animation)")


def list_animations(path: str | Path) -> list[str]:
    """Names of a motion file's animations (glTF, with their lengths) or takes (FBX), each with the name its clip
    is read as where that is the file's (an exporter's default name: `io.gltf.clip_name`); one unnamed clip for
    BVH, npz and recordings."""
    from s2h_viewer.io.gltf import clip_name, list_gltf_animations
    path = Path(path)
    suffix = _suffix(path, MOTION_SUFFIXES, "motion")
    if suffix in GLTF_FAMILY:
        clips = [(name, [f"{seconds:.2f} s"]) for name, seconds in list_gltf_animations(path)]
    elif suffix == ".fbx":
        from s2h_viewer.io.fbx import list_fbx_takes
        clips = [(name, []) for name in list_fbx_takes(path)]
    else:
        return [path.stem]
    listed = []
    for index, (name, notes) in enumerate(clips):
        read_as = clip_name(name, path, index)
        if read_as != name:
            notes = [*notes, f"read as {read_as}"]
        listed.append(f"{name or '(no name)'}" + (f" ({'; '.join(notes)})" if notes else ""))
    return listed


def check_motion_export(path: str | Path) -> Path:
    """``path`` as a Path, or the `InputFileError` `save_motion_file` would raise for its format: a suffix it cannot
    write, or FBX with no Blender here. Asked before the work that precedes writing (the window's frames question,
    the CLI's retarget), so the user hears it first."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise InputFileError(path, f"cannot write motion as {suffix or 'a suffix-less file'}; "
                                   f"use {', '.join(EXPORT_SUFFIXES)}")
    if suffix == ".fbx":
        from s2h_viewer.io.blender import require_blender
        require_blender(path)
    return path


def save_motion_file(path: str | Path, motion: Motion, hand: HandModel) -> Path:
    """Write ``motion`` (on ``hand``) as npz, BVH, GLB or FBX (through Blender), chosen by suffix, atomically."""
    path = check_motion_export(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        from s2h_viewer.io.npz import save_motion
        return save_motion(motion, path)
    if suffix == ".bvh":
        from s2h_viewer.io.bvh import save_bvh
        return save_bvh(path, motion, hand)
    if suffix == ".fbx":
        from s2h_viewer.io.fbx_export import save_fbx_motion
        return save_fbx_motion(path, motion, hand)
    from s2h_viewer.io.gltf import save_gltf_motion
    return save_gltf_motion(path, motion, hand)


def export_sidecar(path: str | Path, hand: HandModel) -> Path | None:
    """The TBS frames sidecar that `save_motion_file` writes beside a motion on ``hand`` exported to ``path``
    (the BVH and GLB writers do: `io.annotation.save_hand_frames`), None for npz; what an export's report
    names."""
    from s2h_viewer.io.annotation import hand_side, sidecar_path
    path = Path(path)
    return sidecar_path(path, hand_side(hand)) if path.suffix.lower() in (".bvh", ".glb") else None


def read_rig_skeleton(path: str | Path):
    """The `RigSkeleton` (names, rest world matrices, parents) of a glTF, FBX or BVH rig file."""
    path = Path(path)
    suffix = _suffix(path, (*GLTF_FAMILY, ".fbx", ".bvh"), "rig")
    from s2h_viewer.io.rig import RigSkeleton
    if suffix in GLTF_FAMILY:
        from s2h_viewer.io.gltf import read_document
        doc = read_document(path)
        return RigSkeleton(doc.names, doc.world, doc.parents)
    if suffix == ".fbx":
        from s2h_viewer.io.fbx import _read
        return _read(path)[0]
    from s2h_viewer.io.bvh import bvh_skeleton, read_bvh
    return bvh_skeleton(read_bvh(path))


def _recognition_skeleton(path: Path):
    """The skeleton recognition reads: a BVH's with its zero-length bones folded (`io.bvh.fold_zero_length`)."""
    if path.suffix.lower() == ".bvh":
        from s2h_viewer.io.bvh import folded_skeleton, read_bvh
        return folded_skeleton(read_bvh(path))[0]
    return read_rig_skeleton(path)


def rig_unit(path: str | Path, mapping, options: RigOptions = RigOptions()):
    """The `io.units.UnitChoice` a rig file is read in, for its recognised ``mapping`` (what `s2h rig` says)."""
    from s2h_viewer.io.rig import file_unit
    return file_unit(_recognition_skeleton(Path(path)), mapping, path, options.unit,
                     None if Path(path).suffix.lower() == ".bvh" else "m")


def recognise_file(path: str | Path, options: RigOptions = RigOptions()):
    """The `RigMapping` of a rig file's hand (what `s2h rig` reports), without building the hand."""
    path = Path(path)
    from s2h_viewer.io.rig import recognise
    o = options.for_file(path)
    if path.suffix.lower() in GLTF_FAMILY:
        from s2h_viewer.io.gltf import _recognise, read_document
        return _recognise(read_document(path), o.side, o.scheme, o.joint_map)
    if path.suffix.lower() == ".bvh":
        from s2h_viewer.io.bvh import read_bvh, recognise_bvh
        return recognise_bvh(path, read_bvh(path), o.side, o.scheme, o.joint_map)[2]
    return recognise(read_rig_skeleton(path), path, o.side, o.scheme, o.joint_map)


def joint_map_template(path: str | Path, side: str | None = None) -> dict[str, str]:
    """A joint map for a rig file: every joint the names give filled in, the others left empty to edit."""
    from s2h_viewer.hand import topology as topo
    from s2h_viewer.hand.rig_mapping import best_name_match, sides_named

    names = read_rig_skeleton(path).names
    chosen = side or ("left" if sides_named(names) == {"left"} else "right")
    found = best_name_match(names, chosen).joints
    return {joint: found.get(joint, "") for joint in topo.JOINT_NAMES}


def suggested_joint_map(path: str | Path, side: str | None = None) -> dict[str, str]:
    """A joint map to start editing from: the file's sidecar map where it names bones the rig has (a sidecar
    that cannot be read is skipped: it is what is being replaced), the names' guesses (`joint_map_template`)
    elsewhere."""
    template = joint_map_template(path, side)
    try:
        found = saved_joint_map(path, side)
    except InputFileError:
        return template
    if found is None:
        return template
    saved = found[0]
    names = set(read_rig_skeleton(path).names)
    return {joint: saved[joint] if saved.get(joint) in names else bone for joint, bone in template.items()}
