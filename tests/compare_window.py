"""The compare window both GUI test modules open: a short clip on birch, iris as the target (or ``targets``),
TBS Copy and ASRN (or ``methods``), its settings in a temporary file, shown and with its first comparison computed
(or, with ``compute=False``, not yet started). ``repeats`` plays the clip that many times over: a test
that must catch ASM-Opt while it runs (to cancel it, or act beside it) needs seconds of work to catch,
however fast ASM-Opt gets."""

from __future__ import annotations

import copy
import dataclasses
import functools
from collections.abc import Callable

import numpy as np

from PySide6.QtCore import QSettings, QTimer
from PySide6.QtWidgets import QApplication, QWidget

from s2h_viewer.app.main_window import CompareSetup, MainWindow
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.motions.synthesis import synthesize


def open_compare_window(qtbot, sample_hands, tmp_path, methods: tuple[str, ...] = ("tbs_copy", "asrn"),
                        compute: bool = True, repeats: int = 1, targets: tuple[str, ...] = ("iris",)) -> MainWindow:
    motion = copy.deepcopy(short_clip(sample_hands["birch"]))  # a test may change its clip
    if repeats > 1:
        motion = dataclasses.replace(motion, q_tbs=np.tile(motion.q_tbs, (repeats, 1, 1)),
                                     labels=np.tile(motion.labels, repeats))
    setup = CompareSetup(motion, sample_hands["birch"], [sample_hands[name] for name in targets], list(methods))
    return open_window(qtbot, setup, tmp_path, compute=compute)


@functools.lru_cache(maxsize=2)
def short_clip(hand: HandModel) -> Motion:
    """The window's clip, fitted to ``hand`` once per session (the fit took 0.75 of the window's 1.8 s to open)."""
    return synthesize(["fist", "ok", "v_sign"], hand, seed=4, name="short")


def open_window(qtbot, setup: CompareSetup, tmp_path, size: tuple[int, int] = (1000, 700),
                compute: bool = True) -> MainWindow:
    """The window on ``setup``, its settings in a temporary file ticking the setup's methods, shown at ``size``
    and with its first comparison computed (unless ``compute`` is False)."""
    settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
    settings.setValue("compare/methods", list(setup.methods))
    win = MainWindow(setup, settings)
    win.resize(*size)
    qtbot.addWidget(win, before_close_func=lambda w: (  # closed without a "save?" question
        w.undo_stack.clear(), w.compare.fixing.forget_unsaved()))
    win.show()
    if not compute:
        return win
    with qtbot.waitSignal(win.comparison_ready, timeout=120_000):
        win.start_comparison()
    return win


def when_shown(kind: type[QWidget], then: Callable[[QWidget], None]) -> None:
    """Once a window of ``kind`` shows (a modal dialog runs its own loop), call ``then(dialog)``: answer it as a
    user would."""
    def look() -> None:
        shown = next((w for w in QApplication.topLevelWidgets() if isinstance(w, kind) and w.isVisible()), None)
        if shown is None:
            QTimer.singleShot(50, look)
        else:
            then(shown)
    QTimer.singleShot(0, look)
