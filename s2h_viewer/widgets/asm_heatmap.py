"""The 20 x 29 ASM error matrix of one retarget at the current frame, as a colour image with axis
labels (joint names) and a tooltip naming the cell's joint pair and its error.

It follows every frame the view draws, so it must cost next to nothing per frame: the labels are
painted once into a pixmap, and a frame only writes the cell colours (a colour table lookup, each cell
repeated ``CELL`` x ``CELL`` times) into one reused image in the screen's pixel order (Qt's RGB32), which
the paint copies as it is: no scaling, no conversion (a third of the scaled drawing's cost)."""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from PySide6.QtCore import QRect, Qt, Signal
from PySide6.QtGui import QColor, QFont, QImage, QPainter, QPixmap
from PySide6.QtWidgets import QLabel, QToolTip, QVBoxLayout, QWidget

from s2h_viewer.hand import topology as topo
from s2h_viewer.render.compare_scene import ERROR_COLOURMAP, ERROR_RANGE

#: the mouse on the heatmap, for Help's list
MOUSE = (("hover a heatmap cell", "its joint pair and error"),
         ("click a heatmap row (a cell or its name)", "that joint's bend on the error curve, the source's beside it"))

CELL = 12  # pixels per matrix cell
LEFT, TOP = 78, 70  # room for the row and column labels
ROW_NAMES = topo.FINGER_JOINT_NAMES
COLUMN_NAMES = topo.FINGER_JOINT_NAMES + tuple(f"palm anchor {i + 1}" for i in range(topo.N_ANCHORS))
COLOURS = 256  # entries of the colour table
MASKED_GREY = 200
CELLS = QRect(LEFT, TOP, topo.N_ASM_COLUMNS * CELL, topo.N_FINGER_JOINTS * CELL)  # the matrix, in the widget


def colour_table() -> np.ndarray:
    """(COLOURS + 1, 3) uint8: the error colour map over ERROR_RANGE, then grey for masked cells."""
    table = (colormaps[ERROR_COLOURMAP](np.linspace(0.0, 1.0, COLOURS))[:, :3] * 255).round().astype(np.uint8)
    return np.vstack([table, np.full((1, 3), MASKED_GREY, dtype=np.uint8)])


def screen_order(rgb: np.ndarray) -> np.ndarray:
    """(..., 4) uint8 pixels of Qt's RGB32 (0xffRRGGBB: blue, green, red, 255 in memory) for (..., 3) RGB."""
    return np.concatenate([rgb[..., ::-1], np.full(rgb.shape[:-1] + (1,), 255, dtype=np.uint8)], axis=-1)


def colour_indices(cell_error: np.ndarray) -> np.ndarray:
    """Each cell's row in ``colour_table``: its error scaled over ERROR_RANGE (clipped), masked cells last."""
    lo, hi = ERROR_RANGE
    scaled = np.rint(np.clip((cell_error - lo) / (hi - lo), 0.0, 1.0) * (COLOURS - 1))  # NaN stays NaN
    return np.where(np.isnan(cell_error), COLOURS, scaled).astype(np.intp)  # few numpy calls: it runs every frame


def spaced(name: str) -> str:
    """'index_pip' -> 'index pip'."""
    return name.replace("_", " ")


def short(name: str) -> str:
    """'index_pip' -> 'index pip'; 'palm anchor 3' -> 'anchor 3' (the axis labels)."""
    return spaced(name).replace("palm anchor", "anchor")


def axis_labels() -> QPixmap:
    """The joint names along both axes on white, the matrix area left empty (painted once)."""
    pixmap = QPixmap(LEFT + topo.N_ASM_COLUMNS * CELL, TOP + topo.N_FINGER_JOINTS * CELL)
    pixmap.fill(QColor("white"))
    painter = QPainter(pixmap)
    painter.setFont(QFont(painter.font().family(), 7))
    for row, name in enumerate(ROW_NAMES):
        painter.drawText(0, TOP + row * CELL, LEFT - 3, CELL, Qt.AlignmentFlag.AlignRight |
                         Qt.AlignmentFlag.AlignVCenter, short(name))
    painter.rotate(-90)  # column names read upwards
    for column, name in enumerate(COLUMN_NAMES):
        painter.drawText(-TOP + 3, LEFT + column * CELL, TOP - 3, CELL, Qt.AlignmentFlag.AlignLeft |
                         Qt.AlignmentFlag.AlignVCenter, short(name))
    painter.end()
    return pixmap


