"""The compare grid as pyvista data, for any plotter: the app's Qt viewport and `s2h render`'s
off-screen one. The source once, in a column spanning every row; then one row per target hand and
one subplot per method. Each retargeted hand's skin is coloured by its per-joint ASM error
(1 - cosine against the source) at the current frame, spread over the surface by the skin weights;
meshes are drawn at most `DISPLAY_FACES` faces with one camera-following light (software OpenGL
draws triangles slowly). Every camera is linked.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import pyvista as pv
import trimesh
from scipy.spatial import ConvexHull, QhullError
from vtkmodules.vtkRenderingCore import vtkActor2D, vtkCellPicker, vtkMapper, vtkTextProperty, vtkTextRenderer

from s2h_viewer.annotate.trust import frame_warning
from s2h_viewer.geometry import distance_to_segments
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import HandPose
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.skinning import skin_vertices
from s2h_viewer.render.keypoint_dots import KeypointDots
from s2h_viewer.render.scene import (BONE_COLOUR, CAMERA_DIRECTIONS, PALM_OPACITY, SKIN_COLOUR, display_hand,
                                    palm_fan, skeleton, surface, to_view)
from s2h_viewer.render.text_lock import TEXT_LOCK
from s2h_viewer.retarget.comparison import Comparison, MethodResult
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.semantics.contacts import CONTACT_PAIRS, SITES, detect_contacts, pad_centres, touching_and_near
from s2h_viewer.wording import counted

ERROR_RANGE = (0.0, 0.1)  # 1 - cosine; 0.1 is already a clearly different pose
ERROR_COLOURMAP = "plasma"
DISPLAY_FACES = 10_000
PLAYING_FACES = 3_000  # while the window plays: a third of the triangles, a quarter less time per frame
COLOUR_BAR_SHARE = 0.065  # of the grid's width: the colour bar's column, however many hand columns
LABEL_PX = 13  # the grid's labels' font size, in pixels, where their cell has room for it
MIN_LABEL_PX = 9  # and at least, in small cells: smaller glyphs are no longer read at a glance
#: the picture height LABEL_PX was chosen for: a taller export (2160 pixels) draws its labels larger in proportion
LABEL_REFERENCE_HEIGHT = 1000
#: pixels between a label and its cell's top and left edges (and the band's bottom): clear of the selected cell's
#: 3-pixel frame (at 4 its first line touched it, in the grid and in an exported picture: a fresh-eyes user)
LABEL_PAD = 7
BAND_SHARE = 0.35  # of a cell's height: the font shrinks until the labels' band fits in it
MAX_BAND_SHARE = 0.45  # at most: a cell too short for every line even at MIN_LABEL_PX leaves out the last ones
LABEL_LINES = 3  # a retarget's label: method -> target, S_finger, the share of frames keeping the signature
WIDEST_LINE = "S_finger 0.000"  # the widest line the font shrinks to keep whole (longer ones are elided)
ELLIPSIS = "\u2026"
TEXT_DPI = 72  # VTK's render windows' default: a font size in points is then in pixels
#: contacts in three states, each its own colour (none of them in the skin's plasma colours): kept (the source
#: makes it too; every contact of the source), lost (the source makes it, the retarget does not) and invented
#: (the retarget makes it, the source does not: a false touch is not a kept one)
CONTACT_COLOUR = "#1a9850"
LOST_COLOUR = "#ff1f1f"
INVENTED_COLOUR = "#0a84ff"
CONTACT_STATES = (("kept contact", CONTACT_COLOUR), ("lost contact", LOST_COLOUR),
                  ("invented contact", INVENTED_COLOUR))  # short: the legend's text is scaled to its box, and
#: "invented: the source does not" drew it 6 pixels tall in a narrow cell (what each means: View's menu, README)
#: the overlays' pixel sizes (bones, contact links, pad dots) in a cell OVERLAY_CELL pixels on its short side or
#: more; smaller cells scale them down (at least `OVERLAY_LEAST`): fixed dots would hide a small cell's fingers.
#: A dot is narrower than two touching pads' centres are apart (about 18 pixels at 300), so their link shows.
OVERLAY_PX = (3, 6, 11)
OVERLAY_LEAST = (1, 2, 4)
OVERLAY_CELL = 300
ON_TOP_OFFSET = -1e6  # depth offset (OpenGL polygon-offset units) of the contact overlay: in front of any skin
#: a target whose frames are unsure or guessed (`annotate.trust`): a banner at its cells' bottom
BANNER_COLOUR, BANNER_BACKGROUND = "#8a4b00", "#ffe0b2"
#: the source's ghost over a retarget shown alone (`Ghost`)
GHOST_COLOUR, GHOST_OPACITY = "#9e9e9e", 0.35
#: and a skeleton-only source's bones: thin lines in the skin's grey at its opacity were all but invisible on the
#: light background (a fresh-eyes user saw no ghost at all), dark slate ones on the heatmap's dark purple skin
GHOST_BONES_COLOUR, GHOST_BONES_OPACITY = "#00acc1", 0.9
#: the selected retarget's cell is framed in this colour, this many pixels wide
SELECTED_COLOUR, SELECTED_WIDTH = "#1565c0", 3.0
#: the contact legend's size in pixels (one line per state), LABEL_PAD from its cell's bottom left corner
LEGEND_PX = (170, 54)
#: each contact pair (``semantics.contacts.CONTACT_PAIRS``) as two indices into ``contact_sites``.
PAIR_SITES = np.array([[SITES.index(a), SITES.index(b)] for a, b in CONTACT_PAIRS], dtype=np.int64)


@dataclass
class Skin:
    """One level of detail of a hand's skin: the model it comes from, its posed surface, the actor."""

    hand: HandModel
    mesh: pv.PolyData
    actor: pv.Actor
    closed: bool
    points: np.ndarray  # the mesh's points, a view of its VTK array (written each frame)
    error: np.ndarray | None  # its error scalars, likewise; None on the source


@dataclass
class PosedSkin:
    """One skin's vertices (view space) and per-vertex error at one frame, ready to write into its mesh."""

    frame: int
    skin: Skin
    points: np.ndarray
    error: np.ndarray | None


