"""A pyvista plotter rendered off screen and shown as an image in a plain Qt widget, the 3D widget of both
modes; the mouse turns the camera through VTK's interactor as in VTK's own Qt widget.

Why not a window on screen: under software OpenGL (llvmpipe on X) a VTK window pays for presenting each
frame (glX swap: ~7 ms a frame at 900 x 700) on top of the off-screen drawing; and pyvistaqt's
``QOpenGLWidget`` makes Qt compose the whole window through OpenGL on every repaint. Off screen, VTK
draws into its framebuffer (the path `s2h render` and the off-screen benchmark take), the widget reads
it back once (one copy) and Qt paints it with the rest of the window
(`benchmarks/bench_window_playback.py` compares the two). ``update()`` asks for a frame; a paint with
nothing new (a dialog moved over the view) shows the last frame again without rendering.

``threaded``: frames are drawn in a render thread that owns the OpenGL context (VTK releases the GIL while
it draws), so Qt paints the rest of the window, and the next frame is skinned, while VTK draws this one.
Then the scene may change only when no frame is being drawn: `wait` first (`CompareView` does), and
anything that needs OpenGL runs through `call`. Unthreaded, a paint renders in the GUI thread."""

from __future__ import annotations

import sys
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import TypeVar

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, QPointF, Qt, QTimer, Signal
from PySide6.QtGui import QImage, QMouseEvent, QPainter, QWheelEvent
from PySide6.QtWidgets import QSizePolicy, QWidget
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
from vtkmodules.vtkInteractionStyle import vtkInteractorStyleTrackballCamera
from vtkmodules.vtkRenderingUI import vtkGenericRenderWindowInteractor

GIL_SWITCH_INTERVAL = 0.0005  # seconds the render thread waits at most for the GIL between its VTK calls
WHEEL_STEP = 120  # Qt's angle delta of one wheel notch: one VTK zoom step
T = TypeVar("T")


def window_plotter(**plotter_options) -> pv.Plotter:
    """An off-screen pyvista plotter for a `PlotterWidget`, without multisampling (software OpenGL pays
    3-4x for it)."""
    plotter = pv.Plotter(off_screen=True, **plotter_options)
    plotter.render_window.SetMultiSamples(0)
    return plotter


