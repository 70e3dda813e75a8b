"""Keyboard focus back to the main window when a dialog that had it closes. Under an X server without a
window manager (Xvfb, a kiosk) nobody hands the focus on when a dialog is unmapped: it falls to the root
window, no Qt window is active, and the window's shortcuts (Space, Ctrl+Z) stay dead until a click."""

from __future__ import annotations

from PySide6.QtCore import QEvent, QObject, QTimer
from PySide6.QtGui import QGuiApplication, QWindow
from PySide6.QtWidgets import QApplication, QWidget


class FocusKeeper(QObject):
    """Watches each of our windows that takes the focus (a dialog, a progress window); when one hides while it
    has the focus, activates ``main`` once nothing else holds it: no modal dialog is up (a question that opens a
    file dialog, say) and no other shown window has the focus. A dialog that closes while another program has
    the focus takes nothing from it (it had no focus to hand on)."""

    def __init__(self, main: QWidget):
        super().__init__(main)
        self.main = main
        QGuiApplication.instance().focusWindowChanged.connect(self._watch)

    def _watch(self, window: QWindow | None) -> None:
        """Watch the window that took the focus for its hiding (a static dialog is deleted right after, and Qt
        then drops its focus without a ``focusWindowChanged``: the hide is the one sign)."""
        if window is not None and window is not self.main.windowHandle():
            window.installEventFilter(self)  # once per window: Qt drops an earlier install of the same filter

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() == QEvent.Type.Hide and watched is QGuiApplication.focusWindow():
            QTimer.singleShot(0, self._give_back)
        return False

    def _give_back(self) -> None:
        """``main`` active again, unless it is hidden or minimised or the focus went somewhere of ours."""
        focus = QGuiApplication.focusWindow()
        if QApplication.activeModalWidget() is not None or (focus is not None and focus.isVisible()):
            return
        if self.main.isVisible() and not self.main.isMinimized():
            self.main.activateWindow()
