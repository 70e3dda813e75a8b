"""The real window driven by a script (README screenshots, the window benchmark): the main window on
the shipped samples with throwaway settings, and a wait on its threaded work."""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from PySide6.QtCore import QEventLoop, QSettings, QTimer
from PySide6.QtWidgets import QApplication

from s2h_viewer.app.main_window import MainWindow, default_setup


def wait_for(signal=None, seconds: float = 300.0) -> None:
    """Run the event loop until ``signal`` fires or ``seconds`` pass."""
    loop = QEventLoop()
    if signal is not None:
        signal.connect(loop.quit)
    QTimer.singleShot(int(seconds * 1000), loop.quit)
    loop.exec()


def settle() -> None:
    """Let Qt lay out and paint (the 3D view renders in its paint) before a grab."""
    for _ in range(20):
        QApplication.processEvents()


def screen_image(window, path: str | Path) -> None:
    """Save what the X server shows of ``window`` (dialogs and tooltips over it included), once the
    X server's expose events (a dialog just closed) are drawn."""
    from PIL import ImageGrab
    wait_for(seconds=0.5)
    settle()
    top_left = window.mapToGlobal(window.rect().topLeft())
    ImageGrab.grab(bbox=(top_left.x(), top_left.y(), top_left.x() + window.width(),
                         top_left.y() + window.height())).save(str(path))


@contextmanager
def scripted_window(size: tuple[int, int] = (1400, 900)) -> Iterator[MainWindow]:
    """The main window on the shipped samples, shown, its comparison ready; the user's settings untouched."""
    QApplication.instance() or QApplication(sys.argv)
    with tempfile.TemporaryDirectory() as tmp:
        window = MainWindow(default_setup(), QSettings(str(Path(tmp) / "settings.ini"), QSettings.Format.IniFormat))
        window.resize(*size)
        window.show()
        window.start_comparison()
        wait_for(window.comparison_ready)
        try:
            yield window
        finally:
            window.undo_stack.clear()  # a script's annotation edits are throwaway: no "save?" question
            window.compare.fixing.forget_unsaved()  # and so are its corrections
            window.close()
