"""A pyvista plotter rendered off screen and shown as an image in a plain Qt widget, the 3D widget of both
modes; the mouse turns the camera through VTK's interactor as in VTK's own Qt widget.

Why not a window on screen: under software OpenGL (llvmpipe on X) a VTK window pays for presenting each
frame (glX swap: ~7 ms a frame at 900 x 700) on top of the off-screen drawing; and pyvistaqt's
``QOpenGLWidget`` makes Qt compose the whole window through OpenGL on every repaint. Off screen, VTK
draws into its framebuffer (the path `s2h render` and the off-screen benchmark take), the widget reads
it back once, top row first (`TopRowFirst`), and Qt paints it with the rest of the window
(`benchmarks/bench_window_playback.py` compares the two). ``update()`` asks for a frame, drawn in the
next paint; ``render()`` draws one now. A paint with nothing new (a dialog moved over the view) shows the
last frame again without rendering."""

from __future__ import annotations

import ctypes
import ctypes.util

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, QPointF, Qt
from PySide6.QtGui import QImage, QMouseEvent, QPainter, QWheelEvent
from PySide6.QtWidgets import QSizePolicy, QWidget
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
from vtkmodules.vtkInteractionStyle import vtkInteractorStyleTrackballCamera
from vtkmodules.vtkRenderingUI import vtkGenericRenderWindowInteractor

from s2h_viewer.render.text_lock import TEXT_LOCK

WHEEL_STEP = 120  # Qt's angle delta of one wheel notch: one VTK zoom step
GL_PACK_INVERT_MESA = 0x8758
#: what the mouse does to the camera of every 3D view (VTK's trackball camera style), for Help's list
MOUSE = (("left drag", "rotate the camera"), ("Shift+left drag or middle drag", "pan"),
         ("right drag or wheel", "zoom"))


def window_plotter(**plotter_options) -> pv.Plotter:
    """An off-screen pyvista plotter for a `PlotterWidget`, without multisampling (software OpenGL pays
    3-4x for it) and without copying each frame to a display buffer: the widget reads the frame from the
    buffer VTK draws into (a copy of the whole frame saved, some 8% of the frames/s while playing)."""
    plotter = pv.Plotter(off_screen=True, **plotter_options)
    plotter.render_window.SetMultiSamples(0)
    plotter.render_window.SetSwapBuffers(False)
    return plotter


class TopRowFirst:
    """Frames read back top row first by the OpenGL driver itself where it can (Mesa's GL_MESA_pack_invert:
    llvmpipe under Xvfb, Linux's Mesa drivers), through GLVND's OpenGL library; elsewhere the widget flips
    each frame in numpy (a copy of the whole frame: the driver's way gives some 7% more frames/s playing)."""

    def __init__(self):
        name = ctypes.util.find_library("OpenGL")
        self._gl = ctypes.CDLL(name) if name else None
        self.supported: bool | None = None if self._gl is not None else False  # None: not tried yet

    def begin(self) -> bool:
        """Ask the current context for top-row-first reads; False (and nothing changed) where it cannot."""
        if self.supported is False:
            return False
        if self.supported is None:
            while self._gl.glGetError():  # errors left by others: the one asked about below must be ours
                pass
        self._gl.glPixelStorei(GL_PACK_INVERT_MESA, 1)
        if self.supported is None:
            self.supported = self._gl.glGetError() == 0  # GL_INVALID_ENUM: a driver without the extension
        return self.supported

    def end(self) -> None:
        """Reads in OpenGL's order again (VTK's own reads, screenshots, expect it)."""
        self._gl.glPixelStorei(GL_PACK_INVERT_MESA, 0)


TOP_ROW_FIRST = TopRowFirst()


