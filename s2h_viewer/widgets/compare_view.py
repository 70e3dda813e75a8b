"""Compare mode's viewport: the compare grid (`render.compare_scene`) in one `QtInteractor` with
linked cameras, no multisampling (software OpenGL pays 3-4x for it), redrawn on ``show_frame``.

The widget renders the scene in its own paint, so a new frame asks for a repaint (``update``)
rather than rendering too (that drew every frame twice); exports render synchronously."""

from __future__ import annotations

import numpy as np
from pyvistaqt import QtInteractor
from PySide6.QtWidgets import QVBoxLayout, QWidget

from s2h_viewer.render.compare_scene import PosedHand, grid_layout, populate
from s2h_viewer.retarget.comparison import Comparison


class CompareView(QWidget):
    """Source + targets x methods, synchronised on ``show_frame``."""

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self._layout = QVBoxLayout(self)
        self._layout.setContentsMargins(0, 0, 0, 0)
        self.interactor: QtInteractor | None = None
        self.comparison: Comparison | None = None
        self._hands: list[PosedHand] = []
        self.opacity = 1.0

    def set_comparison(self, comparison: Comparison) -> None:
        """Lay out one subplot per hand: the source once, then a row per target, a column per method."""
        self.comparison = comparison
        if self.interactor is not None:  # pyvista fixes the subplot layout at construction: start afresh
            self._layout.removeWidget(self.interactor)
            self.interactor.close()
            self.interactor.deleteLater()
        self.interactor = QtInteractor(self, multi_samples=0, auto_update=False, **grid_layout(comparison))
        self._layout.addWidget(self.interactor)
        self._hands = populate(self.interactor, comparison, self.opacity)
        self.show_frame(0)
    def show_frame(self, frame: int) -> None:
        for hand in self._hands:
            hand.show(frame)
        if self.interactor is not None:
            self.interactor.update()

    def set_mesh_opacity(self, opacity: float) -> None:
        self.opacity = opacity
        for hand in self._hands:
            hand.set_opacity(opacity)
        if self.interactor is not None:
            self.interactor.update()

    def grab_rgb(self) -> np.ndarray:
        """The current view as an (H, W, 3) uint8 image (what screenshot and video export save)."""
        self.interactor.render()
        return np.asarray(self.interactor.screenshot(return_img=True))[..., :3]
