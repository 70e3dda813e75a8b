"""Annotation mode's view: one hand at rest, see-through, each joint's TBS frame as three arrows
(twist red, bend green, splay blue), a joint list with the solver's confidence, and two handles that
turn the selected joint's frame about its twist axis while they are dragged: a ring about the joint in
the 3D view and a dial beside it. The dial and its readout show how far the selected frame is turned from
the frame it had when the hand was opened, whichever handle turned it (and after an undo or a redo).
Until a hand is opened the view is a hint saying how to open one (`set_hint`), not a blank 3D view."""

from __future__ import annotations

import numpy as np
import pyvista as pv
from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import QDial, QLabel, QListWidget, QSplitter, QStackedLayout, QVBoxLayout, QWidget

from s2h_viewer.annotate.editing import AnnotationSession, rotate_about_twist, signed_angle_about
from s2h_viewer.hand import topology as topo
from s2h_viewer.render.scene import (AXIS_COLOURS, BONE_COLOUR, SKIN_COLOUR, display_hand, pose_frame, skeleton,
                                     surface, to_view)
from s2h_viewer.widgets.rotation_handle import RotationRing, nearest_on_screen
from s2h_viewer.widgets.vtk_widget import PlotterWidget, window_plotter

LEGEND = ("TBS frames: twist (along the bone) red, bend green, splay (out of the back) blue. Drag the "
          "selected joint's ring (or the dial) to turn its frame about the twist axis.")
#: the mouse in the annotation view beyond the camera (`vtk_widget.MOUSE`), for Help's list
MOUSE = (("click a joint (in 3D or the list)", "select it and show its ring about its twist axis"),
         ("drag the ring (it lights up under the pointer) or the dial",
          "turn the selected joint's frame about its twist axis"),
         ("Shift+drag the ring", "turn it a tenth as far as the pointer goes (fine turns)"))
#: the ring's radius and the arrows' length as shares of the hand's length
RING_RADIUS = 0.09
ARROW_LENGTH = 0.12


def _arrows(session: AnnotationSession, axis: int, selected: int) -> pv.PolyData:
    hand = session.hand
    origins = to_view(hand, hand.rest_positions[topo.ARTICULATED_JOINTS])
    cloud = pv.PolyData(origins)
    cloud["vectors"] = to_view(hand, session.frames[:, :, axis])
    cloud["size"] = np.where(np.arange(topo.N_ARTICULATED) == selected, 1.6, 1.0)
    return cloud.glyph(orient="vectors", scale="size", factor=ARROW_LENGTH * hand.hand_length,
                       geom=pv.Arrow(shaft_radius=0.05, tip_radius=0.12))


