"""Annotate mode (its own tab): one hand's TBS frames, the solver run off the GUI thread, undoable
turns of a joint's frame and solver runs, the sidecar saved next to the hand file, and a question
before unsaved edits or manual frames would be lost."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
from PySide6.QtCore import QObject, Signal
from PySide6.QtGui import QAction, QKeySequence, QUndoCommand, QUndoStack
from PySide6.QtWidgets import QMenu, QMessageBox, QWidget

from s2h_viewer.annotate.editing import AnnotationSession
from s2h_viewer.annotate.solver import TbsSolution, solve_tbs_frames
from s2h_viewer.app.tasks import TaskRunner
from s2h_viewer.errors import S2HError
from s2h_viewer.hand import topology as topo
from s2h_viewer.io.annotation import Annotation
from s2h_viewer.hand.model import HandModel
from s2h_viewer.retarget.progress import report
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


class SolveCommand(QUndoCommand):
    """One solver run (undoable): the session's frames, set_by and confidence before and after."""

    def __init__(self, mode: "AnnotateMode", before: Annotation, after: Annotation, before_from: str):
        super().__init__("run the TBS solver")
        self.mode, self.before, self.after, self.before_from = mode, before, after, before_from

    def _set(self, state: Annotation, frames_from: str) -> None:
        self.mode.session.restore(state, frames_from)
        self.mode.view.refresh_list()
        self.mode.view.refresh()

    def redo(self) -> None:
        self._set(self.after, "solver")

    def undo(self) -> None:
        self._set(self.before, self.before_from)


def ask(parent: QWidget | None, title: str, text: str, buttons: list[tuple[str, QMessageBox.ButtonRole]]) -> int:
    """A modal question; the index of the button the user chose (the last one, Cancel, if closed)."""
    box = QMessageBox(QMessageBox.Icon.Question, title, text, parent=parent)
    box.setObjectName("annotate_question")
    added = [box.addButton(label, role) for label, role in buttons]
    box.setDefaultButton(added[0])
    box.setEscapeButton(added[-1])
    box.exec()
    clicked = box.clickedButton()
    return added.index(clicked) if clicked in added else len(added) - 1


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

    def fill_menu(self, annotate_menu: QMenu) -> None:
        """The solver and saving in Annotate (undo and redo are the window's: they follow the visible tab)."""
        for text, slot, shortcut in (("Run TBS solver", self.run_solver, "Ctrl+R"),
                                     ("Save annotation", self.save, "Ctrl+Shift+S")):
            action = QAction(text, annotate_menu)
            action.setShortcut(QKeySequence(shortcut))
            action.triggered.connect(slot)
            annotate_menu.addAction(action)

    def open(self, hand: HandModel, path: str) -> None:
        """Show ``hand`` for annotation with its sidecar's frames, who set them and their confidence, or the
        frames the loader gave it (the solver's, scored)."""
        try:
            session = AnnotationSession.open(hand, Path(path))
        except S2HError as exc:
            self.error(str(exc))
            return
        self.session = session
        self.undo_stack.clear()
        self.view.set_session(session)
        review = sum(session.needs_review(j) for j in range(topo.N_ARTICULATED))
        self.status(f"{hand.name}: frames from {session.frames_from}, {review} joint(s) to review")

    def confirm_discard(self, doing: str) -> bool:
        """True when nothing unsaved would be lost by ``doing`` (e.g. "opening another hand"), or the user
        saved or chose to discard; False when they cancelled or the save failed."""
        if self.session is None or self.undo_stack.isClean():
            return True
        choice = ask(self.view.window(), "Unsaved annotation",
                     f"{self.session.hand.name} has frame edits that are not saved. Save them before {doing}?",
                     [("Save", QMessageBox.ButtonRole.AcceptRole), ("Discard", QMessageBox.ButtonRole.DestructiveRole),
                      ("Cancel", QMessageBox.ButtonRole.RejectRole)])
        return choice == 1 or (choice == 0 and self.save() is not None)

    def run_solver(self) -> None:
        """Solve off the GUI thread; when joints were set by hand, ask first whether to keep them."""
        if self.session is None:
            self.error("Open a hand to annotate first (Annotate > Open hand).")
            return
        manual = self.session.manual_joints()
        keep_manual = False
        if manual:
            names = ", ".join(topo.ARTICULATED_NAMES[j] for j in manual)
            choice = ask(self.view.window(), "Run the TBS solver",
                         f"{len(manual)} joint(s) were set by hand ({names}). The solver would replace their "
                         f"frames. (Either way, Ctrl+Z undoes the solver run.)",
                         [("Keep manual frames", QMessageBox.ButtonRole.AcceptRole),
                          ("Replace all", QMessageBox.ButtonRole.DestructiveRole),
                          ("Cancel", QMessageBox.ButtonRole.RejectRole)])
            if choice == 2:
                return
            keep_manual = choice == 0
        hand = self.session.hand

        def solve() -> TbsSolution:
            report(0.0, f"casting rays at {hand.name}")
            return solve_tbs_frames(hand)

        self.runner.start(solve, "Running the TBS solver...", lambda solution: self._on_solution(solution, keep_manual))

    def _on_solution(self, solution: TbsSolution, keep_manual: bool) -> None:
        session = self.session
        before, before_from = session.annotation(), session.frames_from
        session.apply_solution(solution, keep_manual)
        self.undo_stack.push(SolveCommand(self, before, session.annotation(), before_from))
        review = sum(session.needs_review(j) for j in range(topo.N_ARTICULATED))
        kept = f", {len(session.manual_joints())} manual frame(s) kept" if keep_manual else ""
        self.status(f"solver: {review} joint(s) to review{kept}")
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
