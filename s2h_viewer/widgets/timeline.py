"""Playback timeline: play/pause, scrub, step, loop, speed, a readout of the frame (index/last, the frame
count) and its time (of the clip's length), the pose the clip holds there (a clip of labelled poses or
gestures: which of the 35 poses is this?), and the frame rate actually drawn.

Playback runs against the clock: each tick shows the frame that real time (times the speed) has
reached since play started, so a view that draws slower than the clip drops frames instead of
slowing the clip down. Ticks come at twice the rate frames fall due at the chosen speed, and once
more as soon as a frame is drawn: a view slower than that rate draws back to back, never waiting.
``frame_changed`` fires for every frame shown (the view, the heatmap and the error curve follow each);
the slider, the frame box and the readouts follow at most WIDGET_RATE times a second while playing, every
frame otherwise: repainting the slider alone cost a frame drawn at 75 frames/s a twentieth of its time,
and no eye reads a frame number changing faster. In and out points (`mark_in`, `mark_out`) mark a range
playback stays in (looping within it), the exports' frames dialog offers and the error curve shades. Space, the arrow keys and the Ctrl shortcuts (Ctrl+E, Ctrl+S, ...) stay the
window's shortcuts even when the frame box has the focus (its line edit would take them otherwise)."""

from __future__ import annotations

import time

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import (QCheckBox, QComboBox, QHBoxLayout, QLabel, QProxyStyle, QPushButton, QSlider, QSpinBox,
                               QStyle, QWidget)

from s2h_viewer.render.caption import frame_readout
from s2h_viewer.widgets.shortcut_keys import leave_shortcut_keys

SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0)
WIDGET_RATE = 30.0  # refreshes per second of the slider, the frame box and the readouts while playing
MAX_DRAW_WAIT = 0.2  # seconds a tick waits for the view to draw the frame asked before asking anew


class _ClickJumps(QProxyStyle):
    """A click on the slider's groove jumps to the frame under the pointer (and a drag from there follows
    it), where Qt's default pages by a step per click."""

    def styleHint(self, hint, option=None, widget=None, data=None) -> int:
        if hint == QStyle.StyleHint.SH_Slider_AbsoluteSetButtons:
            return Qt.MouseButton.LeftButton.value
        return super().styleHint(hint, option, widget, data)


def fixed_size(label: QLabel, widest: str) -> None:
    """Size ``label`` for its widest text once: a label whose size may change asks the whole window to
    lay out and repaint on every new text (every frame, while playing)."""
    label.setFixedSize(label.fontMetrics().horizontalAdvance(widest) + 8, label.sizeHint().height())


