"""`Motion`: finger rotations over time in TBS space, plus the semantic labels a synthesiser knows."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from s2h_viewer.errors import InvalidMotionError
from s2h_viewer.hand import topology as topo


@dataclass(eq=False)
class Motion:
    """``q_tbs`` (T, 15, 4) unit quaternions (w, x, y, z), identity = the hand's rest pose.

    ``labels`` (T,) names the gesture held at each frame ("" while moving between gestures);
    ``hand_name`` is the hand it was authored or retargeted on.
    """

    q_tbs: np.ndarray
    fps: float = 30.0
    name: str = ""
    hand_name: str = ""
    labels: np.ndarray = field(default=None)  # type: ignore[assignment]
    meta: dict = field(default_factory=dict)  # provenance, e.g. the gesture script and seed it was made from

    def __post_init__(self) -> None:
        self.q_tbs = np.asarray(self.q_tbs, dtype=np.float32)
        if self.labels is None:
            self.labels = np.full(len(self.q_tbs), "", dtype=object)
        self.labels = np.asarray(self.labels, dtype=object)
        self.validate()

    def validate(self) -> None:
        """Raise `InvalidMotionError` naming the motion and the problem."""
        q = self.q_tbs
        if q.ndim != 3 or q.shape[1:] != (topo.N_ARTICULATED, 4):
            raise InvalidMotionError(f"motion {self.name!r}: rotations have shape {q.shape}, expected (T, 15, 4)")
        if len(q) == 0:
            raise InvalidMotionError(f"motion {self.name!r}: has no frames")
        bad = ~np.isfinite(q).all(axis=(1, 2))
        if bad.any():
            raise InvalidMotionError(f"motion {self.name!r}: NaN or infinite rotations in {int(bad.sum())} frames "
                                     f"(first at frame {int(np.flatnonzero(bad)[0])})")
        norms = np.linalg.norm(q, axis=-1)
        if np.any(norms < 0.5) or np.any(norms > 1.5):
            raise InvalidMotionError(f"motion {self.name!r}: rotations are not unit quaternions "
                                     f"(norms from {norms.min():.3g} to {norms.max():.3g})")
        if not np.isfinite(self.fps) or self.fps <= 0:
            raise InvalidMotionError(f"motion {self.name!r}: frame rate {self.fps} is not positive")
        if self.labels.shape != (len(q),):
            raise InvalidMotionError(f"motion {self.name!r}: {self.labels.shape[0]} labels for {len(q)} frames")

    @property
    def n_frames(self) -> int:
        return len(self.q_tbs)

    @property
    def duration(self) -> float:
        """Seconds."""
        return self.n_frames / self.fps
