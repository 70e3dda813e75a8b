"""The bar over a retarget shown alone, for fixing it: what a drag of the ring does (the joint, the axis it
turns about, the frames a new key blends over) and what the joint's corrections are. The work is the
owner's (`app.retarget_fixing`); this only shows and asks."""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QFontMetrics
from PySide6.QtWidgets import (QComboBox, QHBoxLayout, QLabel, QSizePolicy, QSpinBox, QToolButton, QVBoxLayout,
                               QWidget)

from s2h_viewer.retarget.corrections import AXES
from s2h_viewer.widgets.shortcut_keys import leave_shortcut_keys

#: frames a new key eases in over before it and out over after it, unless a marked range holds the frame
DEFAULT_EASE = 10
HINT = ("Fix: click a joint, drag its ring (Shift: finer, R: next axis, Esc: let go); keys blend over the marked range "
        "or the ease frames")


#: lines the readout shows before it elides
READOUT_LINES = 2


def wrapped_lines(text: str, metrics: QFontMetrics, width: int, most: int) -> list[str]:
    """``text`` broken at spaces into lines ``width`` pixels wide in ``metrics``' font, at most ``most`` of them:
    the last holds the rest, elided at the right."""
    words = text.split()
    lines, current, taken = [], "", 0
    while taken < len(words) and len(lines) < most - 1:
        candidate = f"{current} {words[taken]}" if current else words[taken]
        if metrics.horizontalAdvance(candidate) <= width:
            current, taken = candidate, taken + 1
        elif current:
            lines.append(current)
            current = ""
        else:
            break  # one word wider than a line: the last line elides it
    rest = " ".join(([current] if current else []) + words[taken:])
    return lines + [metrics.elidedText(rest, Qt.TextElideMode.ElideRight, width)] if rest else lines


class CorrectionBar(QWidget):
    """``axis`` (one of `AXES`), ``ease_in`` / ``ease_out`` (frames); ``delete_key`` and ``clear_joint`` are the
    buttons' requests (the Fix menu has them too)."""

    delete_key = Signal()
    clear_joint = Signal()

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self._said = HINT
        self.readout = QLabel(HINT)
        # two lines whatever it says (the whole text in its tooltip): a bar that grew would shrink the 3D view under
        # the ring being dragged, and one line cut the hint and a fix's frames at 1000 pixels
        self.readout.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Fixed)
        self.readout.setFixedHeight(READOUT_LINES * self.readout.fontMetrics().lineSpacing())
        self.axis_choice = QComboBox()
        self.axis_choice.addItems(list(AXES))
        self.axis_choice.setCurrentIndex(AXES.index("bend"))
        self.axis_choice.setToolTip("the joint's own axis the ring turns it about (R: the next one)")
        self.ease_in, self.ease_out = QSpinBox(), QSpinBox()
        for box, text in ((self.ease_in, "eases in over this many frames before it"),
                          (self.ease_out, "eases out over this many frames after it")):
            box.setRange(0, 100_000)
            box.setValue(DEFAULT_EASE)
            box.setToolTip(f"a new key {text} (unless the marked range holds its frame: then over the range); on a "
                           f"pose the clip holds, the key holds over the pose and eases only between poses")
        self._key_filter = leave_shortcut_keys(self, self.ease_in, self.ease_out)
        buttons = []
        for text, signal, tip in (("Delete key", self.delete_key, "the joint's key at this frame (Shift+K)"),
                                  ("Clear joint", self.clear_joint, "every correction of the joint (Ctrl+Shift+K)")):
            button = QToolButton()
            button.setText(text)
            button.setToolTip(tip)
            button.clicked.connect(signal)
            buttons.append(button)
        controls = QHBoxLayout()
        controls.setContentsMargins(0, 0, 0, 0)
        for widget in (QLabel("turn about"), self.axis_choice, QLabel("ease in"), self.ease_in, QLabel("out"),
                       self.ease_out, QLabel("frames"), *buttons):
            controls.addWidget(widget)
        controls.addStretch(1)
        layout = QVBoxLayout(self)  # two rows: the controls fit the view's width at the window's smallest
        layout.setContentsMargins(4, 2, 4, 2)
        layout.setSpacing(2)
        layout.addWidget(self.readout)
        layout.addLayout(controls)
        self.hide()

    @property
    def axis(self) -> str:
        return AXES[self.axis_choice.currentIndex()]

    def next_axis(self) -> None:
        self.axis_choice.setCurrentIndex((self.axis_choice.currentIndex() + 1) % len(AXES))

    def say(self, text: str) -> None:
        """At most `READOUT_LINES` lines, the last elided to the bar's width (the whole text in its tooltip)."""
        self._said = text
        self.readout.setToolTip(text)
        self._elide()

    def _elide(self) -> None:
        self.readout.setText("\n".join(wrapped_lines(self._said, self.readout.fontMetrics(),
                                                     max(self.readout.width(), 40), READOUT_LINES)))

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        self._elide()
