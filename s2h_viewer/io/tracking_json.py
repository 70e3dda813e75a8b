"""What the tracking JSON readers share: parsing a file whose "format" says what it is, and its common fields."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from s2h_viewer.errors import InputFileError
from s2h_viewer.io.npz import bracket_depth

#: deepest nesting a tracking document needs (frames of joints of coordinates, with room to spare)
MAX_DEPTH = 8


def parse_document(path: Path) -> dict:
    """The JSON object in ``path``; one line naming the problem if it is not one (truncated, not JSON)."""
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputFileError(path, f"is not UTF-8 text (byte {exc.start}): not a tracking JSON file") from None
    depth = bracket_depth(text)
    if depth > MAX_DEPTH:
        raise InputFileError(path, f"JSON is nested {depth} levels deep, more than a tracking file's {MAX_DEPTH}")
    try:
        document = json.loads(text)
    except json.JSONDecodeError as exc:
        where = "ends before the JSON does (truncated?)" if exc.pos >= len(text.rstrip()) else \
            f"is not valid JSON at line {exc.lineno}, column {exc.colno} ({exc.msg})"
        raise InputFileError(path, where) from None
    if not isinstance(document, dict):
        raise InputFileError(path, "holds JSON that is not an object with a \"format\"")
    return document


def frame_rate(path: Path, fps: object, given: float | None = None) -> float:
    """A positive, finite frame rate from the file (or ``given`` by the user, which wins)."""
    value = given if given is not None else fps
    what = "--fps" if given is not None else '"fps"'
    if value is None:
        raise InputFileError(path, 'has no "fps": give the frame rate with --fps')
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise InputFileError(path, f"{what} is {value!r}: a frame rate must be a positive number")
    return float(value)


def handedness_field(path: Path, value: object) -> str | None:
    """"left", "right" or None (absent) from a ``"handedness"`` field, any case."""
    if value is None:
        return None
    side = str(value).strip().lower()
    if side not in ("left", "right"):
        raise InputFileError(path, f'"handedness" is {value!r}: expected "left" or "right"')
    return side


def labels_field(path: Path, labels: object, n_frames: int) -> np.ndarray | None:
    """A pose name per frame, where the file gives ``"labels"``."""
    if labels is None:
        return None
    if not isinstance(labels, list) or len(labels) != n_frames or not all(isinstance(x, str) for x in labels):
        raise InputFileError(path, f'"labels" must be {n_frames} strings, one per frame')
    return np.array(labels, dtype=object)
