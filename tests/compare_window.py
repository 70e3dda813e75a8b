"""The compare window both GUI test modules open: a short clip on birch, iris as the target, TBS Copy
and ASRN, its settings in a temporary file, shown and with its first comparison computed."""

from __future__ import annotations

from PySide6.QtCore import QSettings

from s2h_viewer.app.main_window import CompareSetup, MainWindow
from s2h_viewer.motions.synthesis import synthesize


def open_compare_window(qtbot, sample_hands, tmp_path) -> MainWindow:
    motion = synthesize(["fist", "ok", "v_sign"], sample_hands["birch"], seed=4, name="short")
    setup = CompareSetup(motion, sample_hands["birch"], [sample_hands["iris"]], ["tbs_copy", "asrn"])
    settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
    settings.setValue("compare/methods", ["tbs_copy", "asrn"])
    win = MainWindow(setup, settings)
    win.resize(1000, 700)
    qtbot.addWidget(win, before_close_func=lambda w: w.undo_stack.clear())  # closed without a "save?" question
    win.show()
    with qtbot.waitSignal(win.comparison_ready, timeout=120_000):
        win.start_comparison()
    return win
