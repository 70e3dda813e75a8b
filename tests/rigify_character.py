"""A Rigify character written by Blender (scripts/rigify_hands.py, run by the Blender venv's Python): a rig from a
Blender user's own tools, for the tests that read it and that read our exports of it back in Blender."""

from __future__ import annotations

import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BLENDER_PYTHON = ROOT / ".venv-blender" / "bin" / "python"


def rigify_character(folder: Path, suffix: str) -> Path:
    """``folder``/rigify_character.<suffix> (glb or fbx), written by Blender's exporter of that format."""
    path = folder / f"rigify_character.{suffix}"
    done = subprocess.run([str(BLENDER_PYTHON), str(ROOT / "scripts" / "rigify_hands.py"), str(path)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0 and path.exists(), done.stderr[-2000:]
    return path
