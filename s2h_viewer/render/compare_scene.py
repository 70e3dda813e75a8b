"""The compare grid as pyvista data, for any plotter: the app's Qt viewport and `s2h render`'s
off-screen one. The source once, in a column spanning every row; then one row per target hand and
one subplot per method. Each retargeted hand's skin is coloured by its per-joint ASM error
(1 - cosine against the source) at the current frame, spread over the surface by the skin weights;
meshes are drawn at most `DISPLAY_FACES` faces with one camera-following light (software OpenGL
draws triangles slowly). Every camera is linked.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyvista as pv
import trimesh

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import HandPose
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.skinning import skin_vertices
from s2h_viewer.render.scene import BONE_COLOUR, SKIN_COLOUR, display_hand, skeleton, surface, to_view
from s2h_viewer.retarget.comparison import Comparison
from s2h_viewer.retarget.methods import METHODS

ERROR_RANGE = (0.0, 0.1)  # 1 - cosine; 0.1 is already a clearly different pose
ERROR_COLOURMAP = "plasma"
DISPLAY_FACES = 10_000


class PosedHand:
    """The pyvista data of one hand in one subplot, updated in place each frame."""

    def __init__(self, plotter: pv.Plotter, hand: HandModel, pose: HandPose, joint_error: np.ndarray | None,
                 opacity: float):
        self.hand, self.pose, self.joint_error = hand, pose, joint_error
        self.error_actor = self.mesh = None
        if hand.mesh is not None:
            self.mesh = surface(hand, to_view(hand, skin_vertices(hand, pose, 0)))
            self.closed = is_closed_outward(self.mesh)
            if joint_error is None:
                self.mesh_actor = plotter.add_mesh(self.mesh, color=SKIN_COLOUR, specular=0.2, reset_camera=False)
            else:
                self.mesh["error"] = np.zeros(self.mesh.n_points)
                self.mesh_actor = self.error_actor = plotter.add_mesh(
                    self.mesh, scalars="error", cmap=ERROR_COLOURMAP, clim=ERROR_RANGE, specular=0.2,
                    show_scalar_bar=False, reset_camera=False)
            self.set_opacity(opacity)
        else:  # a skeleton-only hand (BVH): bones as tubes
            self.bones = skeleton(hand, pose, 0)
            plotter.add_mesh(self.bones, color=BONE_COLOUR, line_width=4, reset_camera=False)

    def show(self, frame: int) -> None:
        if self.mesh is None:
            self.bones.points = to_view(self.hand, self.pose.positions[frame].numpy().astype(np.float64))
            return
        self.mesh.points[:] = to_view(self.hand, skin_vertices(self.hand, self.pose, frame))  # in place: no new
        self.mesh.GetPoints().Modified()  # VTK arrays per frame
        if self.joint_error is not None:
            per_rotating = np.zeros(topo.N_ROTATING)  # wrist 0, then each articulated joint's ASM row
            per_rotating[1:] = np.nan_to_num(self.joint_error[frame, topo.ARTICULATED_JOINTS - 1])
            self.mesh.point_data["error"][:] = self.hand.mesh.weights @ per_rotating
            self.mesh.point_data.GetArray("error").Modified()

    def set_opacity(self, opacity: float) -> None:
        """See-through below 1; an opaque closed skin skips its back faces (about a third of the drawing)."""
        if self.mesh is not None:
            self.mesh_actor.prop.opacity = opacity
            self.mesh_actor.prop.culling = "back" if self.closed and opacity >= 1.0 else "none"


def is_closed_outward(mesh: pv.PolyData) -> bool:
    """Watertight with outward-facing triangles: only then are its back faces never seen."""
    closed = trimesh.Trimesh(np.asarray(mesh.points), mesh.regular_faces, process=False)
    return bool(closed.is_watertight and closed.is_winding_consistent and closed.volume > 0)


def grid_layout(comparison: Comparison) -> dict:
    """Plotter keywords for the grid: a row per target, a column per method after the source's column,
    which is merged over all rows (the source is drawn once)."""
    rows = len(dict.fromkeys(id(r.target) for r in comparison.results)) or 1
    shape = (rows, 1 + len(comparison.results) // rows)
    return {"shape": shape, "groups": [(np.s_[:], 0)] if rows > 1 else None, "border": False}


def populate(plotter: pv.Plotter, comparison: Comparison, opacity: float = 1.0,
             display_faces: int | None = DISPLAY_FACES) -> list[PosedHand]:
    """Fill a plotter made with ``**grid_layout(comparison)``; returns the hands to update per frame."""
    displayed: dict[int, HandModel] = {}

    def shown(hand: HandModel) -> HandModel:
        if display_faces is None:
            return hand
        if id(hand) not in displayed:
            displayed[id(hand)] = display_hand(hand, display_faces)
        return displayed[id(hand)]

    panels = [((0, 0), shown(comparison.source), comparison.source_pose, None, f"source: {comparison.source.name}")]
    for row, target in enumerate(dict.fromkeys(id(r.target) for r in comparison.results)):
        results = [r for r in comparison.results if id(r.target) == target]
        panels += [((row, 1 + k), shown(r.target), r.pose, r.joint_error,
                    f"{METHODS[r.method].label} -> {r.target.name}\nS_palm {r.scores.s_palm:.3f}  "
                    f"S_finger {r.scores.s_finger:.3f}") for k, r in enumerate(results)]
    hands = []
    for cell, hand, pose, error, label in panels:
        plotter.subplot(*cell)
        plotter.set_background("white")
        plotter.renderer.remove_all_lights()  # one light that follows the camera: a quarter of the
        plotter.renderer.add_light(pv.Light(light_type="headlight"))  # shading cost of pyvista's five-light kit
        hands.append(PosedHand(plotter, hand, pose, error, opacity))
        plotter.add_text(label, font_size=9, color="black", position="upper_left")
        plotter.view_vector((0.15, 0.45, -0.85), viewup=(1.0, 0.0, 0.0))
        plotter.reset_camera()
        plotter.camera.zoom(0.8)  # room for a moving hand and the label
    coloured = next((h.error_actor for h in hands if h.error_actor is not None), None)
    if coloured is not None:
        plotter.subplot(*panels[-1][0])
        plotter.add_scalar_bar("ASM error (1 - cos)", mapper=coloured.mapper, vertical=True, position_x=0.76,
                               position_y=0.08, height=0.55, width=0.1, title_font_size=10, label_font_size=9,
                               color="black", n_labels=4, fmt="%.2f")
    plotter.link_views()
    return hands


def render_comparison(comparison: Comparison, path: str | Path, frame: int | None = None,
                      size: tuple[int, int] = (1400, 900),
                      progress: Callable[[int, int], None] | None = None) -> Path:
    """Off screen: one frame as PNG (``frame``, default 0), or every frame as MP4/GIF (by suffix)."""
    from s2h_viewer.io.atomic import atomic_path
    from s2h_viewer.render.video import VIDEO_SUFFIXES, write_video

    path = Path(path)
    plotter = pv.Plotter(off_screen=True, window_size=size, **grid_layout(comparison))
    plotter.render_window.SetMultiSamples(0)
    hands = populate(plotter, comparison)
    plotter.show(auto_close=False)

    def image(f: int) -> np.ndarray:
        for hand in hands:
            hand.show(f)
        plotter.render()
        if progress:
            progress(f + 1, comparison.n_frames)
        return np.asarray(plotter.screenshot(return_img=True))[..., :3]

    try:
        if path.suffix.lower() in VIDEO_SUFFIXES:
            return write_video(path, (image(f) for f in range(comparison.n_frames)), comparison.motion.fps)
        from PIL import Image
        with atomic_path(path) as tmp:
            Image.fromarray(image(frame or 0)).save(tmp, format="PNG")
        return path
    finally:
        plotter.close()