class AnnotationView(QWidget):
    """Emits ``frame_edited(joint, frame_before, frame_after)`` when a drag of a handle ends."""

    frame_edited = Signal(int, object, object)

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.session: AnnotationSession | None = None
        self.selected = 0
        self._drag_base: np.ndarray | None = None
        self._dial_at_grab = 0
        self._sense_at_grab = 1  # the dial's sense on screen when it was grabbed (see `screen_sense`)
        self._opened: np.ndarray | None = None  # (15, 3, 3) the frames the hand was opened with
        self.plotter = window_plotter()
        self.interactor = PlotterWidget(self.plotter, self)
        self.ring = RotationRing(self.interactor, self._begin_drag, self._turn_to, self._end_drag, self._clicked)
        self.joints = QListWidget()
        self.dial = QDial()
        self.dial.setRange(-180, 180)
        self.dial.setWrapping(True)
        self.dial.setNotchesVisible(True)
        self.angle_label = QLabel()
        self.angle_label.setWordWrap(True)  # a longer joint name or angle wraps: the panel keeps its width
        self.legend = QLabel(LEGEND)
        self.legend.setWordWrap(True)
        side = QWidget()
        side_layout = QVBoxLayout(side)
        header = QLabel("Joints (solver confidence, or manual)")
        for widget in (header, self.joints, self.angle_label, self.dial, self.legend):
            side_layout.addWidget(widget)
        self.editor = QSplitter()
        self.editor.addWidget(self.interactor)
        self.editor.addWidget(side)
        self.editor.setStretchFactor(0, 3)
        self.hint = QLabel("Open a hand to annotate.")
        self.hint.setObjectName("annotate_hint")
        self.hint.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.hint.setWordWrap(True)
        self.hint.setMargin(24)
        font = self.hint.font()
        font.setPointSizeF(font.pointSizeF() * 1.3)
        self.hint.setFont(font)
        self.pages = QStackedLayout(self)
        self.pages.setContentsMargins(0, 0, 0, 0)
        self.pages.addWidget(self.hint)  # shown until a hand is opened
        self.pages.addWidget(self.editor)
        self.interactor.Initialize()
        self.joints.currentRowChanged.connect(self.select)
        self.dial.sliderPressed.connect(self._begin_drag)
        self.dial.valueChanged.connect(self._dial_turned)
        self.dial.sliderReleased.connect(self._end_drag)
        self._arrow_meshes: list[pv.PolyData] = []

    def set_hint(self, text: str) -> None:
        """What the view says until a hand is opened (how to open one)."""
        self.hint.setText(text)

    def set_session(self, session: AnnotationSession) -> None:
        """Show a newly opened hand: its mesh, skeleton, frames and joint list replace the last hand's (or the
        hint)."""
        self.pages.setCurrentWidget(self.editor)
        self.session = session
        self.selected = 0
        self._drag_base = None
        self._opened = session.frames.copy()
        plotter = self.plotter
        plotter.clear()
        plotter.set_background("white")
        hand = display_hand(session.hand)
        if hand.mesh is not None:
            plotter.add_mesh(surface(hand, to_view(hand, hand.mesh.vertices)), color=SKIN_COLOUR, opacity=0.3,
                             pickable=False)
        plotter.add_mesh(skeleton(hand, pose_frame(hand, hand.rest_tbs)), color=BONE_COLOUR, line_width=3,
                         pickable=False)
        self._arrow_meshes = [_arrows(session, axis, self.selected) for axis in range(3)]
        for mesh, colour in zip(self._arrow_meshes, AXIS_COLOURS):
            plotter.add_mesh(mesh, color=colour, pickable=False)
        self.ring.attach()
        plotter.add_text(f"{session.hand.name}: annotation", font_size=10, color="black", position="upper_left")
        plotter.view_vector((0.5, 0.35, -0.8), viewup=(1.0, 0.0, 0.0))
        plotter.reset_camera()
        self.refresh_list()
        self.refresh()

    def joint_centres(self) -> np.ndarray:
        """(15, 3) the articulated joints in view space, where their frames and the ring are drawn."""
        return to_view(self.session.hand, self.session.hand.rest_positions[topo.ARTICULATED_JOINTS])

    def _clicked(self, x: int, y: int) -> None:
        """A click in 3D (VTK display pixels) selects the joint nearest to it on screen, if one is near."""
        if self.session is None:
            return
        joint = nearest_on_screen(self.plotter.renderer, self.joint_centres(), x, y)
        if joint is not None:
            self.select(joint)

    def refresh_list(self) -> None:
        self.joints.blockSignals(True)
        self.joints.clear()
        self.joints.addItems([self.session.describe(j) for j in range(topo.N_ARTICULATED)])
        self.joints.setCurrentRow(self.selected)
        self.joints.blockSignals(False)

    def refresh(self) -> None:
        """Redraw the arrows and the ring from the session's frames (after an edit, an undo, a solver run)."""
        if self.session is None:
            return
        for mesh, axis in zip(self._arrow_meshes, range(3)):
            mesh.copy_from(_arrows(self.session, axis, self.selected))
        view_frame = to_view(self.session.hand, self.session.frames[self.selected].T).T
        self.ring.place(self.joint_centres()[self.selected], view_frame, RING_RADIUS * self.session.hand.hand_length)
        self._show_turn()
        self.interactor.render()

    def screen_sense(self) -> int:
        """+1 where a turn about the selected twist axis (right-hand rule) looks clockwise from the camera (the
        axis points away from it), -1 where it looks anticlockwise: the dial turns as the ring does on screen."""
        toward_camera = np.asarray(self.plotter.camera.position) - self.ring.centre  # the ring as `refresh` placed it
        return -1 if float(np.dot(self.ring.axis, toward_camera)) > 0 else 1

    def turn_from_opened(self) -> float:
        """Degrees the selected joint's frame is turned about its twist axis from its frame at opening."""
        opened, now = self._opened[self.selected], self.session.frames[self.selected]
        return signed_angle_about(opened[:, 0], opened[:, 1], now[:, 1])

    def _show_turn(self) -> None:
        """The dial and the readout say the selected frame's turn, however it came (ring, dial, undo, solver)."""
        degrees = self.turn_from_opened()
        on_screen = self.screen_sense() * degrees
        way = "clockwise" if on_screen >= 0 else "anticlockwise"
        self.angle_label.setText(f"{topo.ARTICULATED_NAMES[self.selected]}: turned {abs(on_screen):.0f} deg {way} "
                                 f"as seen here ({degrees:+.0f} deg about its twist axis) from its frame at opening")
        self.dial.blockSignals(True)
        self.dial.setValue((round(on_screen) + 180) % 360 - 180)
        self.dial.blockSignals(False)

    def select(self, joint: int) -> None:
        if joint < 0 or self.session is None:
            return
        self.selected = joint
        if self.joints.currentRow() != joint:
            self.joints.setCurrentRow(joint)
        self.refresh()

    def _begin_drag(self) -> None:
        self._drag_base = self.session.frames[self.selected].copy() if self.session is not None else None
        self._dial_at_grab = self.dial.value()
        self._sense_at_grab = self.screen_sense() if self.session is not None else 1

    def _dial_turned(self, degrees: int) -> None:
        """The dial shows the turn from the frame at opening as seen on screen: a drag turns the frame by what
        the dial moved since the grab, clockwise on the dial being clockwise on the ring."""
        self._turn_to(self._sense_at_grab * float((degrees - self._dial_at_grab + 180) % 360 - 180))

    def _turn_to(self, degrees: float) -> None:
        """Live: the selected frame is its frame at the grab turned by ``degrees`` about its twist axis."""
        if self._drag_base is None or self.session is None:
            return
        self.session.frames[self.selected] = rotate_about_twist(self._drag_base, degrees)
        self.refresh()

    def _end_drag(self) -> None:
        if self._drag_base is None or self.session is None:
            return
        before, after = self._drag_base, self.session.frames[self.selected].copy()
        self._drag_base = None
        if not np.allclose(before, after):
            self.frame_edited.emit(self.selected, before, after)

    def turn_selected(self, degrees: int) -> None:
        """What one drag of the dial by ``degrees`` does, for keyboard users and tests: press, turn, release."""
        self.dial.sliderPressed.emit()
        self.dial.setValue((self.dial.value() + degrees + 180) % 360 - 180)
        self.dial.sliderReleased.emit()
