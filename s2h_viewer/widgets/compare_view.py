"""A grid of linked 3D views, one row per target hand: the source, then one view per method.

One `QtInteractor` with subplots and `link_views`, so every camera moves together and one render
window draws everything (no multisampling: software OpenGL pays 3-4x for it). Each retargeted
hand's skin is coloured by its per-joint ASM error (1 - cosine against the source) at the current
frame, spread over the surface by the skin weights, with a shared colour bar. Meshes are drawn at
most `DISPLAY_FACES` faces (`render.scene.display_hand`).
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from pyvistaqt import QtInteractor
from PySide6.QtWidgets import QVBoxLayout, QWidget

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import HandPose
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.skinning import skin_vertices
from s2h_viewer.render.scene import BONE_COLOUR, SKIN_COLOUR, display_hand, skeleton, to_view
from s2h_viewer.retarget.comparison import Comparison
from s2h_viewer.retarget.methods import METHODS

ERROR_RANGE = (0.0, 0.1)  # 1 - cosine; 0.1 is already a clearly different pose
ERROR_COLOURMAP = "plasma"
DISPLAY_FACES = 10000


class _HandActors:
    """The pyvista data of one hand in one subplot, updated in place each frame."""

    def __init__(self, plotter: pv.Plotter, hand: HandModel, pose: HandPose, joint_error: np.ndarray | None,
                 opacity: float):
        self.hand, self.pose, self.joint_error = hand, pose, joint_error
        self.error_actor = self.mesh = None
        if hand.mesh is not None:
            faces = np.hstack([np.full((len(hand.mesh.faces), 1), 3), hand.mesh.faces]).astype(np.int64)
            self.mesh = pv.PolyData(to_view(hand, skin_vertices(hand, pose, 0)), faces)
            if joint_error is None:
                self.mesh_actor = plotter.add_mesh(self.mesh, color=SKIN_COLOUR, opacity=opacity, specular=0.2,
                                                   reset_camera=False)
            else:
                self.mesh["error"] = np.zeros(self.mesh.n_points)
                self.mesh_actor = self.error_actor = plotter.add_mesh(
                    self.mesh, scalars="error", cmap=ERROR_COLOURMAP, clim=ERROR_RANGE, opacity=opacity,
                    specular=0.2, show_scalar_bar=False, reset_camera=False)
        else:  # a skeleton-only hand (BVH): bones as tubes
            self.bones = skeleton(hand, pose, 0)
            plotter.add_mesh(self.bones, color=BONE_COLOUR, line_width=4, reset_camera=False)

    def show(self, frame: int) -> None:
        if self.mesh is None:
            self.bones.points = to_view(self.hand, self.pose.positions[frame].numpy().astype(np.float64))
            return
        self.mesh.points = to_view(self.hand, skin_vertices(self.hand, self.pose, frame))
        if self.joint_error is not None:
            per_rotating = np.zeros(topo.N_ROTATING)  # wrist 0, then each articulated joint's ASM row
            per_rotating[1:] = np.nan_to_num(self.joint_error[frame, topo.ARTICULATED_JOINTS - 1])
            self.mesh["error"] = self.hand.mesh.weights @ per_rotating

    def set_opacity(self, opacity: float) -> None:
        if self.mesh is not None:
            self.mesh_actor.GetProperty().SetOpacity(opacity)


class CompareView(QWidget):
    """Source + targets x methods, synchronised on ``show_frame``."""

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self._layout = QVBoxLayout(self)
        self._layout.setContentsMargins(0, 0, 0, 0)
        self.interactor: QtInteractor | None = None
        self.comparison: Comparison | None = None
        self._hands: list[_HandActors] = []
        self.opacity = 1.0

    def set_comparison(self, comparison: Comparison) -> None:
        """Lay out one subplot per hand: the source first, then each (target, method)."""
        self.comparison = comparison
        light = {}  # display meshes, one per hand

        def lighter(hand: HandModel) -> HandModel:
            if id(hand) not in light:
                light[id(hand)] = display_hand(hand, DISPLAY_FACES)
            return light[id(hand)]

        targets = list(dict.fromkeys(id(r.target) for r in comparison.results))
        columns = 1 + len(comparison.results) // max(len(targets), 1)
        rows = max(len(targets), 1)
        panels = []
        for t in targets:
            panels.append((lighter(comparison.source), comparison.source_pose, None,
                           f"source: {comparison.source.name}"))
            panels += [(lighter(r.target), r.pose, r.joint_error,
                        f"{METHODS[r.method].label} -> {r.target.name}\nS_palm {r.scores.s_palm:.3f}  "
                        f"S_finger {r.scores.s_finger:.3f}") for r in comparison.results if id(r.target) == t]
        if self.interactor is not None:  # pyvista fixes the subplot layout at construction: start afresh
            self._layout.removeWidget(self.interactor)
            self.interactor.close()
            self.interactor.deleteLater()
        plotter = self.interactor = QtInteractor(self, shape=(rows, columns), border=False, multi_samples=0,
                                                 auto_update=False)
        self._layout.addWidget(plotter)
        self._hands = []
        for i, (hand, pose, error, label) in enumerate(panels):
            plotter.subplot(i // columns, i % columns)
            plotter.set_background("white")
            self._hands.append(_HandActors(plotter, hand, pose, error, self.opacity))
            plotter.add_text(label, font_size=9, color="black", position="upper_left")
            plotter.view_vector((0.15, 0.45, -0.85), viewup=(1.0, 0.0, 0.0))
            plotter.reset_camera()
        coloured = next((h.error_actor for h in self._hands if h.error_actor is not None), None)
        if coloured is not None:
            plotter.subplot((len(panels) - 1) // columns, (len(panels) - 1) % columns)
            plotter.add_scalar_bar("ASM error (1 - cos)", mapper=coloured.mapper, vertical=True, position_x=0.84,
                                   position_y=0.08, height=0.55, width=0.1, title_font_size=10, label_font_size=9,
                                   color="black", n_labels=4, fmt="%.2f")
        plotter.link_views()
        self.show_frame(0)

    def show_frame(self, frame: int) -> None:
        for hand in self._hands:
            hand.show(frame)
        if self.interactor is not None:
            self.interactor.render()

    def set_mesh_opacity(self, opacity: float) -> None:
        self.opacity = opacity
        for hand in self._hands:
            hand.set_opacity(opacity)
        if self.interactor is not None:
            self.interactor.render()

    def grab_rgb(self) -> np.ndarray:
        """The current view as an (H, W, 3) uint8 image (what screenshot and video export save)."""
        self.interactor.render()
        return np.asarray(self.interactor.screenshot(return_img=True))[..., :3]
