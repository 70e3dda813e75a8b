"""The main window: compare mode on a timeline, heatmaps, scores, exports. Work runs off the GUI thread."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

from collections.abc import Callable

import numpy as np
from PySide6.QtCore import QObject, QSettings, QThread, Signal
from PySide6.QtGui import QAction, QKeySequence, QUndoCommand, QUndoStack
from PySide6.QtWidgets import (QComboBox, QFileDialog, QMainWindow, QMessageBox, QProgressDialog, QSplitter,
                               QTabWidget, QVBoxLayout, QWidget)

from s2h_viewer.annotate.editing import AnnotationSession
from s2h_viewer.annotate.solver import solve_tbs_frames
from s2h_viewer.errors import S2HError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.retarget.comparison import Comparison, build_comparison
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.widgets.annotation_view import AnnotationView
from s2h_viewer.widgets.asm_heatmap import AsmHeatmap
from s2h_viewer.widgets.compare_view import CompareView
from s2h_viewer.widgets.scores_table import ScoresTable
from s2h_viewer.widgets.timeline import Timeline

RECENT_FILES = 8
SHORTCUTS = (("Space", "play / pause"), ("Left / Right", "previous / next frame"), ("Home / End", "first / last frame"),
             ("Ctrl+O", "open a motion"), ("Ctrl+T", "add a target hand"), ("Ctrl+S", "export a screenshot"),
             ("Ctrl+E", "export a video"), ("Ctrl+Shift+O", "open a hand to annotate"), ("Ctrl+R", "run the TBS solver"),
             ("Ctrl+Shift+S", "save the annotation sidecar"), ("Ctrl+Z / Ctrl+Shift+Z", "undo / redo a frame turn"),
             ("click a joint / the list", "select it; drag the dial to turn its frame about the twist axis"))


@dataclass
class CompareSetup:
    """What compare mode shows: a motion on its source hand, retargeted onto targets with methods."""

    motion: Motion
    source: HandModel
    targets: list[HandModel]
    methods: list[str] = field(default_factory=lambda: ["tbs_copy", "asrn"])


class Task(QObject):
    """Runs ``fn(progress)`` in a QThread; reports progress, the result, or the error's one-line message."""

    progress = Signal(int, int, str)
    finished = Signal(object)
    failed = Signal(str)

    def __init__(self, fn: Callable[[Callable[[int, int, str], None]], object]):
        super().__init__()
        self.fn = fn

    def run(self) -> None:
        try:
            self.finished.emit(self.fn(lambda done, total, what: self.progress.emit(done, total, what)))
        except (S2HError, KeyError, ValueError) as exc:
            self.failed.emit(str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc))


class EditFrameCommand(QUndoCommand):
    """One turn of a joint's TBS frame (undoable): the frame and its "set by" before and after."""

    def __init__(self, window: "MainWindow", joint: int, before: np.ndarray, after: np.ndarray, before_by: str):
        super().__init__(f"turn {topo.ARTICULATED_NAMES[joint]}")
        self.window, self.joint, self.before, self.after, self.before_by = window, joint, before, after, before_by

    def _set(self, frame: np.ndarray, by: str) -> None:
        session = self.window.annotation
        session.frames[self.joint] = frame
        session.set_by[self.joint] = by
        self.window.annotate_view.select(self.joint)
        self.window.annotate_view.refresh_list()
        self.window.annotate_view.refresh()

    def redo(self) -> None:
        self._set(self.after, "manual")

    def undo(self) -> None:
        self._set(self.before, self.before_by)


