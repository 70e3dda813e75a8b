"""Per-method clip scores (S_palm, S_finger, contacts, violations, sideways flexion, signature kept, invented
contacts) for every target, in a table; a target whose frames are unsure reads "! name" on orange.
Names longer than ``NAME_WIDTH`` are elided in the middle (the full name in the cell's tooltip; drag a
header edge to widen a column) and the table asks for the width of all its columns, so a long target
name never pushes a score out of sight. A score with nothing to count (the precision of a retarget that
makes no contact, the recall of a source that makes none) reads "n/a", its reason in the tooltip."""

from __future__ import annotations

import math

from PySide6.QtCore import QSize, Qt
from PySide6.QtGui import QBrush, QColor, QPalette
from PySide6.QtWidgets import QHeaderView, QStyledItemDelegate, QTableWidget, QTableWidgetItem, QWidget

from s2h_viewer.annotate.trust import frame_warning
from s2h_viewer.render.compare_scene import BANNER_BACKGROUND, BANNER_COLOUR
from s2h_viewer.retarget.comparison import Comparison
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.semantics.flexion import THUMB_FOLLOWS_FROM, thumb_words
from s2h_viewer.semantics.signature import lost_pose_lines
from s2h_viewer.widgets.text_dialog import TextDialog
from s2h_viewer.widgets.tooltips import wrapped
from s2h_viewer.wording import counted

#: what the Kept column (here and in a batch's table) counts
KEPT_TIP = ("share of frames that keep the source's signature: each finger extended, bent or curled as in the "
            "source, the thumb's touches, a thumb out to its side where the source's is (a thumbs-up), on the curled "
            "fingers where the source's rests on them (the horns), across the palm where the source's lies across "
            "it (a four), no finger bending sideways, no invented pad contact (1: every frame)")
#: (header, score key or None for a name column, header tooltip)
COLUMNS = (("Method", None, "retargeting method"), ("Target", None, "target hand"),
           ("S_palm", "s_palm", "finger-palm semantic similarity to the source (1 is the same)"),
           ("S_finger", "s_finger", "finger-finger semantic similarity to the source (1 is the same)"),
           ("Contact\nP", "contact_precision", "contact precision: pad contacts made that the source makes"),
           ("Contact\nR", "contact_recall", "contact recall: pad contacts of the source that are kept"),
           ("Palm\nR", "palm_contact_recall", "fingertip-on-palm contacts of the source that are kept"),
           ("Viol.\nadded", "added_violation_rate", "share of joint angles the retarget puts over 5 deg further "
                                                     "outside the anatomical limits than the source's own (a clip "
                                                     "authored past them stays past them: TBS Copy adds none)"),
           ("Side-\nways", "sideways_deg", "the worst sideways bend of a PIP/DIP at its tightest curls, degrees "
                                            "(0: a clean curl toward the palm; authored clips reach 8-22); red past "
                                            "25, or past the source's own figure + 5 where the source bends more"),
           ("Thumb", "thumb_follow", "how closely the thumb follows the source's: the correlation over the clip of "
                                     "each thumb angle (the metacarpal across and out of the palm, the MCP and IP "
                                     "bends) with the source's, the worst of them (1: it does what the source's does); "
                                     "red under 0.9"),
           ("Kept", "signature_kept", KEPT_TIP),
           ("Inv-\nented", "invented_contacts", "frames where the retarget makes a contact the source does not "
                                               "come near, fingertip to fingertip or fingertip on the palm (within "
                                               "3% of the hand; drawn blue by the contact overlay)"))
TARGET_COLUMN = 1
KEPT_COLUMN, SIDEWAYS_COLUMN, THUMB_COLUMN = (next(c for c, (_, key, _) in enumerate(COLUMNS) if key == name)
                                              for name in ("signature_kept", "sideways_deg", "thumb_follow"))
SHOWN_ROWS, MIN_ROWS = 6, 2  # rows the table asks room for, and keeps in view at least
NAME_WIDTH = 140  # pixels: widest a name column starts (drag the header edge for more)
#: a sideways bend past the limit, in the table and over the error curve (in the table on this background)
SIDEWAYS_RED, SIDEWAYS_BACKGROUND = "#c62828", "#ffcdd2"
#: invented pairs the Invented cell's tooltip names (most frames first), and poses lost the Kept cell's names
INVENTED_LISTED, POSES_LISTED = 5, 8
#: why a score is n/a (NaN), per score key
UNDEFINED = {"sideways_deg": "n/a: no finger curls", "contact_precision": "n/a: the retarget makes no pad contact, so no precision to measure",
             "contact_recall": "n/a: the source makes no pad contact, so no recall to measure",
             "palm_contact_recall": "n/a: the source puts no fingertip on the palm, so no recall to measure",
             "thumb_follow": "n/a: the source's thumb barely moves, so no motion to follow"}


