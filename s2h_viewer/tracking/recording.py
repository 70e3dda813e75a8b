"""`KeypointRecording`: what any tracking reader gives, 21 keypoints per frame in the project's joint order.

Positions are in metres in the recording's own space; a frame the tracker lost is NaN throughout and
``valid`` is False there. Orientations (WebXR/OpenXR give them) are each joint's TBS-convention axes
(columns twist, bend, splay), None where the format has none.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.mirror import reflection

#: a hand smaller or larger than this (wrist to middle knuckle, metres) is not in metres
PALM_LENGTH_RANGE = (0.03, 0.2)
#: a keypoint further than this (metres) from the recording's origin is not a tracked hand (nor a unit slip)
MAX_COORDINATE = 1e6


@dataclass(eq=False)
class KeypointRecording:
    """A tracked hand over time, in the project's 21-joint order (`topology.JOINT_NAMES`)."""

    positions: np.ndarray  # (T, 21, 3) float64 metres; NaN on frames the tracker lost
    fps: float
    side: str  # "right" or "left": the hand the keypoints form
    name: str
    format: str  # "webxr-hand", "openxr-hand", "mediapipe-hand", "keypoint-array"
    orientations: np.ndarray | None = None  # (T, 21, 3, 3) columns (twist, bend, splay); a tip copies its parent
    radii: np.ndarray | None = None  # (21,) metres, where the recording gives joint radii
    labels: np.ndarray | None = None  # (T,) a pose name per frame, where the file gives one
    notes: list[str] = field(default_factory=list)  # how the side (and anything else guessed) was read

    @property
    def n_frames(self) -> int:
        return len(self.positions)

    @property
    def valid(self) -> np.ndarray:
        """(T,) True where the frame holds keypoints."""
        return np.isfinite(self.positions).all(axis=(1, 2))


def handedness_score(positions: np.ndarray, orientations: np.ndarray | None = None) -> float:
    """> 0 for a right hand, < 0 for a left one, near 0 when the frames cannot tell (a flat hand, no
    orientations). ``positions`` (T, 21, 3) with NaN frames allowed.

    With the palm normal taken as (pinky knuckle x index knuckle) from the wrist, a right hand's back faces
    along it, so: its joint frames' splay axes point along it (orientations), its curled fingers' tips and
    its thumb lie on the other side (positions)."""
    ok = np.isfinite(positions).all(axis=(1, 2))
    p = positions[ok] - positions[ok, :1]
    with np.errstate(all="ignore"):  # frames a tracker collapsed (a palm of no size) say nothing: dropped
        normal = np.cross(p[:, topo.joint_index("pinky_mcp")], p[:, topo.joint_index("index_mcp")])
        size = np.linalg.norm(normal, axis=-1)
        palm = np.linalg.norm(p[:, topo.joint_index("middle_mcp")], axis=-1)
        keep = np.isfinite(size) & (size > 1e-12) & (palm > 1e-6)
    if not keep.any():
        return 0.0
    ok[ok] = keep
    p, normal, palm = p[keep], normal[keep] / size[keep, None], palm[keep]
    if orientations is not None:
        splay = orientations[ok][:, [0, *topo.KNUCKLE_JOINTS[1:]]][..., 2]  # wrist and finger MCPs: (n, 5, 3)
        return float(np.einsum("nkc,nc->nk", splay, normal).mean())
    depth = np.einsum("njc,nc->nj", p, normal) / palm[:, None]  # out of the back, in palm lengths
    back_side = depth[:, topo.TIP_JOINTS[1:]].mean(1) + depth[:, [topo.joint_index("thumb_mcp"),
                                                                  topo.joint_index("thumb_ip")]].mean(1)
    return float(-np.median(back_side))


def right_handed(recording: KeypointRecording) -> tuple[np.ndarray, np.ndarray | None]:
    """Positions and orientations as a right hand's (a left one reflected across its x = 0 plane, its axes
    with bend flipped to stay right-handed: `hand.mirror`'s convention)."""
    if recording.side == "right":
        return recording.positions, recording.orientations
    s = reflection((1.0, 0.0, 0.0))
    orientations = None
    if recording.orientations is not None:
        orientations = s @ recording.orientations @ np.diag([1.0, -1.0, 1.0])
    return recording.positions @ s.T, orientations


def check_scale(recording: KeypointRecording, path) -> None:
    """Refuse a recording whose hand is not metre-sized (another unit, or not a hand)."""
    from s2h_viewer.errors import InputFileError

    p = recording.positions[recording.valid]
    palm = float(np.median(np.linalg.norm(p[:, topo.joint_index("middle_mcp")] - p[:, 0], axis=-1)))
    low, high = PALM_LENGTH_RANGE
    if not low <= palm <= high:
        raise InputFileError(path, f"wrist to middle knuckle is {palm:.4g} (median over frames), not a hand in "
                                   f"metres ({low}-{high} m): tracked keypoints must be in metres")
    far = np.abs(p).max(axis=(1, 2)) > MAX_COORDINATE
    if far.any():
        frame = int(np.flatnonzero(recording.valid)[np.argmax(far)])
        raise InputFileError(path, f"frame {frame} holds a keypoint {np.abs(p[np.argmax(far)]).max():.3g} m from "
                                   f"the origin, beyond any tracking space ({MAX_COORDINATE:g} m)")


def sided_by_geometry(recording: KeypointRecording, side: str | None) -> KeypointRecording:
    """Set a positions-only recording's side from the hand its keypoints form; where the user names the
    other side (``side``), mirror the keypoints into that hand. Notes say which it was."""
    score = handedness_score(recording.positions)
    seen = "right" if score >= 0 else "left"
    sure = abs(score) > 0.02
    if side and side != seen and sure:
        recording.positions = recording.positions @ reflection((1.0, 0.0, 0.0)).T
        recording.notes.append(f"side: {side} (--side; the keypoints formed a {seen} hand and were mirrored)")
        seen = side
    elif side:
        recording.notes.append(f"side: {side} (--side)")
        seen = side
    else:
        recording.notes.append(f"side: {seen} (from the keypoints' geometry"
                               + ("" if sure else "; unclear in these frames, give --side") + ")")
    recording.side = seen
    return recording
