"""The progress dialog of every long job (retargets, video export, TBS solver). Jobs can run side by side,
so a dialog that shows while others are places itself under the lowest of them: none covers another."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QProgressDialog, QWidget

GAP = 8  # pixels between stacked dialogs


class JobProgressDialog(QProgressDialog):
    """Non-modal (the window stays usable), shown after ``delay_ms``, never closing or resetting itself:
    its job closes it. ``cancel_text`` None: no Cancel button."""

    def __init__(self, label: str, cancel_text: str | None, maximum: int, parent: QWidget, title: str,
                 delay_ms: int = 300):
        super().__init__(label, cancel_text, 0, maximum, parent)
        self.setWindowTitle(title)
        self.setWindowModality(Qt.WindowModality.NonModal)
        self.setMinimumDuration(delay_ms)
        self.setAutoClose(False)
        self.setAutoReset(False)

    def others(self) -> list["JobProgressDialog"]:
        """The other job dialogs of this window that are on screen."""
        return [d for d in self.parentWidget().window().findChildren(JobProgressDialog)
                if d is not self and d.isVisible()]

    def showEvent(self, event) -> None:
        super().showEvent(event)  # Qt has centred it on its parent by now
        others = self.others()
        if others:
            lowest = max(others, key=lambda d: d.frameGeometry().bottom())
            self.move(lowest.frameGeometry().left(), lowest.frameGeometry().bottom() + GAP)
