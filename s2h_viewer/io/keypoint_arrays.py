"""Keypoint arrays: ``.npy`` of shape (T, 21, 3), or an ``.npz`` holding one such array (``keypoints`` or
``landmarks``, optionally ``fps``), in MediaPipe's landmark order (the project's joint order), metres.
A frame that is NaN throughout is a frame the tracker lost; a partly NaN frame is refused. No pickles."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand import topology as topo
from s2h_viewer.io.tracking_json import frame_rate
from s2h_viewer.tracking.recording import KeypointRecording, check_scale, sided_by_geometry

ARRAY_KEYS = ("keypoints", "landmarks")


def is_keypoint_npz(path: Path) -> bool:
    """An npz whose arrays are keypoints, not the project's own hand or motion (those carry ``schema``)."""
    try:
        with zipfile.ZipFile(path) as archive:
            names = {n.removesuffix(".npy") for n in archive.namelist()}
    except (zipfile.BadZipFile, OSError, NotImplementedError):  # the last: a damaged "version needed" field
        return False
    return "schema" not in names and bool(names & set(ARRAY_KEYS) or len(names - {"fps"}) == 1)


def _check_npy_size(path: Path) -> None:
    """An .npy's header declares its array's shape and type: the bytes after it must be exactly that many
    (numpy itself ignores bytes appended after the data)."""
    with path.open("rb") as stream:
        version = np.lib.format.read_magic(stream)
        read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else \
            np.lib.format.read_array_header_2_0
        shape, _, dtype = read_header(stream)
        offset = stream.tell()
    declared = offset + int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    size = path.stat().st_size
    if size != declared:
        raise InputFileError(path, f"its header declares a {'x'.join(map(str, shape))} {dtype} array "
                                   f"({declared - offset} bytes of data), the file holds {size - offset}")


def _load(path: Path) -> tuple[np.ndarray, object]:
    try:
        if path.suffix.lower() == ".npy":
            _check_npy_size(path)
            return np.load(path, allow_pickle=False), None
        with np.load(path, allow_pickle=False) as arrays:
            keys = [k for k in ARRAY_KEYS if k in arrays.files] or [k for k in arrays.files if k != "fps"]
            if len(keys) != 1:
                raise InputFileError(path, f"holds arrays {', '.join(arrays.files)}: expected one keypoint array "
                                           f"(named {' or '.join(ARRAY_KEYS)})")
            fps = arrays["fps"] if "fps" in arrays.files else None
            return arrays[keys[0]], (float(fps) if fps is not None and fps.size == 1 else fps)
    except InputFileError:
        raise
    except ValueError as exc:  # object arrays (pickles) and damaged headers
        raise InputFileError(path, f"is not a plain numeric array file ({exc})") from None
    except (zipfile.BadZipFile, OSError, EOFError, NotImplementedError) as exc:
        raise InputFileError(path, f"is not a readable .npy/.npz file ({type(exc).__name__}: {exc})") from None


def read_keypoint_array(path: Path, fps: float | None = None, side: str | None = None) -> KeypointRecording:
    """The recording in a keypoint array file; ``fps`` (the user's) wins over the file's."""
    values, file_fps = _load(path)
    if values.dtype.kind not in "fiu":
        raise InputFileError(path, f"holds {values.dtype} values, not numbers")
    if values.ndim != 3 or values.shape[1:] != (topo.N_JOINTS, 3):
        raise InputFileError(path, f"array has shape {values.shape}, expected (frames, 21, 3): 21 landmarks in "
                                   f"MediaPipe's order")
    if not len(values):
        raise InputFileError(path, "has no frames")
    positions = values.astype(np.float64)
    finite = np.isfinite(positions)
    partly = np.flatnonzero(finite.any(axis=(1, 2)) & ~finite.all(axis=(1, 2)))
    if len(partly):
        raise InputFileError(path, f"frame {partly[0]} is partly NaN or infinite ({len(partly)} such frames): "
                                   f"a lost frame is NaN throughout")
    if not finite.all(axis=(1, 2)).any():
        raise InputFileError(path, f"all {len(positions)} frames are NaN: the hand was never tracked")
    positions[~finite.all(axis=(1, 2))] = np.nan
    given = fps is not None or file_fps is not None
    rate = frame_rate(path, file_fps if fps is None else None, fps) if given else 30.0
    recording = KeypointRecording(positions=positions, fps=rate, side="right", name=path.stem,
                                  format="keypoint-array")
    if fps is None and file_fps is None:
        recording.notes.append("fps: 30 (assumed; give --fps)")
    check_scale(recording, path)
    return sided_by_geometry(recording, side)
