"""The window's one-key shortcuts stay the window's while a number box has the focus: a spin box's line edit
claims every printable key (Qt's ShortcutOverride) to type it, so F (frame the hand), R (the ring's next axis) or
Space (play) did nothing after a click into the ease boxes of the fixing bar; none of them is a digit."""

from __future__ import annotations

from PySide6.QtCore import QEvent, QObject, Qt
from PySide6.QtWidgets import QAbstractSpinBox, QWidget

#: keys a number box leaves to the window's shortcuts (digits, signs, Backspace, Up/Down stay the box's)
PASSED_KEYS = (Qt.Key.Key_Space, Qt.Key.Key_Left, Qt.Key.Key_Right, Qt.Key.Key_Home, Qt.Key.Key_End,
               Qt.Key.Key_BracketLeft, Qt.Key.Key_BracketRight,  # the worst-frame keys
               Qt.Key.Key_I, Qt.Key.Key_O,  # the in and out points
               Qt.Key.Key_F, Qt.Key.Key_R, Qt.Key.Key_K)  # frame the hand; fixing: the ring's axis, its keys


class LeaveShortcutKeys(QObject):
    """Refuses a widget's claim (ShortcutOverride) on `PASSED_KEYS` and Ctrl combinations: the window's shortcuts
    get them (a Ctrl key no shortcut takes still reaches the widget)."""

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        return event.type() == QEvent.Type.ShortcutOverride and (
            event.key() in PASSED_KEYS or bool(event.modifiers() & Qt.KeyboardModifier.ControlModifier))


def leave_shortcut_keys(owner: QObject, *widgets: QWidget) -> LeaveShortcutKeys:
    """Install one `LeaveShortcutKeys` (owned by ``owner``) on each widget, and on a spin box's line edit too (the
    part that has the focus)."""
    keys = LeaveShortcutKeys(owner)
    for widget in widgets:
        widget.installEventFilter(keys)
        if isinstance(widget, QAbstractSpinBox):
            widget.lineEdit().installEventFilter(keys)
    return keys
