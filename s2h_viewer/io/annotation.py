"""The TBS annotation sidecar: one per hand, ``<hand file stem>.<side>.tbs.json`` beside the hand file, loaded
with it (``<name>.bvh.<side>.tbs.json`` beside a BVH); motion exports write their hand's frames as one
(`save_hand_frames`). A full-body character has two hands, each annotated on its own.

Schema (version 2; version 1, ``<stem>.tbs.json`` without a side, is still read, see `load_annotation`)::

    {"schema": "s2h-tbs-annotation", "version": 2, "side": "right" | "left",
     "hand_file": "right.glb", "hand_sha256": "<hex digest of the hand file>",
     "joints": {"thumb_cmc": {"frame": [[...], [...], [...]], "set_by": "solver" | "manual",
                              "confidence": 0.9 | null (not scored)}, ... 15 joints},
     "diagnostics": ["..."]}

``frame`` rows are the hand-space matrix rows (columns twist, bend, splay). The hash ties the
annotation to the exact file it was made for: a changed hand file makes the sidecar an error,
never silently wrong frames.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from s2h_viewer.errors import InputFileError, reading, require_readable_file
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.io.atomic import atomic_path

SCHEMA = "s2h-tbs-annotation"
VERSION = 2
#: version 1 sidecars (before the side was recorded) are read as side-less
READ_VERSIONS = (1, 2)
SIDES = ("right", "left")
SET_BY = ("solver", "manual")
MAX_SIDECAR_BYTES = 16 * 1024 ** 2


@dataclass
class Annotation:
    """Per articulated joint (15): frame, who set it, and the solver's confidence (NaN: never scored)."""

    frames: np.ndarray  # (15, 3, 3)
    set_by: list[str]
    confidence: np.ndarray  # (15,)
    diagnostics: list[str] = field(default_factory=list)
    side: str | None = None  # the hand it was made for; None: a version 1 sidecar, which did not say


def hand_side(hand: HandModel) -> str:
    """The side a hand was read as (a hand without one, procedural or npz, is a right hand)."""
    return hand.meta.get("side") or "right"


def _stem(hand_file: Path) -> str:
    """A BVH's sidecar keeps its suffix, so that the GLB export of the same motion under the same stem, or the
    rig file it was exported from, keeps its own."""
    return hand_file.name if hand_file.suffix.lower() == ".bvh" else hand_file.stem


def sidecar_path(hand_file: str | Path, side: str) -> Path:
    """``<stem>.<side>.tbs.json``: the sidecar of one hand of ``hand_file``."""
    if side not in SIDES:
        raise ValueError(f"side must be one of {SIDES}, not {side!r}")
    hand_file = Path(hand_file)
    return hand_file.with_name(f"{_stem(hand_file)}.{side}.tbs.json")


def legacy_sidecar_path(hand_file: str | Path) -> Path:
    """``<stem>.tbs.json``: where s2h before version 2 wrote the one sidecar of a file, for whichever hand."""
    hand_file = Path(hand_file)
    return hand_file.with_name(f"{_stem(hand_file)}.tbs.json")


def file_sha256(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _confidence_json(confidence: float) -> float | None:
    """A confidence as JSON: null for a frame nobody scored (NaN is not JSON)."""
    return round(float(confidence), 4) if np.isfinite(confidence) else None


def save_annotation(annotation: Annotation, hand_file: str | Path, side: str, path: str | Path | None = None
                    ) -> Path:
    """Write the annotation of ``hand_file``'s ``side`` hand atomically to ``path`` (default: that hand's
    sidecar, where loading looks for it); returns the path written. An `OSError` leaves no file, and an
    existing one as it was."""
    hand_file = Path(hand_file)
    joints = {name: {"frame": np.round(annotation.frames[a], 8).tolist(), "set_by": annotation.set_by[a],
                     "confidence": _confidence_json(annotation.confidence[a])}
              for a, name in enumerate(topo.ARTICULATED_NAMES)}
    document = {"schema": SCHEMA, "version": VERSION, "side": side, "hand_file": hand_file.name,
                "hand_sha256": file_sha256(hand_file), "joints": joints, "diagnostics": annotation.diagnostics}
    path = sidecar_path(hand_file, side) if path is None else Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(document, indent=1) + "\n")
    return path