class PlotterWidget(QWidget):
    """``plotter``'s off-screen render window shown in a widget, the camera turned by the mouse (trackball:
    left drag rotates, Shift+left or middle drag pans, right drag or the wheel zooms)."""

    def __init__(self, plotter: pv.Plotter, parent: QWidget | None = None):
        super().__init__(parent)
        self.plotter = plotter
        self.alive = True
        self._window = plotter.render_window
        self._interactor = vtkGenericRenderWindowInteractor()
        self._interactor.SetRenderWindow(self._window)
        self._interactor.SetInteractorStyle(vtkInteractorStyleTrackballCamera())
        self._interactor.EnableRenderOff()  # the camera style's renders become requests for a paint
        self._interactor.AddObserver("RenderEvent", lambda *_: self.update())
        self._pixels = vtkUnsignedCharArray()
        self._image: QImage | None = None
        self._stale = True  # the scene changed since the last render
        self._button = Qt.MouseButton.NoButton
        self._wheel = 0
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)  # the image covers the widget: no background
        self.setMouseTracking(True)
        self.setFocusPolicy(Qt.FocusPolicy.WheelFocus)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)

    def Initialize(self) -> None:
        """Start the interactor (the render window gets its context on the first render)."""
        self._interactor.Initialize()

    def GetRenderWindow(self):
        return self._window

    def update(self, *area) -> None:
        """Ask for a new frame, drawn in the next paint (several requests before it make one render)."""
        self._stale = True
        super().update(*area)

    def render(self) -> None:
        """Draw now (what picking and a drag's live feedback read), shown in the next paint."""
        if self.alive:
            self._render()
            super().update()

    def _size(self) -> tuple[int, int]:
        scale = self.devicePixelRatioF()
        return max(1, round(self.width() * scale)), max(1, round(self.height() * scale))

    def _render(self) -> None:
        """Render off screen and read the frame back into ``_image`` (top row first)."""
        width, height = self._size()
        if tuple(self._window.GetSize()) != (width, height):
            self._window.SetSize(width, height)
            self._interactor.SetSize(width, height)
        with TEXT_LOCK:  # not while a video export's thread lays out its labels (`render.text_lock`)
            self._window.Render()
        self._rows = self._read_rows(width, height)
        self._image = QImage(self._rows.data, width, height, 4 * width, QImage.Format.Format_RGBX8888)
        self._image.setDevicePixelRatio(self.devicePixelRatioF())
        self._stale = False

    def _read_rows(self, width: int, height: int) -> np.ndarray:
        """The frame just drawn as (height, width, 4) RGBA, top row first (OpenGL's rows run bottom up)."""
        if self._pixels.GetNumberOfValues() != 4 * width * height:
            self._pixels = vtkUnsignedCharArray()  # a new array: the last image keeps the old one it shows
            self._pixels.SetNumberOfComponents(4)
            self._pixels.SetNumberOfTuples(width * height)
        top_row_first = TOP_ROW_FIRST.begin()
        try:
            self._window.GetRGBACharPixelData(0, 0, width - 1, height - 1, 0, self._pixels)
        finally:
            if top_row_first:
                TOP_ROW_FIRST.end()
        rows = vtk_to_numpy(self._pixels).reshape(height, width, 4)
        return rows if top_row_first else np.ascontiguousarray(rows[::-1])

    def paintEvent(self, event) -> None:
        if not self.alive:  # a paint queued before ``close_plotter`` would render into a freed window
            return
        if self._stale or self._image is None or (self._image.width(), self._image.height()) != self._size():
            self._render()
        QPainter(self).drawImage(0, 0, self._image)

    def resizeEvent(self, event) -> None:
        if self.alive:
            width, height = self._size()
            self._window.SetSize(width, height)
            self._interactor.SetSize(width, height)
            self._interactor.ConfigureEvent()
            self.update()

    # --- the mouse, as VTK's interactor hears it (display pixels, y up) ---
    def _tell(self, position: QPointF, modifiers, repeat: int = 0) -> None:
        scale = self.devicePixelRatioF()
        self._interactor.SetEventInformation(round(position.x() * scale), round((self.height() - position.y() - 1) * scale),
                                             int(bool(modifiers & Qt.KeyboardModifier.ControlModifier)),
                                             int(bool(modifiers & Qt.KeyboardModifier.ShiftModifier)), "\0", repeat)

    def mousePressEvent(self, event: QMouseEvent) -> None:
        self._tell(event.position(), event.modifiers(), int(event.type() == QEvent.Type.MouseButtonDblClick))
        self._button = event.button()
        press = {Qt.MouseButton.LeftButton: self._interactor.LeftButtonPressEvent,
                 Qt.MouseButton.RightButton: self._interactor.RightButtonPressEvent,
                 Qt.MouseButton.MiddleButton: self._interactor.MiddleButtonPressEvent}.get(self._button)
        if press is not None:
            press()

    mouseDoubleClickEvent = mousePressEvent

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        self._tell(event.position(), event.modifiers())
        release = {Qt.MouseButton.LeftButton: self._interactor.LeftButtonReleaseEvent,
                   Qt.MouseButton.RightButton: self._interactor.RightButtonReleaseEvent,
                   Qt.MouseButton.MiddleButton: self._interactor.MiddleButtonReleaseEvent}.get(self._button)
        self._button = Qt.MouseButton.NoButton
        if release is not None:
            release()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        self._tell(event.position(), event.modifiers())
        self._interactor.MouseMoveEvent()

    def wheelEvent(self, event: QWheelEvent) -> None:
        self._wheel += event.angleDelta().y()
        self._tell(event.position(), event.modifiers())
        if self._wheel >= WHEEL_STEP:
            self._interactor.MouseWheelForwardEvent()
            self._wheel = 0
        elif self._wheel <= -WHEEL_STEP:
            self._interactor.MouseWheelBackwardEvent()
            self._wheel = 0

    def enterEvent(self, event) -> None:
        self._interactor.EnterEvent()

    def leaveEvent(self, event) -> None:
        self._interactor.LeaveEvent()

    def close_plotter(self) -> None:
        """Free the render window; the widget draws nothing after this."""
        if self.alive:
            self.alive = False
            self._image = None
            self._interactor.SetRenderWindow(None)
            self.plotter.close()
