"""Playback timeline: play/pause, scrub, step, loop, speed, and the frame rate actually drawn."""

from __future__ import annotations

import time

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import QCheckBox, QComboBox, QHBoxLayout, QLabel, QPushButton, QSlider, QSpinBox, QWidget

SPEEDS = (0.25, 0.5, 1.0, 2.0)


class Timeline(QWidget):
    """Emits ``frame_changed(frame)``; the clip's own fps times playback, scaled by the speed."""

    frame_changed = Signal(int)

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.n_frames, self.clip_fps = 1, 30.0
        self.play_button = QPushButton("Play")
        self.play_button.setCheckable(True)
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.spin = QSpinBox()
        self.loop = QCheckBox("Loop")
        self.loop.setChecked(True)
        self.speed = QComboBox()
        self.speed.addItems([f"{s:g}x" for s in SPEEDS])
        self.speed.setCurrentIndex(SPEEDS.index(1.0))
        self.fps_label = QLabel("-- fps")
        layout = QHBoxLayout(self)
        for widget in (self.play_button, self.slider, self.spin, self.loop, self.speed, self.fps_label):
            layout.addWidget(widget)
        layout.setStretch(1, 1)
        self._timer = QTimer(self)
        self._timer.timeout.connect(self._tick)
        self._drawn: list[float] = []
        self.play_button.toggled.connect(self.set_playing)
        self.slider.valueChanged.connect(self._set_from_widget)
        self.spin.valueChanged.connect(self._set_from_widget)
        self.speed.currentIndexChanged.connect(lambda _: self._restart_timer())
        self.set_clip(1, 30.0)

    @property
    def frame(self) -> int:
        return self.slider.value()

    def set_clip(self, n_frames: int, fps: float) -> None:
        self.n_frames, self.clip_fps = max(1, n_frames), fps
        for widget in (self.slider, self.spin):
            widget.blockSignals(True)
            widget.setRange(0, self.n_frames - 1)
            widget.setValue(0)
            widget.blockSignals(False)
        self.frame_changed.emit(0)

    def set_frame(self, frame: int) -> None:
        frame = max(0, min(self.n_frames - 1, frame))
        if frame != self.frame:
            self.slider.setValue(frame)  # the spin box follows through _set_from_widget

    def step(self, delta: int) -> None:
        self.set_frame(self.frame + delta)

    def set_playing(self, playing: bool) -> None:
        if self.play_button.isChecked() != playing:
            self.play_button.setChecked(playing)  # re-enters through `toggled`
            return
        self.play_button.setText("Pause" if playing else "Play")
        self._drawn.clear()
        if playing:
            self._restart_timer()
        else:
            self._timer.stop()

    def toggle(self) -> None:
        self.set_playing(not self.play_button.isChecked())

    def _restart_timer(self) -> None:
        if self.play_button.isChecked():
            self._timer.start(max(1, int(1000.0 / (self.clip_fps * SPEEDS[self.speed.currentIndex()]))))

    def _set_from_widget(self, frame: int) -> None:
        for widget in (self.slider, self.spin):
            if widget.value() != frame:
                widget.blockSignals(True)
                widget.setValue(frame)
                widget.blockSignals(False)
        self.frame_changed.emit(frame)

    def _tick(self) -> None:
        nxt = self.frame + 1
        if nxt >= self.n_frames:
            if not self.loop.isChecked():
                self.set_playing(False)
                return
            nxt = 0
        self.set_frame(nxt)
        now = time.perf_counter()
        self._drawn = [t for t in self._drawn if now - t < 1.0] + [now]
        self.fps_label.setText(f"{len(self._drawn):d} fps")
