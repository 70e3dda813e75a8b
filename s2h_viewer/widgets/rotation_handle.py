"""A rotation handle in a 3D view, as in a DCC tool: a ring about one joint's twist axis with a knob on
its bend axis. The left mouse grabs the ring (it lights up under the pointer) and turns it; the point
under the pointer stays on the ring while the plane faces the camera, and an edge-on ring turns with
the pointer's angle about its centre on screen. A left click that grabs nothing and does not move is
reported as a click (the view picks a joint with it); any other press goes on to the camera."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pyvista as pv
from vtkmodules.vtkRenderingCore import vtkCellPicker

from s2h_viewer.annotate.editing import ray_plane_point, ring_polyline, signed_angle_about, unwrap_degrees

RING_COLOUR = "#e8a317"
ACTIVE_COLOUR = "#ffe34d"
#: a press and release this many pixels apart or fewer are a click, not a camera drag
CLICK_PIXELS = 4
#: observers run before the interactor style's (priority 0), so a grab of the ring never moves the camera
PRIORITY = 10.0


class RotationRing:
    """The ring in ``plotter``: ``on_begin()``, ``on_turn(degrees since the grab)``, ``on_end()`` for a drag,
    ``on_click(x, y)`` (VTK display pixels) for a click that missed the ring."""

    def __init__(self, plotter, on_begin: Callable[[], None], on_turn: Callable[[float], None],
                 on_end: Callable[[], None], on_click: Callable[[int, int], None]):
        self.plotter = plotter
        self.on_begin, self.on_turn, self.on_end, self.on_click = on_begin, on_turn, on_end, on_click
        self.mesh = pv.PolyData()
        self.actor = None
        self.centre = np.zeros(3)
        self.axis = np.array([1.0, 0.0, 0.0])
        self.dragging = False
        self._hovered = False
        self._press: tuple[int, int] | None = None
        self._start: np.ndarray | None = None  # grab point: on the ring's plane (3,) or on screen (2,)
        self._last = 0.0
        self._total = 0.0
        self._picker = vtkCellPicker()
        self._picker.PickFromListOn()
        self._picker.SetTolerance(0.004)
        interactor = plotter.iren.interactor
        for event, handler in (("LeftButtonPressEvent", self._pressed), ("MouseMoveEvent", self._moved),
                               ("LeftButtonReleaseEvent", self._released)):
            self._observe(interactor, event, handler)

    @staticmethod
    def _observe(interactor, event: str, handler: Callable[[int, int], bool]) -> None:
        """Run ``handler(x, y)`` before the camera does; when it returns True the camera never sees the event."""
        tags: list[int] = []

        def callback(obj, _event) -> None:
            if handler(*obj.GetEventPosition()):
                obj.GetCommand(tags[0]).SetAbortFlag(1)

        tags.append(interactor.AddObserver(event, callback, PRIORITY))

    def attach(self) -> None:
        """Add the ring's actor to the plotter (again after ``plotter.clear()``)."""
        self.actor = self.plotter.add_mesh(self.mesh, color=RING_COLOUR, name="rotation_ring", reset_camera=False,
                                           smooth_shading=True)
        self._picker.InitializePickList()
        self._picker.AddPickList(self.actor)
        self._hovered = False

    def place(self, centre: np.ndarray, frame: np.ndarray, radius: float) -> None:
        """Put the ring about ``frame``'s twist axis (column 0) at ``centre``, the knob on its bend axis."""
        self.centre, self.axis = np.asarray(centre, float), np.asarray(frame[:, 0], float)
        points = ring_polyline(self.centre, frame, radius)
        ring = pv.lines_from_points(np.vstack([points, points[:1]])).tube(radius=0.06 * radius, n_sides=12)
        knob = pv.Sphere(radius=0.16 * radius, center=self.centre + radius * frame[:, 1])
        self.mesh.copy_from((ring + knob).extract_surface(algorithm=None))

    # --- geometry of the pointer ---
    def _ray(self, x: int, y: int) -> tuple[np.ndarray, np.ndarray]:
        """The ray under display pixel (x, y): its origin on the near plane and its direction."""
        renderer = self.plotter.renderer
        ends = []
        for depth in (0.0, 1.0):
            renderer.SetDisplayPoint(x, y, depth)
            renderer.DisplayToWorld()
            world = np.array(renderer.GetWorldPoint())
            ends.append(world[:3] / world[3])
        return ends[0], ends[1] - ends[0]

    def _screen_centre(self) -> np.ndarray:
        renderer = self.plotter.renderer
        renderer.SetWorldPoint(*self.centre, 1.0)
        renderer.WorldToDisplay()
        return np.array(renderer.GetDisplayPoint()[:2])

    def _grab_point(self, x: int, y: int, on_screen: bool) -> np.ndarray | None:
        """The pointer as a vector from the ring's centre: on its plane, or on screen for an edge-on ring."""
        if on_screen:
            return np.array([x, y], float) - self._screen_centre()
        point = ray_plane_point(*self._ray(x, y), self.centre, self.axis)
        return None if point is None else point - self.centre

    def _angle(self, x: int, y: int) -> float | None:
        """Degrees about the twist axis from the grab to the pointer (None where the pointer gives none)."""
        on_screen = self._start.shape == (2,)
        current = self._grab_point(x, y, on_screen)
        if current is None:
            return None
        if not on_screen:
            return signed_angle_about(self.axis, self._start, current)
        screen = float(np.degrees(np.arctan2(np.cross(self._start, current), np.dot(self._start, current))))
        towards_viewer = -np.array(self.plotter.camera.GetDirectionOfProjection())
        return screen if np.dot(self.axis, towards_viewer) >= 0 else -screen

    def _over_ring(self, x: int, y: int) -> bool:
        return self.actor is not None and self.actor.GetVisibility() and \
            bool(self._picker.Pick(x, y, 0.0, self.plotter.renderer)) and self._picker.GetActor() is self.actor

    def _highlight(self, on: bool) -> None:
        if on != self._hovered and self.actor is not None:
            self._hovered = on
            self.actor.prop.color = ACTIVE_COLOUR if on else RING_COLOUR
            self.plotter.render()

    # --- mouse events (VTK display pixels); True swallows the event ---
    def _pressed(self, x: int, y: int) -> bool:
        self._press = (x, y)
        if not self._over_ring(x, y):
            return False
        start = self._grab_point(x, y, on_screen=False)
        self._start = start if start is not None else self._grab_point(x, y, on_screen=True)
        self.dragging, self._last, self._total = True, 0.0, 0.0
        self._highlight(True)
        self.on_begin()
        return True

    def _moved(self, x: int, y: int) -> bool:
        if not self.dragging:
            if self._press is None:
                self._highlight(self._over_ring(x, y))
            return False
        angle = self._angle(x, y)
        if angle is not None:
            self._total = unwrap_degrees(self._total, self._last, angle)
            self._last = angle
            self.on_turn(self._total)
        return True

    def _released(self, x: int, y: int) -> bool:
        press, self._press = self._press, None
        if self.dragging:
            self.dragging = False
            self._highlight(self._over_ring(x, y))
            self.on_end()
            return True
        if press is not None and max(abs(x - press[0]), abs(y - press[1])) <= CLICK_PIXELS:
            self.on_click(x, y)
        return False