class _Matrix(QWidget):
    """The labels, the cells scaled up and the frame number in the empty corner; hovering a cell shows its
    joint pair and error."""

    def __init__(self, heatmap: "AsmHeatmap"):
        super().__init__()
        self.heatmap = heatmap
        self.labels = axis_labels()
        self.setFixedSize(self.labels.size())  # a fixed size: a new frame repaints it, never lays out the window
        self.setMouseTracking(True)

    def paintEvent(self, event) -> None:
        painter = QPainter(self)
        heatmap = self.heatmap
        for rect in event.region():  # a new frame: the frame number and the cells, not the labels between
            if heatmap.current is None or not CELLS.contains(rect):
                painter.drawPixmap(rect, self.labels, rect)
        if heatmap.current is not None:
            painter.drawImage(CELLS.topLeft(), heatmap.image)
            if heatmap.row is not None:  # the joint chosen (its angle curve): its row outlined
                painter.setPen(QColor("white"))
                painter.drawRect(CELLS.left(), TOP + heatmap.row * CELL, CELLS.width() - 1, CELL - 1)
            painter.setPen(self.palette().windowText().color())  # not the outline's white: on white, unseen
            painter.drawText(QRect(0, 0, LEFT - 3, TOP - 3), Qt.AlignmentFlag.AlignRight |
                             Qt.AlignmentFlag.AlignBottom, f"frame {heatmap.frame}")

    def mousePressEvent(self, event) -> None:
        cell = self.heatmap.cell_at(int(event.position().x()), int(event.position().y()))
        if cell is None and LEFT > event.position().x() >= 0 and TOP <= event.position().y() < CELLS.bottom():
            cell = (int(event.position().y() - TOP) // CELL, 0)  # a row's name
        if cell is not None:
            self.heatmap.choose_row(cell[0])

    def mouseMoveEvent(self, event) -> None:
        text = self.heatmap.cell_text(int(event.position().x()), int(event.position().y()))
        if text:
            QToolTip.showText(event.globalPosition().toPoint(), text, self)
        else:
            QToolTip.hideText()


class AsmHeatmap(QWidget):
    """Rows: the 20 finger joints; columns: 20 finger joints then 9 palm anchors. A click on a row (its cells
    or its name) chooses that joint: ``row_chosen(row)`` (the error curve's joint angle follows it)."""

    row_chosen = Signal(int)

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.current: np.ndarray | None = None  # the matrix shown
        self.row: int | None = None  # the joint chosen, outlined
        self.frame = -1  # the frame it belongs to
        self._colours = screen_order(colour_table())
        self._pixels = np.zeros((CELLS.height(), CELLS.width(), 4), dtype=np.uint8)
        self.image = QImage(self._pixels.data, CELLS.width(), CELLS.height(), 4 * CELLS.width(),
                            QImage.Format.Format_RGB32)  # a view of ``_pixels``: a frame writes the array only
        self.matrix = _Matrix(self)
        self.legend = QLabel(f"ASM error (1 - cos): {ERROR_RANGE[0]:g} dark to {ERROR_RANGE[1]:g}+ bright, grey "
                             f"masked; rows: the {topo.N_FINGER_JOINTS} finger joints, columns: the same, then "
                             f"{topo.N_ANCHORS} palm anchors. Hover a cell for its pair; click a row: its "
                             f"joint's bend on the curve (Ctrl+Shift+G).")
        self.legend.setWordWrap(True)  # as wide as the matrix, and as tall as its lines then need: a layout
        self.legend.setFixedWidth(self.matrix.width())  # gives a wrapped label too little height, drawing it
        self.legend.setMinimumHeight(self.legend.heightForWidth(self.matrix.width()))  # over the matrix
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 4, 0, 0)
        for widget in (self.matrix, self.legend):
            layout.addWidget(widget)

    def cell_at(self, x: int, y: int) -> tuple[int, int] | None:
        """(row, column) of the matrix cell under image pixel (x, y), or None off the matrix."""
        row, column = (y - TOP) // CELL, (x - LEFT) // CELL
        if x < LEFT or y < TOP or row >= topo.N_FINGER_JOINTS or column >= topo.N_ASM_COLUMNS:
            return None
        return row, column

    def cell_text(self, x: int, y: int) -> str:
        cell = self.cell_at(x, y)
        if cell is None or self.current is None:
            return ""
        value = self.current[cell]
        error = "masked" if np.isnan(value) else f"1 - cos = {value:.3f}"
        return f"{spaced(ROW_NAMES[cell[0]])} to {spaced(COLUMN_NAMES[cell[1]])}: {error}"  # as the axes spell them

    def choose_row(self, row: int) -> None:
        self.show_row(row)
        self.row_chosen.emit(row)

    def show_row(self, row: int | None) -> None:
        """Frame row ``row`` (None: no row) without choosing it: the joint the error curve shows."""
        self.row = row
        self.matrix.update(CELLS)

    def show_matrix(self, cell_error: np.ndarray, frame: int) -> None:
        """Show ``cell_error`` (20, 29), the matrix of ``frame``: new cell colours in the same image, a repaint."""
        self.current, self.frame = cell_error, frame
        cells = self._colours[colour_indices(cell_error)]
        self._pixels[:] = np.repeat(np.repeat(cells, CELL, axis=0), CELL, axis=1)
        self.matrix.update(0, 0, LEFT, TOP)  # the frame number
        self.matrix.update(CELLS)  # the cells: not the labels
