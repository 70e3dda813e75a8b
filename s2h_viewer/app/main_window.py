"""The main window: a shell of menus, files and recent files around the modes, one tab each
(``compare_mode``, ``annotate_mode``); exports live in ``exports``, threaded work in ``tasks``."""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from PySide6.QtCore import QSettings, QTimer, Signal
from PySide6.QtGui import QAction, QActionGroup, QKeySequence, QUndoGroup
from PySide6.QtWidgets import QDialog, QFileDialog, QMainWindow, QMessageBox, QTabWidget

from s2h_viewer.app import exports, retarget_fixing
from s2h_viewer.app.annotate_mode import AnnotateMode, ask, os_problem
from s2h_viewer.app.batch_browser import BatchBrowser
from s2h_viewer.app.compare_mode import (ANGLE_CURVE, ASM_CURVE, RESIDUAL_CURVE, SIDEWAYS_CURVE, CompareMode,
                                         CompareSetup, default_setup)
from s2h_viewer.app.focus import FocusKeeper
from s2h_viewer.app.job_progress import JobProgress, strip_height
from s2h_viewer.app.opened_clips import OpenedClips
from s2h_viewer.app.tasks import TaskRunner
from s2h_viewer.errors import S2HError, TooFewBonesError, UnrecognisedRigError, reading
from s2h_viewer.hand.model import HandModel
from s2h_viewer.io.annotation import hand_side
from s2h_viewer.io.files import check_motion_export, export_sidecar
from s2h_viewer.retarget.comparison import with_distinct_names
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.widgets import annotation_view, asm_heatmap, compare_view, error_curve, vtk_widget

__all__ = ["CompareSetup", "MainWindow", "default_setup", "run"]

RECENT_FILES = 8
MIN_SIZE = (1000, 700)  # the smallest window whose panels all hold (the heatmap whole, two score rows, the curve)
#: the window's size at its first launch, where the screen holds it (`first_size`)
FIRST_SIZE = (1400, 900)
#: room left on the screen for the window's title bar and frame, which its size does not count
FRAME_ROOM = (16, 48)
STATUS_MS_EXPORT = 15_000  # a written or cancelled export says so this long in the status bar
MESSAGE_MARGIN = 24  # pixels of the status bar a message leaves free: its grip and padding
#: hand files a target can be (a BVH holds a motion on a skeleton, no mesh to colour: not offered)
TARGET_HAND_FILTER = "Hands (*.glb *.gltf *.vrm *.fbx *.npz)"
RIG_FILTER = "Rigs (*.glb *.gltf *.vrm *.fbx)"  # hand files with bones to map
#: Help's mouse sections, (heading, (gesture, what it does)...), each list kept by the widget the mouse acts on
#: (the keys are read from the menus' own actions, `MainWindow.shortcut_lines`)
MOUSE_SECTIONS = (("Mouse, in the 3D views of both tabs", vtk_widget.MOUSE),
                  ("Mouse, in Compare", compare_view.MOUSE + retarget_fixing.MOUSE + asm_heatmap.MOUSE
                                        + error_curve.MOUSE),
                  ("Mouse, in Annotate", annotation_view.MOUSE))


WRAPPED = "Wrapped round"  # the status bar's word when ] or [ wraps round the clip or the marked range


def first_size(available: tuple[int, int]) -> tuple[int, int]:
    """The window's size at its first launch on a screen whose free area is ``available`` (pixels): `FIRST_SIZE`
    within it, never under `MIN_SIZE` (at 1400 x 900 on a 1280 x 1024 screen, the heatmap and the speed box were
    cut off at its right edge)."""
    return (max(MIN_SIZE[0], min(FIRST_SIZE[0], available[0] - FRAME_ROOM[0])),
            max(MIN_SIZE[1], min(FIRST_SIZE[1], available[1] - FRAME_ROOM[1])))


