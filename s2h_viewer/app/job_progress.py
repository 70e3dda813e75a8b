"""The progress of every long job (retargets, video export, TBS solver): a strip in the window's status bar,
its label, a bar and Cancel, so it covers nothing (floating dialogs sat over the loop, speed and fps controls
and the error curve). Jobs can run side by side: each has its own strip, of one fixed width (a long label is
elided, its whole text in the tooltip), laid side by side at the status bar's right."""

from __future__ import annotations

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtWidgets import QFrame, QHBoxLayout, QLabel, QMainWindow, QProgressBar, QPushButton, QWidget

WIDTH = 380  # pixels: every job strip's width
GAP = 8  # pixels of label room left for its margins


def strip_height(widget: QWidget) -> int:
    """A job strip's height in ``widget``'s font: the status bar keeps it always, so a job starting or ending
    never moves the panels above (an export sized to the view would no longer match it)."""
    return max(QPushButton("Cancel").sizeHint().height(), 2 * widget.fontMetrics().lineSpacing()) + 6


class JobProgress(QFrame):
    """Shown after ``delay_ms`` (a job that ends sooner never flashes a strip), never closing itself: its job
    closes it. ``cancel_text`` None: no Cancel button. ``canceled`` when Cancel is clicked."""

    canceled = Signal()

    def __init__(self, label: str, cancel_text: str | None, maximum: int, parent: QWidget, title: str,
                 delay_ms: int = 300):
        window = parent.window()
        super().__init__(window)
        self.setObjectName(title)
        self.setFrameShape(QFrame.Shape.StyledPanel)
        self.setFixedWidth(WIDTH)
        self.setFixedHeight(strip_height(window))
        self._label = QLabel()
        self._bar = QProgressBar()
        self._bar.setRange(0, maximum)
        self._bar.setTextVisible(True)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(4, 1, 4, 1)
        layout.addWidget(self._label, 1)
        layout.addWidget(self._bar)
        if cancel_text is not None:
            button = QPushButton(cancel_text)
            button.clicked.connect(self.canceled)
            layout.addWidget(button)
        self.setLabelText(label)
        self.hide()
        if isinstance(window, QMainWindow):
            window.statusBar().addPermanentWidget(self)
        self._closed = False
        QTimer.singleShot(delay_ms, self._show_if_running)

    def _show_if_running(self) -> None:
        if not self._closed:
            self.show()

    def setValue(self, value: int) -> None:
        self._bar.setValue(value)

    def value(self) -> int:
        return self._bar.value()

    def maximum(self) -> int:
        return self._bar.maximum()

    def setLabelText(self, text: str) -> None:
        """The label, each line elided in the middle to the strip's label room (the strip never grows)."""
        self.setToolTip(text)
        room = WIDTH // 2 - GAP
        self._label.setText("\n".join(self.fontMetrics().elidedText(line, Qt.TextElideMode.ElideMiddle, room)
                                      for line in text.split("\n")))

    def labelText(self) -> str:
        return self._label.text()

    def close(self) -> bool:
        """The job ended: the strip leaves the status bar."""
        self._closed = True
        window = self.window()
        if isinstance(window, QMainWindow):
            window.statusBar().removeWidget(self)
        return super().close()
