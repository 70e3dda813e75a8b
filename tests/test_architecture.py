"""The architecture DESIGN.md fixes: the core imports no Qt (only app/ and widgets/ do), only batch/ imports Dask,
and the commands that need neither torch nor a window start without them."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path


def test_core_imports_no_qt():
    code = ("import sys, s2h_viewer.cli, s2h_viewer.io.files, s2h_viewer.retarget.comparison, "
            "s2h_viewer.render.offscreen, s2h_viewer.render.video, s2h_viewer.annotate.report; "
            "print(sorted(m for m in sys.modules if m.startswith(('PySide6', 'pyvistaqt', 'qtpy'))))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


def _imports(code: str, prefixes: tuple[str, ...]) -> list[str]:
    """The modules starting with ``prefixes`` that running ``code`` in a fresh interpreter has imported."""
    done = subprocess.run([sys.executable, "-c", f"import sys; {code}; print(sorted({{m.split('.')[0] for m in "
                                                 f"sys.modules if m.startswith({prefixes!r})}}))"],
                          capture_output=True, text=True, check=True)
    return eval(done.stdout.strip())


def test_only_the_batch_package_imports_dask():
    everything_else = ("import s2h_viewer.cli, s2h_viewer.io.files, s2h_viewer.retarget, s2h_viewer.render.offscreen, "
                       "s2h_viewer.batch.plan, s2h_viewer.batch.task, s2h_viewer.batch.runner, s2h_viewer.app.main_window")
    assert _imports(everything_else, ("dask", "distributed")) == []
    assert _imports("import s2h_viewer.batch.cluster", ("dask", "distributed")) == ["dask", "distributed"]


def test_help_and_rig_recognition_start_without_torch_vtk_or_qt():
    # `s2h --help` and `s2h rig FILE` pay only for what they use (issue 23: 4.2 s and 4.4 s, mostly torch)
    heavy = ("torch", "vtkmodules", "pyvista", "PySide6", "trimesh")
    assert _imports("import s2h_viewer.cli as c; c.build_parser()", heavy) == []
    rig = str(Path(__file__).parents[1] / "assets" / "hands" / "real" / "godot_hand_r.gltf")
    assert _imports(f"from s2h_viewer.io.files import recognise_file; recognise_file({rig!r})", heavy) == []
