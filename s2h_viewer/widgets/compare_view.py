"""Compare mode's viewport: the compare grid (`render.compare_scene`) in one render window with
linked cameras, rendered off screen and shown as an image (`widgets.vtk_widget`), redrawn on ``show_frame``.

A new frame asks for a repaint (``update``): one render per frame for the whole grid. While the
timeline plays, each skin of the grid is drawn with fewer faces; paused or shown alone, the full
display mesh. A double-click on a hand shows its viewport alone (solo), a second one brings the grid
back. ``drawn`` fires after every render, so the timeline can show the frames actually drawn per
second. While playing, the frame expected next is posed on a worker thread (numpy alone) while the
current one is drawn (`prefetch`): the GUI thread then only copies it in. The worker starts when the
render does: VTK lets go of Python's lock while it draws, where the GUI thread's own Python (the heatmap,
the curve, the paint) would wait for the worker to let go of it."""

from __future__ import annotations

import dataclasses
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, QObject, Signal
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter
from PySide6.QtWidgets import QVBoxLayout, QWidget

from s2h_viewer.render.compare_scene import (PLAYING_FACES, CellLabel, PosedHand, PosedSkin, ViewOptions,
                                             apply_options, colour_bar_beside_solo, fit_cells, grid_layout,
                                             populate)
from s2h_viewer.retarget.comparison import Comparison
from s2h_viewer.widgets.vtk_widget import PlotterWidget, window_plotter

#: the mouse in the grid beyond the camera (`vtk_widget.MOUSE`), for Help's list
MOUSE = (("double-click a hand", "show it alone and select it; double-click again for the grid"),)


