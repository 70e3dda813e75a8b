"""FBX in (ufbx): a rigged hand or one hand of a character, and its takes as motion.

ufbx converts units to metres and reads the bind pose; it runs in a child process (`fbx_scene`).
FBX out goes through Blender (`fbx_export`).
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from s2h_viewer.errors import InputFileError, reading, require_readable_file
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.rig import RigMesh, RigSkeleton, bone_indices, build_hand, motion_from_world_rotations, recognise

READ_TIMEOUT_S = 300


def _read(path: Path, fps: float = 30.0) -> tuple[RigSkeleton, RigMesh | None, list[tuple[str, np.ndarray]]]:
    """Skeleton, skinned mesh and takes (name, (T, N, 3, 3) world rotations) of an FBX file, read by
    `fbx_scene` in a child process (see there why)."""
    require_readable_file(path)
    with tempfile.TemporaryDirectory(prefix="s2h-fbx-") as tmp:
        out = Path(tmp) / "scene.npz"
        try:
            done = subprocess.run([sys.executable, "-m", "s2h_viewer.io.fbx_scene", str(path), str(out), str(fps)],
                                  capture_output=True, text=True, timeout=READ_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            raise InputFileError(path, f"reading it took over {READ_TIMEOUT_S} s; gave up") from None
        if done.returncode != 0 or not out.exists():
            why = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else f"exit status {done.returncode}"
            if done.returncode < 0:
                why = f"the FBX library crashed reading it (signal {-done.returncode})"
            raise InputFileError(path, f"not a readable FBX file ({why})")
        with np.load(out) as arrays:
            data = {k: arrays[k] for k in arrays.files}
    names = json.loads(str(data["names_json"]))
    if not np.isfinite(data["world"]).all():
        raise InputFileError(path, "bone transforms contain NaN or infinite values")
    skeleton = RigSkeleton(names, data["world"], data["parents"])
    mesh = None
    if "mesh_vertices" in data:
        mesh = RigMesh(data["mesh_vertices"], data["mesh_faces"], data["mesh_bone_index"], data["mesh_bone_weight"])
    takes = [(name, data[f"take_{t}"]) for t, name in enumerate(json.loads(str(data["take_names_json"])))]
    return skeleton, mesh, takes


def load_fbx_hand(path: str | Path, side: str | None = None, scheme: str | None = None,
                  joint_map: dict[str, str] | None = None, name: str | None = None, unit: str | None = None,
                  hinges_from: str | Path | None = None) -> HandModel:
    """The hand of an FBX file (a lone hand or one hand of a character), annotated, as a right hand; the
    solver's frames checked against the hinges of its own takes, or of ``hinges_from``'s (`annotate.hinges`)."""
    path = Path(path)
    with reading(path, "an FBX hand"):
        skeleton, mesh, takes = _read(path)
        if not skeleton.names:
            raise InputFileError(path, "has no nodes (no skeleton)")
        return build_hand(path, skeleton, recognise(skeleton, path, side, scheme, joint_map), mesh, name, unit,
                          hinge_evidence=hinges_from or (path if takes else None))


def list_fbx_takes(path: str | Path) -> list[str]:
    """The names of the file's animation takes, in file order."""
    return [name for name, _ in _read(Path(path))[2]]


def load_fbx_motion(path: str | Path, hand: HandModel, take: str | int | None = None, fps: float = 30.0) -> Motion:
    """Take ``take`` (name or index; the first by default) of the file, sampled at ``fps``, as finger
    rotations on ``hand``."""
    path = Path(path)
    with reading(path, "an FBX take"):
        return _take_motion(path, hand, take, fps)


def _take_motion(path: Path, hand: HandModel, take: str | int | None, fps: float) -> Motion:
    from s2h_viewer.io.gltf import clip_name, pick_animation  # the one rule for picking and naming an animation

    skeleton, _, takes = _read(path, fps)
    index = pick_animation([name for name, _ in takes], take, path, "take")
    rotating = bone_indices(skeleton.names, hand, path)
    name, world = takes[index]
    return motion_from_world_rotations(hand, world[:, rotating], fps, path, clip_name(name, path, index))
