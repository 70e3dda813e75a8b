"""A Rigify character written by Blender (scripts/rigify_hands.py, run by the Blender venv's Python): a rig from a
Blender user's own tools, for the tests that read it and that read our exports of it back in Blender."""

from __future__ import annotations

import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BLENDER_PYTHON = ROOT / ".venv-blender" / "bin" / "python"


def rigify_characters(folder: Path, suffixes: tuple[str, ...] = ("glb", "fbx")) -> dict[str, Path]:
    """Per suffix (glb, fbx), ``folder``/rigify_character.<suffix>, written by Blender's exporter of that format: one
    character, made once (Rigify's generation: some 15 s)."""
    paths = {suffix: folder / f"rigify_character.{suffix}" for suffix in suffixes}
    done = subprocess.run([str(BLENDER_PYTHON), str(ROOT / "scripts" / "rigify_hands.py"), *map(str, paths.values())],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0 and all(p.exists() for p in paths.values()), done.stderr[-2000:]
    return paths