class PosedHand:
    """The pyvista data of one hand in one subplot, updated in place each frame. Given a ``playing_hand``
    (the same hand with fewer faces), that one is drawn while playing and the full one when paused."""

    def __init__(self, plotter: pv.Plotter, hand: HandModel, pose: HandPose, joint_error: np.ndarray | None,
                 opacity: float, playing_hand: HandModel | None = None):
        self.hand, self.pose, self.joint_error = hand, pose, joint_error
        self.overlay: Overlays | None = None
        self.keypoints: KeypointDots | None = None  # a tracked source's recorded keypoints
        self.renderer = plotter.renderer  # the subplot it is drawn in
        self.warned = False  # its target's frames are unsure (`annotate.trust`): framed in the banner's colour
        self.label: CellLabel | None = None  # its cell's text
        self.banner: CellLabel | None = None  # its warning at the cell's bottom, if any
        self.banner_tip = ""  # the whole warning, for a tooltip over the banner
        self.border: vtkActor2D | None = None
        self.frame, self.playing = 0, False
        self.levels: list[Skin] = []  # the full skin, then the one drawn while playing (if any)
        self._reach: np.ndarray | None = None
        if hand.mesh is not None:
            models = [hand] + ([playing_hand] if playing_hand is not None and playing_hand is not hand else [])
            self.levels = [self._add_skin(plotter, model) for model in models]
            self.set_opacity(opacity)
        else:  # a skeleton-only hand (BVH, the VRM robot): bones, their joints as dots, the palm see-through
            self.bones, self.palm = skeleton(hand, pose, 0), palm_fan(hand, pose, 0)
            plotter.add_mesh(self.palm, color=SKIN_COLOUR, opacity=PALM_OPACITY, reset_camera=False)
            plotter.add_mesh(self.bones, color=BONE_COLOUR, line_width=4, reset_camera=False)
            plotter.add_mesh(self.bones, style="points", color=BONE_COLOUR, point_size=JOINT_DOT_PX,
                             render_points_as_spheres=True, reset_camera=False)
        self._show_levels()

    def _add_skin(self, plotter: pv.Plotter, hand: HandModel) -> Skin:
        mesh = surface(hand, to_view(hand, skin_vertices(hand, self.pose, 0)))
        if self.joint_error is None:
            actor = plotter.add_mesh(mesh, color=SKIN_COLOUR, specular=0.2, reset_camera=False)
        else:
            mesh["error"] = np.zeros(mesh.n_points)
            actor = plotter.add_mesh(mesh, scalars="error", cmap=ERROR_COLOURMAP, clim=ERROR_RANGE, specular=0.2,
                                     show_scalar_bar=False, reset_camera=False)
            mesh.set_active_scalars("error")  # the mesh straight into the mapper: pyvista puts a Python stage
            actor.mapper.SetInputData(mesh)  # between them that runs on every changed frame (~1 ms a frame)
        error = np.asarray(mesh.point_data["error"]) if self.joint_error is not None else None
        return Skin(hand, mesh, actor, is_closed_outward(mesh), np.asarray(mesh.points), error)

    @property
    def reach(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """What the hand's cell must show whichever frame is drawn (`fit_view_angle`), in view space: the corners
        of the hull of every joint in every frame of the clip, how far the skin reaches past each of them (the
        thickness of the bones either side of its joint: a finger's, a mitten's far more), and the skin the wrist
        alone moves (the palm's heel, a forearm's stub: still in the view, past the wrist joint)."""
        if self._reach is None:
            joints = to_view(self.hand, self.pose.positions.reshape(-1, 3).numpy().astype(np.float64))
            around = np.full(topo.N_JOINTS, BONE_MARGIN * self.hand.hand_length)  # per joint
            rigid = np.zeros((0, 3))
            if self.hand.mesh is not None:
                skin = to_view(self.hand, skin_vertices(self.hand, self.pose, 0))
                bone = np.argmax(np.asarray(self.hand.mesh.weights), axis=1)  # 0: the wrist, k: rotating joint k's
                rigid = skin[bone == 0][_hull_corners(skin[bone == 0])]
                for k in range(1, topo.N_ROTATING):  # how far its skin lies from each bone, at the first frame
                    start = topo.ARTICULATED_JOINTS[k - 1]
                    if (bone == k).any():
                        far = float(distance_to_segments(skin[bone == k], joints[start], joints[start + 1]).max())
                        around[[start, start + 1]] = np.maximum(around[[start, start + 1]], far)
            corners = _hull_corners(joints)
            self._reach = (joints[corners], around[corners % topo.N_JOINTS], rigid)
        return self._reach

    @property
    def skin(self) -> Skin | None:
        """The level drawn now: the lighter one while playing, if there is one."""
        return self.levels[-1 if self.playing else 0] if self.levels else None

    @property
    def mesh(self) -> pv.PolyData | None:
        return self.skin.mesh if self.levels else None

    @property
    def mesh_actor(self) -> pv.Actor | None:
        return self.skin.actor if self.levels else None

    @property
    def error_actor(self) -> pv.Actor | None:
        """The full skin's actor when it is coloured by the error (its mapper feeds the colour bar)."""
        return self.levels[0].actor if self.levels and self.joint_error is not None else None

    def set_playing(self, playing: bool) -> None:
        """Draw the lighter skin while playing, the full one when paused (posed at the current frame)."""
        if playing != self.playing:
            self.playing = playing
            self._show_levels()
            self.show(self.frame)

    def _show_levels(self) -> None:
        for level in self.levels:
            level.actor.visibility = level is self.skin

    def posed_skin(self, frame: int) -> PosedSkin | None:
        """The drawn skin's vertices (view space) and error colours at ``frame``, computed with numpy alone
        (no VTK: a worker thread may pose the next frame while this one is drawn); None without a skin."""
        if not self.levels:
            return None
        skin = self.skin
        error = None
        if self.joint_error is not None:
            per_rotating = np.zeros(topo.N_ROTATING)  # wrist 0, then each articulated joint's ASM row
            per_rotating[1:] = np.nan_to_num(self.joint_error[frame, topo.ARTICULATED_JOINTS - 1])
            error = skin.hand.mesh.weights @ per_rotating
        return PosedSkin(frame, skin, to_view(skin.hand, skin_vertices(skin.hand, self.pose, frame)), error)

    def show(self, frame: int, posed: PosedSkin | None = None) -> None:
        """Pose the hand at ``frame``; ``posed``: its `posed_skin`, if computed ahead (used when it is that
        frame's and the skin drawn now)."""
        self.frame = frame
        if self.overlay is not None:
            self.overlay.show(frame)
        if self.keypoints is not None:
            self.keypoints.show(frame)
        if not self.levels:
            self.bones.points = self.palm.points = to_view(self.hand,
                                                           self.pose.positions[frame].numpy().astype(np.float64))
            return
        if posed is None or posed.frame != frame or posed.skin is not self.skin:
            posed = self.posed_skin(frame)
        skin = posed.skin
        skin.points[:] = posed.points  # in place, through views made once: no new VTK arrays or wrappers per frame
        skin.mesh.GetPoints().Modified()
        if posed.error is not None:
            skin.error[:] = posed.error
            skin.mesh.GetPointData().GetArray("error").Modified()

    def set_result(self, pose: HandPose, joint_error: np.ndarray | None, text: str) -> None:
        """Another motion on the same hand (a corrected retarget): posed, coloured and labelled from it now."""
        self.pose, self.joint_error = pose, joint_error
        self._reach = None  # its frames reach elsewhere now
        if self.overlay is not None:
            self.overlay.set_pose(pose)
        if self.label is not None:
            self.label.set_text(text)
        self.show(self.frame)

    def set_framed(self, selected: bool) -> None:
        """Frame the cell: in `SELECTED_COLOUR` when it is the selected retarget, else in the banner's colour if
        its frames are unsure, else not at all."""
        colour, width = (SELECTED_COLOUR, SELECTED_WIDTH) if selected else (BANNER_COLOUR, 2.0)
        if not selected and not self.warned:
            if self.border is not None:
                self.border.SetVisibility(False)
            return
        if self.border is None:
            self.border = self.renderer.add_border(color=colour, width=width)
        self.border.GetProperty().SetColor(pv.Color(colour).float_rgb)
        self.border.GetProperty().SetLineWidth(2 * width)  # pyvista doubles it: half is clipped at the edge
        self.border.SetVisibility(True)

    def joint_under(self, x: float, y: float) -> int | None:
        """The articulated joint (`topology.ARTICULATED_NAMES` index) whose bone the skin drawn at display pixel
        (x, y) moves most (its vertex's largest skinning weight): a click on a finger's skin picks the joint
        turning that part, the front one where fingers overlap on screen. None off the skin or on the palm."""
        skin = self.skin
        if skin is None or not skin.actor.visibility:
            return None
        picker = vtkCellPicker()
        picker.SetTolerance(0.0)
        picker.PickFromListOn()
        picker.AddPickList(skin.actor)
        if not picker.Pick(x, y, 0.0, self.renderer):
            return None
        corners = np.asarray(skin.mesh.get_cell(picker.GetCellId()).point_ids)
        vertex = corners[np.linalg.norm(skin.points[corners] - picker.GetPickPosition(), axis=1).argmin()]
        column = int(np.argmax(skin.hand.mesh.weights[vertex]))
        return column - 1 if column > 0 else None  # column 0: the wrist's (the palm)

    def set_opacity(self, opacity: float) -> None:
        """See-through below 1; an opaque closed skin skips its back faces (about a third of the drawing)."""
        for level in self.levels:
            level.actor.prop.opacity = opacity
            level.actor.prop.culling = "back" if level.closed and opacity >= 1.0 else "none"


def is_closed_outward(mesh: pv.PolyData) -> bool:
    """Watertight with outward-facing triangles: only then are its back faces never seen."""
    closed = trimesh.Trimesh(np.asarray(mesh.points), mesh.regular_faces, process=False)
    return bool(closed.is_watertight and closed.is_winding_consistent and closed.volume > 0)


def grid_layout(comparison: Comparison, rows: int | None = None) -> dict:
    """Plotter keywords for the grid: a row per target (``rows`` at least: a last page of fewer targets keeps
    its pages' row height, so its hands keep their scale), a column per method after the source's column
    (the source drawn once, top left, in a cell the size of the others so every hand has the same
    scale), and a narrow last column, merged over the rows, for the colour bar (it covers no hand)."""
    targets = len(dict.fromkeys(id(r.target) for r in comparison.results)) or 1
    columns = 1 + len(comparison.results) // targets
    rows = max(targets, rows or 0)
    groups = [(np.s_[:], columns)] + ([(np.s_[1:], 0)] if rows > 2 else [])
    return {"shape": (rows, columns + 1), "groups": groups, "border": False,
            "col_weights": [1.0] * columns + [columns * COLOUR_BAR_SHARE / (1.0 - COLOUR_BAR_SHARE)]}


def source_cell_below(plotter: pv.Plotter) -> tuple[int, int] | None:
    """The empty cell under the source (a grid of two rows or more: two targets, or a last page of one that keeps
    its pages' rows), where the clip's legend goes; in the source's cell, it covered a short cell's hand."""
    return (1, 0) if plotter.shape[0] > 1 else None


def plain_text() -> None:
    """Draw every VTK text as it is written: by default VTK hands a string holding '|' or '$' to its MathText
    backend, which makes '|' a column break (an FBX take "Armature|counting" read "Armature   counting")."""
    import vtkmodules.vtkRenderingFreeType  # noqa: F401  (registers the text renderer GetInstance returns)
    vtkTextRenderer.GetInstance().SetDefaultBackend(vtkTextRenderer.FreeType)


@dataclass
class CellLabel:
    """A cell's text at its top left: the full text kept, drawn in the cell's font size (`label_font`) with each
    line elided to the cell's width, so a long name ends in an ellipsis instead of being cut at the cell's edge."""

    renderer: pv.Renderer
    actor: pv.Text
    text: str
    fitted: tuple = ()  # the cell's size and the font it was last fitted to
    bottom: bool = False  # a banner: at the cell's bottom left, one line
    shorter: tuple[str, ...] = ()  # the text said in fewer words, longest first: the first that fits is drawn

    def set_text(self, text: str) -> None:
        """New text, fitted to its cell at the next `fit_cells`."""
        self.text, self.fitted = text, ()

    def fit(self, width: int, height: int, font: tuple[int, int]) -> None:
        """Draw it in a ``width`` x ``height`` pixel cell with ``font`` (`label_font`'s size and lines kept)."""
        if (width, height, font) == self.fitted:
            return
        self.fitted = (width, height, font)
        px, lines = font
        self.actor.prop.font_size = px
        room = width - 2 * LABEL_PAD
        text = self.text
        if self.shorter and text_extent(text, px)[0] > room:
            text = next((t for t in self.shorter if text_extent(t, px)[0] <= room), self.shorter[-1])
        kept = text.split("\n")[:lines]
        self.actor.SetInput("\n".join(elide(line, px, room) for line in kept))
        self.actor.SetPosition(LABEL_PAD / width, LABEL_PAD / height if self.bottom else 1.0 - LABEL_PAD / height)


    def drawn_height(self) -> int:
        """Pixels from the cell's edge to past the text's far side as last fitted (0 before a fit)."""
        if not self.fitted:
            return 0
        return text_extent(self.actor.GetInput(), self.fitted[2][0])[1] + 2 * LABEL_PAD


def add_banner(plotter: pv.Plotter, text: str, shorter: tuple[str, ...] = ()) -> CellLabel:
    """A warning at the bottom left of the current subplot, dark on a light orange band, fitted as the labels
    (``shorter``: the same in fewer words, longest first, drawn where the whole does not fit)."""
    actor = plotter.add_text(text, position=(0.02, 0.02), viewport=True, color=BANNER_COLOUR)
    actor.prop.font_size = LABEL_PX
    actor.prop.SetFontFamilyToArial()
    actor.prop.SetVerticalJustificationToBottom()
    actor.prop.SetBackgroundColor(pv.Color(BANNER_BACKGROUND).float_rgb)
    actor.prop.SetBackgroundOpacity(1.0)
    return CellLabel(plotter.renderer, actor, text, bottom=True, shorter=shorter)


def add_label(plotter: pv.Plotter, text: str) -> CellLabel:
    """Text at the top left of the current subplot, in pixels whatever the cell's size (pyvista's corner
    annotation scales its font with the viewport: five methods made it unreadably small); `CellLabel.fit` sizes it."""
    actor = plotter.add_text(text, position=(0.02, 0.98), viewport=True, color="black")
    actor.prop.font_size = LABEL_PX
    actor.prop.SetFontFamilyToArial()  # the family `text_extent` measures
    actor.prop.SetVerticalJustificationToTop()
    return CellLabel(plotter.renderer, actor, text)


@lru_cache(maxsize=16)
def _text_property(px: int) -> vtkTextProperty:
    """A text property as the labels': Arial at ``px`` pixels (VTK's default line spacing)."""
    prop = vtkTextProperty()
    prop.SetFontFamilyToArial()
    prop.SetFontSize(px)
    return prop


def text_extent(text: str, px: int) -> tuple[int, int]:
    """Width and height in pixels of ``text`` at ``px`` pixels, as VTK will draw it (its own glyph measure)."""
    plain_text()
    box = [0, 0, 0, 0]
    with TEXT_LOCK:
        vtkTextRenderer.GetInstance().GetBoundingBox(_text_property(px), text, box, TEXT_DPI)
    return box[1] - box[0] + 1, box[3] - box[2] + 1


@lru_cache(maxsize=64)
def band_height(lines: int, px: int) -> int:
    """Pixels from a cell's top to below ``lines`` lines of its label at ``px``, with a LABEL_PAD above and below."""
    return text_extent("\n".join([WIDEST_LINE] * lines), px)[1] + 2 * LABEL_PAD


@lru_cache(maxsize=256)
def label_font(width: int, height: int, largest: int = LABEL_PX) -> tuple[int, int]:
    """The labels' font size and lines kept in a ``width`` x ``height`` pixel cell: the largest size up to
    LABEL_PX whose widest line fits the width and whose band BAND_SHARE of the height; else MIN_LABEL_PX with
    the lines whose band fits MAX_BAND_SHARE (the title at least), so the hand keeps most of a small cell."""
    for px in range(largest, MIN_LABEL_PX - 1, -1):
        if (text_extent(WIDEST_LINE, px)[0] <= width - 2 * LABEL_PAD
                and band_height(LABEL_LINES, px) <= BAND_SHARE * height):
            return px, LABEL_LINES
    lines = next((n for n in range(LABEL_LINES, 1, -1) if band_height(n, MIN_LABEL_PX) <= MAX_BAND_SHARE * height), 1)
    return MIN_LABEL_PX, lines


def text_band(width: int, height: int, largest: int = LABEL_PX) -> int:
    """Pixels at the top of a ``width`` x ``height`` cell kept for its label: the hand is drawn below them."""
    px, lines = label_font(width, height, largest)
    return band_height(lines, px)


#: what ends a target's name told apart from another's (`retarget.comparison.distinct_name`): " (left)", " (fbx)",
#: " #2"; an elided line keeps it (two cells read "TBS Copy -> human-female…" for both hands: a fresh-eyes user)
_TELLER = re.compile(r" (\([a-z0-9]{1,6}\)|#\d+)$")


def elide(line: str, px: int, width: int) -> str:
    """``line`` whole if it fits ``width`` pixels at ``px``, else its longest start that fits with an ellipsis,
    and the end that tells a target from another's if the line has one (`_TELLER`) and there is room for it."""
    if text_extent(line, px)[0] <= width:
        return line
    teller = _TELLER.search(line)
    end = teller.group(0) if teller and text_extent(ELLIPSIS + teller.group(0), px)[0] < width / 2 else ""
    line = line[:len(line) - len(end)]
    low, high = 0, len(line)  # the longest start that fits with the ellipsis: binary search on its length
    while low < high:
        mid = (low + high + 1) // 2
        fits = text_extent(line[:mid].rstrip() + ELLIPSIS + end, px)[0] <= width
        low, high = (mid, high) if fits else (low, mid - 1)
    return line[:low].rstrip() + ELLIPSIS + end


def cell_pixels(plotter: pv.Plotter, renderer: pv.Renderer) -> tuple[int, int]:
    """The width and height in pixels of ``renderer``'s viewport in the plotter's window now."""
    width, height = plotter.render_window.GetSize()
    x0, y0, x1, y1 = renderer.GetViewport()
    return max(1, round((x1 - x0) * width)), max(1, round((y1 - y0) * height))


def label_px_for(picture_height: int) -> int:
    """The labels' largest font size in a picture ``picture_height`` pixels tall: LABEL_PX, larger in proportion
    in an export taller than LABEL_REFERENCE_HEIGHT (a 4K picture's labels read as the window's do)."""
    return max(LABEL_PX, round(LABEL_PX * picture_height / LABEL_REFERENCE_HEIGHT))


def fit_cells(plotter: pv.Plotter, hands: list["PosedHand"], labels: list[CellLabel],
              largest: int = LABEL_PX) -> None:
    """The drawn cells to their size now (the window's size and solo change it): the labels in one font, the
    smallest cell's (the grid's cells differ by a pixel of rounding, the legend's may span rows); each hand's
    overlays (`Overlays.fit`); the shared camera for a hand's cell (`fit_view_angle`)."""
    drawn = [(label, cell_pixels(plotter, label.renderer)) for label in labels if label.renderer.GetDraw()]
    if drawn:
        font = label_font(min(w for _, (w, _) in drawn), min(h for _, (_, h) in drawn), largest)
        for label, (width, height) in drawn:
            label.fit(width, height, font)
    shown = [hand for hand in hands if hand.renderer.GetDraw()]
    for hand in shown:
        if hand.overlay is not None:
            hand.overlay.fit(min(cell_pixels(plotter, hand.renderer)))
        if hand.keypoints is not None:
            hand.keypoints.fit(min(cell_pixels(plotter, hand.renderer)))
    legend = hands[0].overlay.legend if hands and hands[0].overlay is not None else None
    if legend is not None:
        legend.fit(*cell_pixels(plotter, legend.renderer))
    if shown:
        fit_view_angle(plotter, shown[0].renderer, largest, shown)


def result_label(result: MethodResult) -> str:
    """A retarget's cell text: method and target, its S_finger and kept scores (and the poses kept, of a clip of
    poses: "kept 0.538 of frames, 19/35 poses"); a corrected one's method starred
    (a start of line that survives eliding) and its keys counted; a target with no skin says its bones are drawn
    uncoloured (a fresh-eyes user saw grey sticks and no colour bar, and nothing said why), and a mitten's skin
    that its bones are drawn through it (`apply_options`: another read its see-through skin against the View
    menu's unticked "Semi-transparent skin")."""
    keys = result.corrections.n_keys
    star, fixed = ("*", f", {counted(keys, 'fix', 'fixes')}") if keys else ("", "")
    bones = (", no skin: bones" if result.target.mesh is None else
             ", mitten: bones" if result.target.meta.get("unparted_fingers") else "")
    # two measures, each named: "kept 0.538 (19/35 poses)" read as one figure that did not add up (two users)
    poses = (f" of frames, {result.poses_held - len(result.poses_lost)}/{result.poses_held} poses"
             if result.poses_held else "")
    return (f"{METHODS[result.method].label}{star} -> {result.target.name}\nS_finger {result.scores.s_finger:.3f}\n"
            f"kept {result.scores.signature_kept:.3f}{poses}{fixed}{bones}")


#: the source cell's banner where the source's skeleton rests in a pose (`semantics.rest_pose`)
SOURCE_IN_POSE = "! rests in a pose: give the rig it was made for"


def populate(plotter: pv.Plotter, comparison: Comparison, opacity: float = 1.0,
             display_faces: int | None = DISPLAY_FACES,
             playing_faces: int | None = None) -> tuple[list[PosedHand], list[CellLabel]]:
    """Fill a plotter made with ``**grid_layout(comparison)``; returns the hands to update per frame and the
    cells' labels, fitted to the window's size now (`fit_cells` again when it changes).
    ``playing_faces``: each skin also at that many faces, drawn while playing (`PosedHand.set_playing`)."""
    plain_text()
    for renderer in plotter.renderers:  # every cell white: the hands', the legends', a last page's empty rows
        renderer.set_background("white")
    lighter: dict[tuple[int, int | None], HandModel] = {}

    def light(hand: HandModel, faces: int | None) -> HandModel:
        if faces is None:
            return hand
        if (id(hand), faces) not in lighter:
            lighter[id(hand), faces] = display_hand(hand, faces)
        return lighter[id(hand), faces]

    source_contacts = touching_and_near(comparison.source, comparison.source_pose)
    fit = comparison.motion.fit
    panels = [((0, 0), comparison.source, comparison.source_pose, None, None,
               f"source: {comparison.source.name}" + ("" if fit is None else
                                                     f"\ntracked: fit residual {np.nanmean(fit.residual_mm):.1f} mm"))]
    for row, target in enumerate(dict.fromkeys(id(r.target) for r in comparison.results)):
        results = [r for r in comparison.results if id(r.target) == target]
        panels += [((row, 1 + k), r.target, r.pose, r.joint_error, source_contacts, result_label(r))
                   for k, r in enumerate(results)]
    hands, labels = [], []
    for cell, hand, pose, error, expected, label in panels:
        plotter.subplot(*cell)
        plotter.renderer.remove_all_lights()  # one light that follows the camera: a quarter of the
        plotter.renderer.add_light(pv.Light(light_type="headlight"))  # shading cost of pyvista's five-light kit
        posed = PosedHand(plotter, light(hand, display_faces), pose, error, opacity,
                          playing_hand=None if playing_faces is None else light(hand, playing_faces))
        posed.overlay = Overlays(plotter, hand, pose, expected)
        posed.renderer = plotter.renderer
        if cell == (0, 0) and fit is not None:
            posed.keypoints = KeypointDots(plotter, hand, fit.keypoints, fit.filled)
        hands.append(posed)
        posed.label = add_label(plotter, label)
        labels.append(posed.label)
        warning = frame_warning(hand) if expected is not None else None
        if warning is not None:  # the banner at the cell's bottom, the cell framed: it is not the next row's
            whole, *fewer = (f"! {banner}" for banner in warning.banners)
            posed.banner, posed.banner_tip = add_banner(plotter, whole, tuple(fewer)), warning.describe()
            posed.warned = True
            posed.set_framed(False)
        elif expected is None and hand.meta.get("rest_note"):  # a skeleton-only source resting in a pose
            posed.banner = add_banner(plotter, SOURCE_IN_POSE)
            posed.banner_tip = (f"{hand.name}: {hand.meta['rest_note']}; open the clip again and give the rig it "
                                f"was made for")
        if posed.banner is not None:
            labels.append(posed.banner)
    below = source_cell_below(plotter)
    if below is not None:
        plotter.subplot(*below)
        labels.append(add_label(plotter, f"clip: {comparison.motion.name}\n{comparison.n_frames} frames at "
                                         f"{comparison.motion.fps:g} fps"))
    plotter.subplot(*(below or (0, 0)))  # the clip's cell, else the source's: the contact colours' legend
    hands[0].overlay.legend = ContactLegend(plotter)
    coloured = next((h.error_actor for h in hands if h.error_actor is not None), None)
    plotter.subplot(0, plotter.shape[1] - 1)
    if coloured is not None:
        bar = plotter.add_scalar_bar("1 - cos", mapper=coloured.mapper, vertical=True, position_x=0.25,
                                     position_y=0.1, height=0.8, width=0.4, title_font_size=10, label_font_size=9,
                                     color="black", n_labels=4, fmt="%.2f")
        bar.SetVerticalTitleSeparation(12)  # pixels: the title clear of the top label, not over it
    plotter.link_views()
    fit_cells(plotter, hands, labels)
    set_camera(plotter, "default", [h.hand for h in hands])
    return hands, labels


def show_alone(plotter: pv.Plotter, hands: list[PosedHand], viewports: list[tuple[float, ...]], index: int) -> None:
    """Hand ``index``'s cell alone over the whole grid (its colour bar beside a retarget, the contacts' legend
    in it), -1: the grid again; ``viewports`` the renderers' grid viewports."""
    solo = hands[index].renderer if index >= 0 else None
    for renderer, viewport in zip(plotter.renderers, viewports):
        renderer.SetViewport(*((0.0, 0.0, 1.0, 1.0) if renderer is solo else viewport))
        renderer.SetDraw(solo is None or renderer is solo)
    legend = hands[0].overlay.legend if hands and hands[0].overlay is not None else None
    if legend is not None:  # the contacts' legend with the hand alone (its own cell is not drawn then)
        there = solo if solo is not None else legend.home
        legend.move_to(there, right=there is not legend.home)
    if index >= 0 and hands[index].error_actor is not None:
        colour_bar_beside_solo(plotter)  # a retarget alone keeps the colour bar of its error colours


def colour_bar_beside_solo(plotter: pv.Plotter) -> None:
    """A retarget shown alone keeps the colour bar of its error colours: the one hand viewport drawn gives
    the bar's column (its share of the grid's width) back to the bar, drawn again on the right."""
    bar = plotter.renderers[plotter.renderers.loc_to_index((0, plotter.shape[1] - 1))]
    solo = next(r for r in plotter.renderers if r.GetDraw() and r is not bar)
    solo.SetViewport(0.0, 0.0, 1.0 - COLOUR_BAR_SHARE, 1.0)
    bar.SetViewport(1.0 - COLOUR_BAR_SHARE, 0.0, 1.0, 1.0)
    bar.SetDraw(True)


#: the grid's camera presets (`scene.CAMERA_DIRECTIONS`), "default" the three-quarter view
CAMERA_PRESETS = {"default" if name == "three_quarter" else name: direction
                  for name, direction in CAMERA_DIRECTIONS.items()}


VIEW_ANGLE = 30.0  # degrees, vertical
FIT_ASPECT = 0.65  # width / height of a cell's hand part under which a hand's width would not fit at VIEW_ANGLE
#: the camera's distance from the palm centre, in lengths of the largest hand (`set_camera`)
CAMERA_DISTANCE = 3.0
#: a skeleton's drawn bones' reach beyond its joints, in lengths of the hand
BONE_MARGIN = 0.02
#: a skeleton-only hand's joints, as dots this many pixels across
JOINT_DOT_PX = 9
#: room kept around the hands' reach, as a share of it: a hand reaching furthest keeps clear of its cell's frame
REACH_ROOM = 1.08


def fit_view_angle(plotter: pv.Plotter, renderer, largest: int = LABEL_PX,
                   hands: list[PosedHand] | None = None) -> None:
    """Fit the shared camera to ``renderer``'s cell (every hand's cell has its size): the hand drawn below the
    cell's text band (`text_band`), the picture moved down by the band (the camera's window centre up) and the
    view angle widened so the part below it shows what the whole cell showed at VIEW_ANGLE; more where that
    part is narrower than FIT_ASPECT (one target: tall cells), and more where one of ``hands`` reaches past the
    part's sides or ends in some frame of its clip, seen from the camera's side at its preset distance (five
    methods' narrow cells cut the thumb of a thumbs-up seen from the palm). Zooming moves the camera, not the
    angle, so calling this before every render keeps the user's zoom."""
    width, height = cell_pixels(plotter, renderer)
    band = min(text_band(width, height, largest), height - 1) / height  # of the cell's height
    widen = max(1.0, FIT_ASPECT * (1.0 - band) * height / width) / (1.0 - band)
    if hands:  # tangents: the hands' reach against what the view shows at VIEW_ANGLE
        across, along = _reach_from_camera(plotter.camera, hands,
                                           CAMERA_DISTANCE * max(h.hand.hand_length for h in hands))
        seen = np.tan(np.radians(VIEW_ANGLE / 2)) / REACH_ROOM
        widen = max(widen, across * height / (seen * width), along / (seen * (1.0 - band)))
    plotter.camera.view_angle = 2.0 * np.degrees(np.arctan(np.tan(np.radians(VIEW_ANGLE / 2)) * widen))
    plotter.camera.SetWindowCenter(0.0, band)  # in [-1, 1] over the cell: the hand's part's middle at its centre


def _hull_corners(points: np.ndarray) -> np.ndarray:
    """The indices of the corners of the convex hull of (N, 3) ``points`` (all where they span no volume)."""
    if len(points) >= 5:
        try:
            return ConvexHull(points).vertices
        except QhullError:  # flat, or a single pose of a skeleton on a line
            pass
    return np.arange(len(points))


def _reach_from_camera(camera: pv.Camera, hands: list[PosedHand], distance: float) -> tuple[float, float]:
    """How far ``hands`` reach from the middle of the view, across it and along its up axis, as the tangents of
    their angles seen from the camera's direction at ``distance`` from its focal point (perspective: a thumb
    held toward the camera looks longer), over their clips, skin included."""
    position, focal, up = (np.asarray(v, dtype=np.float64) for v in (camera.position, camera.focal_point, camera.up))
    forward = focal - position
    forward /= max(np.linalg.norm(forward), 1e-12)
    up = up - forward * (up @ forward)
    up /= max(np.linalg.norm(up), 1e-12)
    right = np.cross(forward, up)
    eye = focal - forward * distance
    across = along = 0.0
    for hand in hands:
        joints, around, rigid = hand.reach
        for points, margin in ((joints, around), (rigid, 0.0)):
            if not len(points):
                continue
            offsets = points - eye
            depth = np.maximum(offsets @ forward, 1e-6)
            across = max(across, float(((np.abs(offsets @ right) + margin) / depth).max()))
            along = max(along, float(((np.abs(offsets @ up) + margin) / depth).max()))
    return across, along


def set_camera(plotter: pv.Plotter, preset: str, hands: list[HandModel]) -> None:
    """Point the shared camera at the palm centre from a preset direction, far enough for the largest hand
    (every viewport shares the camera and has the same size: one scale for source and targets)."""
    direction, up = CAMERA_PRESETS[preset]
    extent = max(h.hand_length for h in hands)
    d = np.asarray(direction) / np.linalg.norm(direction)
    centre = np.array([0.4, 0.0, 0.0]) * extent  # the palm frame's origin is the wrist; fingers along x
    camera = plotter.camera
    camera.focal_point = centre
    camera.position = centre + d * extent * CAMERA_DISTANCE
    camera.up = up
    fit_view_angle(plotter, plotter.renderers[0])  # the source's cell: the size of every hand's
    for renderer in plotter.renderers:
        renderer.ResetCameraClippingRange()


class Overlays:
    """A hand's skeleton and its contacts, drawn over the skin when switched on: each contact a link between
    its two pads (round dots), in `CONTACT_STATES`' colours: on a retarget, kept, lost (the source's, missed)
    and invented (made where the source does not come near, `contacts.touching_and_near`); on the source, its own
    (kept).
    ``expected``: the source's contacts and its near ones, (T, 15) bool each; None on the source."""

    def __init__(self, plotter: pv.Plotter, hand: HandModel, pose: HandPose,
                 expected: tuple[np.ndarray, np.ndarray] | None):
        self.hand, self.expected = hand, expected
        self.set_pose(pose)
        self.legend: ContactLegend | None = None  # on the source's overlays: the one legend of the grid
        self.bones = skeleton(hand, pose, 0)
        self.polys = [pv.PolyData(self.sites[0]) for _ in CONTACT_STATES]
        self.links, self.lost_links, self.invented_links = self.polys  # kept, lost, invented
        bone, link, dot = OVERLAY_PX
        self.actors = [plotter.add_mesh(self.bones, color=BONE_COLOUR, line_width=bone, reset_camera=False)]
        self.actors += [plotter.add_mesh(poly, color=colour, line_width=link, point_size=dot,
                                         render_points_as_spheres=True, reset_camera=False)
                        for poly, (_, colour) in zip(self.polys, CONTACT_STATES)]
        # contacts drawn over the skin: the pads' centres lie inside the fingers (an opaque hand shown alone hid
        # every one). The offsets act only in VTK's polygon-offset mode, which is process-wide (a static).
        vtkMapper.SetResolveCoincidentTopologyToPolygonOffset()
        for actor in self.actors[1:]:
            actor.mapper.SetRelativeCoincidentTopologyPointOffsetParameter(ON_TOP_OFFSET)
            actor.mapper.SetRelativeCoincidentTopologyLineOffsetParameters(0.0, ON_TOP_OFFSET)
        self.show_skeleton = self.show_contacts = False
        self._update_visibility()

    def set_pose(self, pose: HandPose) -> None:
        """The contacts in their states and the pads of ``pose`` (every frame)."""
        self.pose = pose
        self.contacts = detect_contacts(self.hand, pose)
        if self.expected is None:
            self.lost = self.invented = None
            self.states = [self.contacts, None, None]
        else:
            touching, near = self.expected
            self.lost, self.invented = touching & ~self.contacts, self.contacts & ~near
            self.states = [self.contacts & touching, self.lost, self.invented]
        self.sites = to_view(self.hand, contact_sites(self.hand, pose))  # (T, 6, 3)

    def fit(self, short_side: int) -> None:
        """Bones, links and dots sized for a cell ``short_side`` pixels on its short side (`OVERLAY_PX`)."""
        scale = min(1.0, short_side / OVERLAY_CELL)
        bone, link, dot = (max(least, round(px * scale)) for px, least in zip(OVERLAY_PX, OVERLAY_LEAST))
        for actor in self.actors:
            width, size = (bone, None) if actor is self.actors[0] else (link, dot)
            if actor.prop.line_width != width:  # set only when it changes: this runs before every render
                actor.prop.line_width = width
            if size is not None and actor.prop.point_size != size:
                actor.prop.point_size = size

    def set_visible(self, skeleton_on: bool, contacts_on: bool) -> None:
        self.show_skeleton, self.show_contacts = skeleton_on, contacts_on
        self._update_visibility()

    def _update_visibility(self) -> None:
        self.actors[0].visibility = self.show_skeleton
        for actor in self.actors[1:]:
            actor.visibility = self.show_contacts
        if self.legend is not None:
            self.legend.actor.SetVisibility(self.show_contacts)

    def show(self, frame: int) -> None:
        if self.show_skeleton:
            self.bones.points = to_view(self.hand, self.pose.positions[frame].numpy().astype(np.float64))
        if self.show_contacts:
            for poly, state in zip(self.polys, self.states):
                mask = None if state is None else state[frame]
                pairs = PAIR_SITES[mask] if mask is not None and mask.any() else np.zeros((0, 2), dtype=np.int64)
                poly.points = self.sites[frame]
                poly.lines = np.column_stack([np.full(len(pairs), 2), pairs]).ravel() if len(pairs) else \
                    np.zeros(0, dtype=np.int64)
                sites = np.unique(pairs)  # the pads involved, as dots at either end of the link
                poly.verts = np.column_stack([np.ones(len(sites), dtype=np.int64), sites]).ravel() if len(sites) \
                    else np.zeros(0, dtype=np.int64)

    def link_at(self, renderer, x: float, y: float, frame: int, reach: float) -> tuple[int, int] | None:
        """The contact link drawn nearest display pixel (x, y) of ``renderer`` (VTK's: from the bottom left) at
        ``frame``, within ``reach`` pixels: (its pair, its state) as indices into `CONTACT_PAIRS` and
        `CONTACT_STATES`; None where the overlay is off or no link is drawn there."""
        if not self.show_contacts:
            return None
        ends = []
        for site in self.sites[frame]:
            renderer.SetWorldPoint(*site, 1.0)
            renderer.WorldToDisplay()
            ends.append(renderer.GetDisplayPoint()[:2])
        ends = np.asarray(ends)
        drawn = [(pair, state) for state, mask in enumerate(self.states) if mask is not None
                 for pair in np.flatnonzero(mask[frame])]
        if not drawn:
            return None
        pairs = PAIR_SITES[[pair for pair, _ in drawn]]
        away = distance_to_segments(np.array([x, y], dtype=float), ends[pairs[:, 0]], ends[pairs[:, 1]])
        nearest = int(np.argmin(away))
        return (int(drawn[nearest][0]), drawn[nearest][1]) if away[nearest] <= reach else None


def contact_words(pair: int, state: int, on_source: bool) -> str:
    """A contact link in words (its tooltip): which pads it joins and what its colour means, and which score
    counts it: the fingertip pairs in Contact P/R, the fingertip-on-palm ones in Palm R (a fresh-eyes user read
    green links beside a Contact R of 0 as a contradiction: they were fingertips on the palm)."""
    a, b = CONTACT_PAIRS[pair]
    what = f"{a} fingertip on the palm" if b == "palm" else f"{a}-{b} fingertips"
    counted_in = "Palm R" if b == "palm" else "Contact P/R"
    if on_source:
        return f"{what}: the source's contact (counted in {counted_in})"
    meaning = ("in contact, as in the source", "lost: the source's contact, not made here",
               "invented: made here where the source's pair is apart")[state]
    return f"{what}: {meaning} (counted in {counted_in})"


class ContactLegend:
    """What the contact overlay's colours mean, at the bottom left of the current subplot, `LEGEND_PX` in size
    whatever the cell's (`fit`); shown with the contact overlay."""

    def __init__(self, plotter: pv.Plotter):
        self.home = self.renderer = plotter.renderer
        self.actor = plotter.add_legend([[text, colour] for text, colour in CONTACT_STATES], bcolor="white",
                                        face="circle", size=(0.5, 0.2), loc="lower left")
        self.actor.SetVisibility(False)
        self.fitted: tuple = ()
        self.right = False  # at the bottom right (of a hand shown alone: its bottom left may hold a banner)

    def move_to(self, renderer, right: bool) -> None:
        """Draw it in ``renderer``'s cell (a hand shown alone, whose cell alone is drawn: the legend's own cell is
        not), at its bottom right with ``right``; fitted again at the next `fit`."""
        self.renderer.RemoveActor(self.actor)
        renderer.AddActor(self.actor)
        self.renderer, self.right, self.fitted = renderer, right, ()

    def fit(self, width: int, height: int) -> None:
        if (width, height) == self.fitted:
            return
        self.fitted = (width, height)
        w, h = min(1.0, LEGEND_PX[0] / width), min(0.5, LEGEND_PX[1] / height)
        x = 1.0 - w - LABEL_PAD / width if self.right else LABEL_PAD / width
        self.actor.GetPositionCoordinate().SetValue(x, LABEL_PAD / height)
        self.actor.GetPosition2Coordinate().SetValue(w, h)


class Ghost:
    """The source drawn see-through over a retarget's cell (what it should look like): its skin as the source's
    cell poses it (its bones for a skeleton-only source), aligned at the wrist (both hands in view space, the
    wrist at the origin) and scaled by the hands' lengths, so a finger that goes astray shows beside its ghost."""

    def __init__(self, source: PosedHand, target: PosedHand):
        self.source = source
        self.scale = target.hand.hand_length / source.hand.hand_length
        shape = source.mesh if source.levels else source.bones
        self.mesh = shape.copy(deep=True)
        self.actor = pv.Actor(mapper=pv.DataSetMapper(self.mesh))
        self.actor.prop.color = GHOST_COLOUR if source.levels else GHOST_BONES_COLOUR
        self.actor.prop.opacity = GHOST_OPACITY if source.levels else GHOST_BONES_OPACITY
        if not source.levels:
            self.actor.prop.line_width = 4
        self.renderer = target.renderer
        self.renderer.add_actor(self.actor, reset_camera=False, render=False)
        self.actor.visibility = False

    def follow(self) -> None:
        """Take the source's pose as its cell shows it now (call after the source is posed)."""
        shape = self.source.mesh if self.source.levels else self.source.bones
        if shape.n_points != self.mesh.n_points:  # the source's other level of detail: its triangles
            self.mesh.copy_from(shape, deep=True)
        self.mesh.points = np.asarray(shape.points) * self.scale

    def set_visible(self, visible: bool) -> None:
        self.actor.visibility = visible

    def remove(self) -> None:
        self.renderer.remove_actor(self.actor, reset_camera=False, render=False)


def solo_ghost(hands: list[PosedHand], options: ViewOptions, solo: int) -> Ghost | None:
    """The source's ghost over retarget hand ``solo`` shown alone, if the options ask for one (else None)."""
    if not options.ghost or solo < 1:
        return None
    ghost = Ghost(hands[0], hands[solo])
    ghost.set_visible(True)
    ghost.follow()
    return ghost


def contact_sites(hand: HandModel, pose: HandPose) -> np.ndarray:
    """(T, 6, 3) float64: the five fingertip pads and the palm centre, in hand space."""
    positions = pose.positions.detach()
    pads = pad_centres(positions).numpy()
    palm = positions[:, list(topo.KNUCKLE_JOINTS[1:]) + [0]].mean(1, keepdim=True).numpy()
    return np.concatenate([pads, palm], 1).astype(np.float64)


@dataclass(frozen=True)
class ViewOptions:
    """How the grid is drawn: the camera preset, the overlays, the skin's opacity."""

    camera: str = "default"
    skeleton: bool = False
    contacts: bool = False
    keypoints: bool = True  # a tracked source's recorded keypoints
    opacity: float = 1.0
    ghost: bool = False  # the source's ghost over a retarget shown alone


SKELETON_OPACITY = 0.4  # the skin's opacity at most while the skeleton overlay is on: bones inside show


def apply_options(plotter: pv.Plotter, hands: list[PosedHand], options: ViewOptions, camera: bool = True) -> None:
    """Opacity and overlays; with ``camera``, the camera preset too (else the camera stays where it is)."""
    for hand in hands:
        # a skin that does not part the fingers (a mitten) cannot show them: its bones are always drawn
        skeleton_on = options.skeleton or bool(hand.hand.meta.get("unparted_fingers"))
        hand.set_opacity(min(options.opacity, SKELETON_OPACITY) if skeleton_on else options.opacity)
        hand.overlay.set_visible(skeleton_on, options.contacts)
        if hand.keypoints is not None:
            hand.keypoints.set_visible(options.keypoints)
    if camera:
        set_camera(plotter, options.camera, [h.hand for h in hands])


@dataclass(frozen=True)
class Framing:
    """What of the window an off-screen render keeps: its camera (position, focal point, up; None: the options'
    preset), the hand shown alone (-1: the grid) and the selected retarget framed (-1: none)."""

    camera: tuple | None = None
    solo: int = -1
    selected: int = -1

    def apply(self, plotter: pv.Plotter, hands: list[PosedHand]) -> None:
        for index, hand in enumerate(hands[1:]):
            hand.set_framed(index == self.selected)
        if self.solo >= 0:
            show_alone(plotter, hands, [tuple(r.GetViewport()) for r in plotter.renderers], self.solo)
        if self.camera is not None:
            camera = plotter.camera
            camera.position, camera.focal_point, camera.up = self.camera
            fit_view_angle(plotter, hands[max(self.solo, 0)].renderer)
            for renderer in plotter.renderers:
                renderer.ResetCameraClippingRange()


def render_comparison(comparison: Comparison, path: str | Path, frame: int | None = None,
                      size: tuple[int, int] = (1400, 900),
                      progress: Callable[[int, int], None] | None = None,
                      caption: Callable[[int], str] | None = None,
                      options: ViewOptions = ViewOptions(), frames: range | None = None,
                      framing: Framing = Framing(), band: int | None = None) -> Path:
    """Off screen: one frame as PNG (``frame``, default 0), or ``frames`` (default: every frame) as MP4/GIF
    (by suffix), ``size`` pixels whatever the window's; ``framing``: the window's camera, solo and selection.

    ``caption(frame)`` adds a line under each image (``frame`` the clip's index) in a band of ``band`` pixels
    (default `caption.BAND`) under the ``size``; ``progress(done, total)``
    counts the images rendered of those asked, is called after every one and may raise
    (``retarget.progress.Cancelled``) to stop: nothing is written then."""
    from s2h_viewer.io.atomic import atomic_path
    from s2h_viewer.render.caption import BAND, add_caption
    from s2h_viewer.render.video import VIDEO_SUFFIXES, write_video

    path = Path(path)
    with TEXT_LOCK:  # its labels laid out and first drawn while the window draws none (an export's worker thread)
        plotter = pv.Plotter(off_screen=True, window_size=size, **grid_layout(comparison))
        plotter.render_window.SetMultiSamples(0)
        hands, labels = populate(plotter, comparison)
        apply_options(plotter, hands, options)
        framing.apply(plotter, hands)
        ghost = solo_ghost(hands, options, framing.solo)
        fit_cells(plotter, hands, labels, label_px_for(size[1]))  # to the cells now (solo: the whole picture)
        plotter.show(auto_close=False)

    video = path.suffix.lower() in VIDEO_SUFFIXES
    shown = (range(comparison.n_frames) if frames is None else frames) if video else range(frame or 0, (frame or 0) + 1)

    def images() -> Iterator[np.ndarray]:
        for done, f in enumerate(shown, 1):
            for hand in hands:
                hand.show(f)
            if ghost is not None:
                ghost.follow()
            plotter.render()
            rgb = np.asarray(plotter.screenshot(return_img=True))[..., :3]
            if progress:
                progress(done, len(shown))
            yield add_caption(rgb, caption(f), band or BAND) if caption else rgb

    try:
        if video:
            return write_video(path, images(), comparison.motion.fps, len(shown))
        from PIL import Image
        with atomic_path(path) as tmp:
            Image.fromarray(next(images())).save(tmp, format="PNG")
        return path
    finally:
        plotter.close()
