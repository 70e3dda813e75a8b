"""The compare window both GUI test modules open: a short clip on birch, iris as the target (or ``targets``),
TBS Copy and ASRN (or ``methods``), its settings in a temporary file, shown and with its first comparison computed
(or, with ``compute=False``, not yet started). ``repeats`` plays the clip that many times over: a test
that must catch ASM-Opt while it runs (to cancel it, or act beside it) needs seconds of work to catch,
however fast ASM-Opt gets.

The first comparison's results are computed once per test process (the queue's own `compute_result` on the same
clip and hands) and handed to each window's state before it starts, as results it computed before: ASRN's and DM's
2-4 s per window were a sixth of `make test`. A test of the first computation itself (its progress, a cancel, what
the queue ran) asks for ``computed_here``; every later retarget a test asks for is the window's own."""

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
from s2h_viewer.retarget.comparison import MethodResult, compute_result, source_semantics


def open_compare_window(qtbot, sample_hands, tmp_path, methods: tuple[str, ...] = ("tbs_copy", "asrn"),
                        compute: bool = True, repeats: int = 1, targets: tuple[str, ...] = ("iris",),
                        computed_here: bool = False) -> MainWindow:
    motion = copy.deepcopy(short_clip(sample_hands["birch"]))  # a test may change its clip
    if repeats > 1:
        motion = dataclasses.replace(motion, q_tbs=np.tile(motion.q_tbs, (repeats, 1, 1)),
                                     labels=np.tile(motion.labels, repeats))
    setup = CompareSetup(motion, sample_hands["birch"], [sample_hands[name] for name in targets], list(methods))
    return open_window(qtbot, setup, tmp_path, compute=compute, computed_before=not computed_here and repeats == 1)


@functools.lru_cache(maxsize=2)
def short_clip(hand: HandModel) -> Motion:
    """The window's clip, fitted to ``hand`` once per session (the fit took 0.75 of the window's 1.8 s to open)."""
    return synthesize(["fist", "ok", "v_sign"], hand, seed=4, name="short")


@functools.lru_cache(maxsize=2)
def _short_clip_semantics(source: HandModel) -> tuple:
    return source_semantics(short_clip(source), source)


@functools.lru_cache(maxsize=None)
def _short_clip_result(source: HandModel, target: HandModel, method: str) -> MethodResult:
    return compute_result(short_clip(source), source, _short_clip_semantics(source)[1], target, method)


def _give_results_computed_before(win: MainWindow, setup: CompareSetup) -> None:
    """The window's state holds the short clip's semantics and every retarget its setup asks for, as if computed
    before (copies: a test may change what it is shown; each result on the state's own target, which may be
    renamed beside the others)."""
    state = win.compare.state
    state.semantics[(id(state.motion), id(state.source))] = copy.deepcopy(_short_clip_semantics(setup.source))
    for given, target in zip(setup.targets, state.targets):
        for method in state.methods:
            result = _short_clip_result(setup.source, given, method)
            state.results[state.key(target, method)] = copy.deepcopy(result, {id(result.target): target})


def open_window(qtbot, setup: CompareSetup, tmp_path, size: tuple[int, int] = (1000, 700),
                compute: bool = True, computed_before: bool = False) -> MainWindow:
    """The window on ``setup``, its settings in a temporary file ticking the setup's methods, shown at ``size``
    and with its first comparison computed (unless ``compute`` is False; ``computed_before``: given, the setup's
    clip being the short clip on its source)."""
    settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
    settings.setValue("compare/methods", list(setup.methods))
    win = MainWindow(setup, settings)
    win.resize(*size)
    qtbot.addWidget(win, before_close_func=lambda w: (  # closed without a "save?" question
        w.undo_stack.clear(), w.compare.fixing.forget_unsaved()))
    win.show()
    if not compute:
        return win
    if computed_before:
        _give_results_computed_before(win, setup)
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
