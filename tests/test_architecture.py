"""The architecture DESIGN.md fixes: the core imports no Qt (only app/ and widgets/ do)."""

from __future__ import annotations

import subprocess
import sys


def test_core_imports_no_qt():
    code = ("import sys, s2h_viewer.cli, s2h_viewer.io.files, s2h_viewer.retarget.comparison, "
            "s2h_viewer.render.offscreen, s2h_viewer.render.video, s2h_viewer.annotate.report; "
            "print(sorted(m for m in sys.modules if m.startswith(('PySide6', 'pyvistaqt', 'qtpy'))))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
