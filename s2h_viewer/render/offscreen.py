"""Off-screen rendering to PNG (VTK falls back to EGL without a display): `s2h render` uses this."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pyvista as pv

from s2h_viewer.hand.model import HandModel
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.render.scene import (AXIS_COLOURS, BONE_COLOUR, CAMERA_DIRECTIONS, PALM_OPACITY, SKIN_COLOUR,
                                     frame_arrows, palm_fan, pose_frame, posed_mesh, skeleton)

#: a caption line's height in a cell, pixels (`add_text` at font size 11): the hand is framed below the caption
CAPTION_LINE_PX = 22
#: the colour of a joint ``render_hands`` marks: the viewer's red of a finger bent sideways
MARK_COLOUR = "#c62828"


def _set_camera(plotter: pv.Plotter, bounds: tuple, view: str, caption_share: float = 0.0) -> None:
    """The camera on ``bounds`` from ``view``'s direction, the hand in the cell's height under the top
    ``caption_share`` of it (a caption's: a VRM robot's fingers were drawn through its name)."""
    direction, up = CAMERA_DIRECTIONS[view]
    centre = np.array([(bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2, (bounds[4] + bounds[5]) / 2])
    radius = 0.5 * np.linalg.norm([bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4]])
    d = np.asarray(direction) / np.linalg.norm(direction)
    distance = 3.9 * radius / (1.0 - caption_share)  # the hand as tall in what is left as in the whole cell before
    screen_up = np.asarray(up, dtype=np.float64) - d * np.dot(up, d)
    screen_up /= np.linalg.norm(screen_up)
    lift = caption_share * distance * math.tan(math.radians(15.0))  # half the view's height times the share
    plotter.camera.focal_point = centre + screen_up * lift
    plotter.camera.position = centre + screen_up * lift + d * distance
    plotter.camera.up = up
    plotter.camera.view_angle = 30.0
    plotter.reset_camera_clipping_range()


def render_hands(hands: list[HandModel], poses: list[np.ndarray], path: str | Path, labels: list[str] | None = None,
                 columns: int | None = None, view: str = "three_quarter", cell_size: tuple[int, int] = (400, 460),
                 show_skeleton: bool = False, show_frames: bool = False, fit_each: bool = False,
                 marked: int | None = None) -> Path:
    """Render each hand in its pose ((15, 4) TBS quaternions) in its own cell of a grid; write a PNG.

    Hands keep their true sizes relative to each other (every cell uses the same camera distance), or with
    ``fit_each`` each fills its cell (a source beside its retarget onto a mitten a quarter its size).
    ``show_frames`` draws each joint's TBS frame as arrows: twist red, bend green, splay blue; ``marked`` (one of
    the 21 joints) is drawn as a red ball on every hand, the skin see-through (the joint a batch row's note names).
    """
    if len(hands) != len(poses):
        raise ValueError(f"{len(hands)} hands but {len(poses)} poses")
    columns = min(columns or 6, len(hands))
    rows = math.ceil(len(hands) / columns)
    plotter = pv.Plotter(off_screen=True, shape=(rows, columns), border=False,
                         window_size=(cell_size[0] * columns, cell_size[1] * rows))
    fk = [pose_frame(hand, q) for hand, q in zip(hands, poses)]
    caption_lines = max(str(text).count("\n") + 1 for text in (labels or [hand.name for hand in hands]))
    meshes = [posed_mesh(hand, pose) if hand.mesh is not None else skeleton(hand, pose) for hand, pose in zip(hands, fk)]
    largest = max(meshes, key=lambda m: np.ptp(np.asarray(m.bounds).reshape(3, 2), axis=1).max())
    for i, (hand, pose, mesh) in enumerate(zip(hands, fk, meshes)):
        # a mitten's skin hides what its fingers do: its bones through it, as the viewer draws it
        see_through = show_skeleton or show_frames or marked is not None or bool(hand.meta.get("unparted_fingers"))
        plotter.subplot(i // columns, i % columns)
        plotter.set_background("white")
        if hand.mesh is not None:
            plotter.add_mesh(mesh, color=SKIN_COLOUR, smooth_shading=True, specular=0.25,
                             opacity=0.35 if see_through else 1.0)
        if see_through or hand.mesh is None:
            plotter.add_mesh(skeleton(hand, pose).tube(radius=0.012 * hand.hand_length), color=BONE_COLOUR)
        if marked is not None:
            at = np.asarray(skeleton(hand, pose).points)[marked]
            plotter.add_mesh(pv.Sphere(radius=0.05 * hand.hand_length, center=at), color=MARK_COLOUR)
        if hand.mesh is None:  # as the viewer draws it: the palm see-through between the knuckles, joints as dots
            plotter.add_mesh(palm_fan(hand, pose), color=SKIN_COLOUR, opacity=PALM_OPACITY)
            plotter.add_mesh(pv.PolyData(np.asarray(mesh.points)).glyph(
                geom=pv.Sphere(radius=0.03 * hand.hand_length), scale=False, orient=False), color=BONE_COLOUR)
        if show_frames:
            for arrows, colour in zip(frame_arrows(hand, pose), AXIS_COLOURS):
                plotter.add_mesh(arrows, color=colour)
        plotter.add_text(labels[i] if labels else hand.name, font_size=11, color="black", position="upper_edge")
        c = np.asarray(mesh.center)
        half = np.ptp(np.asarray((mesh if fit_each else largest).bounds).reshape(3, 2), axis=1) / 2
        _set_camera(plotter, tuple(np.ravel(np.column_stack([c - half, c + half]))), view,
                    min(0.4, CAPTION_LINE_PX * caption_lines / cell_size[1]))
    path = Path(path)
    with atomic_path(path) as tmp:
        plotter.screenshot(str(tmp))
    plotter.close()
    return path