def refuse_foreign_sidecar(motion_file: Path, side: str) -> None:
    """Before a motion export of a ``side`` hand to ``motion_file``: an `InputFileError` if its sidecar name
    holds another file's frames (the hand-made ones of ``<stem>.fbx`` beside an export ``<stem>.glb``, say),
    which `save_hand_frames` would overwrite; an earlier export's own sidecar may go."""
    sidecar = sidecar_path(motion_file, side)
    if not sidecar.exists() and not sidecar.is_symlink():
        return
    owner = _sidecar_owner(sidecar)
    if owner != motion_file.name:
        raise InputFileError(motion_file, f"would overwrite {sidecar.name}, the TBS frames of "
                                          f"{owner or 'another file'}; export under another name")


def _sidecar_document(sidecar: Path) -> dict | None:
    """A sidecar's JSON object read leniently (no hash check), None if it cannot be read as one."""
    try:
        if not sidecar.is_file() or sidecar.stat().st_size > MAX_SIDECAR_BYTES:
            return None
        document = json.loads(sidecar.read_text())
    except (OSError, ValueError, RecursionError):  # JSON and Unicode decode errors are ValueErrors
        return None
    return document if isinstance(document, dict) else None


def _sidecar_owner(sidecar: Path) -> str | None:
    """The hand file a sidecar says it was made for, None if it cannot be read as a sidecar."""
    owner = (_sidecar_document(sidecar) or {}).get("hand_file")
    return owner if isinstance(owner, str) else None


def _marks_kept(sidecar: Path, owner: str, frames: np.ndarray) -> tuple[list[str], np.ndarray]:
    """(set_by, confidence) for ``frames`` written over ``sidecar``: a joint whose frame is the one the
    sidecar of ``owner`` already holds keeps its marks (a hand annotated by hand, exported over its own
    file, stays "manual"); the rest are the hand's frames, unscored."""
    n = topo.N_ARTICULATED
    set_by, confidence = ["solver"] * n, np.full(n, np.nan)
    document = _sidecar_document(sidecar)
    joints = document.get("joints") if document is not None and document.get("hand_file") == owner else None
    if not isinstance(joints, dict):
        return set_by, confidence
    for a, name in enumerate(topo.ARTICULATED_NAMES):
        try:
            frame, by, score = _joint_entry(sidecar, name, joints.get(name))
        except InputFileError:
            continue
        if np.allclose(frame, frames[a], atol=1e-6):
            set_by[a], confidence[a] = by, score
    return set_by, confidence


def save_hand_frames(motion_file: Path, hand: HandModel, to_file: np.ndarray) -> Path:
    """Write the sidecar of the motion file just written at ``motion_file``: ``hand``'s TBS frames turned by
    ``to_file`` into the hand space the file loads in, so that it reads back with the TBS rotations it was
    written with; unscored unless the sidecar there already holds the same frames (`_marks_kept`). Returns
    ``motion_file``."""
    frames = to_file @ hand.rest_frames
    side = hand_side(hand)
    set_by, confidence = _marks_kept(sidecar_path(motion_file, side), motion_file.name, frames)
    save_annotation(Annotation(frames, set_by, confidence,
                               [f"TBS frames of {hand.name}, written with {motion_file.name}"], side),
                    motion_file, side)
    return motion_file


