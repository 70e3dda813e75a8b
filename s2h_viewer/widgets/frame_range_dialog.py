"""The frames of a video or motion export: From and To boxes (indices from 0, as the timeline counts; both
frames exported), the timeline's marked range at first (else the whole clip), with quick choices for the whole
clip, the marked range and the current frame on; Export only while From is not after To (the dialog says why)."""

from __future__ import annotations

from PySide6.QtWidgets import (QDialog, QDialogButtonBox, QFormLayout, QHBoxLayout, QLabel, QPushButton, QSpinBox,
                               QVBoxLayout, QWidget)

from s2h_viewer.wording import counted


class FrameRangeDialog(QDialog):
    """Asks which frames of a clip of ``n_frames`` at ``fps`` go into ``file_name``; ``current`` is the
    timeline's frame."""

    def __init__(self, file_name: str, n_frames: int, fps: float, current: int, parent: QWidget | None = None,
                 what: str = "video", marked: range | None = None):
        super().__init__(parent)
        self.n_frames, self.fps, self.current, self.marked = n_frames, fps, current, marked
        self.setObjectName("frame_range_dialog")
        self.setWindowTitle(f"Export {what}: frames")
        layout = QVBoxLayout(self)
        layout.addWidget(QLabel(f"Frames of the clip to write to {file_name}\n"
                                f"(the clip: frames 0 to {n_frames - 1}; From and To are both written)"))
        self.start, self.end = QSpinBox(), QSpinBox()
        form = QFormLayout()
        for name, box in (("From", self.start), ("To", self.end)):
            box.setObjectName(name.lower())
            box.setRange(0, n_frames - 1)
            box.valueChanged.connect(self._check)
            form.addRow(f"{name} frame:", box)
        layout.addLayout(form)
        quick = QHBoxLayout()
        self.whole_clip = QPushButton("Whole clip")
        self.from_current = QPushButton(f"From the current frame ({current})")
        choices = [(self.whole_clip, self.choose_whole_clip), (self.from_current, self.choose_from_current)]
        if marked is not None:
            self.marked_range = QPushButton(f"The marked range ({marked.start} to {marked[-1]})")
            choices.insert(1, (self.marked_range, self.choose_marked))
        for button, slot in choices:
            button.setAutoDefault(False)  # Return is OK, not a quick choice
            button.clicked.connect(slot)
            quick.addWidget(button)
        layout.addLayout(quick)
        self.summary = QLabel()
        self.summary.setObjectName("frame_range_summary")
        layout.addWidget(self.summary)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setText("Export")
        self.buttons.accepted.connect(self.accept)
        self.buttons.rejected.connect(self.reject)
        layout.addWidget(self.buttons)
        if marked is not None:
            self.choose_marked()
        else:
            self.choose_whole_clip()

    def frames(self) -> range:
        """The frames chosen, From to To included."""
        return range(self.start.value(), self.end.value() + 1)

    def choose_whole_clip(self) -> None:
        self.start.setValue(0)
        self.end.setValue(self.n_frames - 1)

    def choose_marked(self) -> None:
        """The timeline's in and out points (Playback > Mark in / Mark out)."""
        self.start.setValue(self.marked.start)
        self.end.setValue(self.marked[-1])

    def choose_from_current(self) -> None:
        """From the timeline's frame to the clip's end."""
        self.start.setValue(self.current)
        self.end.setValue(self.n_frames - 1)

    def _check(self) -> None:
        """Export (the default button: Return too) enabled only for From <= To; the summary says how many frames
        and seconds, or what is wrong."""
        frames = self.frames()
        ok = len(frames) > 0
        self.buttons.button(QDialogButtonBox.StandardButton.Ok).setEnabled(ok)
        self.summary.setStyleSheet("" if ok else "color: #b00020")
        self.summary.setText(f"{counted(len(frames), 'frame')}, {len(frames) / self.fps:.2f} s" if ok else
                             f"From ({self.start.value()}) is after To ({self.end.value()}): nothing to export")
