"""Manual corrections of TBS frames: the state an annotation session edits, and the one edit it allows
(turning a joint's frame about its twist axis, which must keep following the bone)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.annotate.solver import TbsSolution
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.io.annotation import Annotation


def rotate_about_twist(frame: np.ndarray, degrees: float) -> np.ndarray:
    """``frame`` (3, 3) turned by ``degrees`` about its own twist axis (column 0, unchanged)."""
    turn = Rotation.from_rotvec(np.radians(degrees) * frame[:, 0]).as_matrix()
    return turn @ frame


@dataclass
class AnnotationSession:
    """A hand being annotated: current frames, who set each, the solver's confidence."""

    hand: HandModel
    hand_file: Path | None
    frames: np.ndarray = field(default=None)  # type: ignore[assignment]
    set_by: list[str] = field(default_factory=lambda: ["solver"] * topo.N_ARTICULATED)
    confidence: np.ndarray = field(default_factory=lambda: np.ones(topo.N_ARTICULATED))
    diagnostics: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.frames is None:
            self.frames = self.hand.rest_frames.copy()

    def apply_solution(self, solution: TbsSolution) -> None:
        self.frames = solution.frames.copy()
        self.set_by = ["solver"] * topo.N_ARTICULATED
        self.confidence = solution.confidence.copy()
        self.diagnostics = list(solution.diagnostics)

    def turn(self, joint: int, degrees: float, by: str = "manual") -> None:
        self.frames[joint] = rotate_about_twist(self.frames[joint], degrees)
        self.set_by[joint] = by

    def annotation(self) -> Annotation:
        return Annotation(self.frames.copy(), list(self.set_by), self.confidence.copy(), list(self.diagnostics))
