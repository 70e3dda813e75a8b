"""Annotation mode's view: one hand at rest, see-through, each joint's TBS frame as three arrows
(twist red, bend green, splay blue), a joint list with the solver's confidence, and a rotation
handle (a dial) that turns the selected joint's frame about its twist axis while it is dragged."""

from __future__ import annotations

import numpy as np
import pyvista as pv
from pyvistaqt import QtInteractor
from PySide6.QtCore import Signal
from PySide6.QtWidgets import QDial, QHBoxLayout, QLabel, QListWidget, QSplitter, QVBoxLayout, QWidget

from s2h_viewer.annotate.editing import AnnotationSession, rotate_about_twist
from s2h_viewer.annotate.solver import LOW_CONFIDENCE
from s2h_viewer.hand import topology as topo
from s2h_viewer.render.scene import (AXIS_COLOURS, BONE_COLOUR, SKIN_COLOUR, display_hand, pose_frame, skeleton,
                                     surface, to_view)

LEGEND = "TBS frames: twist (along the bone) red, bend green, splay (out of the back) blue"


def _arrows(session: AnnotationSession, axis: int, selected: int) -> pv.PolyData:
    hand = session.hand
    origins = to_view(hand, hand.rest_positions[topo.ARTICULATED_JOINTS])
    cloud = pv.PolyData(origins)
    cloud["vectors"] = to_view(hand, session.frames[:, :, axis])
    cloud["size"] = np.where(np.arange(topo.N_ARTICULATED) == selected, 1.6, 1.0)
    return cloud.glyph(orient="vectors", scale="size", factor=0.12 * hand.hand_length,
                       geom=pv.Arrow(shaft_radius=0.05, tip_radius=0.12))


class AnnotationView(QWidget):
    """Emits ``frame_edited(joint, frame_before, frame_after)`` when a drag of the handle ends."""

    frame_edited = Signal(int, object, object)

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.session: AnnotationSession | None = None
        self.selected = 0
        self._drag_base: np.ndarray | None = None
        self.interactor = QtInteractor(self, multi_samples=0, auto_update=False)
        self.joints = QListWidget()
        self.dial = QDial()
        self.dial.setRange(-180, 180)
        self.dial.setWrapping(True)
        self.dial.setNotchesVisible(True)
        self.angle_label = QLabel("turn about twist: 0 deg")
        self.legend = QLabel(LEGEND)
        self.legend.setWordWrap(True)
        side = QWidget()
        side_layout = QVBoxLayout(side)
        for widget in (QLabel("Joints (solver confidence)"), self.joints, self.angle_label, self.dial, self.legend):
            side_layout.addWidget(widget)
        splitter = QSplitter()
        splitter.addWidget(self.interactor)
        splitter.addWidget(side)
        splitter.setStretchFactor(0, 3)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(splitter)
        self.joints.currentRowChanged.connect(self.select)
        self.dial.sliderPressed.connect(self._begin_drag)
        self.dial.valueChanged.connect(self._drag)
        self.dial.sliderReleased.connect(self._end_drag)
        self._arrow_meshes: list[pv.PolyData] = []

    def set_session(self, session: AnnotationSession) -> None:
        self.session = session
        plotter = self.interactor
        plotter.clear()
        plotter.set_background("white")
        hand = display_hand(session.hand)
        if hand.mesh is not None:
            plotter.add_mesh(surface(hand, to_view(hand, hand.mesh.vertices)), color=SKIN_COLOUR, opacity=0.3)
        plotter.add_mesh(skeleton(hand, pose_frame(hand, hand.rest_tbs)), color=BONE_COLOUR, line_width=3)
        self._arrow_meshes = [_arrows(session, axis, self.selected) for axis in range(3)]
        for mesh, colour in zip(self._arrow_meshes, AXIS_COLOURS):
            plotter.add_mesh(mesh, color=colour)
        plotter.add_text(f"{session.hand.name}: annotation", font_size=10, color="black", position="upper_left")
        plotter.view_vector((0.15, 0.45, -0.85), viewup=(1.0, 0.0, 0.0))
        plotter.reset_camera()
        plotter.enable_point_picking(self._picked, show_message=False, left_clicking=True, show_point=False,
                                     use_picker=True)
        self.refresh_list()
        self.select(0)

    def _picked(self, point) -> None:
        """A click in 3D selects the nearest joint."""
        if self.session is None or point is None:
            return
        origins = to_view(self.session.hand, self.session.hand.rest_positions[topo.ARTICULATED_JOINTS])
        self.joints.setCurrentRow(int(np.argmin(np.linalg.norm(origins - np.asarray(point), axis=1))))

    def refresh_list(self) -> None:
        s = self.session
        self.joints.blockSignals(True)
        self.joints.clear()
        for j, name in enumerate(topo.ARTICULATED_NAMES):
            flag = "  review" if s.set_by[j] == "solver" and s.confidence[j] < LOW_CONFIDENCE else ""
            self.joints.addItem(f"{name}: {s.confidence[j]:.2f} ({s.set_by[j]}){flag}")
        self.joints.setCurrentRow(self.selected)
        self.joints.blockSignals(False)

    def refresh(self) -> None:
        """Redraw the arrows from the session's frames (after an edit, an undo, a solver run)."""
        if self.session is None:
            return
        for mesh, axis in zip(self._arrow_meshes, range(3)):
            mesh.copy_from(_arrows(self.session, axis, self.selected))
        self.interactor.render()

    def select(self, joint: int) -> None:
        if joint < 0 or self.session is None:
            return
        self.selected = joint
        if self.joints.currentRow() != joint:
            self.joints.setCurrentRow(joint)
        self.refresh()

    def _begin_drag(self) -> None:
        self._drag_base = self.session.frames[self.selected].copy() if self.session is not None else None

    def _drag(self, degrees: int) -> None:
        self.angle_label.setText(f"turn about twist: {degrees} deg")
        if self._drag_base is None or self.session is None:
            return
        self.session.frames[self.selected] = rotate_about_twist(self._drag_base, degrees)
        self.refresh()

    def _end_drag(self) -> None:
        if self._drag_base is None or self.session is None:
            return
        before, after = self._drag_base, self.session.frames[self.selected].copy()
        self._drag_base = None
        self.dial.blockSignals(True)
        self.dial.setValue(0)
        self.dial.blockSignals(False)
        self.angle_label.setText("turn about twist: 0 deg")
        if not np.allclose(before, after):
            self.frame_edited.emit(self.selected, before, after)

    def turn_selected(self, degrees: int) -> None:
        """What one drag of the handle does, for keyboard users and tests: press, turn, release."""
        self.dial.sliderPressed.emit()
        self.dial.setValue(degrees)
        self.dial.sliderReleased.emit()
