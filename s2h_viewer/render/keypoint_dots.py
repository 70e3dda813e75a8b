"""A tracked source's recorded keypoints as dots over its fitted hand: what the tracker saw beside what the fit
made of it (noise, a joint the fitted skeleton cannot follow). A frame the tracker lost, or whose keypoints
were set aside as outliers, draws no dots: the hand there is filled in."""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkRenderingCore import vtkMapper

from s2h_viewer.hand.model import HandModel
from s2h_viewer.render.scene import to_view

KEYPOINT_COLOUR = "#e7298a"
KEYPOINT_PX = 9  # in a cell of `CELL_PX` pixels on its short side or more; smaller cells scale it (at least 4)
CELL_PX = 300
ON_TOP_OFFSET = -1e6  # drawn over the skin, as the contact overlay is


class KeypointDots:
    """The 21 recorded keypoints (hand space, NaN where not used) of each frame, updated in place."""

    def __init__(self, plotter: pv.Plotter, hand: HandModel, keypoints: np.ndarray, filled: np.ndarray):
        self.hand = hand
        self.keypoints = keypoints
        self.filled = filled
        start = np.nan_to_num(to_view(hand, keypoints[0]))
        self.points = pv.PolyData(start)
        self.actor = plotter.add_mesh(self.points, color=KEYPOINT_COLOUR, point_size=KEYPOINT_PX,
                                      render_points_as_spheres=False, reset_camera=False)
        vtkMapper.SetResolveCoincidentTopologyToPolygonOffset()
        self.actor.mapper.SetRelativeCoincidentTopologyPointOffsetParameter(ON_TOP_OFFSET)
        self.visible = True

    def fit(self, short_side: int) -> None:
        size = max(4, round(KEYPOINT_PX * min(1.0, short_side / CELL_PX)))
        if self.actor.prop.point_size != size:
            self.actor.prop.point_size = size

    def set_visible(self, visible: bool) -> None:
        self.visible = visible

    def show(self, frame: int) -> None:
        shown = self.visible and not self.filled[frame]
        self.actor.visibility = shown
        if shown:
            self.points.points = to_view(self.hand, self.keypoints[frame])
