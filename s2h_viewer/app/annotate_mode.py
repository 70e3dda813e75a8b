"""Annotate mode (its own tab): one hand's TBS frames, the solver run off the GUI thread, undoable
turns of a joint's frame, and the sidecar saved next to the hand file."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
from PySide6.QtCore import QObject, Signal
from PySide6.QtGui import QAction, QKeySequence, QUndoCommand, QUndoStack
from PySide6.QtWidgets import QMenu

from s2h_viewer.annotate.editing import AnnotationSession
from s2h_viewer.annotate.solver import solve_tbs_frames
from s2h_viewer.app.tasks import TaskRunner
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.widgets.annotation_view import AnnotationView


class EditFrameCommand(QUndoCommand):
    """One turn of a joint's TBS frame (undoable): the frame and its "set by" before and after."""

    def __init__(self, mode: "AnnotateMode", joint: int, before: np.ndarray, after: np.ndarray, before_by: str):
        super().__init__(f"turn {topo.ARTICULATED_NAMES[joint]}")
        self.mode, self.joint, self.before, self.after, self.before_by = mode, joint, before, after, before_by

    def _set(self, frame: np.ndarray, by: str) -> None:
        session = self.mode.session
        session.frames[self.joint] = frame
        session.set_by[self.joint] = by
        self.mode.view.select(self.joint)
        self.mode.view.refresh_list()
        self.mode.view.refresh()

    def redo(self) -> None:
        self._set(self.after, "manual")

    def undo(self) -> None:
        self._set(self.before, self.before_by)


class AnnotateMode(QObject):
    """The Annotate tab's state and actions; ``view`` is the tab's widget."""

    annotation_ready = Signal()

    def __init__(self, runner: TaskRunner, error: Callable[[str], None], status: Callable[[str], None],
                 parent: QObject | None = None):
        super().__init__(parent)
        self.runner, self.error, self.status = runner, error, status
        self.view = AnnotationView()
        self.session: AnnotationSession | None = None
        self.undo_stack = QUndoStack(self)
        self.view.frame_edited.connect(self._frame_edited)

    def fill_menus(self, edit_menu: QMenu, annotate_menu: QMenu) -> None:
        """Undo/redo in Edit; the solver and saving in Annotate."""
        undo = self.undo_stack.createUndoAction(edit_menu, "Undo")
        undo.setShortcut(QKeySequence.StandardKey.Undo)
        redo = self.undo_stack.createRedoAction(edit_menu, "Redo")
        redo.setShortcut(QKeySequence.StandardKey.Redo)
        edit_menu.addActions([undo, redo])
        for text, slot, shortcut in (("Run TBS solver", self.run_solver, "Ctrl+R"),
                                     ("Save annotation", self.save, "Ctrl+Shift+S")):
            action = QAction(text, annotate_menu)
            action.setShortcut(QKeySequence(shortcut))
            action.triggered.connect(slot)
            annotate_menu.addAction(action)

    def open(self, hand: HandModel, path: str) -> None:
        """Show ``hand`` (its sidecar or solver frames come with it) for annotation."""
        self.session = AnnotationSession(hand, Path(path))
        self.undo_stack.clear()
        self.view.set_session(self.session)
        self.status(f"{hand.name}: frames from {hand.meta.get('annotation', 'the file')}")

    def run_solver(self) -> None:
        if self.session is None:
            self.error("Open a hand to annotate first (Annotate > Open hand).")
            return
        hand = self.session.hand

        def solve(progress):
            progress(0, 1, f"casting rays at {hand.name}")
            return solve_tbs_frames(hand)

        self.runner.start(solve, "Running the TBS solver...", 1, self._on_solution)

    def _on_solution(self, solution) -> None:
        self.session.apply_solution(solution)
        self.undo_stack.clear()
        self.view.refresh_list()
        self.view.refresh()
        review = int(solution.needs_review.sum())
        self.status(f"solver: {review} joint(s) to review")
        self.annotation_ready.emit()

    def _frame_edited(self, joint: int, before: np.ndarray, after: np.ndarray) -> None:
        previous = self.session.set_by[joint]
        self.undo_stack.push(EditFrameCommand(self, joint, before, after, previous))

    def save(self) -> Path | None:
        from s2h_viewer.io.annotation import save_annotation
        session = self.session
        if session is None or session.hand_file is None or session.hand_file.suffix == "":
            self.error("Open a hand file to annotate first; sample hands by name have no file to annotate.")
            return None
        try:
            path = save_annotation(session.annotation(), session.hand_file)
        except OSError as exc:
            self.error(f"{session.hand_file}: could not save the annotation ({exc})")
            return None
        self.undo_stack.setClean()
        self.status(f"wrote {path}")
        return path
