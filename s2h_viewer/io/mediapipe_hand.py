"""MediaPipe hand landmarks in JSON (``"format": "mediapipe-hand"``).

``"frames"``: per video frame, ``HandLandmarkerResult.hand_world_landmarks`` of one hand (21 landmarks in
MediaPipe's order, which is the project's joint order; metres; each ``[x, y, z]`` or ``{"x", "y", "z"}``),
``null`` where no hand was found.

Which hand: MediaPipe's ``"handedness"`` label assumes a mirrored (selfie) image, so it names the
performer's hand, while the world landmarks keep the image's geometry, which is the mirror image of that
hand. The landmarks' own geometry decides which hand they form; the label is reported, not used. ``--side``
names the hand to read them as: where it is not the hand the geometry forms, the landmarks are mirrored
(a video that was not flipped, say).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand import topology as topo
from s2h_viewer.io.tracking_json import frame_rate, handedness_field, labels_field
from s2h_viewer.tracking.recording import KeypointRecording, check_scale, sided_by_geometry


def _landmarks(path: Path, t: int, frame: object) -> np.ndarray:
    if not isinstance(frame, list) or len(frame) != topo.N_JOINTS:
        count = len(frame) if isinstance(frame, list) else "no list of"
        raise InputFileError(path, f"frame {t} holds {count} landmarks, not {topo.N_JOINTS}")
    points = []
    for i, mark in enumerate(frame):
        if isinstance(mark, dict):
            mark = [mark.get(k) for k in ("x", "y", "z")]
        if not isinstance(mark, list) or len(mark) != 3 or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for v in mark):
            raise InputFileError(path, f"frame {t} landmark {i} is not three numbers [x, y, z]")
        points.append(mark)
    values = np.asarray(points, dtype=np.float64)
    if not np.isfinite(values).all():
        raise InputFileError(path, f"frame {t} holds NaN or infinite values (a frame with no hand is null)")
    return values


def read_mediapipe_hand(path: Path, document: dict, side: str | None = None) -> KeypointRecording:
    """The recording in a parsed mediapipe-hand document."""
    fps = frame_rate(path, document.get("fps"))
    frames = document.get("frames")
    if not isinstance(frames, list) or not frames:
        raise InputFileError(path, '"frames" must be a non-empty list of frames')
    positions = np.full((len(frames), topo.N_JOINTS, 3), np.nan)
    for t, frame in enumerate(frames):
        if frame is not None:
            positions[t] = _landmarks(path, t, frame)
    if not np.isfinite(positions).all(axis=(1, 2)).any():
        raise InputFileError(path, f"all {len(frames)} frames are null: no hand was found in any frame")
    label = handedness_field(path, document.get("handedness"))
    recording = KeypointRecording(positions=positions, fps=fps, side="right", name=path.stem,
                                  format="mediapipe-hand", labels=labels_field(path, document.get("labels"),
                                                                               len(frames)))
    check_scale(recording, path)
    if label:
        recording.notes.append(f"MediaPipe's handedness label: {label.capitalize()} (for a mirrored image; "
                               f"not used)")
    return sided_by_geometry(recording, side)


def save_mediapipe_hand(path: str | Path, recording: KeypointRecording, handedness: str | None = None) -> Path:
    """Write ``recording``'s keypoints as a mediapipe-hand JSON (lost frames as null), atomically; what a
    tool that logs ``hand_world_landmarks`` per frame would write."""
    import json

    from s2h_viewer.io.atomic import atomic_path

    frames = [None if not np.isfinite(f).all() else np.round(f, 6).tolist() for f in recording.positions]
    document = {"format": "mediapipe-hand", "fps": recording.fps,
                **({"handedness": handedness} if handedness else {}), "frames": frames}
    if recording.labels is not None:
        document["labels"] = [str(x) for x in recording.labels]
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(document, separators=(",", ":")))
    return path
