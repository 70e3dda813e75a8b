"""Per-method clip scores (S_palm, S_finger, contacts, violations) for every target, in a table."""

from __future__ import annotations

from PySide6.QtWidgets import QTableWidget, QTableWidgetItem, QWidget

from s2h_viewer.retarget.comparison import Comparison
from s2h_viewer.retarget.methods import METHODS

COLUMNS = (("Method", None), ("Target", None), ("S_palm", "s_palm"), ("S_finger", "s_finger"),
           ("Contact P", "contact_precision"), ("Contact R", "contact_recall"), ("Palm R", "palm_contact_recall"),
           ("Violations", "violation_rate"))


class ScoresTable(QTableWidget):
    def __init__(self, parent: QWidget | None = None):
        super().__init__(0, len(COLUMNS), parent)
        self.setHorizontalHeaderLabels([c for c, _ in COLUMNS])
        self.verticalHeader().setVisible(False)
        self.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)

    def show_comparison(self, comparison: Comparison) -> None:
        self.setRowCount(len(comparison.results))
        for row, result in enumerate(comparison.results):
            values = result.scores.as_dict()
            cells = [METHODS[result.method].label, result.target.name]
            cells += [f"{values[key]:.3f}" for _, key in COLUMNS[2:]]
            for col, text in enumerate(cells):
                self.setItem(row, col, QTableWidgetItem(text))
        self.resizeColumnsToContents()
