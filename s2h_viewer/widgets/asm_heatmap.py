"""The 20 x 29 ASM error matrix of one retarget at the current frame, as a colour image with axis
labels (joint names) and a tooltip naming the cell's joint pair and its error."""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QFont, QImage, QPainter, QPixmap
from PySide6.QtWidgets import QLabel, QToolTip, QVBoxLayout, QWidget

from s2h_viewer.hand import topology as topo
from s2h_viewer.render.compare_scene import ERROR_COLOURMAP, ERROR_RANGE

CELL = 12  # pixels per matrix cell
LEFT, TOP = 78, 70  # room for the row and column labels
ROW_NAMES = topo.FINGER_JOINT_NAMES
COLUMN_NAMES = topo.FINGER_JOINT_NAMES + tuple(f"palm anchor {i + 1}" for i in range(topo.N_ANCHORS))


def error_image(cell_error: np.ndarray) -> np.ndarray:
    """(20 * CELL, 29 * CELL, 3) uint8: error coloured over ERROR_RANGE, masked cells grey."""
    lo, hi = ERROR_RANGE
    scaled = np.clip((np.nan_to_num(cell_error, nan=lo) - lo) / (hi - lo), 0.0, 1.0)
    rgb = (colormaps[ERROR_COLOURMAP](scaled)[..., :3] * 255).astype(np.uint8)
    rgb[np.isnan(cell_error)] = 200
    return np.repeat(np.repeat(rgb, CELL, axis=0), CELL, axis=1)


def short(name: str) -> str:
    """'index_pip' -> 'index pip'; 'palm anchor 3' -> 'anchor 3'."""
    return name.replace("palm anchor", "anchor").replace("_", " ")


class _MatrixLabel(QLabel):
    """The image; hovering a cell shows its joint pair and error."""

    def __init__(self, heatmap: "AsmHeatmap"):
        super().__init__()
        self.heatmap = heatmap
        self.setMouseTracking(True)

    def mouseMoveEvent(self, event) -> None:
        text = self.heatmap.cell_text(int(event.position().x()), int(event.position().y()))
        if text:
            QToolTip.showText(event.globalPosition().toPoint(), text, self)
        else:
            QToolTip.hideText()


class AsmHeatmap(QWidget):
    """Rows: the 20 finger joints; columns: 20 finger joints then 9 palm anchors."""

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.title = QLabel("ASM error")
        self.image = _MatrixLabel(self)
        self.image.setAlignment(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop)
        self.image.setMinimumSize(LEFT + topo.N_ASM_COLUMNS * CELL, TOP + topo.N_FINGER_JOINTS * CELL)
        self.legend = QLabel(f"rows: the {topo.N_FINGER_JOINTS} finger joints; columns: the same 20, then "
                             f"{topo.N_ANCHORS} palm anchors. Colour: 1 - cos, {ERROR_RANGE[0]:g} (dark) to "
                             f"{ERROR_RANGE[1]:g}+ (bright); grey: masked. Hover a cell for its joint pair.")
        self.legend.setWordWrap(True)
        layout = QVBoxLayout(self)
        for widget in (self.title, self.image, self.legend):
            layout.addWidget(widget)
        self.current: np.ndarray | None = None

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
        return f"{ROW_NAMES[cell[0]]} to {COLUMN_NAMES[cell[1]]}: {error}"

    def show_matrix(self, cell_error: np.ndarray, title: str) -> None:
        self.current = cell_error
        rgb = np.ascontiguousarray(error_image(cell_error))
        h, w = rgb.shape[:2]
        pixmap = QPixmap(LEFT + w, TOP + h)
        pixmap.fill(QColor("white"))
        painter = QPainter(pixmap)
        painter.drawImage(LEFT, TOP, QImage(rgb.data, w, h, 3 * w, QImage.Format.Format_RGB888))
        painter.setFont(QFont(painter.font().family(), 7))
        for row, name in enumerate(ROW_NAMES):
            painter.drawText(0, TOP + row * CELL, LEFT - 3, CELL, Qt.AlignmentFlag.AlignRight |
                             Qt.AlignmentFlag.AlignVCenter, short(name))
        painter.rotate(-90)  # column names read upwards
        for column, name in enumerate(COLUMN_NAMES):
            painter.drawText(-TOP + 3, LEFT + column * CELL, TOP - 3, CELL, Qt.AlignmentFlag.AlignLeft |
                             Qt.AlignmentFlag.AlignVCenter, short(name))
        painter.end()
        self.image.setPixmap(pixmap)
        self.title.setText(title)