class Timeline(QWidget):
    """Emits ``frame_changed(frame)``; the clip's own fps times playback, scaled by the speed."""

    frame_changed = Signal(int)
    range_changed = Signal(object)  # the marked range (a range of frames), or None when cleared

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.n_frames, self.clip_fps = 1, 30.0
        self.play_button = QPushButton("Play")
        self.play_button.setCheckable(True)
        self.play_button.setFocusPolicy(Qt.FocusPolicy.NoFocus)  # Space is play/pause, not "press the button"
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self._slider_style = _ClickJumps()  # the application's style underneath (not owned)
        self._slider_style.setParent(self.slider)
        self.slider.setStyle(self._slider_style)
        self.spin = QSpinBox()
        self._key_filter = leave_shortcut_keys(self, self.spin, self.slider)
        self.readout = QLabel()
        self.pose_label = QLabel()
        self.pose_label.setToolTip("the pose the clip holds at this frame")
        self._labels: list[str] = []
        self.loop = QCheckBox("Loop")
        self.loop.setChecked(True)
        self.speed = QComboBox()
        self.speed.addItems([f"{s:g}x" for s in SPEEDS])
        self.speed.setCurrentIndex(SPEEDS.index(1.0))
        self.fps_label = QLabel("-- fps")
        self.fps_label.setToolTip("frames drawn per second while playing")
        fixed_size(self.fps_label, "888 fps")
        layout = QHBoxLayout(self)
        for widget in (self.play_button, self.slider, self.spin, self.readout, self.pose_label, self.loop, self.speed,
                       self.fps_label):
            layout.addWidget(widget)
        layout.setStretch(1, 1)
        self._timer = QTimer(self)
        self._timer.setTimerType(Qt.TimerType.PreciseTimer)
        self._timer.timeout.connect(self._tick)
        self._frame = 0
        self.marked: range | None = None  # the in and out points (both included): playback stays in them
        self._widgets_at = 0.0  # when the slider, the frame box and the readouts were last refreshed
        self._anchor = (0.0, 0)  # (clock, frame) when playback started or last changed speed / was scrubbed
        self._drawn: list[float] = []
        self._asked_at: float | None = None  # when playback asked for a frame the view has not drawn yet
        self.play_button.toggled.connect(self.set_playing)
        self.slider.valueChanged.connect(self._set_from_widget)
        self.spin.valueChanged.connect(self._set_from_widget)
        self.speed.currentIndexChanged.connect(lambda _: self._speed_changed())
        self.set_clip(1, 30.0)

    @property
    def frame(self) -> int:
        """The frame shown (while playing, the slider may lag it by one refresh of the widgets)."""
        return self._frame

    @property
    def playing(self) -> bool:
        return self.play_button.isChecked()

    def set_clip(self, n_frames: int, fps: float, labels=None) -> None:
        """A clip of ``n_frames`` at ``fps``; ``labels``: the pose held at each frame ("" between), if it has any."""
        self.n_frames, self.clip_fps = max(1, n_frames), fps
        self._labels = [str(label) for label in labels] if labels is not None and any(labels) else []
        self.pose_label.setVisible(bool(self._labels))
        if self._labels:
            fixed_size(self.pose_label, max((self._pose_text(f) for f in range(len(self._labels))),
                                            key=self.pose_label.fontMetrics().horizontalAdvance))
        for widget in (self.slider, self.spin):
            widget.blockSignals(True)
            widget.setRange(0, self.n_frames - 1)
            widget.setValue(0)
            widget.blockSignals(False)
        fixed_size(self.readout, self._readout_text(self.n_frames - 1))
        self._frame = 0
        self.clear_range()
        self._show_widgets()
        self.frame_changed.emit(0)

    @property
    def play_range(self) -> range:
        """The frames playback runs through: the marked range, else the whole clip."""
        return self.marked if self.marked is not None else range(self.n_frames)

    def mark_in(self) -> None:
        """The current frame starts the marked range (its end stays, or is the clip's last frame)."""
        end = self.marked[-1] if self.marked is not None and self.marked[-1] >= self.frame else self.n_frames - 1
        self._set_marked(range(self.frame, end + 1))

    def mark_out(self) -> None:
        """The current frame ends the marked range (its start stays, or is the clip's first frame)."""
        start = self.marked.start if self.marked is not None and self.marked.start <= self.frame else 0
        self._set_marked(range(start, self.frame + 1))

    def clear_range(self) -> None:
        self._set_marked(None)

    def _set_marked(self, marked: range | None) -> None:
        if marked is not None and len(marked) == self.n_frames:
            marked = None  # the whole clip: nothing marked
        if marked != self.marked:
            self.marked = marked
            self.range_changed.emit(marked)

    def set_frame(self, frame: int) -> None:
        frame = max(0, min(self.n_frames - 1, frame))
        if frame != self.frame:
            self._set_from_widget(frame)

    def step(self, delta: int) -> None:
        self.set_frame(self.frame + delta)

    def set_playing(self, playing: bool) -> None:
        if self.play_button.isChecked() != playing:
            self.play_button.setChecked(playing)  # re-enters through `toggled`
            return
        self.play_button.setText("Pause" if playing else "Play")
        self._drawn.clear()
        if playing:
            span = self.play_range
            if self.frame not in span or (not self.loop.isChecked() and self.frame == span[-1]):
                self.set_frame(span.start)  # outside the range, or played to its end: Play plays it again
            self._restart_clock()
            self._timer.start(self._tick_interval())
        else:
            self._timer.stop()
            self._show_widgets()  # the frame the view stopped at, wherever the throttled widgets were

    def toggle(self) -> None:
        self.set_playing(not self.playing)

    def note_drawn(self) -> None:
        """The view drew a frame: while playing, the label shows the frames drawn in the last second."""
        self._asked_at = None
        if not self.playing:
            return
        now = time.perf_counter()
        self._drawn = [t for t in self._drawn if now - t < 1.0] + [now]
        QTimer.singleShot(0, self, self._tick)  # the next due frame now, not at the timer's next tick

    def drawn_rate(self) -> float:
        """Frames drawn per second over the last second of playback (0 before two are drawn)."""
        if len(self._drawn) < 2 or self._drawn[-1] <= self._drawn[0]:
            return 0.0
        return (len(self._drawn) - 1) / (self._drawn[-1] - self._drawn[0])

    def _tick_interval(self) -> int:
        """Milliseconds between ticks: half the time between frames at the chosen speed."""
        return max(1, int(500.0 / (self.clip_fps * SPEEDS[self.speed.currentIndex()])))

    def _speed_changed(self) -> None:
        self._restart_clock()
        if self.playing:
            self._timer.start(self._tick_interval())

    def _restart_clock(self, frame: int | None = None) -> None:
        """Play on from ``frame`` (default: the frame shown) as of now."""
        self._anchor = (time.perf_counter(), self.frame if frame is None else frame)

    def _readout_text(self, frame: int) -> str:
        return frame_readout(frame, self.n_frames, self.clip_fps)

    def _pose_text(self, frame: int) -> str:
        label = self._labels[frame] if frame < len(self._labels) else ""
        return f"pose: {label}" if label else "between poses"

    def _set_from_widget(self, frame: int) -> None:
        """The slider or the spin box moved (a person, or `set_frame`): while playing, play on from there."""
        if self.playing:
            self._restart_clock(frame)  # from the frame asked: the one shown is still the old one
        self._show(frame)

    def _show(self, frame: int) -> None:
        """``frame_changed`` for ``frame``, and the slider, the frame box and the readouts when due."""
        self._frame = frame
        if not self.playing or time.perf_counter() - self._widgets_at >= 1.0 / WIDGET_RATE:
            self._show_widgets()
        self.frame_changed.emit(frame)

    def _show_widgets(self) -> None:
        """The slider and the frame box at the frame shown (without their signals), and the readouts."""
        self._widgets_at = time.perf_counter()
        for widget in (self.slider, self.spin):
            if widget.value() != self._frame:
                widget.blockSignals(True)
                widget.setValue(self._frame)
                widget.blockSignals(False)
        self.readout.setText(self._readout_text(self._frame))
        if self._labels:
            self.pose_label.setText(self._pose_text(self._frame))
        self.fps_label.setText(f"{self.drawn_rate():.0f} fps" if self.playing else "-- fps")

    def due_frame(self, ahead: float = 0.0) -> int | None:
        """The frame the clock asks for ``ahead`` seconds from now; None past the end when not looping."""
        started, first = self._anchor
        speed = SPEEDS[self.speed.currentIndex()]
        due = first + int((time.perf_counter() + ahead - started) * self.clip_fps * speed)
        span = self.play_range
        if due > span[-1]:
            if not self.loop.isChecked():
                return None
            due = span.start + (due - span.start) % len(span) if due >= span.start else span.start
        return due

    def next_frame(self) -> int | None:
        """While playing, the frame the clock will most likely ask for next: the one due a drawn frame's time
        from now, at least the next frame (at 1x the view draws faster than the clip); None at the end."""
        if not self.playing:
            return None
        rate = self.drawn_rate()
        due = self.due_frame(ahead=1.0 / rate if rate else 0.0)
        if due is None or due != self.frame:
            return due
        span = self.play_range
        if self.frame + 1 <= span[-1]:
            return self.frame + 1
        return span.start if self.loop.isChecked() else None

    def _tick(self) -> None:
        if not self.playing:  # a tick queued by the last drawn frame, after a pause
            return
        if self._asked_at is not None and time.perf_counter() - self._asked_at < MAX_DRAW_WAIT:
            return  # the last frame is not drawn yet: a new one now would be skinned and never shown
        due = self.due_frame()
        if due is None:  # the end, not looping
            self.set_frame(self.play_range[-1])
            self.set_playing(False)
            return
        if due != self.frame:
            self._asked_at = time.perf_counter()
            self._show(due)  # the clock moves the frame: the anchor stays
