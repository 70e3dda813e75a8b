"""Run by the Blender venv's Python (`make blender`: bpy from PyPI, its own venv, numpy < 2): import a GLB, BVH or
FBX into an empty Blender scene, as a user's File > Import does, and write every armature bone's name, parent and
world rotation per frame (quaternions w, x, y, z) at rest and over the animation to a JSON file.

    .venv-blender/bin/python scripts/blender_readback.py [--fps FPS] IN.glb|IN.bvh|IN.fbx OUT.json [IN OUT ...]

Each IN is imported into a scene of its own and written to the OUT after it (one Blender start for many files).
FPS (default 30) is the scene's frame rate while a glTF is imported: its keys land on Blender frames at it.

Imports bpy only: nothing of s2h_viewer (whose numpy is not Blender's).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import bpy


def import_file(path: Path, fps: int) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.fps, bpy.context.scene.render.fps_base = fps, 1.0
    if path.suffix.lower() in (".glb", ".gltf", ".vrm"):
        bpy.ops.import_scene.gltf(filepath=str(path))
    elif path.suffix.lower() == ".bvh":
        bpy.ops.import_anim.bvh(filepath=str(path), update_scene_fps=True, update_scene_duration=True)
    elif path.suffix.lower() == ".fbx":
        bpy.ops.import_scene.fbx(filepath=str(path))
    else:
        raise SystemExit(f"{path}: not a GLB, BVH or FBX")


def frame_range(armature) -> tuple[int, int]:
    action = armature.animation_data.action if armature.animation_data else None
    if action is None:
        return 0, 0
    start, end = action.frame_range
    return int(round(start)), int(round(end))


def read_back(path: Path, fps: int) -> dict:
    import_file(path, fps)
    armature = next(o for o in bpy.context.scene.objects if o.type == "ARMATURE")
    scene = bpy.context.scene
    start, end = frame_range(armature)
    bones = list(armature.pose.bones)
    rest = {b.name: list((armature.matrix_world @ b.bone.matrix_local).to_quaternion()) for b in bones}
    frames = {b.name: [] for b in bones}
    for frame in range(start, end + 1):
        scene.frame_set(frame)
        for b in bones:
            frames[b.name].append(list((armature.matrix_world @ b.matrix).to_quaternion()))
    return {"file": path.name, "fps": scene.render.fps / scene.render.fps_base, "first_frame": start,
            "bones": [b.name for b in bones],
            "parents": [b.parent.name if b.parent else None for b in bones],
            "rest": rest, "frames": frames}


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description="Blender's reading of GLB, BVH and FBX files, as JSON")
    parser.add_argument("--fps", type=int, default=30, help="the scene's frame rate while a glTF is imported")
    parser.add_argument("files", nargs="+", type=Path, metavar="IN OUT", help="pairs: a file to import, its JSON")
    args = parser.parse_args(argv)
    if len(args.files) % 2:
        parser.error("files come in pairs: IN OUT [IN OUT ...]")
    for source, out in zip(args.files[::2], args.files[1::2]):
        out.write_text(json.dumps(read_back(source, args.fps)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
