"""The progress dialog of every long job (retargets, video export, TBS solver): at the bottom right of
the window (over the error curve and the status bar, not over the grid), of one fixed width (a long
label is elided). Jobs can run side by side, so a dialog that shows while others are places itself
above the highest of them: none covers another."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QProgressDialog, QWidget

GAP = 8  # pixels between stacked dialogs, and from the window's edge
WIDTH = 380  # pixels: every job dialog's width


class JobProgressDialog(QProgressDialog):
    """Non-modal (the window stays usable), shown after ``delay_ms``, never closing or resetting itself:
    its job closes it. ``cancel_text`` None: no Cancel button."""

    def __init__(self, label: str, cancel_text: str | None, maximum: int, parent: QWidget, title: str,
                 delay_ms: int = 300):
        super().__init__("", cancel_text, 0, maximum, parent)
        self.setWindowTitle(title)
        self.setWindowModality(Qt.WindowModality.NonModal)
        self.setFixedWidth(WIDTH)
        self.setLabelText(label)
        self.setMinimumDuration(delay_ms)
        self.setAutoClose(False)
        self.setAutoReset(False)

    def setLabelText(self, text: str) -> None:
        """The label, each line elided in the middle to the dialog's width (the dialog never grows with it)."""
        self.setToolTip(text)
        room = WIDTH - 4 * GAP
        super().setLabelText("\n".join(self.fontMetrics().elidedText(line, Qt.TextElideMode.ElideMiddle, room)
                                       for line in text.split("\n")))

    def others(self) -> list["JobProgressDialog"]:
        """The other job dialogs of this window that are on screen."""
        return [d for d in self.parentWidget().window().findChildren(JobProgressDialog)
                if d is not self and d.isVisible()]

    def showEvent(self, event) -> None:
        super().showEvent(event)  # Qt has centred it on its parent by now: move it to the bottom right
        window = self.parentWidget().window().geometry()  # the window's client area, global coordinates
        frame = self.frameGeometry()
        others = self.others()
        bottom = min(d.frameGeometry().top() for d in others) - GAP if others else window.bottom() - GAP
        self.move(window.right() - GAP - frame.width() + (self.x() - frame.x()),
                  bottom - frame.height() + (self.y() - frame.y()))
