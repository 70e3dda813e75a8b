"""The 20 x 29 ASM error matrix of one retarget at the current frame, as a colour image with a legend."""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from PySide6.QtCore import Qt
from PySide6.QtGui import QImage, QPixmap
from PySide6.QtWidgets import QLabel, QVBoxLayout, QWidget

from s2h_viewer.hand import topology as topo
from s2h_viewer.render.compare_scene import ERROR_COLOURMAP, ERROR_RANGE

CELL = 12  # pixels per matrix cell


def error_image(cell_error: np.ndarray) -> np.ndarray:
    """(20 * CELL, 29 * CELL, 3) uint8: error coloured over ERROR_RANGE, masked cells grey."""
    lo, hi = ERROR_RANGE
    scaled = np.clip((np.nan_to_num(cell_error, nan=lo) - lo) / (hi - lo), 0.0, 1.0)
    rgb = (colormaps[ERROR_COLOURMAP](scaled)[..., :3] * 255).astype(np.uint8)
    rgb[np.isnan(cell_error)] = 200
    return np.repeat(np.repeat(rgb, CELL, axis=0), CELL, axis=1)


class AsmHeatmap(QWidget):
    """Rows: the 20 finger joints; columns: 20 finger joints then 9 palm anchors."""

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.title = QLabel("ASM error")
        self.image = QLabel()
        self.image.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.image.setMinimumSize(topo.N_ASM_COLUMNS * CELL, topo.N_FINGER_JOINTS * CELL)
        self.legend = QLabel(f"rows: {topo.N_FINGER_JOINTS} finger joints (thumb CMC .. pinky tip); columns: the same "
                             f"20, then {topo.N_ANCHORS} palm anchors. Colour: 1 - cos, {ERROR_RANGE[0]:g} (dark) to "
                             f"{ERROR_RANGE[1]:g}+ (bright); grey: masked.")
        self.legend.setWordWrap(True)
        layout = QVBoxLayout(self)
        for widget in (self.title, self.image, self.legend):
            layout.addWidget(widget)
        self.current: np.ndarray | None = None

    def show_matrix(self, cell_error: np.ndarray, title: str) -> None:
        self.current = cell_error
        rgb = np.ascontiguousarray(error_image(cell_error))
        h, w = rgb.shape[:2]
        self.image.setPixmap(QPixmap.fromImage(QImage(rgb.data, w, h, 3 * w, QImage.Format.Format_RGB888).copy()))
        self.title.setText(title)
