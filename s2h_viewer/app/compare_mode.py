"""Compare mode (its own tab): a motion on its source hand retargeted onto targets with methods, on a
timeline with the selected retarget's error curve, the ASM heatmap and the scores table beside it.

All of it follows one ``CompareState``, changed only through this class's actions (methods, add or
remove a target, load a motion, select, cancel). Each action queues the retargets it lacks or cancels
running ones it no longer needs (``RetargetQueue``); results are cached per (motion, source, target,
method), so ticking a method computes that method alone. The grid shows the state once everything it
asks for is computed; Cancel goes back to what the grid showed, and the menus follow (before the
first grid, to the methods computed for every target: none ticked, an empty grid, if none is); the
changes it drops are undone on the undo stack, so Redo makes them again.
Results nothing asks for any more (an unticked method) stay in a bounded spare cache while the motion
and their target stay, so ticking the method again is instant. Ticking or unticking methods, adding and
removing a target are undoable (its own undo stack: Edit > Undo in this tab): undo and redo bring back
the results they had, nothing recomputed."""

from __future__ import annotations

import dataclasses
import html
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QAction, QUndoCommand, QUndoStack
from PySide6.QtWidgets import QComboBox, QFrame, QLabel, QMenu, QScrollArea, QSplitter, QVBoxLayout, QWidget

from s2h_viewer.annotate.trust import frame_warning
from s2h_viewer.app.job_progress import JobProgress
from s2h_viewer.app.retarget_fixing import RetargetFixing
from s2h_viewer.app.retarget_queue import RetargetQueue
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.files import RigOptions, load_motion_file
from s2h_viewer.render.compare_scene import BANNER_COLOUR
from s2h_viewer.retarget.compare_state import CompareState, ResultKey
from s2h_viewer.retarget.comparison import Comparison, MethodResult, corrected_result, with_distinct_names
from s2h_viewer.retarget.corrections import Corrections
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.semantics.flexion import bend_angles
from s2h_viewer.semantics.signature import frame_sideways
from s2h_viewer.widgets.asm_heatmap import AsmHeatmap, spaced
from s2h_viewer.widgets.compare_view import CompareView
from s2h_viewer.widgets.error_curve import ErrorCurve
from s2h_viewer.widgets.scores_table import SIDEWAYS_RED, ScoresTable
from s2h_viewer.widgets.timeline import Timeline

PROGRESS_STEPS = 1000
TABLE_SHARE = 0.25  # of the panels' height: the most the scores table takes until its splitter is dragged
#: what the error curve can show (`CompareMode.show_curve`)
ASM_CURVE, SIDEWAYS_CURVE, RESIDUAL_CURVE, ANGLE_CURVE = "asm", "sideways", "residual", "angle"
#: frames of results (every frame's pose and ASM error) the spare cache of unticked methods holds at most
SPARE_FRAMES = 100_000


@dataclass
class CompareSetup:
    """What compare mode starts with: a motion on its source hand, retargeted onto targets with methods."""

    motion: Motion
    source: HandModel
    targets: list[HandModel]
    methods: list[str] = field(default_factory=lambda: ["tbs_copy", "asrn"])
    #: the methods were named (`s2h view --methods`): they win over the ones ticked when the window last closed
    methods_named: bool = False
    #: the file the motion was read from and the options it was read with (None: made, not read): opened again
    #: unchanged, it is this clip (`app.opened_clips`); the clip shown at launch was computed again before
    path: Path | None = None
    options: RigOptions = field(default_factory=RigOptions)
    #: the hand file it was read onto (`s2h view --source`), where its own skeleton was not used
    rig_file: str | None = None


def default_setup() -> CompareSetup:
    """The shipped samples: the gestures clip on birch, onto a realistic and a stylised held-out hand."""
    from s2h_viewer import samples
    path = samples.ASSETS_DIR / next(m["file"] for m in samples.read_index()["motions"] if m["name"] == "gestures")
    motion = load_motion_file(path)[0]
    return CompareSetup(motion, samples.load_sample_hand(motion.hand_name),
                        [samples.load_sample_hand("iris"), samples.load_sample_hand("laurel")], path=path)


