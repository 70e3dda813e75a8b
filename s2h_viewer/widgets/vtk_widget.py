"""A pyvista plotter drawn in VTK's own native-window Qt widget (``QVTKRenderWindowInteractor``), the
3D widget of both modes.

Not pyvistaqt's ``QtInteractor``: that is a ``QOpenGLWidget``, and one of those anywhere in a window
makes Qt compose the whole window through OpenGL on every repaint (under software OpenGL, the window
drew compare-mode playback at 0.7x the rate it draws without one, `benchmarks/bench_window_playback.py`).
The native widget renders straight into its own X window, in its paint: ``update()`` asks for a frame,
``render()`` draws one now."""

from __future__ import annotations

import pyvista as pv
from PySide6.QtWidgets import QWidget
from vtkmodules.qt.QVTKRenderWindowInteractor import QVTKRenderWindowInteractor
from vtkmodules.vtkInteractionStyle import vtkInteractorStyleTrackballCamera


def window_plotter(**plotter_options) -> pv.Plotter:
    """A pyvista plotter for a native widget, without multisampling (software OpenGL pays 3-4x for it)."""
    plotter = pv.Plotter(off_screen=False, **plotter_options)
    plotter.render_window.SetMultiSamples(0)
    return plotter


class PlotterWidget(QVTKRenderWindowInteractor):
    """``plotter``'s render window in a native widget, the camera turned by the mouse (trackball)."""

    def __init__(self, plotter: pv.Plotter, parent: QWidget | None = None):
        super().__init__(parent, rw=plotter.render_window)
        self.plotter = plotter
        self.alive = True
        self.GetRenderWindow().GetInteractor().SetInteractorStyle(vtkInteractorStyleTrackballCamera())

    def render(self) -> None:
        """Draw now (pyvista's own ``render`` waits for a ``show`` that a widget never calls)."""
        if self.alive:
            self.GetRenderWindow().Render()

    def paintEvent(self, event) -> None:
        if self.alive:  # a paint queued before ``close_plotter`` would render into a freed window
            super().paintEvent(event)

    def resizeEvent(self, event) -> None:
        if self.alive:
            super().resizeEvent(event)

    def close_plotter(self) -> None:
        """Free the render window; the widget draws nothing after this."""
        if self.alive:
            self.alive = False
            self.Finalize()
            self.plotter.close()