def _cell(key: str, scores, held_at=lambda frame: "", lost_poses: str | None = None) -> tuple[str, str | None]:
    """A score's text and tooltip (None: the column's), from `RetargetScores`; ``held_at``: the pose held at a frame
    (`Motion.held_at`), ``lost_poses``: on a clip of poses, the Kept cell's tooltip (`poses_tip`)."""
    value = getattr(scores, key)
    if isinstance(value, float) and math.isnan(value):
        return "n/a", UNDEFINED.get(key, "n/a")
    if key == "invented_contacts":
        return f"{value}", scores.invented_words(INVENTED_LISTED)
    if key == "added_violation_rate":
        return f"{value:.3f}", (f"{value:.3f} of the (frame, joint) angles more than 5 deg further outside the "
                                f"anatomical limits than the source's; outside them at all: "
                                f"{scores.violation_rate:.3f}, the source itself: "
                                f"{scores.source_violation_rate:.3f} (a clip authored past them stays past them)")
    if key == "thumb_follow":
        return f"{value:.2f}", thumb_words(value, scores.thumb_follow_at)
    if key == "sideways_deg":  # to a tenth: 25.4 is past 25 and red, and a red "25" read as a rule broken at 25
        return f"{value:.1f}", scores.sideways_words(held_at)
    if key == "signature_kept" and lost_poses is not None:  # a clip of poses: which the retarget loses, and how
        return f"{value:.3f}", lost_poses
    return f"{value:.3f}", None


def poses_tip(result) -> str:
    """The Kept cell's tooltip on a clip of poses: how many the retarget keeps, and what each one lost loses (the
    first `POSES_LISTED`: the whole list is a double-click away, `poses_text`)."""
    lost = lost_pose_lines(result.poses_lost, result.motion.labels)
    kept = f"{result.poses_held - len(lost)} of {counted(result.poses_held, 'pose')} kept"
    listed = "".join(f"\n{name}: {', '.join(what)}" for name, what in lost[:POSES_LISTED])
    more = (f"\n... and {len(lost) - POSES_LISTED} more: double-click for all"
            if len(lost) > POSES_LISTED else "")
    return f"{kept}" + (f"; lost:{listed}{more}" if lost else " (every one)")


def poses_text(result) -> str:
    """Every pose ``result`` loses and what it loses, a line each (the Kept cell's double-click): the tooltip's
    list stopped at 8 of 16 and the rest were only in `s2h evaluate`'s CSV (a fresh-eyes user)."""
    lost = lost_pose_lines(result.poses_lost, result.motion.labels)
    head = f"{result.name}: {result.poses_held - len(lost)} of {counted(result.poses_held, 'pose')} kept"
    return head + ("".join(f"\n\n{name}:\n  " + "\n  ".join(what) for name, what in lost) if lost
                   else " (every one)")


class OwnColours(QStyledItemDelegate):
    """A cell with colours of its own keeps them in a selected row: the red of a finger bent sideways and the orange of
    a target with unsure frames were hidden under the selection's blue, on the very retarget being looked at."""

    def initStyleOption(self, option, index) -> None:
        super().initStyleOption(option, index)
        for role, shown in ((Qt.ItemDataRole.BackgroundRole, QPalette.ColorRole.Highlight),
                            (Qt.ItemDataRole.ForegroundRole, QPalette.ColorRole.HighlightedText)):
            colour = index.data(role)
            if colour is not None:
                option.palette.setBrush(shown, QBrush(colour))