class PlotterWidget(QWidget):
    """``plotter``'s off-screen render window shown in a widget, the camera turned by the mouse (trackball:
    left drag rotates, Shift+left or middle drag pans, right drag or the wheel zooms)."""

    rendered = Signal()  # a new frame is ready to paint (emitted in the GUI thread)
    render_started = Signal()  # the render thread started a frame: the scene must not change until `wait`
    _job_done = Signal()  # emitted in the render thread: its frame is ready to take

    def __init__(self, plotter: pv.Plotter, parent: QWidget | None = None, threaded: bool = False):
        super().__init__(parent)
        self.plotter = plotter
        self.alive = True
        #: called in the GUI thread before each render (the render thread runs no Python callbacks)
        self.before_render: Callable[[], None] = lambda: None
        self._window = plotter.render_window
        self._interactor = vtkGenericRenderWindowInteractor()
        self._interactor.SetRenderWindow(self._window)
        self._interactor.SetInteractorStyle(vtkInteractorStyleTrackballCamera())
        self._interactor.EnableRenderOff()  # the camera style's renders become requests for a paint
        self._interactor.AddObserver("RenderEvent", lambda *_: self.update())
        self._thread = ThreadPoolExecutor(1, thread_name_prefix="render") if threaded else None
        if threaded:
            sys.setswitchinterval(min(sys.getswitchinterval(), GIL_SWITCH_INTERVAL))
        self._job: Future | None = None  # the frame the render thread is drawing
        self._start_queued = False
        self._job_done.connect(self._take_frame)
        self._pixels = vtkUnsignedCharArray()
        self._rows: np.ndarray | None = None  # the last frame's pixels, which ``_image`` shows
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
        """Ask for a new frame (several requests before it is drawn make one render). Threaded, it starts
        once control is back in the event loop, not in the next paint."""
        self._stale = True
        if self._thread is not None and not self._start_queued:
            self._start_queued = True
            QTimer.singleShot(0, self, self._start_queued_frame)
        super().update(*area)

    def draw_now(self) -> None:
        """Ask for a new frame and, threaded, start drawing it now (the caller changes the scene no more)."""
        self._stale = True
        if self._thread is not None and self._job is None and self._image is not None and self.alive:
            self._start_frame()
        super().update()

    def render(self) -> None:
        """Draw now (what picking and a drag's live feedback read), shown in the next paint."""
        if self.alive:
            self._show_rows(self.grab_frame())
            super().update()

    def grab_frame(self) -> np.ndarray:
        """Render the scene as it is now at the widget's size: (H, W, 4) RGBA rows, top first."""
        self.wait()
        return self._run(self._render, self._size())

    def wait(self) -> None:
        """Let the frame being drawn in the render thread finish (the scene may change after this)."""
        if self._job is not None:
            self._job.result()
            self._take_frame()

    def call(self, function: Callable[[], T]) -> T:
        """``function()`` where the OpenGL context lives (the render thread, if any), no frame being drawn."""
        self.wait()
        return self._run(function)

    def _run(self, function, *args):
        return function(*args) if self._thread is None else self._thread.submit(function, *args).result()

    def _start_queued_frame(self) -> None:
        self._start_queued = False
        if self.alive and self._stale and self._job is None and self._image is not None:
            self._start_frame()

    def _start_frame(self) -> None:
        """Draw a frame in the render thread; its image is taken when done (``_take_frame``)."""
        self.before_render()
        self._stale = False
        self._job = self._thread.submit(self._render, self._size())
        self._job.add_done_callback(lambda _: self._job_done.emit())
        self.render_started.emit()

    def _take_frame(self) -> None:
        """The render thread's frame (if not taken yet) becomes the image painted next."""
        job, self._job = self._job, None
        if job is not None:
            self._show_rows(job.result())
            super().update()

    def _size(self) -> tuple[int, int]:
        scale = self.devicePixelRatioF()
        return max(1, round(self.width() * scale)), max(1, round(self.height() * scale))

    def _render(self, size: tuple[int, int]) -> np.ndarray:
        """Render off screen at ``size`` and read the frame back: (H, W, 4), top row first."""
        width, height = size
        if tuple(self._window.GetSize()) != size:  # resizes the framebuffer: OpenGL, so here
            self._window.SetSize(width, height)
        self._window.Render()
        self._window.GetRGBACharPixelData(0, 0, width - 1, height - 1, 0, self._pixels)
        return np.ascontiguousarray(vtk_to_numpy(self._pixels).reshape(height, width, 4)[::-1])  # GL: bottom up

    def _show_rows(self, rows: np.ndarray) -> None:
        """``rows`` (from `_render`) become the image painted; ``rendered`` tells who counts frames."""
        self._rows = rows  # the image is a view of it
        self._image = QImage(rows.data, rows.shape[1], rows.shape[0], 4 * rows.shape[1],
                             QImage.Format.Format_RGBX8888)
        self._image.setDevicePixelRatio(self.devicePixelRatioF())
        self.rendered.emit()

    def paintEvent(self, event) -> None:
        if not self.alive:  # a paint queued before ``close_plotter`` would render into a freed window
            return
        sized = self._image is not None and (self._image.width(), self._image.height()) == self._size()
        if (self._stale or not sized) and self._job is None:
            if self._thread is not None:  # drawn in the render thread; the last frame shown meanwhile
                self._start_frame()
            else:
                self.before_render()
                self._stale = False
                self._show_rows(self._render(self._size()))
        painter = QPainter(self)
        if self._image is not None:
            painter.drawImage(0, 0, self._image)
        else:  # the first frame is still being drawn
            painter.fillRect(self.rect(), Qt.GlobalColor.white)

    def resizeEvent(self, event) -> None:
        if self.alive:
            self.wait()
            width, height = self._size()
            self._interactor.SetSize(width, height)  # the render window follows in the next render
            self._interactor.ConfigureEvent()
            self.update()

    # --- the mouse, as VTK's interactor hears it (display pixels, y up) ---
    def _tell(self, position: QPointF, modifiers, repeat: int = 0) -> None:
        scale = self.devicePixelRatioF()
        self._interactor.SetEventInformation(round(position.x() * scale), round((self.height() - position.y() - 1) * scale),
                                             int(bool(modifiers & Qt.KeyboardModifier.ControlModifier)),
                                             int(bool(modifiers & Qt.KeyboardModifier.ShiftModifier)), "\0", repeat)

    def mousePressEvent(self, event: QMouseEvent) -> None:
        self.wait()
        self._tell(event.position(), event.modifiers(), int(event.type() == QEvent.Type.MouseButtonDblClick))
        self._button = event.button()
        press = {Qt.MouseButton.LeftButton: self._interactor.LeftButtonPressEvent,
                 Qt.MouseButton.RightButton: self._interactor.RightButtonPressEvent,
                 Qt.MouseButton.MiddleButton: self._interactor.MiddleButtonPressEvent}.get(self._button)
        if press is not None:
            press()

    mouseDoubleClickEvent = mousePressEvent

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        self.wait()
        self._tell(event.position(), event.modifiers())
        release = {Qt.MouseButton.LeftButton: self._interactor.LeftButtonReleaseEvent,
                   Qt.MouseButton.RightButton: self._interactor.RightButtonReleaseEvent,
                   Qt.MouseButton.MiddleButton: self._interactor.MiddleButtonReleaseEvent}.get(self._button)
        self._button = Qt.MouseButton.NoButton
        if release is not None:
            release()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        self.wait()
        self._tell(event.position(), event.modifiers())
        self._interactor.MouseMoveEvent()

    def wheelEvent(self, event: QWheelEvent) -> None:
        self.wait()
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
            self.wait()
            self.alive = False
            self._image = None
            self._interactor.SetRenderWindow(None)
            self._run(self.plotter.close)  # frees OpenGL resources: in the context's thread
            if self._thread is not None:
                self._thread.shutdown()