def _joint_entry(path: Path, name: str, entry) -> tuple[np.ndarray, str, float]:
    """One joint's (frame, set_by, confidence), each checked for type and range."""
    if not isinstance(entry, dict):
        raise InputFileError(path, f"joint {name}: expected an object, found a JSON {type(entry).__name__}")
    frame = entry.get("frame")
    if (not isinstance(frame, list) or len(frame) != 3
            or not all(isinstance(row, list) and len(row) == 3 for row in frame)
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for row in frame for v in row)):
        raise InputFileError(path, f"joint {name}: frame must be 3 rows of 3 numbers")
    set_by = entry.get("set_by", "solver")
    if set_by not in SET_BY:
        raise InputFileError(path, f"joint {name}: unknown set_by value {set_by!r}; expected solver or manual")
    confidence = entry.get("confidence", 1.0)
    if confidence is None:  # not scored (a frame from the hand file, say)
        return np.array(frame, dtype=np.float64), set_by, float("nan")
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float)) or not 0 <= confidence <= 1:
        raise InputFileError(path, f"joint {name}: confidence {confidence!r} is not a number from 0 to 1")
    return np.array(frame, dtype=np.float64), set_by, float(confidence)


def load_annotation(hand_file: str | Path, side: str) -> Annotation | None:
    """The sidecar of ``hand_file``'s ``side`` hand, else its version 1 side-less sidecar (``side`` None in
    the result: the caller checks that its frames fit this hand, see `io.rig.annotate`), else None; an
    `InputFileError` naming the sidecar if it is damaged, of another schema, version or side, or made for a
    different version of the hand file."""
    for path in (sidecar_path(hand_file, side), legacy_sidecar_path(hand_file)):
        if path.exists():
            with reading(path, "a TBS annotation sidecar"):
                annotation = _read_annotation(path, Path(hand_file))
            if annotation.side not in (side, None):
                raise InputFileError(path, f"holds the {annotation.side} hand's frames, not the {side} one's: "
                                           f"renamed? save the {side} hand's annotation again")
            return annotation
    return None


def _read_annotation(path: Path, hand_file: Path) -> Annotation:
    require_readable_file(path, MAX_SIDECAR_BYTES)
    try:
        document = json.loads(path.read_text())
    except RecursionError:
        raise InputFileError(path, "not a TBS annotation (JSON nested too deeply)") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputFileError(path, f"not valid JSON ({exc})") from None
    if not isinstance(document, dict) or document.get("schema") != SCHEMA:
        raise InputFileError(path, f"not an s2h TBS annotation (schema {SCHEMA!r} expected)")
    if document.get("version") not in READ_VERSIONS:
        raise InputFileError(path, f"annotation version {document.get('version')!r} is not supported "
                                   f"(this s2h reads versions {', '.join(map(str, READ_VERSIONS))})")
    side = document.get("side") if document["version"] >= 2 else None
    if document["version"] >= 2 and side not in SIDES:
        raise InputFileError(path, f"side {side!r} is not right or left")
    if document.get("hand_sha256") != file_sha256(hand_file):
        raise InputFileError(path, f"was made for a different version of {hand_file.name} (its hash "
                                   f"differs); re-run `s2h annotate --save` or delete the sidecar")
    joints = document.get("joints")
    if not isinstance(joints, dict):
        raise InputFileError(path, "joints must be an object of joint name -> entry")
    missing = [n for n in topo.ARTICULATED_NAMES if n not in joints]
    if missing:
        raise InputFileError(path, f"no frame for {', '.join(missing)}")
    entries = [_joint_entry(path, n, joints[n]) for n in topo.ARTICULATED_NAMES]
    frames = np.stack([e[0] for e in entries])
    set_by = [e[1] for e in entries]
    confidence = np.array([e[2] for e in entries])
    if not np.isfinite(frames).all():
        raise InputFileError(path, "frames must be finite 3 x 3 matrices")
    error = np.abs(frames.transpose(0, 2, 1) @ frames - np.eye(3)).max()
    if error > 1e-4 or np.any(np.linalg.det(frames) < 0):
        raise InputFileError(path, f"frames are not right-handed rotations (orthonormality error {error:.2g})")
    diagnostics = document.get("diagnostics", [])
    if not isinstance(diagnostics, list) or not all(isinstance(d, str) for d in diagnostics):
        raise InputFileError(path, "diagnostics must be a list of strings")
    return Annotation(frames, set_by, confidence, diagnostics, side)
