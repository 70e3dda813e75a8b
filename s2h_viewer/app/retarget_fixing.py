"""Fixing a retarget in Compare (the Fix menu): in a retarget shown alone, click a joint and drag its ring to
turn it about its bend, splay or twist axis at the current frame. Each drag is a key on the joint's offset
curve (`retarget.corrections`) blended over the marked range (else held over the pose the frame holds and eased
over the frames around it: `corrections.key_span`), undoable on Compare's undo stack; the cell, scores, heatmap
and curves follow while the ring is dragged. Every motion export of the retarget carries its corrections, with a
sidecar beside it recording them (`io.corrections`), which Fix > Load corrections and ``s2h retarget
--corrections`` read back."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shiboken6
from PySide6.QtCore import QObject, QTimer
from PySide6.QtGui import QAction, QKeySequence, QUndoCommand
from PySide6.QtWidgets import QApplication, QMenu, QMessageBox

from s2h_viewer.app.annotate_mode import ask
from s2h_viewer.hand import topology as topo
from s2h_viewer.io.corrections import CorrectionsFile, load_corrections, save_corrections
from s2h_viewer.render.compare_scene import ON_TOP_OFFSET
from s2h_viewer.render.scene import to_view
from s2h_viewer.retarget.compare_state import ResultKey
from s2h_viewer.retarget.comparison import MethodResult
from s2h_viewer.retarget.corrections import AXES, Corrections, describe_keys, key_span, turn_about
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.widgets.correction_bar import HINT, CorrectionBar
from s2h_viewer.widgets.rotation_handle import RotationRing, nearest_on_screen, nearest_segment_on_screen
from s2h_viewer.wording import counted

#: while the ring is dragged the whole clip is measured again at most this often (ms)
LIVE_MS = 40
#: the ring's radius as a share of the hand's length, and at least this many pixels on screen when placed
RING_RADIUS, RING_PX = 0.09, 48
#: the mouse in a retarget shown alone, for Help's list
MOUSE = (("click a joint of a retarget shown alone (or a finger's skin: the joint that turns it)",
          "pick it for fixing (its ring appears)"),
         ("drag the ring", "turn the joint at this frame: a correction key (Fix menu)"),
         ("Shift+drag the ring", "turn it a tenth as far as the pointer goes (fine turns)"))
#: a click this near a joint on screen picks it (pixels), else the joint turning the skin or bone under it
JOINT_PIXELS = 6
#: each joint a click can pick (tips pick the joint that moves them): (joint index, articulated index)
PICKABLE = [(int(j), a) for a, j in enumerate(topo.ARTICULATED_JOINTS)] + \
    [(int(t), topo.ARTICULATED_NAMES.index(topo.JOINT_NAMES[t - 1])) for t in topo.TIP_JOINTS]


class FixCommand(QUndoCommand):
    """One change of a retarget's corrections (a drag, a deleted key, a range): undo and redo show the retarget
    measured before and after, nothing recomputed."""

    def __init__(self, fixing: "RetargetFixing", key: ResultKey, before: MethodResult, after: MethodResult,
                 text: str):
        super().__init__(text)
        self.fixing, self.key, self.before, self.after = fixing, key, before, after

    def redo(self) -> None:
        self.fixing.mode.show_result(self.key, self.after)

    def undo(self) -> None:
        self.fixing.mode.show_result(self.key, self.before)


@dataclass
class Drag:
    """A drag of the ring under way: what it turns, from what, over which frames; the turn so far."""

    key: ResultKey
    before: MethodResult
    joint: int
    frame: int
    axis: str
    frames: tuple[int, int]  # the key's start and end (a key already at its frame keeps its own)
    hold: tuple[int, int] | None  # the frames it holds its whole turn over (None: its frame alone)
    sense: float  # +1, or -1 where the view mirrors the hand (a turn on screen is the other way in hand space)
    degrees: float = 0.0

    def corrections(self) -> Corrections:
        turn = turn_about(self.axis, self.sense * self.degrees)
        return self.before.corrections.with_turn(self.joint, self.frame, turn, *self.frames, self.hold)


#: degrees further sideways (the worst PIP/DIP, `semantics.flexion`) that make a fix read as worse
SIDEWAYS_WORSE = 2.0


def score_change(before: MethodResult, after: MethodResult, base: str = "before") -> str:
    """"kept 0.95 -> 0.90, S_finger 0.928 -> 0.909, sideways 44 -> 83 deg (worse than before)": a fix's effect on
    the scores a user ranks by. A fresh-eyes user's 107-degree turn lowered S_finger and nothing said so; another's
    splay bent a finger 39 deg further sideways, and read "S_finger 0.901 -> 0.901"."""
    b, a = before.scores, after.scores
    bent = np.nan_to_num(a.sideways_deg) - np.nan_to_num(b.sideways_deg)  # a finger turned sideways off its curl
    worse = (a.signature_kept < b.signature_kept - 1e-9 or a.s_finger < b.s_finger - 5e-4 or bent > SIDEWAYS_WORSE
             or a.added_violation_rate > b.added_violation_rate + 1e-9)
    sideways = (f", sideways {np.nan_to_num(b.sideways_deg):.0f} -> {np.nan_to_num(a.sideways_deg):.0f} deg"
                if abs(bent) >= 1.0 else "")
    # a finger bent back past straight read "worse" and nothing said why (a fresh-eyes user)
    violations = (f", violations {b.added_violation_rate:.3f} -> {a.added_violation_rate:.3f}"
                  if f"{a.added_violation_rate:.3f}" != f"{b.added_violation_rate:.3f}" else "")
    return (f"kept {b.signature_kept:.3f} -> {a.signature_kept:.3f}, S_finger {b.s_finger:.3f} -> {a.s_finger:.3f}"
            + sideways + violations + (f" (worse than {base}: Ctrl+Z undoes it)" if worse else ""))


class RetargetFixing(QObject):
    """The fixing of Compare mode ``mode``'s retargets: the bar over a retarget shown alone, the ring, the Fix
    menu's actions, the corrections' saving and loading."""

    def __init__(self, mode):
        super().__init__(mode)
        self.mode = mode
        self.bar = CorrectionBar()
        mode.view.add_bar(self.bar)
        self.joint: int | None = None  # the articulated joint picked
        self._picked_on: ResultKey | None = None  # the retarget it was picked on
        self._before_click: tuple | None = None  # the joint, its retarget and the time before the last click picked
        self.ring: RotationRing | None = None
        self._drag: Drag | None = None
        self._saved: dict[ResultKey, Corrections] = {}  # the corrections last exported or saved, per retarget
        self._files: dict[Path, ResultKey] = {}  # each sidecar written or read, and the retarget it holds
        self._live = QTimer(self)
        self._live.setSingleShot(True)
        self._live.setInterval(LIVE_MS)
        self._live.timeout.connect(self._measure_drag)
        mode.view.grid_built.connect(self._follow_solo)
        mode.view.solo_changed.connect(self._follow_solo)
        mode.view.double_clicked.connect(self._double_clicked)
        mode.timeline.frame_changed.connect(self._frame_changed)
        mode.timeline.play_button.toggled.connect(self._playing_changed)
        mode.result_changed.connect(self._place)
        self.bar.axis_choice.currentIndexChanged.connect(lambda _: self._place())
        self.bar.delete_key.connect(self.delete_key)
        self.bar.clear_joint.connect(self.clear_joint)

    # --- what is being fixed ---
    def _solo(self) -> tuple[ResultKey, MethodResult] | None:
        """The retarget shown alone and its key, or None (the grid, the source alone, nothing computed)."""
        view = self.mode.view
        if view.solo_hand() is None or self.mode.comparison is None:
            return None
        index = view.result_of_hand(view.solo)
        return self.mode.shown_keys()[index], self.mode.comparison.results[index]

    def _follow_solo(self, *_) -> None:
        """A retarget shown alone gets the bar and a ring in its cell; the grid neither. The picked joint stays
        with its retarget (the grid and back, however it went there) until Esc or another retarget is shown
        alone: a joint picked on one, its ring over the next one's thumb-index contact, read as a stray pick."""
        hand = self.mode.view.solo_hand()
        self._drop_ring()
        self.bar.setVisible(hand is not None)
        shown = self._solo()
        if shown is not None and shown[0] != self._picked_on:
            self.joint = None
        if hand is None:
            return
        self.ring = RotationRing(self.mode.view.interactor, self._begin, self._turn, self._end, self._clicked,
                                 renderer=hand.renderer, on_ring_click=self._clicked_through)
        self.ring.attach()
        mapper = self.ring.actor.mapper  # drawn over the skin, like the contact overlay
        mapper.SetRelativeCoincidentTopologyPolygonOffsetParameters(0.0, ON_TOP_OFFSET)
        self._place()

    def _drop_ring(self) -> None:
        """The ring out of its cell (its grid may be gone already: then it went with it); a drag under way ends
        as if let go (its key kept and undoable, not left on screen unrecorded)."""
        if self._drag is not None:
            self._end()
        ring, self.ring = self.ring, None
        if ring is None or not shiboken6.isValid(ring):
            return
        ring.widget.removeEventFilter(ring)
        if ring.actor is not None and ring.plotter is self.mode.view.plotter:
            ring.renderer.remove_actor(ring.actor, reset_camera=False, render=False)
        ring.deleteLater()

    def _frame_changed(self, frame: int) -> None:
        """The ring follows the frame; while it is dragged the frame stays the drag's (a key goes where it began)."""
        if self._drag is not None and frame != self._drag.frame:
            self.mode.timeline.set_frame(self._drag.frame)
            return
        self._place()

    def _playing_changed(self, playing: bool) -> None:
        """No playback while the ring is dragged (Space during a drag): the key is at the frame shown."""
        if playing and self._drag is not None:
            self.mode.timeline.set_playing(False)
            self.mode.status("Fix: playback waits for the drag to end")

    @contextmanager
    def ring_hidden(self) -> Iterator[None]:
        """The ring hidden meanwhile (an exported picture of the view: the ring is the fixer's, not the picture's)."""
        visible = self.ring is not None and bool(self.ring.actor.GetVisibility())
        if visible:
            self.ring.set_visible(False)
        try:
            yield
        finally:
            if visible:
                self.ring.set_visible(True)
                self.mode.view.interactor.update()

    def _place(self, *_) -> None:
        """The ring about the picked joint's axis as the retarget poses it at the current frame (hidden without a
        joint); the bar says what the joint's corrections are."""
        shown = self._solo()
        if self.ring is None or shown is None or self._drag is not None:
            return
        key, result = shown
        if self.joint is None:
            self.ring.set_visible(False)
            self.bar.say(self._hint(result))
        else:
            frame = self.mode.timeline.frame
            joint = int(topo.ARTICULATED_JOINTS[self.joint])
            target = result.target
            centre = to_view(target, result.pose.positions[frame, joint].numpy().astype(np.float64))
            axes = to_view(target, result.pose.frames[frame, joint].numpy().astype(np.float64).T).T
            first = AXES.index(self.bar.axis)
            self.ring.place(centre, axes[:, [first, (first + 1) % 3, (first + 2) % 3]], self.ring_radius(centre, target))
            self.ring.set_visible(True)
            self.bar.say(self._joint_text(result))
        self.mode.view.interactor.update()

    def ring_radius(self, centre: np.ndarray, target) -> float:
        """`RING_RADIUS` of the hand's length, or `RING_PX` on screen at ``centre`` if that is more: a ring to
        grab however small the hand is drawn."""
        renderer, length = self.ring.renderer, target.hand_length
        up = np.asarray(renderer.GetActiveCamera().GetViewUp())
        ends = []
        for point in (centre, centre + length * up):
            renderer.SetWorldPoint(*point, 1.0)
            renderer.WorldToDisplay()
            ends.append(np.asarray(renderer.GetDisplayPoint()[:2]))
        per_unit = np.linalg.norm(ends[1] - ends[0]) / length  # display pixels per unit of length there
        return max(RING_RADIUS * length, RING_PX / per_unit if per_unit > 0 else 0.0)

    def _hint(self, result: MethodResult) -> str:
        fixes = result.corrections
        return HINT + (f". Fixed: {fixes.describe()}" if fixes else "")  # HINT ends without a stop

    def _joint_text(self, result: MethodResult) -> str:
        name = topo.joint_label(topo.ARTICULATED_NAMES[self.joint])
        correction = result.corrections.of(self.joint)
        if correction is None:
            return f"{name}: no corrections; drag its ring to turn it about its {self.bar.axis} axis at this frame"
        return (f"{name}: {describe_keys(correction)}; here "
                f"{np.degrees(correction.offset_at(self.mode.timeline.frame).magnitude()):.0f} deg off the method's; "
                f"{score_change(result.uncorrected, result, 'the method')}")

    # --- the mouse ---
    def _clicked(self, x: int, y: int) -> None:
        """A click in the cell (VTK display pixels) picks the joint nearest to it on screen, else the joint turning
        the part of the skin under it, else the joint turning the bone drawn nearest to it (a click on the thumb's
        skin between its joints picked nothing, and no click near the wrist reached its CMC: a fresh-eyes user), or
        none, said."""
        shown = self._solo()
        if shown is None:
            return
        self._before_click = (self.joint, self._picked_on, time.monotonic())
        _, result = shown
        positions = to_view(result.target, result.pose.positions[self.mode.timeline.frame].numpy().astype(np.float64))
        nearest = nearest_on_screen(self.ring.renderer, positions[[joint for joint, _ in PICKABLE]], x, y,
                                    JOINT_PIXELS)
        if nearest is not None:
            self._picked(PICKABLE[nearest][1])
            return
        joint = self.mode.view.solo_hand().joint_under(x, y)
        if joint is None:  # off the skin, or a hand with none: the bone drawn nearest, a joint's child the next
            joint = nearest_segment_on_screen(self.ring.renderer, positions[topo.ARTICULATED_JOINTS],
                                              positions[topo.ARTICULATED_JOINTS + 1], x, y)
        if joint is None:
            self.mode.status("Fix: no finger there: click on a finger (its skin picks the joint that turns it)")
        self._picked(joint)

    def _clicked_through(self, x: int, y: int) -> None:
        """A click on the ring that turned nothing: the finger under it, if one is (else the joint stays picked)."""
        hand = self.mode.view.solo_hand()
        joint = hand.joint_under(x, y) if hand is not None else None
        if joint is not None and joint != self.joint:
            self._picked(joint)

    def _double_clicked(self) -> None:
        """A double-click (back to the grid) picks nothing: its first click's pick is undone."""
        before, self._before_click = self._before_click, None
        if before is not None and time.monotonic() - before[2] < QApplication.doubleClickInterval() / 1000 + 0.2:
            self.joint, self._picked_on = before[0], before[1]

    def let_go(self) -> None:
        """Escape: the picked joint let go (its ring hidden); with none picked, a hand shown alone back to the grid.
        A drag under way keeps its joint."""
        if self._drag is not None:
            return
        if self.joint is not None and self._solo() is not None:
            self._picked(None)
        elif self.mode.view.solo >= 0:
            self.mode.view.set_solo(-1)

    def pick(self, joint: str) -> None:
        """Pick ``joint`` (an articulated joint's name) as a click on it would (keyboard users, scripts)."""
        self._picked(topo.ARTICULATED_NAMES.index(joint))

    def _picked(self, joint: int | None) -> None:
        """The joint picked (None: none): its ring, and the error curve's joint bend follows it."""
        self.joint = joint
        shown = self._solo()
        self._picked_on = None if shown is None else shown[0]
        if joint is not None:
            self.mode.choose_joint(int(topo.ARTICULATED_JOINTS[joint]) - 1)  # its heatmap row
        self._place()

    def _key_frames(self, result: MethodResult, frame: int) -> tuple[int, int, tuple[int, int] | None]:
        """The start, end and held frames of the key a drag at ``frame`` makes: the key's own if one is there, else
        the marked range if it holds ``frame``, else the pose held there and the ease frames around it
        (`key_span`)."""
        correction = result.corrections.of(self.joint)
        key = correction.key_at(frame) if correction is not None else None
        if key is not None:
            return key.start, key.end, key.hold
        marked = self.mode.timeline.marked
        if marked is not None and frame in marked:
            return marked.start, marked[-1], None
        return key_span(self.mode.comparison.motion.labels, frame, self.bar.ease_in.value(),
                        self.bar.ease_out.value())

    def _begin(self) -> None:
        shown = self._solo()
        if shown is None or self.joint is None:
            return
        self.mode.timeline.set_playing(False)
        key, result = shown
        frame = self.mode.timeline.frame
        sense = float(np.sign(np.linalg.det(result.target.palm_frame)))
        start, end, hold = self._key_frames(result, frame)
        self._drag = Drag(key, result, self.joint, frame, self.bar.axis, (start, end), hold, sense)

    def _turn(self, degrees: float) -> None:
        if self._drag is not None:
            self._drag.degrees = degrees
            if not self._live.isActive():
                self._live.start()

    def _measure_drag(self) -> None:
        """The clip measured with the turn so far: the cell, scores and curves show it while dragging."""
        drag = self._drag
        if drag is not None:
            now = self.mode.corrected(drag.before, drag.corrections())
            self.mode.show_result(drag.key, now)
            turn = drag.sense * drag.degrees
            way = {"bend": ("curls it in", "opens it out")}.get(drag.axis, ("", ""))[turn < 0]
            # a key already there is turned further: the joint's whole offset, which the bar says after the drag,
            # is not this drag's turn (a fresh-eyes user read +36 while dragging, 28 after)
            total = np.degrees(now.corrections.offset_at(drag.joint, drag.frame).magnitude())
            notes = [note for note in (way, f"{total:.0f} deg off the method's in all"
                                       if abs(total - abs(turn)) >= 1.0 else "") if note]
            held = "" if drag.hold is None else (f"held over the {self.mode.comparison.motion.labels[drag.frame]} "
                                                 f"pose (frames {drag.hold[0]}-{drag.hold[1]}), ")
            said_notes = f" ({'; '.join(notes)})" if notes else ""
            # the frames first: at the end, a 1000-pixel bar cut them off (a fresh-eyes user)
            self.bar.say(f"{topo.joint_label(topo.ARTICULATED_NAMES[drag.joint])}: {drag.axis} {turn:+.0f} deg"
                         f"{said_notes} at frame {drag.frame}, {held}blended over frames {drag.frames[0]}-"
                         f"{drag.frames[1]}; {score_change(drag.before, now)}")

    def _end(self) -> None:
        drag, self._drag = self._drag, None
        self._live.stop()
        if drag is None:
            return
        if abs(drag.degrees) < 0.5:
            self.mode.show_result(drag.key, drag.before)  # nothing turned: no key
            self._place()
            return
        after = self.mode.corrected(drag.before, drag.corrections())
        self._push(drag.key, drag.before, after, f"fix {topo.joint_label(topo.ARTICULATED_NAMES[drag.joint])}: "
                                                 f"{drag.axis} {drag.sense * drag.degrees:+.0f} deg at frame "
                                                 f"{drag.frame}")

    def _push(self, key: ResultKey, before: MethodResult, after: MethodResult, text: str) -> None:
        self.mode.undo_stack.push(FixCommand(self, key, before, after, text))
        self._place()

    # --- the Fix menu ---
    def _change(self, change, text: str, needs_joint: bool = True) -> None:
        """Apply ``change(corrections, joint)`` to the retarget shown alone (undoable), or say why not; one that
        needs no joint acts on the selected retarget in the grid too."""
        shown = self._solo()
        if shown is None and not needs_joint and self.mode.comparison is not None:
            result = self.mode.selected_result()
            shown = self._key_of(result), result
        if shown is None:
            self.mode.status("Fix: show a retarget alone first (double-click it, or Ctrl+M)")
            return
        if needs_joint and self.joint is None:
            self.mode.status("Fix: click a joint of the hand first")
            return
        key, result = shown
        corrections = change(result.corrections, self.joint)
        if corrections == result.corrections:
            self.mode.status(f"Fix: {text}: nothing there to change")
            return
        self._push(key, result, self.mode.corrected(result, corrections), text)

    def _joint_name(self) -> str:
        return topo.joint_label(topo.ARTICULATED_NAMES[self.joint]) if self.joint is not None else "the joint"

    def delete_key(self) -> None:
        """The picked joint's key at the current frame taken away."""
        frame = self.mode.timeline.frame
        self._change(lambda c, j: c.without_key(j, frame), f"delete {self._joint_name()}'s key at frame {frame}")

    def clear_joint(self) -> None:
        self._change(lambda c, j: c.without_joint(j), f"clear {self._joint_name()}'s corrections")

    def clear_all(self) -> None:
        self._change(lambda c, j: Corrections(), "remove the retarget's corrections", needs_joint=False)

    def use_marked_range(self) -> None:
        marked = self.mode.timeline.marked
        if marked is None:
            self.mode.status("Fix: mark a range first (Playback > Mark in I, Mark out O): none is marked (the whole "
                             "clip marked counts as none)")
            return
        frame = self.mode.timeline.frame
        if frame not in marked:
            self.mode.status(f"Fix: the marked range ({marked.start}-{marked[-1]}) does not hold frame {frame}")
            return
        self._change(lambda c, j: c.with_range(j, frame, marked.start, marked[-1]),
                     f"blend {self._joint_name()}'s key at frame {frame} over frames {marked.start}-{marked[-1]}")

    def next_axis(self) -> None:
        self.bar.next_axis()

    def fill_menu(self, menu: QMenu) -> list[QAction]:
        """The Fix menu's entries that act on the retarget shown alone, returned."""
        actions = []
        for text, slot, shortcut in (("Next ring axis (bend, splay, twist)", self.next_axis, "R"),
                                     ("Delete the joint's key at this frame", self.delete_key, "Shift+K"),
                                     ("Clear the joint's corrections", self.clear_joint, "Ctrl+Shift+K"),
                                     ("Let go of the joint (hide its ring); again: back to the grid", self.let_go,
                                      "Esc"),
                                     ("Blend the joint's key at this frame over the marked range",
                                      self.use_marked_range, None),
                                     ("Remove every correction of the retarget", self.clear_all, None)):
            action = QAction(text, menu)
            if shortcut:
                action.setShortcut(QKeySequence(shortcut))
            action.triggered.connect(lambda _=False, run=slot: run())
            menu.addAction(action)
            actions.append(action)
        return actions

    # --- files ---
    def corrections_file(self, result: MethodResult, part: range | None = None) -> CorrectionsFile:
        comparison = self.mode.comparison
        return CorrectionsFile(result.corrections, comparison.motion.name, comparison.n_frames, comparison.motion.fps,
                               comparison.source.name, result.target.name, result.method,
                               None if part is None else (part.start, part[-1]))

    def _key_of(self, result: MethodResult) -> ResultKey | None:
        index = next((i for i, r in enumerate(self.mode.comparison.results) if r is result), None)
        return None if index is None else self.mode.shown_keys()[index]

    def save(self, path: str | Path, result: MethodResult | None = None, part: range | None = None) -> Path:
        """The selected retarget's corrections (or ``result``'s) written to ``path`` (beside a motion export of
        ``part`` of the clip: said in the file); they count as saved, and the retarget saved there before (an
        export of another retarget to the same name) no longer does."""
        result = result or self.mode.selected_result()
        written = save_corrections(path, self.corrections_file(result, part))
        self._held_by(Path(path), self._key_of(result), result.corrections)
        return written

    def _held_by(self, path: Path, key: ResultKey | None, corrections: Corrections | None) -> None:
        """``path`` now holds ``key``'s ``corrections`` (None: the file is gone); whoever it held before is unsaved."""
        path = path.resolve()
        before = self._files.pop(path, None)
        if before is not None and before != key:
            self._saved.pop(before, None)
        if key is not None and corrections is not None:
            self._saved[key] = corrections
            self._files[path] = key

    def holds(self, path: str | Path) -> bool:
        """Whether ``path`` holds corrections this session saved or loaded (they count as unsaved once it is gone)."""
        return Path(path).resolve() in self._files

    def removed(self, path: str | Path) -> str | None:
        """A sidecar an export took away: the retarget whose saved corrections it held counts as unsaved again;
        returns its name for the status line (None if it held none of this session's)."""
        key = self._files.get(Path(path).resolve())
        self._held_by(Path(path), None, None)
        if key is None or self.mode.comparison is None or key not in self.mode.shown_keys():
            return None
        result = self.mode.comparison.results[self.mode.shown_keys().index(key)]
        return result.name

    def load(self, path: str | Path) -> bool:
        """A corrections sidecar applied to the selected retarget (undoable), asking first where it was made on
        another clip, target or method; `InputFileError` if it cannot fit (another clip length). False: declined."""
        file = load_corrections(path, self.mode.comparison.n_frames)
        result = self.mode.selected_result()
        here = (self.mode.comparison.motion.name, result.target.name, result.method)
        if (file.clip, file.target, file.method) != here:
            made = f"{METHODS[file.method].label if file.method in METHODS else file.method} -> {file.target}"
            choice = ask(self.mode.window(), "s2h-viewer: corrections made elsewhere",
                         f"{Path(path).name} was made on {made} (clip {file.clip!r}). Apply it to "
                         f"{result.name} (clip {here[0]!r})?",
                         [("Apply", QMessageBox.ButtonRole.AcceptRole), ("Cancel", QMessageBox.ButtonRole.RejectRole)],
                         "Its keys are turns about each joint's own axes at frame numbers: on another hand or "
                         "method they turn the same joints by the same angles, which may not fix the same thing.")
            if choice != 0:
                return False
        key = self._key_of(result)
        self._push(key, result, self.mode.corrected(result, file.corrections),
                   f"load corrections from {Path(path).name}")
        self._held_by(Path(path), key, file.corrections)
        self.mode.status(f"loaded {counted(file.corrections.n_keys, 'correction key')} "
                         f"({file.corrections.describe()}) from {Path(path).name} onto {result.name}")
        return True

    def unsaved(self) -> list[MethodResult]:
        """The retargets on screen whose corrections were changed since they were last exported or saved. One whose
        corrections were all undone is not: there is nothing to save, and what was saved stays in its file (a
        fresh-eyes user, asked to save them on quitting, got "has no corrections to save" and could only discard)."""
        if self.mode.comparison is None:
            return []
        keys = self.mode.shown_keys()
        return [r for k, r in zip(keys, self.mode.comparison.results)
                if r.corrections and r.corrections != self._saved.get(k, Corrections())]

    def forget_unsaved(self) -> None:
        """Whatever is on screen counts as saved: nothing to ask about when the window closes (a discard)."""
        if self.mode.comparison is not None:
            self._saved.update({k: r.corrections for k, r in zip(self.mode.shown_keys(),
                                                                  self.mode.comparison.results)})

    def confirm_discard(self, doing: str, save_as: Callable[[MethodResult], Path | None]) -> bool:
        """True when no corrections would be lost by ``doing``: none unsaved, or the user saved them (``save_as``
        asks where and writes a retarget's sidecar, None when cancelled) or chose to discard them."""
        unsaved = self.unsaved()
        if not unsaved:
            return True
        names = ", ".join(r.name for r in unsaved)
        choice = ask(self.mode.window(), "s2h-viewer: unsaved corrections",
                     f"Save the corrections of {names} before {doing}?",
                     [("Save...", QMessageBox.ButtonRole.AcceptRole),
                      ("Discard", QMessageBox.ButtonRole.DestructiveRole),
                      ("Cancel", QMessageBox.ButtonRole.RejectRole)],
                     "Save writes each retarget's corrections as a sidecar (Fix > Load corrections and s2h retarget "
                     "--corrections read it); File > Export retargeted motion writes the corrected motion with it. "
                     "Discarded corrections are lost.")
        if choice == 0:
            return all(save_as(result) is not None for result in unsaved)
        return choice == 1