def sideways_text(name: str, scores, motion: Motion) -> str:
    """"ASRN -> iris: worst sideways flexion: ring DIP bends 40 deg sideways at frame 212 (fist), at its tightest
    curls (the source there: 11; ...)" (`RetargetScores.sideways_words`, the poses named from ``motion``'s labels),
    in red past the sideways limit. Named: over the curve it read as the curve's, which may show another quantity."""
    text = html.escape(f"{name}: worst sideways flexion: {scores.sideways_words(motion.held_at)}")
    return f"<span style='color:{SIDEWAYS_RED}'>{text}</span>" if scores.sideways_broken else text


def selected_notes(result: MethodResult, sideways: bool) -> str:
    """The line over the curve: with the sideways curve (``sideways``), the retarget's worst sideways bend; its
    target's unsure frames if any. The sideways line over the ASM error or a joint's bend read as the curve's (two
    fresh-eyes runs): the scores table's "Sideways" column gives it there."""
    warning = frame_warning(result.target)
    lines = [sideways_text(label(result), result.scores, result.motion)] if sideways else []
    if warning is not None:
        note = f"! {result.target.name}: {warning.banner}: retargets may bend there; check them in Annotate"
        lines.append(f"<span style='color:{BANNER_COLOUR}'>{html.escape(note)}</span>")
    return "<br>".join(lines)


def sideways_curve(result: MethodResult) -> np.ndarray:
    """(T,) the error curve's sideways choice: `semantics.signature.frame_sideways` of the retarget."""
    return frame_sideways(result.pose.positions.numpy())


def label(result: MethodResult) -> str:
    """'TBS Copy -> iris', '(fixed)' after it where corrections are applied."""
    return result.name + (" (fixed)" if result.corrections else "")


class SetMethodsCommand(QUndoCommand):
    """Tick or untick methods (undoable): the results of an unticked method wait in the spare cache, so undo
    and redo show them again without computing them."""

    def __init__(self, mode: "CompareMode", methods: list[str]):
        before = list(mode.state.methods)
        ticked = [METHODS[m].label for m in methods if m not in before]
        unticked = [METHODS[m].label for m in before if m not in methods]
        super().__init__(", ".join([f"tick {m}" for m in ticked] + [f"untick {m}" for m in unticked]))
        self.mode, self.before, self.after = mode, before, list(methods)

    def redo(self) -> None:
        self.mode._apply_methods(self.after)

    def undo(self) -> None:
        self.mode._apply_methods(self.before)


class AddTargetCommand(QUndoCommand):
    """Add a target (undoable): undo takes it away keeping its results (and its selection), redo brings it
    back with them."""

    def __init__(self, mode: "CompareMode", hand: HandModel):
        super().__init__(f"add {hand.name}")
        self.mode, self.hand = mode, hand
        self.results: dict[ResultKey, MethodResult] = {}
        self.selected: ResultKey | None = None

    def redo(self) -> None:
        self.mode._restore_target(len(self.mode.state.targets), self.hand, self.results, self.selected)

    def undo(self) -> None:
        index = next(i for i, t in enumerate(self.mode.state.targets) if t is self.hand)
        self.results, self.selected = self.mode._drop_target(index)


class RemoveTargetCommand(QUndoCommand):
    """Remove one target (undoable): undo puts it back where it was, with the results it had, selected again
    if one of its retargets was."""

    def __init__(self, mode: "CompareMode", index: int):
        self.hand = mode.state.targets[index]
        super().__init__(f"remove {self.hand.name}")
        self.mode, self.index = mode, index
        self.results: dict[ResultKey, MethodResult] = {}
        self.selected: ResultKey | None = None

    def redo(self) -> None:
        self.results, self.selected = self.mode._drop_target(self.index)

    def undo(self) -> None:
        self.mode._restore_target(min(self.index, len(self.mode.state.targets)), self.hand, self.results,
                                  self.selected)