class CompareView(QWidget):
    """Source + targets x methods, synchronised on ``show_frame``."""

    drawn = Signal()
    solo_changed = Signal(int)  # the hand shown alone (index into the grid's hands), -1 for the grid

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self._layout = QVBoxLayout(self)
        self._layout.setContentsMargins(0, 0, 0, 0)
        self.interactor: PlotterWidget | None = None
        self.plotter: pv.Plotter | None = None
        self.comparison: Comparison | None = None
        self._hands: list[PosedHand] = []
        self._labels: list[CellLabel] = []
        self.options = ViewOptions()
        self.solo = -1
        self._viewports: list[tuple[float, ...]] = []
        self.frame = 0
        self.playing = False
        self._posing = ThreadPoolExecutor(max_workers=1, thread_name_prefix="posing")
        self._ahead: tuple[int, Future] | None = None  # a frame being posed ahead, and its skins to come
        self._wanted: int | None = None  # the frame to pose ahead once the next render starts
        self.prefetched = self.posed_here = 0  # frames shown from the worker's skins / posed when shown

    @property
    def opacity(self) -> float:
        return self.options.opacity

    def set_comparison(self, comparison: Comparison) -> None:
        """Lay out one subplot per hand: the source, then a row per target, a column per method."""
        kept = None
        if self.plotter is not None and self.comparison is not None and self.comparison.source is comparison.source:
            camera = self.plotter.camera  # the user's camera (dragged or a preset) outlives the grid
            kept = (camera.position, camera.focal_point, camera.up)
        self.comparison = comparison
        self.close_grid()  # pyvista fixes the subplot layout at construction: start afresh
        self.plotter = window_plotter(**grid_layout(comparison))
        self.interactor = PlotterWidget(self.plotter, self)
        self.interactor.installEventFilter(self)
        self.plotter.render_window.AddObserver("StartEvent", lambda *_: self._render_starts())
        self.plotter.render_window.AddObserver("EndEvent", lambda *_: self.drawn.emit())
        self._layout.addWidget(self.interactor)
        if self.isVisible():  # shown and sized now, not at the next event loop: a grab right after draws at its size
            self.interactor.show()
            self._layout.activate()
        self.interactor.Initialize()
        self._hands, self._labels = populate(self.plotter, comparison, self.options.opacity,
                                             playing_faces=PLAYING_FACES)
        self._viewports = [tuple(r.GetViewport()) for r in self.plotter.renderers]
        self.solo = -1
        self._choose_skins()
        apply_options(self.plotter, self._hands, self.options)
        if kept is not None:  # one camera for every viewport still: the same scale for source and targets
            camera = self.plotter.camera
            camera.position, camera.focal_point, camera.up = kept
            for renderer in self.plotter.renderers:
                renderer.ResetCameraClippingRange()
        self.show_frame(min(self.frame, comparison.n_frames - 1))

    def show_frame(self, frame: int) -> None:
        self.frame = frame
        ahead = self._take_ahead(frame)
        for index, hand in enumerate(self._hands):
            hand.show(frame, ahead[index] if ahead else None)
        if self.interactor is not None:
            self.interactor.update()

    def prefetch(self, frame: int | None) -> None:
        """Pose ``frame``'s skins on the worker thread (the frame expected next while playing) from the start
        of the next render, so that showing it only copies them in. A frame asked for then that is another
        is posed when shown."""
        self._wanted = frame

    def _render_starts(self) -> None:
        """The render window starts drawing: the cells fitted to their size now (the widget's size and solo
        change it: labels, overlays, camera), and the worker poses the frame wanted next meanwhile."""
        fit_cells(self.plotter, self._hands, self._labels)
        frame, self._wanted = self._wanted, None
        if frame is None or not self._hands or (self._ahead is not None and self._ahead[0] == frame):
            return
        hands = list(self._hands)
        self._ahead = (frame, self._posing.submit(lambda: [hand.posed_skin(frame) for hand in hands]))

    def _take_ahead(self, frame: int) -> list[PosedSkin | None] | None:
        """The skins posed ahead for ``frame`` (waiting for the worker if it is still at them), or None."""
        ahead, self._ahead = self._ahead, None
        if ahead is None or ahead[0] != frame:
            self.posed_here += 1
            return None
        self.prefetched += 1
        return ahead[1].result()

    def set_playing(self, playing: bool) -> None:
        self.playing = playing
        self._choose_skins()
        if self.interactor is not None:
            self.interactor.update()

    def _choose_skins(self) -> None:
        """Lighter skins (`render.compare_scene.PLAYING_FACES`) while the grid plays; the full ones when
        paused, and for a hand shown alone (one hand draws fast enough at full detail)."""
        for hand in self._hands:
            hand.set_playing(self.playing and self.solo < 0)

    def set_options(self, **changes) -> None:
        """Change the camera preset, overlays or opacity (``ViewOptions`` fields) and redraw."""
        self.options = dataclasses.replace(self.options, **changes)
        if self.interactor is not None:  # the camera moves for a preset only, not for an overlay
            apply_options(self.plotter, self._hands, self.options, camera="camera" in changes)
            self.show_frame(self.frame)

    def set_mesh_opacity(self, opacity: float) -> None:
        self.set_options(opacity=opacity)

    def hand_at(self, x: int, y: int) -> int:
        """The index of the hand whose viewport holds widget pixel (x, y), or -1."""
        w, h = max(1, self.interactor.width()), max(1, self.interactor.height())
        u, v = x / w, 1.0 - y / h
        for index, viewport in enumerate(self.hand_viewports()):
            if viewport[0] <= u < viewport[2] and viewport[1] <= v < viewport[3]:
                return index
        return -1

    def hand_viewports(self) -> list[tuple[float, ...]]:
        """Each hand's viewport in the grid (x0, y0, x1, y1 as fractions, y up), in ``_hands`` order."""
        renderers = list(self.plotter.renderers)
        return [self._viewports[renderers.index(hand.renderer)] for hand in self._hands]

    def set_solo(self, index: int) -> None:
        """Show hand ``index``'s viewport alone over the whole view; -1 restores the grid."""
        self.solo = index
        solo = self._hands[index].renderer if index >= 0 else None
        for renderer, viewport in zip(self.plotter.renderers, self._viewports):
            renderer.SetViewport(*((0.0, 0.0, 1.0, 1.0) if renderer is solo else viewport))
            renderer.SetDraw(solo is None or renderer is solo)
        if index >= 0 and self._hands[index].error_actor is not None:
            colour_bar_beside_solo(self.plotter)  # a retarget alone keeps the colour bar of its error colours
        self._choose_skins()
        self.solo_changed.emit(index)
        self.interactor.update()

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if watched is self.interactor and event.type() == QEvent.Type.MouseButtonDblClick:
            self.set_solo(-1 if self.solo >= 0 else self.hand_at(int(event.position().x()),
                                                                 int(event.position().y())))
            return True
        return False

    def grab_rgb(self) -> np.ndarray:
        """The current view as an (H, W, 3) uint8 image (what screenshot and video export save)."""
        window = self.plotter.render_window
        window.Render()
        grab = vtkWindowToImageFilter()
        grab.SetInput(window)
        grab.SetInputBufferTypeToRGB()
        grab.ReadFrontBufferOff()
        grab.Update()
        image = pv.wrap(grab.GetOutput())
        width, height, _ = image.dimensions
        return np.asarray(image.point_data.active_scalars).reshape(height, width, -1)[::-1, :, :3].copy()

    def close_grid(self) -> None:
        """Free the render window and its widget (a new grid, or the window closing)."""
        if self.interactor is not None:
            self.interactor.hide()
            self._layout.removeWidget(self.interactor)
            self.interactor.close_plotter()
            self.interactor.deleteLater()
            self.interactor = self.plotter = None
            self._hands, self._labels = [], []
            self._ahead = self._wanted = None

    def closeEvent(self, event) -> None:
        self.close_grid()
        self._posing.shutdown(cancel_futures=True)
        super().closeEvent(event)
