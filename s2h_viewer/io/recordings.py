"""Tracking recordings by content: which files are keypoint recordings, and reading one as a
`KeypointRecording` (then `tracking.fitter` makes a hand and a motion of it)."""

from __future__ import annotations

from pathlib import Path

from s2h_viewer.errors import InputFileError, reading, require_readable_file
from s2h_viewer.tracking.recording import KeypointRecording

RECORDING_SUFFIXES = (".json", ".npy", ".npz")
JSON_FORMATS = ("webxr-hand", "openxr-hand", "mediapipe-hand")


def is_recording(path: str | Path) -> bool:
    """A file to read as a tracking recording: JSON or ``.npy`` by suffix, an npz by what it holds."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".json", ".npy"):
        return True
    if suffix == ".npz" and path.is_file():
        from s2h_viewer.io.keypoint_arrays import is_keypoint_npz
        return is_keypoint_npz(path)
    return False


def read_recording(path: str | Path, side: str | None = None, fps: float | None = None) -> KeypointRecording:
    """Read a WebXR/OpenXR joint-pose or MediaPipe landmark JSON, or a keypoint array; ``side`` and ``fps``
    are the user's (``--side``, ``--fps``)."""
    path = require_readable_file(path)
    with reading(path, "a tracking recording"):
        if path.suffix.lower() in (".npy", ".npz"):
            from s2h_viewer.io.keypoint_arrays import read_keypoint_array
            return read_keypoint_array(path, fps, side)
        from s2h_viewer.io.tracking_json import parse_document
        document = parse_document(path)
        kind = str(document.get("format", "")).strip().lower()
        if kind in ("webxr-hand", "openxr-hand"):
            from s2h_viewer.io.webxr_hand import read_webxr_hand
            recording = read_webxr_hand(path, document, side)
        elif kind == "mediapipe-hand":
            from s2h_viewer.io.mediapipe_hand import read_mediapipe_hand
            recording = read_mediapipe_hand(path, document, side)
        else:
            said = f'"format" is {document["format"]!r}' if "format" in document else 'has no "format"'
            raise InputFileError(path, f'{said}: expected one of {", ".join(JSON_FORMATS)} (a tracking '
                                       f'recording)')
        if fps is not None:
            from s2h_viewer.io.tracking_json import frame_rate
            recording.notes.append(f"fps: {fps:g} (--fps; the file says {recording.fps:g})")
            recording.fps = frame_rate(path, None, fps)
        return recording
