"""A batch's ``summary.csv`` as a table, worst first (failures, then the least kept); double-click (or
Enter on) a row to look at that clip, target and method in the compare grid. Sortable by any column."""

from __future__ import annotations

import math
from pathlib import Path

from PySide6.QtCore import QEvent, Qt, Signal
from PySide6.QtGui import QColor, QKeyEvent, QKeySequence, QShortcut
from PySide6.QtWidgets import QHeaderView, QLabel, QTableWidget, QTableWidgetItem, QVBoxLayout, QWidget

from s2h_viewer.batch.summary import COUNTS, worst_first
from s2h_viewer.batch.task import POSES_APART
from s2h_viewer.batch.report import sideways_note
from s2h_viewer.semantics.flexion import THUMB_FOLLOWS_FROM, thumb_words
from s2h_viewer.semantics.signature import sideways_broken
from s2h_viewer.widgets.scores_table import KEPT_TIP, SIDEWAYS_BACKGROUND, SIDEWAYS_RED, OwnColours
from s2h_viewer.widgets.tooltips import wrapped

#: (header, row key, decimals or None for text)
COLUMNS = (("Motion", "motion", None), ("Target", "target", None), ("Method", "method", None),
           ("Status", "status", None), ("Kept", "kept", 3), ("S_finger", "s_finger", 3), ("S_palm", "s_palm", 3),
           ("Contact P", "contact_p", 3), ("Contact R", "contact_r", 3), ("Violations\nadded", "violations_added", 3),
           ("Sideways\n(deg)", "sideways_deg", 1), ("Thumb", "thumb_follow", 2), ("Inv-\nented", "invented", None),
           ("Worst\nframe", "worst_frame", None),
           ("Error or warning", "error", None))
FAILED_COLOUR = QColor("#fde7ea")
#: pixels a heading needs beside its text for the sort arrow a click draws there
SORT_ARROW_PX = 20


class _Item(QTableWidgetItem):
    """A cell that sorts by number where it holds one."""

    def __init__(self, text: str, number: float | None):
        super().__init__(text)
        self.number = number

    def __lt__(self, other: QTableWidgetItem) -> bool:
        if isinstance(other, _Item) and self.number is not None and other.number is not None:
            return self.number < other.number
        return self.text().lower() < other.text().lower()  # (super().__lt__ comes back here under PySide6)


class _TypingTable(QTableWidget):
    """A table that takes the letters typed in it (its search for a row by name) before the window's one-key
    shortcuts do: a fresh-eyes user typed a motion's name to find its row, and R turned the fixing ring's axis and O
    marked a range. Space still plays."""

    def event(self, event: QEvent) -> bool:
        if event.type() == QEvent.Type.ShortcutOverride and isinstance(event, QKeyEvent) and event.text().strip() \
                and not event.modifiers() & ~Qt.KeyboardModifier.ShiftModifier:
            event.accept()
            return True
        return super().event(event)


