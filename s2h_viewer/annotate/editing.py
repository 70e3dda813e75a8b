"""Manual corrections of TBS frames: the state an annotation session edits, the one edit it allows
(turning a joint's frame about its twist axis, which must keep following the bone), and the geometry
a rotation handle needs to turn a mouse drag into that turn."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.annotate.solver import LOW_CONFIDENCE, TbsSolution, solve_tbs_frames
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.io.annotation import Annotation, hand_side, load_annotation

#: what a session's frames came from, per ``hand.meta["annotation"]`` (a hand file without it carries its frames)
FROM_FILE = "the hand file"


def rotate_about_twist(frame: np.ndarray, degrees: float) -> np.ndarray:
    """``frame`` (3, 3) turned by ``degrees`` about its own twist axis (column 0, unchanged)."""
    turn = Rotation.from_rotvec(np.radians(degrees) * frame[:, 0]).as_matrix()
    return turn @ frame


def signed_angle_about(axis: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    """Degrees that turn ``start`` onto ``end`` about ``axis`` (right hand), both seen in the plane normal
    to ``axis``; in (-180, 180]."""
    axis = axis / np.linalg.norm(axis)
    return float(np.degrees(np.arctan2(np.dot(axis, np.cross(start, end)), np.dot(start, end))))


def ray_plane_point(origin: np.ndarray, direction: np.ndarray, centre: np.ndarray, normal: np.ndarray,
                    min_cosine: float = 0.15) -> np.ndarray | None:
    """Where the ray meets the plane through ``centre`` normal to ``normal``; None when the ray runs
    nearly along the plane (within ``min_cosine``) or away from it, where a drag would jump."""
    direction = direction / np.linalg.norm(direction)
    normal = normal / np.linalg.norm(normal)
    facing = float(np.dot(direction, normal))
    if abs(facing) < min_cosine:
        return None
    t = float(np.dot(centre - origin, normal)) / facing
    return None if t < 0 else origin + t * direction


def ring_polyline(centre: np.ndarray, frame: np.ndarray, radius: float, n: int = 96) -> np.ndarray:
    """(n, 3) points of the circle about ``frame``'s twist axis (column 0) through its bend axis (angle 0)."""
    angles = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return centre + radius * (np.cos(angles)[:, None] * frame[:, 1] + np.sin(angles)[:, None] * frame[:, 2])


def unwrap_degrees(previous_total: float, previous: float, current: float) -> float:
    """A running turn from successive angles in (-180, 180]: the ring may be dragged round more than once."""
    step = (current - previous + 180.0) % 360.0 - 180.0
    return previous_total + step


@dataclass
class AnnotationSession:
    """A hand being annotated: current frames, who set each, the solver's confidence (NaN: not scored)."""

    hand: HandModel
    hand_file: Path | None
    frames: np.ndarray = field(default=None)  # type: ignore[assignment]
    set_by: list[str] = field(default_factory=lambda: ["solver"] * topo.N_ARTICULATED)
    confidence: np.ndarray = field(default_factory=lambda: np.full(topo.N_ARTICULATED, np.nan))
    diagnostics: list[str] = field(default_factory=list)
    frames_from: str = FROM_FILE

    def __post_init__(self) -> None:
        if self.frames is None:
            self.frames = self.hand.rest_frames.copy()

    @classmethod
    def open(cls, hand: HandModel, hand_file: Path | None) -> "AnnotationSession":
        """The session of a freshly loaded hand: its sidecar's frames, set_by and confidence when the loader
        took the sidecar; the solver's confidence when the loader solved; else the file's own frames, unscored."""
        how = hand.meta.get("annotation")
        session = cls(hand, hand_file, frames_from=how or FROM_FILE)
        saved = load_annotation(hand_file, hand_side(hand)) if how == "sidecar" and hand_file is not None else None
        if saved is not None:
            session.frames = saved.frames.copy()
            session.set_by = list(saved.set_by)
            session.confidence = saved.confidence.copy()
            session.diagnostics = list(saved.diagnostics)
        elif how == "solver" and hand.mesh is not None:
            session.apply_solution(solve_tbs_frames(hand))
        return session

    def apply_solution(self, solution: TbsSolution, keep_manual: bool = False) -> None:
        """Take the solver's frames; with ``keep_manual`` the joints a person set keep theirs."""
        keep = np.array([keep_manual and by == "manual" for by in self.set_by])
        self.frames = np.where(keep[:, None, None], self.frames, solution.frames)
        self.set_by = ["manual" if k else "solver" for k in keep]
        self.confidence = np.where(keep, self.confidence, solution.confidence)
        self.diagnostics = list(solution.diagnostics)
        self.frames_from = "solver"

    def manual_joints(self) -> list[int]:
        return [j for j, by in enumerate(self.set_by) if by == "manual"]

    def needs_review(self, joint: int) -> bool:
        """A solver frame scored below `LOW_CONFIDENCE` (an unscored or manual frame is not flagged)."""
        return self.set_by[joint] == "solver" and bool(self.confidence[joint] < LOW_CONFIDENCE)

    def describe(self, joint: int) -> str:
        """The joint list's line: name, confidence (or what the frame came from), who set it, a review flag. A
        frame turned by hand says "manual": the solver's confidence no longer speaks for it."""
        name = topo.ARTICULATED_NAMES[joint]
        if self.set_by[joint] == "manual":
            return f"{name}: manual"
        score = self.confidence[joint]
        shown = f"{score:.2f}" if np.isfinite(score) else "not scored"
        by = self.set_by[joint] if np.isfinite(score) else f"from {self.frames_from}"
        flag = "  review" if self.needs_review(joint) else ""
        return f"{name}: {shown} ({by}){flag}"

    def restore(self, state: Annotation, frames_from: str) -> None:
        """Go back to a state taken with `annotation` (undo and redo of a solver run)."""
        self.frames = state.frames.copy()
        self.set_by = list(state.set_by)
        self.confidence = state.confidence.copy()
        self.diagnostics = list(state.diagnostics)
        self.frames_from = frames_from

    def annotation(self) -> Annotation:
        return Annotation(self.frames.copy(), list(self.set_by), self.confidence.copy(), list(self.diagnostics),
                          hand_side(self.hand))
