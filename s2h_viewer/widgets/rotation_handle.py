"""A rotation handle in a 3D view, as in a DCC tool: a ring about one joint's twist axis. The left
mouse grabs the ring (it lights up under the pointer) and turns it; the point under the pointer
stays on the ring while the plane faces the camera, and the grabbed point of a ring seen edge-on
follows the pointer along its path on screen, like a wheel seen from the side. A left click that
grabs nothing and does not move is reported as a click (the view picks a joint with it); any other
press goes on to the camera.

The mouse is read from the 3D widget's Qt events, ahead of VTK: once VTK's camera style takes a press it
holds the mouse until the release, so VTK observers never hear how a click ended."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, QObject, Qt
from vtkmodules.vtkRenderingCore import vtkCellPicker

from s2h_viewer.annotate.editing import ray_plane_point, ring_polyline, signed_angle_about, unwrap_degrees
from s2h_viewer.geometry import distance_to_segments

RING_COLOUR = "#e8a317"
ACTIVE_COLOUR = "#ffe34d"
#: a press and release this many pixels apart or fewer are a click, not a camera drag
CLICK_PIXELS = 4
#: the ring follows the pointer on its plane while the view ray meets the plane at this cosine or more
#: (about 70 deg off face-on); nearer edge-on it rolls under the pointer instead
FACING = 0.35
PRESSES = (QEvent.Type.MouseButtonPress, QEvent.Type.MouseButtonDblClick)
#: a click this many pixels from a joint on screen, or nearer, picks it (`nearest_on_screen`)
PICK_PIXELS = 24
#: with Shift held, a drag turns the ring this share of the pointer's turn (for fine corrections)
FINE_SHARE = 0.1
#: an edge-on ring rolls at least this share of its on-screen radius per radian of turn (`_roll_pixels`)
ROLL_LEAST = 0.5
#: how near the pointer must be to the ring to grab it (VTK's pick tolerance: a share of the window's diagonal)
PICK_TOLERANCE = 0.008


def is_click(pressed: tuple[int, int], released: tuple[int, int]) -> bool:
    """A press at ``pressed`` released at ``released`` (pixels) is a click, not a drag (`CLICK_PIXELS`)."""
    return max(abs(released[0] - pressed[0]), abs(released[1] - pressed[1])) <= CLICK_PIXELS


def on_display(renderer, points: np.ndarray) -> np.ndarray:
    """(N, 2) display pixels where ``renderer`` draws the (N, 3) view-space ``points``."""
    on_screen = []
    for point in points:
        renderer.SetWorldPoint(*point, 1.0)
        renderer.WorldToDisplay()
        on_screen.append(renderer.GetDisplayPoint()[:2])
    return np.asarray(on_screen, dtype=np.float64).reshape(-1, 2)


def nearest_on_screen(renderer, points: np.ndarray, x: int, y: int, within: float = PICK_PIXELS) -> int | None:
    """The index of the view-space point of ``points`` drawn nearest to display pixel (x, y) in ``renderer``, if it
    is ``within`` pixels; else None (what a click on a joint picks, in Annotate and in a retarget being fixed)."""
    distance = np.linalg.norm(on_display(renderer, points) - (x, y), axis=1)
    return int(distance.argmin()) if distance.min() <= within else None


def nearest_segment_on_screen(renderer, starts: np.ndarray, ends: np.ndarray, x: int, y: int,
                              within: float = PICK_PIXELS) -> int | None:
    """The index of the view-space segment ``starts[i]`` - ``ends[i]`` drawn nearest to display pixel (x, y), if it
    is ``within`` pixels; else None (a click on a finger's bone, between its joints)."""
    pixel = np.array([x, y], dtype=float)
    distance = distance_to_segments(pixel, on_display(renderer, starts), on_display(renderer, ends))
    return int(distance.argmin()) if distance.min() <= within else None


@dataclass
class Grab:
    """Where a drag of the ring began: the pixel, the pointer on the ring's plane (None: edge-on), and for
    an edge-on ring the pixels it rolls per radian."""

    pixel: np.ndarray
    plane: np.ndarray | None
    roll: np.ndarray | None


class RotationRing(QObject):
    """The ring in ``widget``'s plotter (a `widgets.vtk_widget.PlotterWidget`), in ``renderer`` (default: the
    plotter's current one; a cell of a grid): ``on_begin()``, ``on_turn(degrees since the grab)``, ``on_end()``
    for a drag, ``on_click(x, y)`` (VTK display pixels) for a click that missed the ring, ``on_ring_click(x, y)``
    (if given) for one on the ring that turned nothing (the ring lies over the bones beside its joint)."""

    def __init__(self, widget, on_begin: Callable[[], None], on_turn: Callable[[float], None],
                 on_end: Callable[[], None], on_click: Callable[[int, int], None], renderer=None,
                 on_ring_click: Callable[[int, int], None] | None = None):
        super().__init__(widget)
        self.widget, self.plotter = widget, widget.plotter
        self.renderer = renderer if renderer is not None else widget.plotter.renderer
        self.on_begin, self.on_turn, self.on_end, self.on_click = on_begin, on_turn, on_end, on_click
        self.on_ring_click = on_ring_click
        self.mesh = pv.PolyData()
        self.actor = None
        self.centre = np.zeros(3)
        self.axis = np.array([1.0, 0.0, 0.0])
        self.radius = 1.0
        self.dragging = False
        self._hovered = False
        self._press: tuple[int, int] | None = None
        self._fine = False  # Shift held on the last move
        self._grab: Grab | None = None
        self._last = 0.0
        self._total = 0.0
        self._picker = vtkCellPicker()
        self._picker.PickFromListOn()
        self._picker.SetTolerance(PICK_TOLERANCE)
        widget.installEventFilter(self)

    def eventFilter(self, watched, event) -> bool:
        """The 3D widget's left-button presses, releases and all moves; True keeps one from the camera."""
        kind = event.type()
        if kind == QEvent.Type.MouseMove:
            self._fine = bool(event.modifiers() & Qt.KeyboardModifier.ShiftModifier)
            handler = self._moved
        elif kind in PRESSES and event.button() == Qt.MouseButton.LeftButton:
            handler = self._pressed
        elif kind == QEvent.Type.MouseButtonRelease and event.button() == Qt.MouseButton.LeftButton:
            handler = self._released
        else:
            return False
        scale = self.widget.devicePixelRatioF()  # VTK's display pixels: device pixels, y up
        position = event.position()
        return handler(round(position.x() * scale), round((self.widget.height() - position.y() - 1) * scale))

    def attach(self) -> None:
        """Add the ring's actor to its renderer (again after ``plotter.clear()``)."""
        self.actor = pv.Actor(mapper=pv.DataSetMapper(self.mesh))  # the tube's own normals: smooth shading
        self.actor.prop.color = RING_COLOUR
        self.renderer.add_actor(self.actor, name="rotation_ring", reset_camera=False, render=False)
        self._picker.InitializePickList()
        self._picker.AddPickList(self.actor)
        self._hovered = False

    def set_visible(self, visible: bool) -> None:
        """Shown and grabbable, or neither."""
        if self.actor is not None:
            self.actor.visibility = visible

    def place(self, centre: np.ndarray, frame: np.ndarray, radius: float) -> None:
        """Put the ring about ``frame``'s twist axis (column 0) at ``centre``."""
        self.centre, self.axis, self.radius = np.asarray(centre, float), np.asarray(frame[:, 0], float), radius
        points = ring_polyline(self.centre, frame, radius)
        self.mesh.copy_from(pv.lines_from_points(np.vstack([points, points[:1]])).tube(radius=0.07 * radius,
                                                                                        n_sides=12))

    # --- geometry of the pointer ---
    def _ray(self, x: int, y: int) -> tuple[np.ndarray, np.ndarray]:
        """The ray under display pixel (x, y): its origin on the near plane and its direction."""
        renderer = self.renderer
        ends = []
        for depth in (0.0, 1.0):
            renderer.SetDisplayPoint(x, y, depth)
            renderer.DisplayToWorld()
            world = np.array(renderer.GetWorldPoint())
            ends.append(world[:3] / world[3])
        return ends[0], ends[1] - ends[0]

    def _to_display(self, point: np.ndarray) -> np.ndarray:
        renderer = self.renderer
        renderer.SetWorldPoint(*point, 1.0)
        renderer.WorldToDisplay()
        return np.array(renderer.GetDisplayPoint()[:2])

    def _plane_vector(self, x: int, y: int) -> np.ndarray | None:
        """The pointer on the ring's plane, from its centre (None where the ray runs nearly along the plane)."""
        point = ray_plane_point(*self._ray(x, y), self.centre, self.axis, min_cosine=FACING)
        return None if point is None else point - self.centre

    def _roll_pixels(self, grabbed: np.ndarray) -> np.ndarray:
        """On screen, the way and the pixels per radian that the grabbed point of the ring moves as the ring
        turns: an edge-on ring rolls under the pointer like a wheel seen from the side. At least half the ring's
        radius on screen per radian: grabbed near where the ring turns away from the camera, its point hardly
        moves on screen, and a few pixels of drag would turn it a half turn."""
        radial = grabbed - self.centre - np.dot(grabbed - self.centre, self.axis) * self.axis
        velocity = self.radius * np.cross(self.axis, radial / np.linalg.norm(radial))
        roll = self._to_display(self.centre + radial + velocity) - self._to_display(self.centre + radial)
        least = ROLL_LEAST * float(np.linalg.norm(self._to_display(self.centre + radial) -
                                                  self._to_display(self.centre)))
        if np.linalg.norm(roll) < least:
            way = roll if np.linalg.norm(roll) > 1e-9 else np.array([1.0, 0.0])
            roll = way / np.linalg.norm(way) * least
        return roll

    def _angle(self, x: int, y: int) -> float | None:
        """Degrees about the twist axis from the grab to the pointer (None where the pointer gives none)."""
        grab = self._grab
        if grab.plane is None:
            moved = np.array([x, y], float) - grab.pixel
            return float(np.degrees(np.dot(moved, grab.roll) / np.dot(grab.roll, grab.roll)))
        current = self._plane_vector(x, y)
        return None if current is None else signed_angle_about(self.axis, grab.plane, current)

    def _over_ring(self, x: int, y: int) -> bool:
        return self.actor is not None and self.actor.GetVisibility() and \
            bool(self._picker.Pick(x, y, 0.0, self.renderer)) and self._picker.GetActor() is self.actor

    def _highlight(self, on: bool) -> None:
        if on != self._hovered and self.actor is not None:
            self._hovered = on
            self.actor.prop.color = ACTIVE_COLOUR if on else RING_COLOUR
            self.widget.render()

    # --- mouse events (VTK display pixels); True swallows the event ---
    def _pressed(self, x: int, y: int) -> bool:
        self._press = (x, y)
        if not self._over_ring(x, y):
            return False
        plane = self._plane_vector(x, y)
        roll = self._roll_pixels(np.array(self._picker.GetPickPosition())) if plane is None else None
        self._grab = Grab(np.array([x, y], float), plane, roll)
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
            step = unwrap_degrees(0.0, self._last, angle)
            self._total += FINE_SHARE * step if self._fine else step  # Shift held: a tenth of the pointer's turn
            self._last = angle
            self.on_turn(self._total)
        return True

    def _released(self, x: int, y: int) -> bool:
        press, self._press = self._press, None
        if self.dragging:
            self.dragging = False
            self._highlight(self._over_ring(x, y))
            self.on_end()
            if self.on_ring_click is not None and press is not None and is_click(press, (x, y)):
                self.on_ring_click(x, y)
            return True
        if press is not None and is_click(press, (x, y)):
            self.on_click(x, y)
        return False
