"""A long text in a dialog that fits the screen: Help's list of shortcuts in a message box was 1052 pixels tall
on a 1000-pixel screen, its OK button out of reach; here it scrolls."""

from __future__ import annotations

from PySide6.QtWidgets import QDialog, QDialogButtonBox, QPlainTextEdit, QVBoxLayout, QWidget

#: the share of the screen's height (and width) the dialog takes at most
SCREEN_SHARE = 0.8


class TextDialog(QDialog):
    """``text`` read-only and scrollable, with a Close button, sized to its text within `SCREEN_SHARE` of the
    screen."""

    def __init__(self, parent: QWidget | None, title: str, text: str):
        super().__init__(parent)
        self.setWindowTitle(title)
        layout = QVBoxLayout(self)
        self.text = QPlainTextEdit(text)
        self.text.setReadOnly(True)
        self.text.setLineWrapMode(QPlainTextEdit.LineWrapMode.NoWrap)
        layout.addWidget(self.text)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close)
        buttons.rejected.connect(self.reject)
        layout.addWidget(buttons)
        metrics = self.text.fontMetrics()
        lines = text.splitlines() or [""]
        wanted_w = max(metrics.horizontalAdvance(line) for line in lines) + 60
        wanted_h = metrics.lineSpacing() * len(lines) + 90
        screen = (parent.screen() if parent is not None else self.screen()).availableGeometry()
        self.resize(min(wanted_w, int(SCREEN_SHARE * screen.width())),
                    min(wanted_h, int(SCREEN_SHARE * screen.height())))
