"""One entry point per direction, by file suffix: hands and motions in, retargeted motion out.

Hands: ``.npz`` (the project's), ``.glb``/``.gltf``, ``.fbx``, ``.bvh`` (skeleton only), or the name
of a shipped sample hand. Motions: ``.npz``, ``.bvh``, ``.glb``/``.gltf`` animation, ``.fbx`` take.
Retargeted motion out: ``.npz``, ``.bvh``, ``.glb``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from s2h_viewer.errors import InputFileError, reading, require_readable_file
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rig_mapping import load_user_mapping

HAND_SUFFIXES = (".npz", ".glb", ".gltf", ".fbx", ".bvh")
MOTION_SUFFIXES = (".npz", ".bvh", ".glb", ".gltf", ".fbx")
EXPORT_SUFFIXES = (".npz", ".bvh", ".glb")


@dataclass(frozen=True)
class RigOptions:
    """How to read a rig: which hand of a character, which naming scheme, or a user joint map."""

    side: str = "right"
    scheme: str | None = None
    joint_map: str | Path | None = None

    def mapping(self) -> dict[str, str] | None:
        return load_user_mapping(self.joint_map) if self.joint_map else None


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
    if suffix in (".glb", ".gltf"):
        from s2h_viewer.io.gltf import load_gltf_hand
        return load_gltf_hand(path, options.side, options.scheme, options.mapping())
    if suffix == ".fbx":
        from s2h_viewer.io.fbx import load_fbx_hand
        return load_fbx_hand(path, options.side, options.scheme, options.mapping())
    from s2h_viewer.io.bvh import load_bvh
    return load_bvh(path, options.side, options.scheme, options.mapping())[0]


def load_motion_file(path: str | Path, hand: HandModel | None = None, options: RigOptions = RigOptions()
                     ) -> tuple[Motion, HandModel | None]:
    """A motion and the hand it is performed on: the file's own rig for BVH/glTF/FBX (``hand`` may be
    given to skip re-reading it), None for an npz (its ``hand_name`` names a sample hand)."""
    path = Path(path)
    suffix = _suffix(require_readable_file(path), MOTION_SUFFIXES, "motion")
    with reading(path, "a motion"):
        return _load_motion(path, suffix, hand, options)


def _load_motion(path: Path, suffix: str, hand: HandModel | None, options: RigOptions
                 ) -> tuple[Motion, HandModel | None]:
    if suffix == ".npz":
        from s2h_viewer.io.npz import load_motion
        return load_motion(path), hand
    if suffix == ".bvh":
        from s2h_viewer.io.bvh import load_bvh
        rig, motion = load_bvh(path, options.side, options.scheme, options.mapping())
        return motion, rig
    rig = hand or _load_hand(path, suffix, options)
    if suffix in (".glb", ".gltf"):
        from s2h_viewer.io.gltf import load_gltf_motion
        return load_gltf_motion(path, rig), rig
    from s2h_viewer.io.fbx import load_fbx_motion
    return load_fbx_motion(path, rig), rig


def save_motion_file(path: str | Path, motion: Motion, hand: HandModel) -> Path:
    """Write ``motion`` (on ``hand``) as npz, BVH or GLB, chosen by suffix, atomically."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise InputFileError(path, f"cannot write motion as {suffix or 'a suffix-less file'}; "
                                   f"use {', '.join(EXPORT_SUFFIXES)}")
    if suffix == ".npz":
        from s2h_viewer.io.npz import save_motion
        return save_motion(motion, path)
    if suffix == ".bvh":
        from s2h_viewer.io.bvh import save_bvh
        return save_bvh(path, motion, hand)
    from s2h_viewer.io.gltf import save_gltf_motion
    return save_gltf_motion(path, motion, hand)
