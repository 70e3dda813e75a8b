"""Blender as a subprocess: the FBX writer s2h does not have. Blender (bpy on PyPI: Python 3.11, numpy < 2) lives
in a venv of its own (`make blender` makes ``.venv-blender`` in a checkout; ``S2H_BLENDER_PYTHON`` names another),
and runs the scripts in `io.blender_scripts`, which import bpy only."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from s2h_viewer.errors import InputFileError

CHECKOUT_VENV = Path(__file__).resolve().parents[2] / ".venv-blender" / "bin" / "python"
SCRIPTS = Path(__file__).resolve().parent / "blender_scripts"
RUN_TIMEOUT_S = 600


def blender_python() -> Path | None:
    """The Python with bpy: ``S2H_BLENDER_PYTHON`` where set, else the checkout's ``.venv-blender``; None if neither
    is there."""
    named = os.environ.get("S2H_BLENDER_PYTHON")
    path = Path(named) if named else CHECKOUT_VENV
    return path if path.is_file() else None


def require_blender(for_file: Path) -> Path:
    """`blender_python`, or an `InputFileError` naming ``for_file`` that says how to get it."""
    python = blender_python()
    if python is None:
        raise InputFileError(for_file, "writing FBX goes through Blender, which is not installed here: run `make "
                                       "blender` (or set S2H_BLENDER_PYTHON to a Python with bpy), or write .glb, "
                                       "which Blender, Unity and Unreal import")
    return python


def run_blender(script: str, *args: str, for_file: Path) -> None:
    """Run ``io/blender_scripts/<script>.py`` with ``args`` in Blender; an `InputFileError` naming ``for_file``
    when Blender is not installed or the script fails."""
    python = require_blender(for_file)
    try:
        done = subprocess.run([str(python), str(SCRIPTS / f"{script}.py"), *args], capture_output=True, text=True,
                              timeout=RUN_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        raise InputFileError(for_file, f"Blender took over {RUN_TIMEOUT_S} s; gave up") from None
    if done.returncode != 0:
        last = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else f"exit status {done.returncode}"
        raise InputFileError(for_file, f"Blender could not write it ({last})")
