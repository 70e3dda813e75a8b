"""Regenerate the README's screenshots of the real window (needs an X display; `make screenshots`
starts Xvfb without one):

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python scripts/make_screenshots.py

docs/compare_mode.png: the default samples at frame 120; docs/annotation_mode.png: the WebXR hand
solved, its middle PIP selected.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from PySide6.QtWidgets import QApplication

from s2h_viewer.app.scripted import scripted_window, wait_for
from s2h_viewer.samples import ASSETS_DIR

DOCS = Path(__file__).resolve().parent.parent / "docs"


def settle() -> None:
    """Let Qt lay out and paint before a grab."""
    for _ in range(20):
        QApplication.processEvents()


def main() -> None:
    with scripted_window() as window, tempfile.TemporaryDirectory() as tmp:
        window.timeline.set_frame(120)
        settle()
        window.grab().save(str(DOCS / "compare_mode.png"))

        hand = shutil.copy(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb", Path(tmp))
        window.annotate_file(str(hand))
        window.run_solver()
        wait_for(window.annotation_ready)
        window.annotate_view.select(7)  # middle_pip
        settle()
        window.grab().save(str(DOCS / "annotation_mode.png"))
    print(f"wrote {DOCS / 'compare_mode.png'} and {DOCS / 'annotation_mode.png'}")


if __name__ == "__main__":
    main()