class MainWindow(QMainWindow):
    comparison_ready = Signal()
    annotation_ready = Signal()

    def __init__(self, setup: CompareSetup, settings: QSettings | None = None, open_options=None):
        super().__init__()
        from s2h_viewer.io.files import RigOptions
        self.opened_clips = OpenedClips()  # a file opened again unchanged: the same clip, its results cached
        if setup.path is not None:  # the clip shown at launch too
            self.opened_clips.remember(OpenedClips.key(setup.path, (setup.options, setup.rig_file)), setup.motion,
                                        setup.source, OpenedClips.origin_of(setup.path, setup.options.animation,
                                                                            setup.rig_file))
        self.open_options = open_options or RigOptions()  # `s2h view`'s --side, --fps ...: for every file opened
        self._methods_named = setup.methods_named  # `s2h view --methods`: over the ones last ticked
        self.setWindowTitle("s2h-viewer[*]")
        self.settings = settings or QSettings("s2h-viewer", "s2h-viewer")
        from s2h_viewer.samples import ASSETS_DIR
        given = [Path(h.source).resolve() for h in setup.targets if h.source and Path(h.source).is_file()]
        own = [path for path in given if not path.is_relative_to(ASSETS_DIR.resolve())]  # not a shipped file
        if own:  # a hand file named at launch (`s2h view --target`): the next hand is likely beside it
            self.settings.setValue("files/hand_dir", str(own[-1].parent))
        #: a shipped real rig named at launch (`--target assets/hands/real/cryptovoxels.vrm`): the dialogs start
        #: beside it where no folder of the user's is remembered (a fresh-eyes user's Add target opened in the
        #: sample hands' folder), but it is not remembered over the user's own
        self._launch_hand_dir = next((str(path.parent) for path in reversed(given)
                                      if path.parent != (ASSETS_DIR / "hands").resolve()), "")
        self.runner = TaskRunner(self, self.error, self.statusBar().showMessage)
        self.compare = CompareMode(setup, self.error, lambda text: self.statusBar().showMessage(text, 5000))
        self.video_export: exports.VideoExport | None = None
        self._loading: list[tuple[str, str, object]] = []  # (kind, path, motion or hand) the grid does not show yet
        self.annotate = AnnotateMode(self.runner, self.error, lambda text: self.statusBar().showMessage(text, 5000),
                                     self)
        self.compare.comparison_ready.connect(self._remember_shown)
        self.compare.comparison_ready.connect(self._tracking_actions)
        self.compare.comparison_ready.connect(self.comparison_ready)
        self.compare.state_changed.connect(self._state_changed)
        self.annotate.annotation_ready.connect(self.annotation_ready)
        self.annotate.undo_stack.cleanChanged.connect(self._show_unsaved)  # a method: gone with the window
        self.tabs = QTabWidget()
        self.tabs.addTab(self.compare, "Compare")
        self.tabs.addTab(self.annotate.view, "Annotate")
        self.setCentralWidget(self.tabs)
        self.setAcceptDrops(True)
        self.batch_browser = BatchBrowser(self)
        self._build_menus()
        self.focus_keeper = FocusKeeper(self)  # shortcuts keep working after a dialog closes without a window manager
        self.setMinimumSize(*MIN_SIZE)
        self.statusBar().setMinimumHeight(strip_height(self) + 4)  # room for job strips from the start
        geometry = self.settings.value("window/geometry")
        if geometry is not None:
            self.restoreGeometry(geometry)
        else:
            free = self.screen().availableGeometry()
            self.resize(*first_size((free.width(), free.height())))
        self._remember_playback()

    def _remember_playback(self) -> None:
        """The playback speed and looping as the user last left them, kept for the next launch."""
        timeline = self.timeline
        speed = str(self.settings.value("playback/speed", ""))
        if timeline.speed.findText(speed) >= 0:
            timeline.speed.setCurrentIndex(timeline.speed.findText(speed))
        timeline.loop.setChecked(str(self.settings.value("playback/loop", "true")).lower() == "true")
        timeline.speed.currentTextChanged.connect(lambda text: self.settings.setValue("playback/speed", text))
        timeline.loop.toggled.connect(lambda on: self.settings.setValue("playback/loop", on))

    def _to_worst(self, direction: int) -> None:
        """Jump to the next (1) or previous (-1) of the worst frames marked red on the error curve."""
        marked = self.timeline.marked
        step = error_curve.next_worst(self.compare.curve.worst, self.timeline.frame, direction, marked)
        where = "" if marked is None else f" between the marks ({marked.start} to {marked[-1]})"
        if step is None:  # a copy's bends on the source's: nothing parts, nothing marked
            self.statusBar().showMessage(f"No worst frames are marked on the error curve{where}", 5000)
            return
        frame, wrapped = step
        self.timeline.set_frame(frame)
        if wrapped:  # round the end: said, as a search that wraps says it
            first = "first" if direction > 0 else "last"
            self.statusBar().showMessage(f"{WRAPPED} to the {first} worst frame{where}: frame {frame}", 5000)
        elif self.statusBar().currentMessage().startswith(WRAPPED):  # it stayed up over the next jumps
            self.statusBar().clearMessage()

    def _show_unsaved(self, clean: bool) -> None:
        """A '*' in the title and on the Annotate tab while the annotation has edits not saved (the tab's is seen
        where no window manager draws a title)."""
        self.setWindowModified(not clean)
        self.tabs.setTabText(self.tabs.indexOf(self.annotate.view), "Annotate" if clean else "Annotate *")

    # --- the modes' parts, under the names scripts and tests use ---
    @property
    def setup(self) -> CompareSetup:
        return self.compare.setup

    @property
    def comparison(self):
        return self.compare.comparison

    @property
    def view(self):
        return self.compare.view

    @property
    def timeline(self):
        return self.compare.timeline

    @property
    def heatmap(self):
        return self.compare.heatmap

    @property
    def heatmap_choice(self):
        return self.compare.heatmap_choice

    @property
    def scores(self):
        return self.compare.scores

    @property
    def annotate_view(self):
        return self.annotate.view

    @property
    def annotation(self):
        return self.annotate.session

    def _say_undone(self, verb: str, offset: int) -> None:
        """The status bar names the change Edit > Undo took back or Redo made again ("Undone: remove iris"): a
        key press changes a hand or a curve somewhere in the window, and says nothing there of what it was."""
        stack = self.undo_group.activeStack()
        command = stack.command(stack.index() + offset) if stack is not None else None
        if command is not None and command.text():
            self.statusBar().showMessage(f"{verb}: {command.text()}", 5000)

    @property
    def undo_stack(self):
        return self.annotate.undo_stack

    # --- menus and shortcuts ---
    def _action(self, menu, text: str, slot, shortcut: str | None = None, checkable: bool = False) -> QAction:
        action = QAction(text, self)
        if shortcut:
            action.setShortcut(QKeySequence(shortcut))
        action.setCheckable(checkable)
        # a checkable action's slot gets its state; any other's gets nothing (triggered's False read as a path
        # made File > Export retargeted motion skip its questions and Fix > Load corrections fail)
        action.triggered.connect(slot if checkable else lambda _=False: slot())
        menu.addAction(action)
        return action

    def _build_menus(self) -> None:
        bar = self.menuBar()
        file_menu = bar.addMenu("&File")
        open_motion = self._action(file_menu, "Open motion...", self.open_motion, "Ctrl+O")
        # also first in the Targets menu, where a first-time user looked for it
        self.add_target_action = self._action(file_menu, "Add target hand...", self.add_target, "Ctrl+T")
        compare_only = [open_motion, self.add_target_action,
                        self._action(file_menu, "Open batch summary...", self.ask_batch, "Ctrl+B")]
        self.recent_menu = file_menu.addMenu("Open recent")
        self._fill_recent()
        file_menu.addSeparator()
        compare_only += [self._action(file_menu, "Export screenshot (PNG)...", self.export_screenshot, "Ctrl+S"),
                         self._action(file_menu, "Export video (MP4, GIF)...", self.export_video, "Ctrl+E"),
                         self._action(file_menu, "Export retargeted motion...", self.export_motion)]
        self._export_size_menu(file_menu.addMenu("Export size (pictures and videos)"))
        file_menu.addSeparator()
        self._action(file_menu, "Quit", self.close, "Ctrl+Q")
        edit_menu = bar.addMenu("&Edit")
        annotate_menu = bar.addMenu("&Annotate")
        open_hand = self._action(annotate_menu, "Open hand...", self.open_hand_to_annotate, "Ctrl+Shift+O")
        self._action(annotate_menu, "Open hand with joint map...", self.open_hand_with_joint_map)
        self._annotate_only = self.annotate.fill_menu(annotate_menu)  # opening a hand switches to Annotate: always on
        # one undo stack per tab: Edit > Undo acts on the visible tab's work only
        self.undo_group = QUndoGroup(self)
        for stack in (self.compare.undo_stack, self.annotate.undo_stack):
            self.undo_group.addStack(stack)
        undo = self.undo_group.createUndoAction(edit_menu, "Undo")
        undo.setShortcut(QKeySequence.StandardKey.Undo)
        redo = self.undo_group.createRedoAction(edit_menu, "Redo")
        redo.setShortcut(QKeySequence.StandardKey.Redo)
        for action, name in ((undo, "Undo"), (redo, "Redo")):
            action.setProperty("help_name", name)  # for Help: their text names the change ("Undo remove iris")
        # connected after the group's own undo and redo: the stack has moved when these run
        undo.triggered.connect(lambda: self._say_undone("Undone", 0))
        redo.triggered.connect(lambda: self._say_undone("Redone", -1))
        edit_menu.addActions([undo, redo])
        methods_menu = bar.addMenu("&Methods")
        chosen = self.setup.methods if self._methods_named else self.settings.value("compare/methods",
                                                                                    self.setup.methods)
        chosen = [m for m in (chosen if isinstance(chosen, list) else [chosen]) if m in METHODS] or self.setup.methods
        self.compare.state.methods = chosen
        self.method_actions = {}
        for name, method in METHODS.items():
            action = self._action(methods_menu, method.label, self._methods_changed, checkable=True)
            action.setChecked(name in chosen)
            action.setToolTip(method.description)
            self.method_actions[name] = action
        self.targets_menu = bar.addMenu("&Targets")
        self.compare.fill_targets_menu(self.targets_menu, (self.add_target_action,))
        view_menu = bar.addMenu("&View")
        self.see_through = self._action(view_menu, "Semi-transparent skin", self.compare.set_see_through, "Ctrl+H",
                                        checkable=True)
        self.skeleton_overlay = self._action(view_menu, "Skeleton overlay (skin see-through)", lambda on: (
            self.view.set_options(skeleton=on)), "Ctrl+K", checkable=True)
        self.contact_overlay = self._action(view_menu, "Contact overlay (kept green, lost red, invented blue)",
                                            lambda on: self.view.set_options(contacts=on), "Ctrl+J", checkable=True)
        self.ghost = self._action(view_menu, "Ghost of the source over a retarget shown alone",
                                  lambda on: self.view.set_options(ghost=on), "Ctrl+U", checkable=True)
        self.keypoint_dots = self._action(view_menu, "Tracked keypoints on the source (recordings)", lambda on: (
            self.view.set_options(keypoints=on)), "Ctrl+D", checkable=True)
        self.keypoint_dots.setChecked(True)
        # what the error curve shows: radio items, one ticked; a choice's key again goes back to the ASM error
        curves = QActionGroup(self)
        self.asm_curve = self._action(view_menu, "Error curve: ASM error per frame", self._curve_chosen,
                                      checkable=True)
        self.sideways_curve = self._action(view_menu, "Error curve: sideways flexion per frame (deg)",
                                           self._curve_chosen, "Ctrl+G", checkable=True)
        self.angle_curve = self._action(view_menu, "Error curve: the heatmap's joint bend, source and retarget (deg)",
                                        self._curve_chosen, "Ctrl+Shift+G", checkable=True)
        self.compare.heatmap.row_chosen.connect(self._show_joint_curve)
        self.fit_residual = self._action(view_menu, "Error curve: tracking fit residual (recordings)",
                                         self._curve_chosen, "Ctrl+F", checkable=True)
        self._curves = {self.asm_curve: ASM_CURVE, self.sideways_curve: SIDEWAYS_CURVE, self.angle_curve: ANGLE_CURVE,
                        self.fit_residual: RESIDUAL_CURVE}
        for action in self._curves:
            curves.addAction(action)
        self.asm_curve.setChecked(True)
        view_menu.addSeparator()
        for preset, text, key in (("palm", "Camera: palm", "Ctrl+1"), ("back", "Camera: back", "Ctrl+2"),
                                  ("side", "Camera: side", "Ctrl+3"), ("default", "Camera: reset", "Ctrl+0")):
            self._action(view_menu, text, lambda _=False, p=preset: self.view.set_options(camera=p), key)
        self._action(view_menu, "Solo the selected retarget / back to the grid", self._toggle_solo, "Ctrl+M")
        self._action(view_menu, "Frame the hand shown alone (fill the view)", self._frame_hand, "F")
        self._action(view_menu, "Next page of targets (grid)", lambda: self.view.set_page(self.view.page + 1),
                     "Ctrl+PgDown")
        self._action(view_menu, "Previous page of targets (grid)", lambda: self.view.set_page(self.view.page - 1),
                     "Ctrl+PgUp")
        fix_menu = bar.addMenu("Fi&x")
        self.compare.fixing.fill_menu(fix_menu)
        fix_menu.addSeparator()
        self._action(fix_menu, "Save corrections of the selected retarget...", self.save_corrections)
        self._action(fix_menu, "Load corrections onto the selected retarget...", self.load_corrections)
        play = bar.addMenu("&Playback")
        timeline = self.timeline
        self._action(play, "Play / pause", timeline.toggle, "Space")
        self._action(play, "Previous frame", lambda: timeline.step(-1), "Left")
        self._action(play, "Next frame", lambda: timeline.step(1), "Right")
        self._action(play, "First frame", lambda: timeline.set_frame(0), "Home")
        self._action(play, "Last frame", lambda: timeline.set_frame(timeline.n_frames - 1), "End")
        self._action(play, "Mark in: the range starts here", timeline.mark_in, "I")
        self._action(play, "Mark out: the range ends here", timeline.mark_out, "O")
        self._action(play, "Clear the marked range", timeline.clear_range, "Alt+I")
        self._action(play, "Next worst frame (error curve)", lambda: self._to_worst(1), "]")
        self._action(play, "Previous worst frame (error curve)", lambda: self._to_worst(-1), "[")
        help_menu = bar.addMenu("&Help")
        self._action(help_menu, "Keyboard shortcuts", self.show_shortcuts, "F1")
        # a disabled menu's actions are greyed and their shortcuts off (the targets menu: in `_follow_mode`)
        self._compare_only = [*compare_only, methods_menu, view_menu, fix_menu, play]
        keys = open_hand.shortcut().toString(QKeySequence.SequenceFormat.NativeText)
        self.annotate.view.set_hint(f"Open a hand to annotate: Annotate > {open_hand.text().rstrip('.')} ({keys}), "
                                    f"or drop a GLB, glTF, VRM or FBX file here.")
        self.tabs.currentChanged.connect(self._tab_changed)
        self._tab_changed()

    def _annotating(self) -> bool:
        return self.tabs.currentWidget() is self.annotate.view

    def _tab_changed(self, *_) -> None:
        """Undo and redo follow the visible tab, and so do the menus (`_follow_mode`)."""
        self.undo_group.setActiveStack(self.annotate.undo_stack if self._annotating() else self.compare.undo_stack)
        self._follow_mode()

    def _follow_mode(self) -> None:
        """What acts on the other tab's hidden work is disabled (greyed, its shortcuts off) while a tab shows:
        in Annotate, the motion, targets, exports, methods, view and playback of Compare; in Compare, the
        solver and saving of Annotate, which also wait for a hand to be opened."""
        annotating = self._annotating()
        for item in self._compare_only:
            item.setEnabled(not annotating)
        self.targets_menu.setEnabled(not annotating)  # adding a target is there too
        for action in self._annotate_only:
            action.setEnabled(annotating and self.annotation is not None)
        self._enable_recent()

    def shortcut_lines(self) -> list[str]:
        """Help's text, a heading over each section: 'key: Menu > entry' for every menu action with a shortcut,
        read from the actions themselves (so the help cannot drift from the menus), then 'gesture: what it does'
        for the mouse in the 3D views, the grid and the annotation view (`MOUSE_SECTIONS`)."""
        lines = ["Keyboard (from the menus)"]
        listed: set[tuple[str, str]] = set()  # an action in two menus (Add target hand: File and Targets) once

        def walk(menu, path: str) -> None:
            for action in menu.actions():
                if action.menu() is not None:
                    walk(action.menu(), f"{path} > {action.text()}")
                elif action.shortcuts():
                    keys = " or ".join(k.toString(QKeySequence.SequenceFormat.NativeText) for k in action.shortcuts())
                    if (keys, action.text()) in listed:
                        continue
                    listed.add((keys, action.text()))
                    name = action.property("help_name") or action.text().replace("&", "")
                    lines.append(f"{keys}: {path} > {name}")

        for top in self.menuBar().actions():
            walk(top.menu(), top.text().replace("&", ""))
        for heading, gestures in MOUSE_SECTIONS:
            lines += ["", heading, *(f"{gesture}: {what}" for gesture, what in gestures)]
        return lines

    def show_shortcuts(self) -> None:
        from s2h_viewer.widgets.text_dialog import TextDialog
        dialog = TextDialog(self, "Keyboard shortcuts and mouse", "\n".join(self.shortcut_lines()))
        dialog.exec()
        dialog.deleteLater()

    def error(self, message: str) -> None:
        """Every failure the user caused or met ends here: a dialog with the message, nothing silent."""
        self.statusBar().showMessage(message, 10000)
        QMessageBox.critical(self, "s2h-viewer", message)

    def start_comparison(self) -> None:
        self.compare.start_comparison()

    def _methods_changed(self) -> None:
        methods = [name for name, action in self.method_actions.items() if action.isChecked()]
        if not methods:
            self.error("Choose at least one retargeting method.")
            self._state_changed()
            return
        self.compare.methods_from_batch = False  # the user's own choice
        self.settings.setValue("compare/methods", methods)
        self.compare.set_methods(methods)

    def _state_changed(self) -> None:
        """The menus (and the remembered methods, unless a batch row's) say what the compare state holds, after a
        cancel too."""
        if not self.compare.methods_from_batch:  # one row's method had become every later session's only one
            self.settings.setValue("compare/methods", list(self.setup.methods))
        last = self.setup.methods[0] if len(self.setup.methods) == 1 else None
        for name, action in self.method_actions.items():
            action.blockSignals(True)
            action.setChecked(name in self.setup.methods)
            action.blockSignals(False)
            action.setEnabled(name != last)  # the last method stays (as the last target does): nothing to compare
            action.setStatusTip("the last method ticked: tick another before unticking it" if name == last else "")
        self.compare.fill_targets_menu(self.targets_menu, (self.add_target_action,))
        self._follow_mode()

    def _frame_hand(self) -> None:
        if not self.view.frame_hand():
            self.statusBar().showMessage("Frame the hand: show a hand alone first (double-click it, or Ctrl+M)", 5000)

    def _toggle_solo(self) -> None:
        """Ctrl+M: the selected retarget alone in the view, or the grid again (double-click does it too)."""
        if self.view.solo >= 0 or self.comparison is None:
            self.view.set_solo(-1)
            return
        selected = self.comparison.results.index(self.compare.selected_result())
        self.view.set_solo(self.view.hand_of_result(selected))

    # --- files ---
    def _last_dir(self) -> str:
        return str(self.settings.value("files/last_dir", str(Path.home())))

    def _remember(self, path: str, kind: str | None = None) -> None:
        """Remember the folder, and with ``kind`` ("motion", "target", "annotate" or "batch") the file as recent."""
        self.settings.setValue("files/last_dir", str(Path(path).parent))
        if kind:
            recent = [r for r in self._recent() if r != f"{kind}:{path}"]
            self.settings.setValue("files/recent", [f"{kind}:{path}", *recent][:RECENT_FILES])
            self._fill_recent()

    def _recent(self) -> list[str]:
        recent = self.settings.value("files/recent", [])
        return [recent] if isinstance(recent, str) else list(recent or [])

    def _recent_openers(self) -> dict[str, Callable[[str], None]]:
        """How each kind of recent file opens."""
        return {"motion": self.load_motion, "target": self.add_target_file, "annotate": self.annotate_file,
                "batch": self.open_batch}

    def _fill_recent(self) -> None:
        """The recent files, newest first (a hand to annotate opens in Annotate from either tab)."""
        self.recent_menu.clear()
        for entry in self._recent():
            kind, _, path = entry.partition(":")
            if kind in self._recent_openers():
                # every batch's summary is summary.csv: its folder tells them apart
                name = f"{Path(path).parent.name}/{Path(path).name}" if kind == "batch" else Path(path).name
                action = self.recent_menu.addAction(f"{name} ({kind})")
                action.triggered.connect(lambda _=False, p=path, k=kind: self._open_recent(k, p))
                action.setData(kind)
        self.recent_menu.setEnabled(bool(self.recent_menu.actions()))
        self._enable_recent()

    def _open_recent(self, kind: str, path: str) -> None:
        """Open a recent file; one that is gone leaves the menu, with a dialog saying so."""
        if not Path(path).is_file():
            self.settings.setValue("files/recent", [r for r in self._recent() if r != f"{kind}:{path}"])
            self._fill_recent()
            self.error(f"{path}: no longer there (moved or deleted); removed from the recent files.")
            return
        self._recent_openers()[kind](path)

    def _enable_recent(self) -> None:
        """Recent motions, targets and batch summaries are for Compare: disabled in Annotate."""
        for action in self.recent_menu.actions():
            action.setEnabled(action.data() == "annotate" or not self._annotating())

    def _ask_to_open(self, title: str, file_filter: str, then: Callable[[str], None], folder: str | None = None) -> None:
        """A file dialog in ``folder`` (else the last folder); ``then(path)`` unless the user cancels."""
        path, _ = QFileDialog.getOpenFileName(self, title, folder or self._last_dir(), file_filter)
        if path:
            then(path)

    def _load_hand(self, path: str, map_joints: bool = False, side: str | None = None) -> HandModel | None:
        """The hand in ``path`` (its folder remembered), or None after an error dialog or a cancel; with
        ``map_joints`` the user maps its bones first (the joint map dialog); ``side``: that hand of a character, else
        the one `s2h view --side` named (an Add target on a character took its right hand whatever --side said)."""
        side = side or self.open_options.side
        try:
            hand = self._map_and_load(path) if map_joints else self._load_or_map(path, side)
            unit = self._chosen_unit(path, hand) if hand is not None else None
            if unit:
                from s2h_viewer.io.files import load_hand_file
                hand = load_hand_file(path, replace(self.open_options, unit=unit, side=side))
            elif unit is None:
                return None
        except S2HError as exc:
            self.error(str(exc))
            return None
        if hand is None:
            return None
        self._remember(path)
        self.settings.setValue("files/hand_dir", str(Path(path).resolve().parent))
        return hand

    def _chosen_unit(self, path: str, hand: HandModel) -> str | None:
        """Where s2h guessed ``hand``'s length unit from its size and another unit would make a plausible hand
        too, the unit the user picks ("" to keep the guess, None if they cancel); a sure guess is said in the
        status bar ("")."""
        from s2h_viewer.io.units import UNIT_NAMES
        guess = hand.meta.get("unit_guess")
        if guess is None:
            return ""
        name, note = Path(path).name, hand.meta["unit_note"]
        if guess["sure"]:
            self.statusBar().showMessage(f"{name}: {note}", 10000)
            return ""
        units = [guess["unit"], *guess["alternatives"]]
        others = " or ".join(UNIT_NAMES[u] for u in units[1:])
        choice = ask(self, "s2h-viewer: length unit", f"{name}: in which unit are its lengths?",
                     [(UNIT_NAMES[u], QMessageBox.ButtonRole.AcceptRole) for u in units]
                     + [("Cancel", QMessageBox.ButtonRole.RejectRole)],
                     f"{note.split('; ')[0]}; in {others} it would be a plausible hand too.")
        if choice == len(units):
            self.statusBar().showMessage(f"{name}: not opened (its unit not chosen)", 5000)
            return None
        return "" if choice == 0 else units[choice]

    def _load_or_map(self, path: str, side: str | None = None) -> HandModel | None:
        """The hand in ``path`` (its ``side``, if given); where s2h does not recognise its bones (and a joint map
        can make it a hand: not for four fingers), the hand the user maps in the joint map dialog if they want to,
        else None."""
        from s2h_viewer.hand.rig_recognition import TEMPLATE_HINT
        from s2h_viewer.io.files import RigOptions, joint_map_sidecar, load_hand_file
        try:
            return load_hand_file(path, RigOptions(side=side))
        except UnrecognisedRigError as exc:
            if isinstance(exc, TooFewBonesError):
                raise
            finding = exc.problem.removesuffix(f"; {TEMPLATE_HINT}")  # the CLI's way: here the dialog is the way
        choice = ask(self, "s2h-viewer: bones not recognised", f"{Path(path).name}: s2h does not recognise its hand.",
                     [("Map the bones...", QMessageBox.ButtonRole.AcceptRole),
                      ("Cancel", QMessageBox.ButtonRole.RejectRole)],
                     f"{finding}.\n\nMap the bones to the hand's joints yourself? The map is saved beside the file "
                     f"({joint_map_sidecar(path, 'right').name}, or .left. for a left hand) and used whenever the "
                     f"hand is opened again.")
        if choice != 0:
            self.statusBar().showMessage(f"{Path(path).name}: not opened (its bones not mapped)", 5000)
            return None
        return self._map_and_load(path, finding)

    def _map_and_load(self, path: str, finding: str = "") -> HandModel | None:
        """The hand in ``path`` with the joint map the user makes in the dialog (prefilled with the file's saved
        map and what its names say), the map then saved beside the file; None if cancelled or failed (shown)."""
        from s2h_viewer.io.files import (RigOptions, joint_map_sidecar, load_hand_file, read_rig_skeleton,
                                         save_joint_map, suggested_joint_map)
        from s2h_viewer.widgets.joint_map_dialog import JointMapDialog
        with reading(path, "a rig"):
            bones, initial = read_rig_skeleton(path).names, suggested_joint_map(path)
        dialog = JointMapDialog(path, bones, initial, finding, self)
        if dialog.exec() != QDialog.DialogCode.Accepted:
            self.statusBar().showMessage(f"{Path(path).name}: not opened (joint map cancelled)", 5000)
            return None
        mapping = dialog.mapping()
        hand = load_hand_file(path, RigOptions(joint_map=mapping))
        side = hand_side(hand)
        sidecar = joint_map_sidecar(path, side)
        try:
            save_joint_map(path, mapping, side)
        except OSError as exc:
            self.error(f"{sidecar}: could not save the joint map ({os_problem(exc, sidecar)}); the hand is open, "
                       f"but opening it again will ask for its bones again")
        else:
            self.statusBar().showMessage(f"wrote {sidecar}: {Path(path).name} opens with this joint map", 5000)
        return hand

    def _export_size_menu(self, menu) -> None:
        """One item per size of `exports.EXPORT_SIZES`, one ticked (kept for the next launch): PNG and video
        exports are rendered at it whatever the window's size."""
        group = QActionGroup(self)
        saved = str(self.settings.value("export/size", exports.size_text(None)))
        self.export_size_actions = {}
        for size in exports.EXPORT_SIZES:
            text = exports.size_text(size)
            action = self._action(menu, text.capitalize(), lambda _=False, t=text: self.settings.setValue(
                "export/size", t), checkable=True)
            group.addAction(action)
            action.setChecked(text == saved)
            self.export_size_actions[size] = action
        if group.checkedAction() is None:
            self.export_size_actions[None].setChecked(True)

    @property
    def export_size(self) -> tuple[int, int] | None:
        """The size exports are rendered at (File > Export size); None: the view's."""
        return next(size for size, action in self.export_size_actions.items() if action.isChecked())

    def _show_joint_curve(self) -> None:
        """A heatmap row clicked: its joint's bend on the error curve, whatever the curve showed (the heatmap's legend
        says so; a click while it showed the ASM error framed the row and changed nothing else)."""
        if not self.angle_curve.isChecked():
            self.angle_curve.setChecked(True)  # its group unticks the others
            self.compare.show_curve(ANGLE_CURVE)

    def _curve_chosen(self, _checked: bool = False) -> None:
        """The error curve shows the View item ticked; the one shown chosen again (its key pressed twice) gives the
        ASM error back, as the items did when they were checkboxes."""
        chosen = self._curves[next(action for action in self._curves if action.isChecked())]
        if chosen == self.compare.curve_shows and chosen != ASM_CURVE:
            self.asm_curve.setChecked(True)
            chosen = ASM_CURVE
        self.compare.show_curve(chosen)

    def _tracking_actions(self) -> None:
        """The recording-only View items are offered while the source is a tracked recording, whose fit's
        report (as `s2h retarget` prints it) the status bar then shows."""
        tracked = self.comparison is not None and self.comparison.motion.fit is not None
        self.keypoint_dots.setEnabled(tracked)
        # ticked only where it can show: ticked and greyed read as "on, but broken" (three fresh-eyes users); the
        # choice stays the view's, for the next recording
        self.keypoint_dots.setChecked(tracked and self.view.options.keypoints)
        self.fit_residual.setEnabled(tracked)
        if not tracked and self.fit_residual.isChecked():  # no residual to show: the ASM error, ticked
            self.asm_curve.setChecked(True)
            self.compare.show_curve(ASM_CURVE)
        if tracked:
            self.statusBar().showMessage(f"{self.comparison.motion.name}: {self.comparison.motion.fit.describe()}",
                                         60000)

    def _remember_shown(self) -> None:
        """Loads the grid now shows become recent files; loads it does not show (cancelled, failed) wait: a
        Redo may bring a cancelled target back, and it is recent then."""
        comparison = self.comparison
        shown = {id(comparison.motion)} | {id(r.target) for r in comparison.results} if comparison else set()
        for kind, path, loaded in self._loading:
            if id(loaded) in shown:
                self._remember(path, kind)
        self._loading = [entry for entry in self._loading if id(entry[2]) not in shown]

    def open_motion(self) -> None:
        self._ask_to_open("Open motion", "Motions and tracking recordings (*.npz *.bvh *.glb *.gltf *.vrm *.fbx *.json "
                          "*.npy)", self.load_motion,
                          self._start_dir("files/motion_dir", "motions"))

    def load_motion(self, path: str, rig_file: str | None = None) -> None:
        """Open the motion file ``path``, performed on the hand file ``rig_file`` where given (the rig it was made
        for: a skeleton-only clip resting in a pose asks for it)."""
        from s2h_viewer.io.files import load_motion_file
        from s2h_viewer.samples import load_sample_hand
        if rig_file is None and not self.confirm_corrections(f"opening {Path(path).name}"):
            return
        self.compare.methods_from_batch = False  # a motion the user opens: the methods are theirs again
        clip_key = OpenedClips.key(path, (self.open_options, rig_file))  # hashed once, whether read again or not
        opened = self.opened_clips.get(clip_key)
        if opened is not None:  # the same file again, unchanged: its retargets are shown, not computed again
            if opened[1].meta.get("rest_note") and not self._choose_clip_rig(path, opened[1].meta["rest_note"]):
                return
            self._remember(path)
            self._loading.append(("motion", path, opened[0]))
            self.compare.load(*opened)
            return
        performer = None
        if rig_file is not None:
            performer = self._load_hand(rig_file)
            if performer is None:
                return
        try:
            motion, rig = load_motion_file(path, performer, options=self.open_options)
            unit = self._chosen_unit(path, rig) if rig is not None and performer is None else ""
            if unit is None:
                return
            if unit:
                motion, rig = load_motion_file(path, options=replace(self.open_options, unit=unit))
            source = rig or load_sample_hand(motion.hand_name)
        except (S2HError, KeyError) as exc:
            self.error(str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc))
            return
        if source.meta.get("rest_note") and not self._choose_clip_rig(path, source.meta["rest_note"]):
            return
        if rig_file is not None:
            self._clip_rigs(path, rig_file)
        self._remember(path)
        self.settings.setValue("files/motion_dir", str(Path(path).resolve().parent))
        self._loading.append(("motion", path, motion))
        self.opened_clips.remember(clip_key, motion, source,
                                   OpenedClips.origin_of(path, self.open_options.animation, rig_file))
        self.compare.load(motion, source)

    def _choose_clip_rig(self, path: str, note: str, shown: bool = False) -> bool:
        """For a clip whose skeleton rests in a pose, the user's choice: True to open it on that skeleton after all;
        False where it opens on the rig chosen for it before or on a hand file chosen now (`load_motion` again), or
        is cancelled. ``shown``: the clip is on screen already (`s2h view --motion`), to keep or open on a rig."""
        name = Path(path).name
        before = self._clip_rigs(path)
        buttons = ([(f"Open it on {Path(before).name}", QMessageBox.ButtonRole.AcceptRole)] if before else []) + [
            ("Choose its rig's hand file...", QMessageBox.ButtonRole.AcceptRole),
            ("Keep it as it is" if shown else "Open it as it is", QMessageBox.ButtonRole.DestructiveRole)]
        choice = ask(self, "s2h-viewer: the clip's rig", f"{name}: {note}.",
                     buttons + ([] if shown else [("Cancel", QMessageBox.ButtonRole.RejectRole)]),
                     "The hand file of the rig it was made for (the skinned hand with the same bones) gives its "
                     "rotations their true rest; the clip is then read onto that rig's bones."
                     + (f" {Path(before).name} was chosen for it before." if before else ""))
        label = (buttons + [("Cancel", None)])[choice][0]
        if label.startswith("Open it on"):
            self.load_motion(path, before)
        elif label.startswith("Choose"):
            self._ask_to_open(f"The hand file {name} was made for", TARGET_HAND_FILTER,
                              lambda rig_file: self.load_motion(path, rig_file), self._hand_dir())
        elif label == "Cancel":
            self.statusBar().showMessage(f"{name}: not opened", 5000)
        return label.endswith("as it is")

    def _clip_rigs(self, clip: str, rig_file: str | None = None) -> str | None:
        """The hand file last chosen as ``clip``'s rig (None: none, or it is gone); with ``rig_file``, remember it."""
        try:
            rigs = json.loads(str(self.settings.value("files/clip_rigs", "{}")))
        except ValueError:  # a settings file edited by hand: start again
            rigs = {}
        rigs = rigs if isinstance(rigs, dict) else {}
        key = str(Path(clip).resolve())
        if rig_file is not None:
            rigs[key] = str(Path(rig_file).resolve())
            self.settings.setValue("files/clip_rigs", json.dumps(rigs))
        chosen = rigs.get(key)
        return chosen if chosen and Path(chosen).is_file() else None

    def offer_launch_rig(self, setup: CompareSetup) -> None:
        """The clip shown at launch resting in a pose (`s2h view --motion` without --source): the same offer."""
        if setup.path is not None and setup.source.meta.get("rest_note"):
            self._choose_clip_rig(str(setup.path), setup.source.meta["rest_note"], shown=True)

    def ask_batch(self) -> None:
        last = Path(str(self.settings.value("files/batch_dir", "")))
        self._ask_to_open("Open batch summary", "Batch summaries (summary.csv *.csv)", self.open_batch,
                          str(last) if str(last) not in ("", ".") and last.is_dir() else str(Path.cwd()))

    def open_batch(self, path: str) -> None:
        """A batch's summary.csv (`s2h batch`) as a table; double-click a row to show it here."""
        if self.batch_browser.open(path) is not None:
            self.settings.setValue("files/batch_dir", str(Path(path).resolve().parent))
            self._remember(str(Path(path).resolve()), "batch")

    def _hand_dir(self) -> str:
        return self._start_dir("files/hand_dir", "hands", self._launch_hand_dir)

    def _start_dir(self, setting: str, shipped: str, launched: str = "") -> str:
        """Where an open dialog starts: the folder in ``setting`` (the last hand's, the last motion's), else
        ``launched`` (a shipped file's named at launch), else the shipped ``assets/<shipped>``, else the working
        directory."""
        from s2h_viewer.samples import ASSETS_DIR
        last = Path(str(self.settings.value(setting, "")))
        for folder in (last, Path(launched), ASSETS_DIR / shipped):
            if str(folder) not in ("", ".") and folder.is_dir():
                return str(folder)
        return str(Path.cwd())

    def add_target(self) -> None:
        self._ask_to_open("Add target hand", TARGET_HAND_FILTER, self.add_target_file, self._hand_dir())

    def add_target_file(self, path: str) -> None:
        """The hand in ``path`` as one more target; of a character's file (both hands), the hand the user picks,
        or both (the right one alone was all Add target could give, the left only by launching with --side left)."""
        hand = self._load_hand(path)
        if hand is None:
            return
        hands = [hand]
        if hand.meta.get("both_hands") and self.open_options.side is None:
            other = "left" if hand.meta["side"] == "right" else "right"
            accept = QMessageBox.ButtonRole.AcceptRole
            choice = ask(self, "s2h-viewer: which hand", f"{Path(path).name} has both hands.",
                         [(f"{hand.meta['side'].capitalize()} hand", accept), (f"{other.capitalize()} hand", accept),
                          ("Both hands", accept), ("Cancel", QMessageBox.ButtonRole.RejectRole)],
                         "Which to add as a target? (s2h view --side left opens every file's left hand.)")
            if choice == 3:
                return
            if choice > 0:
                second = self._load_hand(path, side=other)
                if second is None:
                    return
                hands = [second] if choice == 1 else with_distinct_names([hand, second])  # each named by its side
        for target in hands:
            added = self.compare.add_target(target)  # perhaps a copy, named apart from the other targets
            if added is not None:  # a new hand: computed later, never at once
                self._loading.append(("target", path, added))

    # --- exports ---
    def _export_dir(self) -> Path:
        """Where exports go: the last export's folder, else the working directory (if writable), else home."""
        last = Path(str(self.settings.value("files/export_dir", "")))
        if str(last) not in ("", ".") and last.is_dir():
            return last
        return Path.cwd() if os.access(Path.cwd(), os.W_OK) else Path.home()

    def _ask_to_save(self, title: str, file_filter: str, path: str | None, name: Callable[[], str]) -> str | None:
        """``path`` when given, else the user's choice, offered as ``name()`` in the export folder (a whole path:
        there); None without a comparison to export."""
        if self.comparison is None:
            return None
        return path or QFileDialog.getSaveFileName(self, title, str(self._export_dir() / name()), file_filter)[0] \
            or None

    def _wrote(self, path: Path, what: str = "") -> Path:
        self.settings.setValue("files/export_dir", str(Path(path).resolve().parent))
        bar = self.statusBar()
        room = bar.width() - sum(w.width() for w in bar.findChildren(JobProgress) if w.isVisible()) - MESSAGE_MARGIN
        bar.showMessage(exports.wrote_text(path, what, bar.fontMetrics(), room), STATUS_MS_EXPORT)
        return path

    def export_screenshot(self, path: str | None = None) -> Path | None:
        """The grid as shown when asked: playback pauses while the file dialog is up (the suggested name holds
        the frame, and the frame written must be that one), then plays on."""
        playing = self.timeline.playing
        self.timeline.set_playing(False)
        try:
            if self.comparison is None:
                return None
            shown = exports.Shown.of(self.compare, grab=self.export_size is None)  # before the dialog waits
            path = self._ask_to_save("Export screenshot", "PNG (*.png)", path, lambda: shown.name(".png", shown.frame))
            return self._wrote(exports.export_screenshot(shown, path, self.export_size)) if path else None
        finally:
            self.timeline.set_playing(playing)

    def export_video(self, path: str | None = None, frames: range | None = None) -> exports.VideoExport | None:
        """Start rendering the clip, or ``frames`` of it, to a video in the background; without ``path`` the user
        chooses the file, then the frames. The job's signals say how it ended."""
        if self.video_export is not None:
            self.error("A video export is running; wait for it or cancel it first.")
            return None
        if self.comparison is None:
            return None
        shown = exports.Shown.of(self.compare)  # what the dialogs' wait must not change
        if not path:
            path, frames = self._ask_video(shown) or (None, None)
        if not path:
            return None
        frames = frames if frames is not None else self.timeline.marked  # a marked range, else the whole clip
        job = exports.VideoExport(shown, path, self, frames, self.export_size)
        what = f" ({exports.frames_text(job.frames, shown.comparison.n_frames)})"
        job.written.connect(lambda written: self._wrote(written, what))
        name = Path(path).name
        job.strip.canceled.connect(lambda: self.statusBar().showMessage(  # said at once: the job stops after a frame
            f"cancelling the video export: {name} will not be written..."))
        job.cancelled.connect(lambda: self.statusBar().showMessage(
            f"video export cancelled: no file written ({name})", STATUS_MS_EXPORT))
        job.failed.connect(self.error)
        for signal in (job.written, job.cancelled, job.failed):
            signal.connect(self._video_export_ended)
        self.video_export = job
        return job.start()

    def _ask_video(self, shown: exports.Shown) -> tuple[str, range] | None:
        """The file, then the frames (`FrameRangeDialog`) the user chooses; None if they cancel either. Playback
        pauses meanwhile (the current frame is one of the choices, and must stay the one offered), then plays on."""
        playing = self.timeline.playing
        self.timeline.set_playing(False)
        try:
            path = self._ask_to_save("Export video", "Video (*.mp4 *.gif)", None, lambda: shown.name(".mp4"))
            if not path:
                return None
            frames = self._ask_frames(path, "video", shown)
            return None if frames is None else (path, frames)
        finally:
            self.timeline.set_playing(playing)

    def _ask_frames(self, path: str, what: str, shown: exports.Shown) -> range | None:
        """The frames of an export to ``path`` of the clip ``shown`` (`FrameRangeDialog`, the marked range first);
        None: cancelled."""
        from s2h_viewer.widgets.frame_range_dialog import FrameRangeDialog
        clip = shown.comparison
        dialog = FrameRangeDialog(Path(path).name, clip.n_frames, clip.motion.fps, shown.frame, self, what=what,
                                  marked=self.timeline.marked)
        frames = dialog.frames() if dialog.exec() == QDialog.DialogCode.Accepted else None
        dialog.deleteLater()
        if frames is None:
            self.statusBar().showMessage(f"{what} export cancelled: no file written ({Path(path).name})", 5000)
        return frames

    def _video_export_ended(self, *_) -> None:
        self.video_export = None

    def export_motion(self, path: str | None = None) -> Path | None:
        if self.comparison is None:
            return None
        shown = exports.Shown.of(self.compare)
        result = shown.selected
        asked = path is None
        row = self.batch_browser.row_of(shown.comparison.motion, result)
        output = Path(row["output"]) if row is not None else None
        beside = output.with_name(f"{output.stem}{'_fixed' if result.corrections else ''}{output.suffix}") \
            if output is not None and output.parent.is_dir() else None  # beside the batch's own output, named as it
        path = self._ask_to_save(f"Export {exports.label(result)}", "Motion (*.glb *.bvh *.npz *.fbx)", path,
                                 lambda: str(beside) if beside is not None else shown.name(".glb"))
        if not path:
            return None
        try:
            check_motion_export(path)  # a format it cannot write (FBX with no Blender): said now, not after the frames
        except S2HError as exc:
            self.error(str(exc))
            return None
        lost = exports.corrections_to_remove(self.compare, shown, path)
        if lost is not None and ask(self, "s2h-viewer: corrections beside the file", f"{Path(path).name}: {lost}.",
                                    [("Export and remove them", QMessageBox.ButtonRole.DestructiveRole),
                                     ("Cancel", QMessageBox.ButtonRole.RejectRole)],
                                    "They were exported with that file in an earlier session: the sidecar is all that "
                                    "holds them. Cancel, then Fix > Load corrections to bring them onto a retarget, "
                                    "or export under another name to keep them.", default=1) != 0:
            return None
        frames = self._ask_frames(path, "motion", shown) if asked else self.timeline.marked
        if asked and frames is None:
            return None
        try:
            written = exports.export_motion(shown, path, frames)
        except S2HError as exc:
            self.error(str(exc))
            return None
        except OSError as exc:  # the motion itself (a fresh-eyes user read "its corrections sidecar" here)
            self.error(f"{path}: could not write ({exc.strerror or exc})")
            return None
        try:
            fixes, removed = exports.export_corrections(self.compare, shown, written, frames)
        except OSError as exc:
            self.error(f"{written}: written, but not its corrections sidecar ({exc.strerror or exc})")
            return None
        sidecar = export_sidecar(written, result.target)
        parts = ([f"its TBS frames {sidecar.name}"] if sidecar is not None else []) + (
            [f"its corrections {fixes.name}"] if fixes is not None else [])
        return self._wrote(written, (f" and {' and '.join(parts)}" if parts else "") + removed)

    def save_corrections(self, path: str | None = None, result=None) -> Path | None:
        """Fix > Save corrections: the selected retarget's (or ``result``'s) corrections as a sidecar
        (`io.corrections`), where the user chooses unless ``path`` is given."""
        if self.comparison is None:
            return None
        result = result or self.compare.selected_result()
        if not result.corrections:
            self.statusBar().showMessage(f"{exports.label(result)} has no corrections to save", STATUS_MS_EXPORT)
            return None
        path = self._ask_to_save(f"Save corrections of {exports.label(result)}", "Corrections (*.corrections.json)",
                                 path, lambda: exports.Shown.of(self.compare).name(".corrections.json", result=result))
        if not path:
            return None
        try:
            return self._wrote(self.compare.fixing.save(path, result))
        except OSError as exc:
            self.error(f"{path}: could not write ({exc.strerror or exc})")
            return None

    def confirm_corrections(self, doing: str) -> bool:
        """Corrections neither exported nor saved: saved (asking where), discarded, or ``doing`` is cancelled."""
        return self.compare.fixing.confirm_discard(doing, lambda result: self.save_corrections(result=result))

    def load_corrections(self, path: str | None = None) -> None:
        """Fix > Load corrections: a sidecar's corrections applied to the selected retarget (undoable)."""
        if self.comparison is None:
            return
        if path is None:
            self._ask_to_open("Load corrections onto the selected retarget", "Corrections (*.corrections.json)",
                              self.load_corrections, str(self._export_dir()))
            return
        try:
            self.compare.fixing.load(path)
        except S2HError as exc:
            self.error(str(exc))

    # --- annotate mode's entry points ---
    def open_hand_to_annotate(self) -> None:
        self._ask_to_open("Open hand to annotate", TARGET_HAND_FILTER, self.annotate_file, self._hand_dir())

    def open_hand_with_joint_map(self) -> None:
        """Annotate > Open hand with joint map...: choose the bone of each joint first, then annotate."""
        self._ask_to_open("Open hand with joint map", RIG_FILTER,
                          lambda path: self.annotate_file(path, map_joints=True), self._hand_dir())

    def annotate_file(self, path: str, map_joints: bool = False) -> None:
        """Load a hand (its sidecar or solver frames come with it; with ``map_joints`` the user maps its bones
        first) and show it in annotation mode; unsaved edits of the last hand are saved or dropped first, as the
        user says."""
        if not self.annotate.confirm_discard("opening another hand"):
            return
        hand = self._load_hand(path, map_joints)
        if hand is None:
            return
        self._remember(path, "annotate")
        self.annotate.open(hand, path)
        if self.annotation is not None and self.annotation.hand is hand:
            self.setWindowTitle(f"s2h-viewer: annotating {Path(path).name} ({hand_side(hand)} hand)[*]")
        self.tabs.setCurrentWidget(self.annotate.view)
        self._follow_mode()  # the solver and saving now have a hand

    def run_solver(self) -> None:
        self.annotate.run_solver()

    def save_annotation(self) -> Path | None:
        return self.annotate.save()

    # --- drag and drop: a motion replaces the clip, a hand is opened for annotation ---
    def dragEnterEvent(self, event) -> None:
        if event.mimeData().hasUrls():
            event.acceptProposedAction()

    def dropEvent(self, event) -> None:
        from s2h_viewer.io.files import MOTION_SUFFIXES
        for url in event.mimeData().urls():
            path = url.toLocalFile()
            rig = Path(path).suffix.lower() in (".glb", ".gltf", ".vrm", ".fbx")
            if rig or self.tabs.currentWidget() is self.annotate.view:
                self.annotate_file(path)
            elif Path(path).suffix.lower() in MOTION_SUFFIXES:
                self.load_motion(path)

    def _confirm_quit_during_export(self) -> bool:
        """Quitting with a video export running: keep exporting (no quit), or cancel it (nothing written) and
        quit. The question counts the frames as they render, and goes away if the export ends meanwhile
        (nothing is left to lose: the quit goes on)."""
        if self.video_export is None:
            return True
        job = self.video_export
        box = QMessageBox(QMessageBox.Icon.Question, "s2h-viewer: video export running", "", parent=self)
        keep = box.addButton("Keep exporting", QMessageBox.ButtonRole.RejectRole)
        quit_button = box.addButton("Cancel export and quit", QMessageBox.ButtonRole.DestructiveRole)
        box.setDefaultButton(keep)

        def refresh() -> None:
            if self.video_export is not job:
                box.done(0)
            else:
                box.setText(f"{Path(job.path).name} is still being rendered ({job.strip.value()} of "
                            f"{job.strip.maximum()} frames). Quitting cancels it and writes no file.")
        refresh()
        live = QTimer(box)
        live.timeout.connect(refresh)
        live.start(250)
        box.exec()
        live.stop()
        if self.video_export is not job:  # it ended while the question was up
            return True
        if box.clickedButton() is not quit_button:
            return False
        job.cancel()
        job.thread.join()  # it stops after the frame it renders; its temporary file goes
        return True

    def resizeEvent(self, event) -> None:
        """Without a window manager nobody enforces the minimum size (an X client may resize the window to
        anything): the window grows back to it."""
        super().resizeEvent(event)
        if self.width() < MIN_SIZE[0] or self.height() < MIN_SIZE[1]:
            QTimer.singleShot(0, lambda: self.resize(max(self.width(), MIN_SIZE[0]), max(self.height(), MIN_SIZE[1])))

    def closeEvent(self, event) -> None:
        if not self.annotate.confirm_discard("quitting") or not self.confirm_corrections("quitting") or \
                not self._confirm_quit_during_export():
            event.ignore()
            return
        self.settings.setValue("window/geometry", self.saveGeometry())
        self.runner.finish()
        self.compare.shutdown()
        self.annotate.view.interactor.close_plotter()
        super().closeEvent(event)


def run(setup: CompareSetup | None = None, open_options=None) -> int:
    """Start the application (``s2h view``)."""
    import sys

    from PySide6.QtWidgets import QApplication
    app = QApplication.instance() or QApplication(sys.argv)
    app.setApplicationName("s2h-viewer")
    setup = setup or default_setup()
    window = MainWindow(setup, open_options=open_options)
    window.show()
    window.activateWindow()  # without a window manager nobody else gives it the keyboard
    window.start_comparison()
    QTimer.singleShot(0, lambda: window.offer_launch_rig(setup))
    return app.exec()
