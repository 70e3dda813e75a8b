"""Regenerate the README's screenshots of the real window (needs an X display; Xvfb will do):

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python scripts/make_screenshots.py

docs/compare_mode.png: the default samples at frame 120; docs/annotation_mode.png: the WebXR hand
solved, its middle PIP selected. Settings go to a throwaway file, never the user's.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

from PySide6.QtCore import QEventLoop, QSettings, QTimer
from PySide6.QtWidgets import QApplication

from s2h_viewer.app.main_window import MainWindow, default_setup
from s2h_viewer.samples import ASSETS_DIR

DOCS = Path(__file__).resolve().parent.parent / "docs"


def wait_for(signal, seconds: float = 300) -> None:
    """Run the event loop until ``signal`` fires (the window's work runs in threads)."""
    loop = QEventLoop()
    signal.connect(loop.quit)
    QTimer.singleShot(int(seconds * 1000), loop.quit)
    loop.exec()


def settle() -> None:
    """Let Qt lay out and paint before a grab."""
    for _ in range(20):
        QApplication.processEvents()


def main() -> None:
    app = QApplication.instance() or QApplication(sys.argv)
    with tempfile.TemporaryDirectory() as tmp:
        window = MainWindow(default_setup(), QSettings(str(Path(tmp) / "settings.ini"), QSettings.Format.IniFormat))
        window.resize(1400, 900)
        window.show()
        window.start_comparison()
        wait_for(window.comparison_ready)
        window.timeline.set_frame(120)
        settle()
        window.grab().save(str(DOCS / "compare_mode.png"))

        hand = shutil.copy(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb", Path(tmp) / "generic-hand-right.glb")
        window.annotate_file(str(hand))
        window.run_solver()
        wait_for(window.annotation_ready)
        window.annotate_view.select(7)  # middle_pip
        settle()
        window.grab().save(str(DOCS / "annotation_mode.png"))
        window.close()
    app.quit()
    print(f"wrote {DOCS / 'compare_mode.png'} and {DOCS / 'annotation_mode.png'}")


if __name__ == "__main__":
    main()
