"""FBX out: the GLB s2h writes (the avatar's own rig, its hand animated: `io.gltf.save_gltf_motion`) converted by
Blender's FBX exporter (`io.blender`), written atomically. No TBS sidecar goes beside it: Blender re-orients bones
on the way, and a reopened FBX gets its frames from the ray solver."""

from __future__ import annotations

import tempfile
from pathlib import Path

from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.io.blender import run_blender


def save_fbx_motion(path: str | Path, motion: Motion, hand: HandModel) -> Path:
    """Write ``motion`` on ``hand`` as an FBX through Blender; an `InputFileError` naming ``path`` (nothing written)
    when Blender is not installed or fails."""
    from s2h_viewer.io.gltf import save_gltf_motion
    path = Path(path)
    with tempfile.TemporaryDirectory(prefix="s2h-fbx-out-") as tmp:
        glb = save_gltf_motion(Path(tmp) / f"{path.stem}.glb", motion, hand)
        fbx = Path(tmp) / f"{path.stem}.fbx"
        run_blender("gltf_to_fbx", str(glb), str(fbx), str(int(round(motion.fps))), for_file=path)
        with atomic_path(path) as out:
            out.write_bytes(fbx.read_bytes())
    return path