class ScoresTable(QTableWidget):
    def __init__(self, parent: QWidget | None = None):
        super().__init__(0, len(COLUMNS), parent)
        self.setHorizontalHeaderLabels([c for c, _, _ in COLUMNS])
        for column, (_, _, tip) in enumerate(COLUMNS):
            self.horizontalHeaderItem(column).setToolTip(wrapped(tip))  # long: on one line it ran off the window
        self.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Interactive)
        self.verticalHeader().setVisible(False)
        self.verticalHeader().setDefaultSectionSize(self.fontMetrics().height() + 8)  # one line per retarget
        self.setWordWrap(False)  # a long name elides: a row never grows to two lines
        self.setTextElideMode(Qt.TextElideMode.ElideMiddle)
        self.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        # a row is one retarget: select whole rows, one at a time, highlighted even with the focus elsewhere
        self.setSelectionBehavior(QTableWidget.SelectionBehavior.SelectRows)
        self.setSelectionMode(QTableWidget.SelectionMode.SingleSelection)
        self.setItemDelegate(OwnColours(self))
        palette = self.palette()
        for role in (QPalette.ColorRole.Highlight, QPalette.ColorRole.HighlightedText):
            palette.setColor(QPalette.ColorGroup.Inactive, role, palette.color(QPalette.ColorGroup.Active, role))
        self.setPalette(palette)
        self._results: list = []  # the comparison's results, a row each
        self.cellDoubleClicked.connect(self._show_poses)

    def _show_poses(self, row: int, column: int) -> None:
        """A double-click on a Kept cell of a clip of poses: every pose that retarget loses, in a dialog of its own
        (not modal: the clip plays on)."""
        if column != KEPT_COLUMN or row >= len(self._results) or not self._results[row].poses_held:
            return
        result = self._results[row]
        self.poses_dialog = TextDialog(self, f"Poses lost: {result.name}", poses_text(result))
        self.poses_dialog.show()
        # it takes the keys (Esc closes it) and hands them back when it closes (`app.focus`): shown without, the
        # window's shortcuts went dead after it closed under an X server with no window manager (a fresh-eyes user)
        self.poses_dialog.raise_()
        self.poses_dialog.activateWindow()

    def _height_for(self, rows: int) -> int:
        return self.horizontalHeader().sizeHint().height() + rows * self.verticalHeader().defaultSectionSize() + \
            2 * self.frameWidth() + self.horizontalScrollBar().sizeHint().height()

    def sizeHint(self) -> QSize:
        """Tall enough for its rows, up to `SHOWN_ROWS` (more scroll), and an empty line under them (where the
        table ends shows), as wide as its columns."""
        return QSize(self.minimumWidth(), self._height_for(max(1, min(self.rowCount(), SHOWN_ROWS)) + 1))

    def minimumSizeHint(self) -> QSize:
        """At least two rows stay in view, however short the window (its splitter gives it no less)."""
        return QSize(self.minimumWidth(), self._height_for(MIN_ROWS))

    def mousePressEvent(self, event) -> None:
        """A click in the empty space under the rows keeps the selected retarget (there always is one)."""
        if self.indexAt(event.position().toPoint()).isValid():
            super().mousePressEvent(event)

    def show_comparison(self, comparison: Comparison) -> None:
        self.setRowCount(len(comparison.results))
        self._results = list(comparison.results)
        for row, result in enumerate(comparison.results):
            warning = frame_warning(result.target)
            target = (f"! {result.target.name}", warning.describe()) if warning else (result.target.name,) * 2
            method = METHODS[result.method].label
            fixes = result.corrections
            cells = [(f"{method} (fixed)", f"{method}, corrected: {fixes.describe()}") if fixes else (method,) * 2,
                     target]
            lost_poses = poses_tip(result) if result.poses_held else None
            cells += [_cell(key, result.scores, result.motion.held_at, lost_poses) for _, key, _ in COLUMNS[2:]]
            for col, (text, tip) in enumerate(cells):
                item = QTableWidgetItem(text)
                if tip is not None:
                    item.setToolTip(wrapped(tip))  # a list of invented pairs, a warning: long
                if (col == SIDEWAYS_COLUMN and result.scores.sideways_broken  # a finger bent sideways, a thumb
                        or col == THUMB_COLUMN and result.scores.thumb_follow < THUMB_FOLLOWS_FROM):  # astray
                    item.setForeground(QColor(SIDEWAYS_RED))
                    item.setBackground(QColor(SIDEWAYS_BACKGROUND))
                if warning is not None and col == TARGET_COLUMN:  # frames unsure: the target's cell says so
                    item.setForeground(QColor(BANNER_COLOUR))
                    item.setBackground(QColor(BANNER_BACKGROUND))
                self.setItem(row, col, item)
        self.resizeColumnsToContents()
        for column, (_, key, _) in enumerate(COLUMNS):
            if key is None and self.columnWidth(column) > NAME_WIDTH:
                self.setColumnWidth(column, NAME_WIDTH)
        # wide enough for every column (names capped above): the side panel makes room, no score hides
        self.setMinimumWidth(self.horizontalHeader().length() + 2 * self.frameWidth() +
                             self.verticalScrollBar().sizeHint().width())
        self.updateGeometry()  # room for its rows now (`sizeHint`)