class BatchTable(QWidget):
    """The rows of one batch; ``row_chosen`` carries the summary row a person double-clicked."""

    row_chosen = Signal(dict)

    def __init__(self, summary: str | Path, rows: list[dict], parent: QWidget | None = None):
        super().__init__(parent)
        self.summary = Path(summary)
        self.rows = worst_first(rows)
        failed = sum(r.get("status") == "failed" for r in self.rows)
        self.setWindowTitle(f"Batch: {Path(summary).parent.name}/{Path(summary).name} ({len(self.rows)} tasks, "
                            f"{failed} failed)")
        self.table = _TypingTable(len(self.rows), len(COLUMNS), self)
        self.table.setHorizontalHeaderLabels([c for c, _, _ in COLUMNS])
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QTableWidget.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QTableWidget.SelectionMode.SingleSelection)
        self.table.setItemDelegate(OwnColours(self.table))  # a red cell stays red in the selected row
        for r, row in enumerate(self.rows):
            for c, (_, key, decimals) in enumerate(COLUMNS):
                value = row.get(key, "")
                if key == "error":
                    value = value or (f"warning: {row['warning']}" if row.get("warning") else "")
                if decimals is not None:
                    number = None if math.isnan(value) else float(value)
                    empty = "n/a" if row.get("status") == "ok" else ""  # a failed task measured nothing
                    text = empty if number is None else f"{number:.{decimals}f}"
                    if key == "kept" and row.get("poses_kept"):
                        text += f" ({row['poses_kept']} poses)"
                    item = _Item(text, number)
                    if key == "kept" and number is not None:
                        lost = str(row.get("poses_lost") or "").replace(POSES_APART, "\n")
                        item.setToolTip(KEPT_TIP + (f"\n\nposes lost:\n{lost}" if lost else ""))
                    item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                else:
                    text = str(value)
                    item = _Item(text, float(text) if key in COUNTS and text.isdigit() else None)
                    if key in COUNTS:
                        item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                    if key == "invented" and row.get("invented_words"):
                        item.setToolTip(wrapped(str(row["invented_words"])))
                if key == "error" and value:
                    item.setToolTip(str(value))
                if key == "violations_added" and number is not None:
                    item.setToolTip(f"joint angles over 5 deg further outside the anatomical limits than the "
                                    f"source's; outside them at all: {row.get('violations', math.nan):.3f}")
                if key == "sideways_deg" and number is not None:
                    item.setToolTip(wrapped(sideways_note(row)))  # the viewer's words, and the page's
                    if sideways_broken(number, row.get("source_sideways_deg", math.nan)):
                        item.setForeground(QColor(SIDEWAYS_RED))
                        item.setBackground(QColor(SIDEWAYS_BACKGROUND))
                if key == "thumb_follow" and number is not None:
                    item.setToolTip(thumb_words(number, str(row.get("thumb_follow_at") or "")))
                    if number < THUMB_FOLLOWS_FROM:
                        item.setForeground(QColor(SIDEWAYS_RED))
                        item.setBackground(QColor(SIDEWAYS_BACKGROUND))
                item.setData(Qt.ItemDataRole.UserRole, r)
                if row.get("status") != "ok":
                    item.setBackground(FAILED_COLOUR)
                self.table.setItem(r, c, item)
        self.table.resizeColumnsToContents()
        for column in range(len(COLUMNS) - 1):  # room for the sort arrow beside a heading: it clipped "Sideways"
            self.table.setColumnWidth(column, self.table.columnWidth(column) + SORT_ARROW_PX)
        self.table.horizontalHeader().setSectionResizeMode(len(COLUMNS) - 1, QHeaderView.ResizeMode.Stretch)
        self.table.horizontalHeader().setSortIndicator(-1, Qt.SortOrder.AscendingOrder)  # worst first until a click
        self.table.setSortingEnabled(True)
        self.table.cellDoubleClicked.connect(lambda r, _c: self._choose(r))
        for key in (Qt.Key.Key_Return, Qt.Key.Key_Enter):  # in the table only: Return in the frame box went back to
            # the row's worst frame, the shortcut being the whole window's (a fresh-eyes user); set apart, as PySide6's
            # constructor drops a context given to it
            shortcut = QShortcut(QKeySequence(key), self.table, lambda: self._choose(self.table.currentRow()))
            shortcut.setContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
        if self.rows:
            self.table.selectRow(0)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 2, 4, 4)
        layout.addWidget(QLabel("Worst first (failures, then the least kept); click a heading to sort, "
                                "double-click a row (or Enter) to show it in Compare at its worst frame."))
        layout.addWidget(self.table)

    def current_row(self) -> tuple[str, str, str] | None:
        """(motion, target, method) of the row selected, None if none."""
        item = self.table.item(self.table.currentRow(), 0) if self.table.currentRow() >= 0 else None
        if item is None:
            return None
        row = self.rows[item.data(Qt.ItemDataRole.UserRole)]
        return row["motion"], row["target"], row["method"]

    def select(self, task: tuple[str, str, str]) -> None:
        """Select the row of ``task`` (motion, target, method), if listed."""
        for table_row in range(self.table.rowCount()):
            row = self.rows[self.table.item(table_row, 0).data(Qt.ItemDataRole.UserRole)]
            if (row["motion"], row["target"], row["method"]) == task:
                self.table.selectRow(table_row)
                return

    def _choose(self, table_row: int) -> None:
        item = self.table.item(table_row, 0)
        if item is not None:
            self.row_chosen.emit(self.rows[item.data(Qt.ItemDataRole.UserRole)])