class CompareMode(QWidget):
    """The Compare tab. ``comparison_ready`` fires when the grid shows everything the state asks for;
    ``state_changed`` whenever methods or targets change (the window's menus follow it)."""

    comparison_ready = Signal()
    state_changed = Signal()
    result_changed = Signal()  # a retarget on screen replaced by its corrected self (`show_result`)

    def __init__(self, setup: CompareSetup, error: Callable[[str], None], status: Callable[[str], None],
                 parent: QWidget | None = None):
        super().__init__(parent)
        self.error, self.status = error, status
        self.state = CompareState(setup.motion, setup.source, with_distinct_names(setup.targets), list(setup.methods))
        #: the methods are a batch's rows' (`replace_comparison`) until the user chooses some or opens a motion: not
        #: remembered for the next session
        self.methods_from_batch = False
        self._shown: tuple | None = None  # (motion, source, targets, methods) on screen: where Cancel returns
        self._shown_index = 0  # the undo stack's index when the grid showed ``_shown``
        self._reverting = False  # Cancel is undoing its dropped changes: they only set the state back
        self._spare: dict[ResultKey, MethodResult] = {}  # results no one asks for now, oldest first
        #: the clips (motion, source) results are kept for, by id: held, so that no new clip takes a kept one's id
        self._clips: dict[tuple[int, int], tuple[Motion, HandModel]] = {}
        self.undo_stack = QUndoStack(self)
        self.comparison: Comparison | None = None
        self.queue = RetargetQueue(self)
        self._done_in_batch = 0
        self._resume_playing = False  # the timeline played when retargets paused it: it plays on after
        self._progress: JobProgress | None = None
        self.curve_shows = ASM_CURVE  # or the sideways flexion, a joint's angle, a tracked fit's residual (View)
        self.curve_joint = topo.FINGER_JOINT_NAMES.index("index_pip")  # the heatmap row whose angle it shows
        self.view = CompareView()
        self.timeline = Timeline()
        self.curve = ErrorCurve()
        self.heatmap = AsmHeatmap()
        self.heatmap_choice = QComboBox()
        self.heatmap_choice.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.heatmap_choice.setMinimumContentsLength(24)  # a long target name elides instead of widening the panel
        self.heatmap_choice.setToolTip("the retarget the heatmap, the error curve, the scores' highlight and "
                                       "exports follow")
        self.scores = ScoresTable()
        self.sideways_note = QLabel()  # the selected retarget's worst sideways bend and unsure frames, in words
        self.sideways_note.setWordWrap(True)
        self.sideways_note.setTextFormat(Qt.TextFormat.RichText)  # escaped names: a plain line showed "-&gt;"
        # a line high even when empty: choosing another curve does not move the panels above (nor an export's size)
        self.sideways_note.setMinimumHeight(self.sideways_note.fontMetrics().lineSpacing())
        self._table_height = 0  # the scores table's height the user dragged its splitter to (0: not dragged)
        layout = QVBoxLayout(self)
        layout.addWidget(self._panels(), 1)
        layout.addWidget(self.timeline)
        layout.addWidget(self.sideways_note)  # a line over the curve: the side panel keeps its height
        layout.addWidget(self.curve)
        self.timeline.frame_changed.connect(self.show_frame)
        self.view.drawn.connect(self.timeline.note_drawn)
        self.timeline.play_button.toggled.connect(self._playing_changed)
        self.curve.frame_clicked.connect(self.timeline.set_frame)
        self.timeline.range_changed.connect(self.curve.set_range)
        self.view.solo_changed.connect(self._hand_chosen)
        self.view.hand_clicked.connect(self._hand_chosen)  # a retarget clicked in the grid is selected
        self.heatmap_choice.currentIndexChanged.connect(self._choice_changed)
        self.heatmap.row_chosen.connect(self.choose_joint)
        self.scores.currentCellChanged.connect(lambda row, *_: self._select_row(row))
        self.queue.result_ready.connect(self._on_result)
        self.queue.semantics_ready.connect(self._on_semantics)
        self.queue.progress.connect(self._on_progress)
        self.queue.failed.connect(self._on_failure)
        self.queue.idle.connect(self._on_idle)
        self.fixing = RetargetFixing(self)

    def _panels(self) -> QSplitter:
        """The grid beside the heatmap, over the scores table the whole width (its columns need more than a side
        panel has at 1000 pixels); splitters between them. The heatmap keeps its size and scrolls where the
        window is too short for it, never squeezed under its legend."""
        side = QWidget()
        side_layout = QVBoxLayout(side)
        side_layout.setContentsMargins(4, 0, 4, 0)
        side_layout.addWidget(self.heatmap_choice)
        side_layout.addWidget(self.heatmap)
        side_layout.addStretch(1)
        scroll = QScrollArea()
        scroll.setWidget(side)
        scroll.setWidgetResizable(True)
        scroll.setFrameShape(QFrame.Shape.NoFrame)
        scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        scroll.setMinimumWidth(side.sizeHint().width() + scroll.verticalScrollBar().sizeHint().width())
        top = QSplitter()
        top.addWidget(self.view)
        top.addWidget(scroll)
        top.setStretchFactor(0, 1)
        top.setStretchFactor(1, 0)
        panels = QSplitter(Qt.Orientation.Vertical)
        panels.addWidget(top)
        panels.addWidget(self.scores)
        panels.setStretchFactor(0, 1)
        panels.setStretchFactor(1, 0)
        panels.setChildrenCollapsible(False)
        panels.splitterMoved.connect(self._table_dragged)
        self.panels = panels
        return panels

    def _table_dragged(self) -> None:
        self._table_height = self.panels.sizes()[1]  # the user's choice: kept from now on

    def _fit_table(self) -> None:
        """The table's share of the panels: its rows up to `TABLE_SHARE` of the height (at least two rows), or the
        height the user dragged it to."""
        total = sum(self.panels.sizes())
        if total <= 0:
            return
        want = self._table_height or min(self.scores.sizeHint().height(), int(TABLE_SHARE * total))
        want = max(want, self.scores.minimumSizeHint().height())
        self.panels.setSizes([total - want, want])

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        self._fit_table()

    @property
    def setup(self) -> CompareState:
        return self.state

    # --- actions: the only ways the state changes ---
    def start_comparison(self) -> None:
        """Compute whatever the state lacks (everything, the first time) and show it."""
        self._sync()

    def set_methods(self, methods: list[str]) -> None:
        """Tick exactly ``methods`` (undoable)."""
        methods = [m for m in METHODS if m in methods]
        if methods != self.state.methods:
            self.undo_stack.push(SetMethodsCommand(self, methods))

    def _apply_methods(self, methods: list[str]) -> None:
        self.state.methods = list(methods)
        self._sync()

    def add_target(self, hand: HandModel) -> HandModel | None:
        """One more target, the last row (undoable), and the hand added: ``hand``, or a copy named apart from the
        other targets (`retarget.comparison.distinct_name`); a hand that is a target already is refused, saying so
        (two identical rows compare nothing), and None returned."""
        if any(target.same_as(hand) for target in self.state.targets):
            self.error(f"{hand.name} is a target already (the same hand: skeleton, frames and mesh); "
                       f"nothing was added")
            return None
        added = with_distinct_names([hand], self.state.targets)[0]
        self.undo_stack.push(AddTargetCommand(self, added))
        return added

    def remove_target(self, index: int) -> None:
        """Drop one target and its results (undoable); the rest stay as computed."""
        self.undo_stack.push(RemoveTargetCommand(self, index))

    def _drop_target(self, index: int) -> tuple[dict[ResultKey, MethodResult], ResultKey | None]:
        """Take target ``index`` away; returns its results and the selection if it was one of them."""
        hand = self.state.targets[index]
        results = {k: r for k, r in self.state.results.items() if k.target == id(hand)}
        selected = self.state.selected if self.state.selected in results else None
        targets = list(self.state.targets)
        del targets[index]
        self.state.targets = targets
        self._sync()
        return results, selected

    def _restore_target(self, index: int, hand: HandModel, results: dict[ResultKey, MethodResult],
                        selected: ResultKey | None = None) -> None:
        """Put a removed target back at ``index``; its results come back from ``results``, not recomputed, and
        ``selected`` (one of them) is the selection again."""
        self._spare.update(results)
        targets = list(self.state.targets)
        targets.insert(index, hand)
        self.state.targets = targets
        if selected is not None:
            self.state.selected = selected
        self._sync()

    def load(self, motion: Motion, source: HandModel) -> None:
        self.state.motion, self.state.source = motion, source
        self._resume_playing = False  # a new clip starts paused
        self.timeline.set_playing(False)
        self._sync()

    def replace_comparison(self, motion: Motion, source: HandModel, targets: list[HandModel],
                           methods: list[str]) -> None:
        """A comparison of its own: ``motion`` onto ``targets`` with ``methods`` alone (a batch row of another clip:
        the grid had kept every earlier target and method, and computed retargets nobody asked for). Its undo
        history starts afresh: the earlier one's commands name targets this one does not have."""
        self.undo_stack.clear()
        self.state.targets, self.state.methods = with_distinct_names(targets), [m for m in METHODS if m in methods]
        self.methods_from_batch = True
        self.load(motion, source)

    def select(self, key: ResultKey, turn_page: bool = True) -> None:
        """One retarget for the heatmap, the error curve, the scores' highlight and the exports; the grid turns
        to its page unless ``turn_page`` is False."""
        self.state.selected = key
        if self.comparison is not None:
            keys = self.shown_keys()
            if key in keys:
                index = keys.index(key)
                for widget, setter in ((self.heatmap_choice, lambda: self.heatmap_choice.setCurrentIndex(index)),
                                       (self.scores, lambda: self.scores.selectRow(index))):
                    widget.blockSignals(True)
                    setter()
                    widget.blockSignals(False)
                alone = self.view.solo_hand() is not None
                self.view.set_selected(index, turn_page)  # a page turned builds the grid anew: no hand alone
                if alone and (self.view.solo_hand() is None or self.view.result_of_hand(self.view.solo) != index):
                    self.view.set_solo(self.view.hand_of_result(index))  # the hand alone is the one selected
            self._show_selected_curve()
            self.show_frame(self.timeline.frame)

    def cancel(self) -> None:
        """Stop every queued and running retarget and go back to what the grid shows; the menus follow."""
        self.queue.cancel_all()
        if self._shown is not None:
            self._reverting = True  # the changes Cancel drops become redoable, not stay undoable
            try:
                self.undo_stack.setIndex(self._shown_index)
            finally:
                self._reverting = False
            motion, source, targets, methods = self._shown
            self.state.motion, self.state.source = motion, source
            self.state.targets, self.state.methods = list(targets), list(methods)
        else:  # nothing shown yet (the first comparison): keep the targets, tick what is computed for all
            self.state.methods = [m for m in self.state.methods
                                  if all(self.state.key(t, m) in self.state.results for t in self.state.targets)]
        self.status("retargeting cancelled" if self.state.methods else "retargeting cancelled: tick a method")
        self._sync()

    # --- keeping the queue and the screen on the state ---
    def shown_keys(self) -> list[ResultKey]:
        """The keys of the retargets on screen, in the comparison's order: of the clip on screen, which is not the
        state's while another clip is computed (keyed by the state's, none matched the selection, and the heatmap
        and the curve showed the first retarget's errors under the selected one's name)."""
        comparison = self.comparison
        if comparison is None:
            return []
        return [ResultKey(id(comparison.motion), id(comparison.source), id(r.target), r.method)
                for r in comparison.results]

    def _sync(self) -> None:
        """Prune what nothing needs, queue what is missing (cancelling what is not wanted), show when complete."""
        if self._reverting:
            return
        keep = set(self.state.wanted())
        self._clips[(id(self.state.motion), id(self.state.source))] = (self.state.motion, self.state.source)
        if self._shown is not None:
            motion, source, targets, methods = self._shown
            keep |= {ResultKey(id(motion), id(source), id(t), m) for t in targets for m in methods}
        self._keep_results(keep)
        missing = self.state.missing()
        was_busy = bool(self.queue.pending())
        self.queue.submit([(k, self.state.motion, self.state.source, self.state.target_of(k)) for k in missing])
        self.state_changed.emit()
        if missing:
            if not was_busy:
                self._done_in_batch = 0
            self._resume_playing |= self.timeline.playing
            self.timeline.set_playing(False)
            self._show_progress()
        else:
            self._close_progress()
            self._resume_playback()
            self._show_state()

    def _keep_results(self, keep: set[ResultKey]) -> None:
        """Results outside ``keep`` go to the spare cache; the spares of these targets that ``keep`` asks for come
        back, of this clip or of one opened again (at most SPARE_FRAMES frames are kept, the oldest dropped
        first); the source's semantics are kept for every clip with results kept."""
        leaving = {k: r for k, r in self.state.results.items() if k not in keep}
        self._spare.update(leaving)
        fixed = [label(r) for r in leaving.values() if r.corrections]
        if fixed:  # a corrected retarget unticked or its target removed: its corrections are kept, say where
            self.status(f"{', '.join(fixed)}: its corrections are kept (Edit > Undo, or tick the method again)")
        targets = {id(t) for t in self.state.targets}
        self._spare = {k: r for k, r in self._spare.items() if k.target in targets}
        self.state.results = {k: r for k, r in self.state.results.items() if k in keep}
        self.state.results.update({k: self._spare.pop(k) for k in keep if k in self._spare})
        frames = sum(len(r.cell_error) for r in self._spare.values())
        for key in [k for k, r in self._spare.items() if not r.corrections]:  # a person's corrections stay
            if frames <= SPARE_FRAMES:
                break
            frames -= len(self._spare.pop(key).cell_error)
        clips = {(id(self.state.motion), id(self.state.source))} | {
            (k.motion, k.source) for k in [*self.state.results, *self._spare]}
        self._clips = {k: c for k, c in self._clips.items() if k in clips}
        self.state.semantics = {k: s for k, s in self.state.semantics.items() if k in self._clips}

    def _same_retarget(self, key: ResultKey | None) -> ResultKey:
        """The shown retarget with ``key``'s target and method (a new clip keeps the selection), else the first."""
        keys = self.shown_keys()
        return next((k for k in keys if key is not None and (k.target, k.method) == (key.target, key.method)),
                    keys[0])

    def _on_semantics(self, key: tuple[int, int], semantics: tuple) -> None:
        if key == (id(self.state.motion), id(self.state.source)):
            self.state.semantics[key] = semantics

    def _on_result(self, key: ResultKey, result: MethodResult) -> None:
        if key in set(self.state.wanted()):
            self.state.results[key] = result
            self._done_in_batch += 1
        if not self.state.missing():
            self._close_progress()
            self._resume_playback()
            self._show_state()

    def _resume_playback(self) -> None:
        """Play on if the retargets just finished or cancelled paused the timeline."""
        if self._resume_playing:
            self._resume_playing = False
            self.timeline.set_playing(True)

    def _on_failure(self, key: ResultKey, message: str) -> None:
        self.cancel()
        self.error(message)

    def _on_idle(self) -> None:
        if not self.queue.pending() and not self.state.missing():
            self._close_progress()

    def _show_state(self) -> None:
        """Put the (complete) state on screen: grid, scores, selection, timeline."""
        comparison = self.state.comparison()
        if comparison is None:
            return
        if self.comparison is not None and comparison.motion is self.comparison.motion and [
                id(r) for r in comparison.results] == [id(r) for r in self.comparison.results]:
            self._shown_index = self.undo_stack.index()
            self.comparison_ready.emit()  # already on screen (a cancel or an undo went back to it)
            return
        new_clip = self.comparison is None or self.comparison.motion is not comparison.motion
        # a retarget shown alone (being fixed) stays so when a method is ticked beside it
        alone = self.shown_keys()[self.view.result_of_hand(self.view.solo)] if self.view.solo_hand() else None
        self.comparison = comparison
        self._shown = (self.state.motion, self.state.source, tuple(self.state.targets), tuple(self.state.methods))
        self._shown_index = self.undo_stack.index()
        self._keep_results(set(self.state.wanted()))
        self.view.set_comparison(comparison)
        self.scores.blockSignals(True)  # its current row moving is no choice: `select` below is (a row of a shorter
        self.scores.show_comparison(comparison)  # clip drew the new grid at the old clip's frame, past its end)
        self.scores.blockSignals(False)
        self._fit_table()
        self.heatmap_choice.blockSignals(True)
        self.heatmap_choice.clear()
        self.heatmap_choice.addItems([label(r) for r in comparison.results])
        self.heatmap_choice.blockSignals(False)
        if new_clip:
            self.timeline.set_clip(comparison.n_frames, comparison.motion.fps, comparison.motion.labels)
        self.select(self._same_retarget(self.state.selected), turn_page=False)  # the user's page stays
        same = [(k.target, k.method) for k in self.shown_keys()]
        if alone is not None and (alone.target, alone.method) in same:  # a new clip's too
            self.view.set_solo(self.view.hand_of_result(same.index((alone.target, alone.method))))
        self.status(f"{comparison.motion.name}: {comparison.n_frames} frames, {len(comparison.results)} retargets")
        self.comparison_ready.emit()

    # --- corrections (`app.retarget_fixing`) ---
    def corrected(self, result: MethodResult, corrections: Corrections) -> MethodResult:
        """``result``'s method retarget with ``corrections`` instead of its own, measured against the clip shown."""
        comparison = self.comparison
        source_asm = self.state.semantics[(id(comparison.motion), id(comparison.source))][1]
        return corrected_result(result, corrections, comparison.motion, comparison.source, source_asm)

    def show_result(self, key: ResultKey, result: MethodResult) -> None:
        """``result`` in place of the retarget ``key`` (a correction, its undo or redo): its cell, the scores, the
        heatmap and the curves follow at once. A retarget not on screen keeps it for when it comes back (an
        unticked method's, a removed target's)."""
        if key in self._spare:
            self._spare[key] = result
        if key in self.state.results:
            self.state.results[key] = result
        keys = self.shown_keys()
        if key not in keys:
            return
        index = keys.index(key)
        results = list(self.comparison.results)
        results[index] = result
        self.comparison = dataclasses.replace(self.comparison, results=results)
        self.view.replace_result(index, self.comparison)
        self.scores.show_comparison(self.comparison)
        self.heatmap_choice.setItemText(index, label(result))
        self.select(self.state.selected if self.state.selected in keys else key, turn_page=False)
        self.result_changed.emit()

    # --- progress ---
    def _show_progress(self) -> None:
        if self._progress is None:
            # in the status bar: the menus and the timeline stay usable while it runs (their actions queue or cancel)
            self._progress = JobProgress("Retargeting...", "Cancel", PROGRESS_STEPS, self, "retargeting")
            self._progress.canceled.connect(self.cancel)
            self._progress.setValue(0)

    def _close_progress(self) -> None:
        if self._progress is not None:
            self._progress.canceled.disconnect(self.cancel)
            self._progress.close()
            self._progress.deleteLater()
            self._progress = None

    def _on_progress(self, fraction: float, what: str) -> None:
        remaining = len(self.queue.pending())
        total = self._done_in_batch + max(remaining, 1)
        overall = (self._done_in_batch + fraction) / total
        text = f"{what} ({self._done_in_batch + 1} of {total})"
        if self._progress is not None:
            self._progress.setValue(int(overall * PROGRESS_STEPS))
            # the retarget over its stage: on one line both were cut in the middle ("ASRN -> iris: c...t fit")
            self._progress.setLabelText(text.replace(": ", "\n", 1))
        self.status(f"retargeting: {text}, {int(overall * 100)}%")  # as the strip's bar: 33%, not 34%

    # --- showing a frame and the selection ---
    def selected_result(self) -> MethodResult:
        """The retarget the heatmap shows (and exports follow)."""
        keys = self.shown_keys()
        key = self.state.selected if self.state.selected in keys else keys[0]
        return self.comparison.results[keys.index(key)]

    def _choice_changed(self, index: int) -> None:
        if self.comparison is not None and 0 <= index < len(self.comparison.results):
            self.select(self.shown_keys()[index])

    def _select_row(self, row: int) -> None:
        if self.comparison is not None and 0 <= row < len(self.comparison.results):
            self.select(self.shown_keys()[row])

    def _hand_chosen(self, hand: int) -> None:
        """A retarget shown alone (double-click, Ctrl+M) or clicked in the grid is the selected one; the source
        changes nothing."""
        if self.comparison is not None and hand >= 1:
            self.select(self.shown_keys()[self.view.result_of_hand(hand)])

    def _show_selected_curve(self) -> None:
        result = self.selected_result()
        fit = self.comparison.motion.fit if self.comparison is not None else None
        if self.curve_shows == RESIDUAL_CURVE and fit is not None:
            self.curve.set_curve(fit.residual_mm, f"{self.comparison.source.name}",
                                 "tracking fit residual per frame, mm",
                                 f"{int(fit.filled.sum())} frames filled (grey). ")
        elif self.curve_shows == ANGLE_CURVE:
            joint = self.curve_joint + 1  # a heatmap row: the finger joints follow the wrist
            name = f"{spaced(topo.JOINT_NAMES[joint])} bend"
            if joint in topo.TIP_JOINTS:  # a tip has no bend: the joint that moves it
                name = f"{spaced(topo.JOINT_NAMES[joint - 1])} bend (it moves the {spaced(topo.JOINT_NAMES[joint])})"
            self.curve.set_curve(bend_angles(result.pose.positions.numpy(), joint), label(result),
                                 f"{name}, deg (grey band: the source's)", decimals=1,
                                 reference=bend_angles(self.comparison.source_pose.positions.numpy(), joint))
        elif self.curve_shows == SIDEWAYS_CURVE:
            self.curve.set_curve(sideways_curve(result), label(result),
                                 "worst sideways bend of a curled PIP/DIP per frame, deg", decimals=1)
        else:
            self.curve.set_curve(result.frame_error, label(result))
        self.curve.set_keys(result.corrections.frames())
        self.sideways_note.setText(selected_notes(result, self.curve_shows == SIDEWAYS_CURVE))

    def choose_joint(self, row: int) -> None:
        """A heatmap row clicked (or a joint picked for fixing): the joint whose angle the curve shows (at once if
        it shows angles)."""
        self.curve_joint = row
        if self.curve_shows == ANGLE_CURVE:
            self.show_curve(ANGLE_CURVE)

    def show_curve(self, quantity: str) -> None:
        """What the error curve shows: `ASM_CURVE` (the selected retarget's ASM error), `SIDEWAYS_CURVE` (its
        worst sideways bend), `ANGLE_CURVE` (the heatmap's chosen joint's bend, the source's beside it) or
        `RESIDUAL_CURVE` (a tracked source's fit residual, mm per frame)."""
        self.curve_shows = quantity
        self.heatmap.show_row(self.curve_joint if quantity == ANGLE_CURVE else None)  # framed: the joint it shows
        if self.comparison is not None:
            self._show_selected_curve()
            self.curve.set_frame(self.timeline.frame)

    def _playing_changed(self, playing: bool) -> None:
        """Lighter skins while playing; paused, the full ones and the heatmap at the frame shown."""
        if playing:
            self._resume_playing = False  # played during the retargets: the user's play / pause stands
        self.view.set_playing(playing)
        if not playing:
            self.show_frame(self.timeline.frame)

    def show_frame(self, frame: int) -> None:
        if self.comparison is None:
            return
        self.view.show_frame(frame)
        self.view.prefetch(self.timeline.next_frame())  # posed on a worker while this frame is drawn
        self.curve.set_frame(frame)
        self.heatmap.show_matrix(self.selected_result().cell_error[frame], frame)  # every frame: it is cheap

    def set_see_through(self, checked: bool) -> None:
        self.view.set_options(opacity=0.4 if checked else 1.0)

    def fill_targets_menu(self, menu: QMenu, leading: tuple[QAction, ...] = ()) -> None:
        """``leading`` (adding a target), then one "Remove <target>" entry per target (rebuilt whenever the state
        changes); the last target stays (without one there is nothing to compare, and the grid would keep showing
        it)."""
        menu.clear()
        if leading:
            menu.addActions(list(leading))
            menu.addSeparator()
        for index, target in enumerate(self.state.targets):
            action = menu.addAction(f"Remove {target.name}")
            action.triggered.connect(lambda _=False, i=index: self.remove_target(i))
            action.setEnabled(len(self.state.targets) > 1)

    def shutdown(self) -> None:
        """Stop the retargets and free the render window (the window is closing)."""
        self.queue.cancel_all()
        self.queue.wait()
        self.view.close_grid()
