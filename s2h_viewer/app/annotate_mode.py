"""Annotate mode (its own tab): one hand's TBS frames, the solver run off the GUI thread, undoable
turns of a joint's frame and solver runs, the sidecar saved next to the hand file (or where the user
chooses), and a question before unsaved edits or manual frames would be lost."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
from PySide6.QtCore import QObject, Signal
from PySide6.QtGui import QAction, QKeySequence, QUndoCommand, QUndoStack
from PySide6.QtWidgets import QFileDialog, QMenu, QMessageBox, QWidget

from s2h_viewer.annotate.editing import AnnotationSession
from s2h_viewer.annotate.solver import TbsSolution, solve_tbs_frames
from s2h_viewer.app.tasks import TaskRunner
from s2h_viewer.errors import S2HError
from s2h_viewer.hand import topology as topo
from s2h_viewer.io.annotation import Annotation, hand_side, save_annotation, sidecar_path
from s2h_viewer.hand.model import HandModel
from s2h_viewer.retarget.progress import report
from s2h_viewer.widgets.annotation_view import AnnotationView

SIDECAR_FILTER = "TBS annotation (*.tbs.json);;JSON (*.json)"


def os_problem(exc: OSError, target: Path) -> str:
    """What went wrong writing ``target``, in words: the system's reason and the file or folder it names, unless
    that is ``target`` itself or a temporary file beside it (no errno numbers, no temporary names)."""
    if exc.strerror is None:
        return str(exc)
    culprit = Path(exc.filename) if isinstance(exc.filename, str) else None
    if culprit is None or culprit == target or (culprit.parent == target.parent and culprit.name.startswith(".")):
        return exc.strerror
    return f"{exc.strerror}: {culprit}"


def _same_annotation(a: Annotation, b: Annotation) -> bool:
    """The same frames, setters and confidences (NaN equal to NaN: joints never scored)."""
    return (a.set_by == b.set_by and np.array_equal(a.frames, b.frames)
            and np.array_equal(a.confidence, b.confidence, equal_nan=True))


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


def ask(parent: QWidget | None, title: str, text: str, buttons: list[tuple[str, QMessageBox.ButtonRole]],
        detail: str = "", default: int = 0) -> int:
    """A modal question (``detail`` under it); the index of the button the user chose (the last one, Cancel,
    if closed); Return presses button ``default``."""
    box = QMessageBox(QMessageBox.Icon.Question, title, text, parent=parent)
    box.setObjectName("annotate_question")
    box.setInformativeText(detail)
    added = [box.addButton(label, role) for label, role in buttons]
    box.setDefaultButton(added[default])
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

    def fill_menu(self, annotate_menu: QMenu) -> list[QAction]:
        """The solver and saving in Annotate, returned: they act on an open hand (undo and redo are the
        window's: they follow the visible tab)."""
        actions = []
        for text, slot, shortcut in (("Run TBS solver", self.run_solver, "Ctrl+R"),
                                     ("Save annotation", self.save, "Ctrl+Shift+S"),
                                     ("Save annotation as...", self.save_as, None)):
            action = QAction(text, annotate_menu)
            if shortcut:
                action.setShortcut(QKeySequence(shortcut))
            action.triggered.connect(lambda _=False, run=slot: run())  # not `checked` as save_as's path
            annotate_menu.addAction(action)
            actions.append(action)
        return actions

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
        unit = f"; {hand.meta['unit_note']}" if hand.meta.get("unit_note") else ""
        self.status(f"{hand.name}: frames from {session.frames_from}, {review} joint(s) to review{unit}")

    def sidecar(self) -> Path | None:
        """Where Save writes: the sidecar of this hand (its side) beside the hand file, found there when the
        hand is opened again (None for a sample hand opened by name: no file to put it beside)."""
        hand_file = self.session.hand_file if self.session is not None else None
        return (sidecar_path(hand_file, hand_side(self.session.hand)) if hand_file is not None and hand_file.suffix
                else None)

    def confirm_discard(self, doing: str) -> bool:
        """True when nothing unsaved would be lost by ``doing`` (e.g. "opening another hand"), or the user
        saved (beside the hand or elsewhere) or chose to discard; False when they cancelled or the save failed
        (its error shown, the edits kept)."""
        if self.session is None or self.undo_stack.isClean():
            return True
        target = self.sidecar()
        where = (f"Save writes them to {target}, where they are read back when the hand is opened again."
                 if target is not None else "This hand was opened by name: it has no file to save them with.")
        choice = ask(self.view.window(), "s2h-viewer: unsaved annotation",
                     f"Save the frame edits of {self.session.hand.name} before {doing}?",
                     [("Save", QMessageBox.ButtonRole.AcceptRole), ("Save As...", QMessageBox.ButtonRole.AcceptRole),
                      ("Discard", QMessageBox.ButtonRole.DestructiveRole),
                      ("Cancel", QMessageBox.ButtonRole.RejectRole)],
                     f"{where} Discarded edits are lost.")
        saved = {0: self.save, 1: self.save_as}.get(choice)
        return saved() is not None if saved is not None else choice == 2

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
        after = session.annotation()
        review = sum(session.needs_review(j) for j in range(topo.N_ARTICULATED))
        kept = f", {len(session.manual_joints())} manual frame(s) kept" if keep_manual else ""
        if _same_annotation(before, after):  # nothing to undo, nothing to save (a rerun on the frames it gave)
            session.frames_from = before_from
            self.status(f"solver: the frames are as they were, {review} joint(s) to review{kept}")
        else:
            self.undo_stack.push(SolveCommand(self, before, after, before_from))
            self.status(f"solver: {review} joint(s) to review{kept}")
        self.annotation_ready.emit()

    def _frame_edited(self, joint: int, before: np.ndarray, after: np.ndarray) -> None:
        previous = self.session.set_by[joint]
        self.undo_stack.push(EditFrameCommand(self, joint, before, after, previous))

    def save(self) -> Path | None:
        """Write the sidecar beside the hand file; its path, or None after an error dialog."""
        return self._write(self.sidecar())

    def save_as(self, path: str | Path | None = None) -> Path | None:
        """Write the annotation to ``path``, else where the user chooses (the dialog offers the sidecar); its
        path, or None when the user cancelled or after an error dialog."""
        target = self.sidecar()
        if path is None and target is not None:
            path = QFileDialog.getSaveFileName(self.view.window(), "Save annotation as", str(target),
                                               SIDECAR_FILTER)[0]
            if not path:
                return None
        return self._write(Path(path) if path else None)

    def _write(self, target: Path | None) -> Path | None:
        """Save to ``target`` atomically and mark the edits saved; on failure an error dialog naming the file
        and the problem, the edits kept as unsaved and no file written."""
        if target is None or self.sidecar() is None:
            self.error("Open a hand file to annotate first; sample hands by name have no file to annotate.")
            return None
        try:
            session = self.session
            path = save_annotation(session.annotation(), session.hand_file, hand_side(session.hand), target)
        except OSError as exc:
            self.error(f"{target}: could not save the annotation ({os_problem(exc, target)})")
            return None
        self.undo_stack.setClean()
        self.status(f"wrote {path}")
        return path
