"""`Motion`: finger rotations over time in TBS space, plus the semantic labels a synthesiser knows."""

from __future__ import annotations

from dataclasses import dataclass, field

import sys

import numpy as np

from s2h_viewer.errors import InvalidMotionError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.chunks import frame_chunks, nonfinite_frames


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
    #: the `tracking.fitter.TrackingFit` this motion was fitted in (keypoints, residual), None for an authored
    #: motion; never saved, and not carried into a retargeted motion
    fit: object = field(default=None, repr=False)

    def __post_init__(self) -> None:
        self.q_tbs = np.asarray(self.q_tbs, dtype=np.float32)
        if self.labels is None:
            self.labels = np.full(len(self.q_tbs), "", dtype=object)
        self.labels = shared_labels(self.labels)
        self.validate()

    def validate(self) -> None:
        """Raise `InvalidMotionError` naming the motion and the problem; checks a chunk of frames at a time,
        so a long clip needs no whole-clip temporaries."""
        q = self.q_tbs
        if q.ndim != 3 or q.shape[1:] != (topo.N_ARTICULATED, 4):
            raise InvalidMotionError(f"motion {self.name!r}: rotations have shape {q.shape}, expected (T, 15, 4)")
        if len(q) == 0:
            raise InvalidMotionError(f"motion {self.name!r}: has no frames")
        n_bad, first_bad = nonfinite_frames(q)
        if n_bad:
            raise InvalidMotionError(f"motion {self.name!r}: NaN or infinite rotations in {n_bad} frames "
                                     f"(first at frame {first_bad})")
        low, high = norm_range(q)
        if low < 0.5 or high > 1.5:
            raise InvalidMotionError(f"motion {self.name!r}: rotations are not unit quaternions "
                                     f"(norms from {low:.3g} to {high:.3g})")
        if not np.isfinite(self.fps) or self.fps <= 0:
            raise InvalidMotionError(f"motion {self.name!r}: frame rate {self.fps} is not positive")
        if self.labels.shape != (len(q),):
            raise InvalidMotionError(f"motion {self.name!r}: {self.labels.size} labels for {len(q)} frames")

    @property
    def n_frames(self) -> int:
        return len(self.q_tbs)

    @property
    def duration(self) -> float:
        """Seconds."""
        return self.n_frames / self.fps

    def held_at(self, frame: int) -> str:
        """" (Sign 3)": the pose or gesture held at ``frame``, " (between poses)" between two, "" in a clip that
        names none (what a message says after a frame number)."""
        if self.labels[frame]:
            return f" ({self.labels[frame]})"
        return " (between poses)" if (self.labels != "").any() else ""


def norm_range(q: np.ndarray) -> tuple[float, float]:
    """Smallest and largest quaternion norm in ``q`` (T, ..., 4), a chunk of frames at a time."""
    low, high = np.inf, -np.inf
    for first, end in frame_chunks(len(q)):
        part = q[first:end]
        norms = np.sqrt(np.einsum("...k,...k->...", part, part))
        low, high = min(low, float(norms.min())), max(high, float(norms.max()))
    return low, high


def shared_labels(values) -> np.ndarray:
    """(T,) object array of labels in which equal labels are one string object: a reference (8 bytes) per
    frame, not a string per frame. Converted a chunk of frames at a time."""
    values = np.asarray(values)
    if values.dtype == object or values.ndim != 1:  # (a wrong shape is `Motion.validate`'s to report)
        return values.astype(object, copy=False)
    out = np.empty(values.shape, dtype=object)
    for first, end in frame_chunks(len(values)):
        names, codes = np.unique(values[first:end], return_inverse=True)
        out[first:end] = np.array([sys.intern(str(name)) for name in names], dtype=object)[codes]
    return out