class MainWindow(QMainWindow):
    comparison_ready = Signal()
    annotation_ready = Signal()

    def __init__(self, setup: CompareSetup, settings: QSettings | None = None):
        super().__init__()
        self.setWindowTitle("s2h-viewer")
        self.settings = settings or QSettings("s2h-viewer", "s2h-viewer")
        self.setup = setup
        self.comparison: Comparison | None = None
        self._thread: QThread | None = None
        self._progress: QProgressDialog | None = None

        self.view = CompareView()
        self.timeline = Timeline()
        self.heatmap = AsmHeatmap()
        self.heatmap_choice = QComboBox()
        self.scores = ScoresTable()
        side = QWidget()
        side_layout = QVBoxLayout(side)
        side_layout.addWidget(self.heatmap_choice)
        side_layout.addWidget(self.heatmap)
        side_layout.addWidget(self.scores)
        splitter = QSplitter()
        splitter.addWidget(self.view)
        splitter.addWidget(side)
        splitter.setStretchFactor(0, 3)
        compare = QWidget()
        layout = QVBoxLayout(compare)
        layout.addWidget(splitter, 1)
        layout.addWidget(self.timeline)
        self.annotate_view = AnnotationView()
        self.annotation: AnnotationSession | None = None
        self.undo_stack = QUndoStack(self)
        self.annotate_view.frame_edited.connect(self._frame_edited)
        self.tabs = QTabWidget()
        self.tabs.addTab(compare, "Compare")
        self.tabs.addTab(self.annotate_view, "Annotate")
        self.setCentralWidget(self.tabs)
        self.setAcceptDrops(True)

        self.timeline.frame_changed.connect(self.show_frame)
        self.heatmap_choice.currentIndexChanged.connect(lambda _: self.show_frame(self.timeline.frame))
        self._build_menus()
        geometry = self.settings.value("window/geometry")
        if geometry is not None:
            self.restoreGeometry(geometry)
        else:
            self.resize(1400, 900)

    # --- menus and shortcuts ---
    def _action(self, menu, text: str, slot, shortcut: str | None = None, checkable: bool = False) -> QAction:
        action = QAction(text, self)
        if shortcut:
            action.setShortcut(QKeySequence(shortcut))
        action.setCheckable(checkable)
        action.triggered.connect(slot)
        menu.addAction(action)
        return action

    def _build_menus(self) -> None:
        bar = self.menuBar()
        file_menu = bar.addMenu("&File")
        self._action(file_menu, "Open motion...", self.open_motion, "Ctrl+O")
        self._action(file_menu, "Add target hand...", self.add_target, "Ctrl+T")
        self.recent_menu = file_menu.addMenu("Open recent")
        self._fill_recent()
        file_menu.addSeparator()
        self._action(file_menu, "Export screenshot (PNG)...", self.export_screenshot, "Ctrl+S")
        self._action(file_menu, "Export video (MP4, GIF)...", self.export_video, "Ctrl+E")
        self._action(file_menu, "Export retargeted motion...", self.export_motion)
        file_menu.addSeparator()
        self._action(file_menu, "Quit", self.close, "Ctrl+Q")
        edit_menu = bar.addMenu("&Edit")
        undo = self.undo_stack.createUndoAction(self, "Undo")
        undo.setShortcut(QKeySequence.StandardKey.Undo)
        redo = self.undo_stack.createRedoAction(self, "Redo")
        redo.setShortcut(QKeySequence.StandardKey.Redo)
        edit_menu.addActions([undo, redo])
        annotate_menu = bar.addMenu("&Annotate")
        self._action(annotate_menu, "Open hand...", self.open_hand_to_annotate, "Ctrl+Shift+O")
        self._action(annotate_menu, "Run TBS solver", self.run_solver, "Ctrl+R")
        self._action(annotate_menu, "Save annotation", self.save_annotation, "Ctrl+Shift+S")
        methods_menu = bar.addMenu("&Methods")
        chosen = self.settings.value("compare/methods", self.setup.methods)
        chosen = [m for m in (chosen if isinstance(chosen, list) else [chosen]) if m in METHODS] or self.setup.methods
        self.setup = dataclasses.replace(self.setup, methods=chosen)
        self.method_actions = {}
        for name, method in METHODS.items():
            action = self._action(methods_menu, method.label, self._methods_changed, checkable=True)
            action.setChecked(name in chosen)
            action.setToolTip(method.description)
            self.method_actions[name] = action
        view_menu = bar.addMenu("&View")
        self.see_through = self._action(view_menu, "Semi-transparent skin", self._toggle_see_through, "Ctrl+H",
                                        checkable=True)
        play = bar.addMenu("&Playback")
        self._action(play, "Play / pause", self.timeline.toggle, "Space")
        self._action(play, "Previous frame", lambda: self.timeline.step(-1), "Left")
        self._action(play, "Next frame", lambda: self.timeline.step(1), "Right")
        self._action(play, "First frame", lambda: self.timeline.set_frame(0), "Home")
        self._action(play, "Last frame", lambda: self.timeline.set_frame(self.timeline.n_frames - 1), "End")
        help_menu = bar.addMenu("&Help")
        self._action(help_menu, "Keyboard shortcuts", self.show_shortcuts, "F1")

    def show_shortcuts(self) -> None:
        QMessageBox.information(self, "Keyboard shortcuts", "\n".join(f"{k}: {what}" for k, what in SHORTCUTS))

    def error(self, message: str) -> None:
        """Every failure the user caused or met ends here: a dialog with the message, nothing silent."""
        self.statusBar().showMessage(message, 10000)
        QMessageBox.critical(self, "s2h-viewer", message)

    # --- computing the comparison off the GUI thread ---
    def _start_task(self, fn, label: str, total: int, on_done: Callable[[object], None]) -> None:
        """Run ``fn(progress)`` off the GUI thread behind a progress dialog; errors become a dialog."""
        if self._thread is not None:
            return
        self.timeline.set_playing(False)
        self._thread = QThread(self)
        task = Task(fn)
        task.moveToThread(self._thread)
        self._thread.started.connect(task.run)
        self._progress = QProgressDialog(label, None, 0, total, self)
        self._progress.setWindowTitle("s2h-viewer")
        self._progress.setMinimumDuration(300)
        task.progress.connect(self._on_progress)
        self._on_done = on_done
        task.finished.connect(self._on_task_done)  # a bound slot of this window: runs on the GUI thread
        task.failed.connect(self._on_failure)
        self._task = task  # held: Qt would otherwise lose the Python object while it runs
        self._thread.start()

    def _on_task_done(self, result: object) -> None:
        self._finish_thread()
        self._on_done(result)

    def start_comparison(self) -> None:
        s = self.setup
        self._start_task(lambda progress: build_comparison(s.motion, s.source, s.targets, s.methods, progress),
                         "Retargeting...", len(s.targets) * len(s.methods), self._on_comparison)

    def _finish_thread(self) -> None:
        if self._progress is not None:
            self._progress.close()
            self._progress = None
        if self._thread is not None:
            self._thread.quit()
            self._thread.wait()
            self._thread = None

    def _on_progress(self, done: int, total: int, what: str) -> None:
        if self._progress is not None:
            self._progress.setMaximum(total)
            self._progress.setValue(done)
            self._progress.setLabelText(what)
        self.statusBar().showMessage(f"{done}/{total}: {what}")

    def _on_failure(self, message: str) -> None:
        self._finish_thread()
        self.error(message)

    def _on_comparison(self, comparison: Comparison) -> None:
        self.comparison = comparison
        self.view.set_comparison(comparison)
        self.scores.show_comparison(comparison)
        self.heatmap_choice.blockSignals(True)
        self.heatmap_choice.clear()
        self.heatmap_choice.addItems([f"{METHODS[r.method].label} -> {r.target.name}" for r in comparison.results])
        self.heatmap_choice.blockSignals(False)
        self.timeline.set_clip(comparison.n_frames, comparison.motion.fps)
        self.statusBar().showMessage(f"{comparison.motion.name}: {comparison.n_frames} frames, "
                                     f"{len(comparison.results)} retargets", 5000)
        self.comparison_ready.emit()

    # --- showing a frame ---
    def show_frame(self, frame: int) -> None:
        if self.comparison is None:
            return
        self.view.show_frame(frame)
        index = max(self.heatmap_choice.currentIndex(), 0)
        result = self.comparison.results[index]
        self.heatmap.show_matrix(result.cell_error[frame], f"ASM error, {METHODS[result.method].label} -> "
                                                           f"{result.target.name}, frame {frame}")

    def _methods_changed(self) -> None:
        methods = [name for name, action in self.method_actions.items() if action.isChecked()]
        if not methods:
            self.error("Choose at least one retargeting method.")
            return
        self.settings.setValue("compare/methods", methods)
        self.setup = dataclasses.replace(self.setup, methods=methods)
        self.start_comparison()

    def _toggle_see_through(self, checked: bool) -> None:
        self.view.set_mesh_opacity(0.4 if checked else 1.0)

    # --- files ---
    def _last_dir(self) -> str:
        return str(self.settings.value("files/last_dir", str(Path.home())))

    def _remember(self, path: str, kind: str | None = None) -> None:
        """Remember the folder, and with ``kind`` ("motion", "target" or "annotate") the file as recent."""
        self.settings.setValue("files/last_dir", str(Path(path).parent))
        if kind:
            recent = [r for r in self._recent() if r != f"{kind}:{path}"]
            self.settings.setValue("files/recent", [f"{kind}:{path}", *recent][:RECENT_FILES])
            self._fill_recent()

    def _recent(self) -> list[str]:
        recent = self.settings.value("files/recent", [])
        return [recent] if isinstance(recent, str) else list(recent or [])

    def _fill_recent(self) -> None:
        self.recent_menu.clear()
        opens = {"motion": self.load_motion, "target": self.add_target_file, "annotate": self.annotate_file}
        for entry in self._recent():
            kind, _, path = entry.partition(":")
            if kind in opens:
                action = self.recent_menu.addAction(f"{Path(path).name} ({kind})")
                action.triggered.connect(lambda _=False, p=path, k=kind: opens[k](p))
        self.recent_menu.setEnabled(bool(self.recent_menu.actions()))

    def _ask_to_open(self, title: str, file_filter: str, then: Callable[[str], None]) -> None:
        """A file dialog in the last folder; ``then(path)`` unless the user cancels."""
        path, _ = QFileDialog.getOpenFileName(self, title, self._last_dir(), file_filter)
        if path:
            then(path)

    def _load_hand(self, path: str, kind: str) -> HandModel | None:
        """The hand in ``path`` (remembered as a recent ``kind``), or None after an error dialog."""
        from s2h_viewer.io.files import load_hand_file
        try:
            hand = load_hand_file(path)
        except S2HError as exc:
            self.error(str(exc))
            return None
        self._remember(path, kind)
        return hand

    def open_motion(self) -> None:
        self._ask_to_open("Open motion", "Motions (*.npz *.bvh *.glb *.gltf *.fbx)", self.load_motion)

    def load_motion(self, path: str) -> None:
        from s2h_viewer.io.files import load_motion_file
        from s2h_viewer.samples import load_sample_hand
        try:
            motion, rig = load_motion_file(path)
            source = rig or load_sample_hand(motion.hand_name)
        except (S2HError, KeyError) as exc:
            self.error(str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc))
            return
        self._remember(path, "motion")
        self.setup = dataclasses.replace(self.setup, motion=motion, source=source)
        self.start_comparison()

    def add_target(self) -> None:
        self._ask_to_open("Add target hand", "Hands (*.glb *.gltf *.fbx *.npz *.bvh)", self.add_target_file)

    def add_target_file(self, path: str) -> None:
        hand = self._load_hand(path, "target")
        if hand is None:
            return
        self.setup = dataclasses.replace(self.setup, targets=[*self.setup.targets, hand])
        self.start_comparison()

    def export_screenshot(self, path: str | None = None) -> Path | None:
        from PIL import Image

        from s2h_viewer.io.atomic import atomic_path
        path = path or QFileDialog.getSaveFileName(self, "Export screenshot", self._last_dir(), "PNG (*.png)")[0]
        if not path or self.comparison is None:
            return None
        with atomic_path(path) as tmp:
            Image.fromarray(self.view.grab_rgb()).save(tmp, format="PNG")
        self._remember(path)
        self.statusBar().showMessage(f"wrote {path}", 5000)
        return Path(path)

    def export_video(self, path: str | None = None) -> Path | None:
        from s2h_viewer.render.video import write_video
        path = path or QFileDialog.getSaveFileName(self, "Export video", self._last_dir(),
                                                   "Video (*.mp4 *.gif)")[0]
        if not path or self.comparison is None:
            return None
        self.timeline.set_playing(False)
        n = self.comparison.n_frames
        progress = QProgressDialog("Rendering video...", "Cancel", 0, n, self)
        progress.setMinimumDuration(300)

        def frames():
            for frame in range(n):
                if progress.wasCanceled():
                    raise _Cancelled()
                self.timeline.set_frame(frame)
                self.show_frame(frame)
                progress.setValue(frame)
                yield self.view.grab_rgb()

        try:
            write_video(path, frames(), self.comparison.motion.fps)
        except _Cancelled:
            self.statusBar().showMessage("video export cancelled; nothing written", 5000)
            return None
        except (OSError, ValueError) as exc:
            self.error(f"{path}: could not write the video ({exc})")
            return None
        finally:
            progress.close()
        self._remember(path)
        self.statusBar().showMessage(f"wrote {path} ({n} frames)", 5000)
        return Path(path)

    def export_motion(self, path: str | None = None) -> Path | None:
        from s2h_viewer.io.files import save_motion_file
        if self.comparison is None:
            return None
        result = self.comparison.results[max(self.heatmap_choice.currentIndex(), 0)]
        path = path or QFileDialog.getSaveFileName(self, f"Export {result.method} -> {result.target.name}",
                                                   self._last_dir(), "Motion (*.glb *.bvh *.npz)")[0]
        if not path:
            return None
        try:
            save_motion_file(path, result.motion, result.target)
        except S2HError as exc:
            self.error(str(exc))
            return None
        self._remember(path)
        self.statusBar().showMessage(f"wrote {path}", 5000)
        return Path(path)

    # --- annotation mode ---
    def open_hand_to_annotate(self) -> None:
        self._ask_to_open("Open hand to annotate", "Hands (*.glb *.gltf *.fbx *.npz)", self.annotate_file)

    def annotate_file(self, path: str) -> None:
        """Load a hand (its sidecar or solver frames come with it) and show it in annotation mode."""
        hand = self._load_hand(path, "annotate")
        if hand is None:
            return
        self.annotation = AnnotationSession(hand, Path(path))
        self.undo_stack.clear()
        self.annotate_view.set_session(self.annotation)
        self.tabs.setCurrentWidget(self.annotate_view)
        self.statusBar().showMessage(f"{hand.name}: frames from {hand.meta.get('annotation', 'the file')}", 5000)

    def run_solver(self) -> None:
        if self.annotation is None:
            self.error("Open a hand to annotate first (Annotate > Open hand).")
            return
        hand = self.annotation.hand

        def solve(progress):
            progress(0, 1, f"casting rays at {hand.name}")
            return solve_tbs_frames(hand)

        self._start_task(solve, "Running the TBS solver...", 1, self._on_solution)

    def _on_solution(self, solution) -> None:
        self.annotation.apply_solution(solution)
        self.undo_stack.clear()
        self.annotate_view.refresh_list()
        self.annotate_view.refresh()
        review = int(solution.needs_review.sum())
        self.statusBar().showMessage(f"solver: {review} joint(s) to review", 5000)
        self.annotation_ready.emit()

    def _frame_edited(self, joint: int, before: np.ndarray, after: np.ndarray) -> None:
        previous = self.annotation.set_by[joint]
        self.undo_stack.push(EditFrameCommand(self, joint, before, after, previous))

    def save_annotation(self) -> Path | None:
        from s2h_viewer.io.annotation import save_annotation
        session = self.annotation
        if session is None or session.hand_file is None or session.hand_file.suffix == "":
            self.error("Open a hand file to annotate first; sample hands by name have no file to annotate.")
            return None
        try:
            path = save_annotation(session.annotation(), session.hand_file)
        except OSError as exc:
            self.error(f"{session.hand_file}: could not save the annotation ({exc})")
            return None
        self.undo_stack.setClean()
        self.statusBar().showMessage(f"wrote {path}", 5000)
        return path

    # --- drag and drop: a motion replaces the clip, a hand is opened for annotation ---
    def dragEnterEvent(self, event) -> None:
        if event.mimeData().hasUrls():
            event.acceptProposedAction()

    def dropEvent(self, event) -> None:
        from s2h_viewer.io.files import MOTION_SUFFIXES
        for url in event.mimeData().urls():
            path = url.toLocalFile()
            if Path(path).suffix.lower() in (".glb", ".gltf", ".fbx") or self.tabs.currentWidget() is self.annotate_view:
                self.annotate_file(path)
            elif Path(path).suffix.lower() in MOTION_SUFFIXES:
                self.load_motion(path)

    def closeEvent(self, event) -> None:
        self.settings.setValue("window/geometry", self.saveGeometry())
        self._finish_thread()
        super().closeEvent(event)


class _Cancelled(Exception):
    """The user cancelled a video export."""


def default_setup() -> CompareSetup:
    """The shipped samples: the gestures clip on birch, onto a realistic and a stylised held-out hand."""
    from s2h_viewer import samples
    motion = next(m for m in samples.load_sample_motions() if m.name == "gestures")
    return CompareSetup(motion, samples.load_sample_hand(motion.hand_name),
                        [samples.load_sample_hand("iris"), samples.load_sample_hand("laurel")])


def run(setup: CompareSetup | None = None) -> int:
    """Start the application (``s2h view``)."""
    import sys

    from PySide6.QtWidgets import QApplication
    app = QApplication.instance() or QApplication(sys.argv)
    app.setApplicationName("s2h-viewer")
    window = MainWindow(setup or default_setup())
    window.show()
    window.start_comparison()
    return app.exec()
