"""The corrections sidecar: a retarget's per-joint offset keys (`retarget.corrections`) as JSON, written
beside every motion exported with corrections (``<motion file name>.corrections.json``: ``take.glb.corrections.json``,
so exports of one name in two formats keep a sidecar each) and read back by
the viewer (Fix > Load corrections) and ``s2h retarget --corrections FILE``.

Schema (version 1)::

    {"format": "s2h-corrections", "version": 1,
     "clip": "gestures", "frames": 378, "fps": 30.0, "source": "birch", "target": "iris", "method": "tbs_copy",
     "joints": [{"joint": "index_pip",
                 "keys": [{"frame": 40, "start": 30, "end": 50, "rotation_deg": [0.0, 25.0, 0.0]}]}]}

Beside a motion export of part of the clip, ``"part": [first, last]`` says which frames the motion file holds (the
keys keep the clip's frame numbers: the sidecar applies to the clip's retarget, as ``s2h retarget`` makes it).
A key: its frame, the frames it eases in from and out to (``start <= frame <= end``), where it holds a pose over
several frames ``"hold": [first, last]`` (``start <= first <= frame <= last <= end``; the whole turn on all of them),
and its turn as a rotation vector in degrees in the joint's TBS frame (its components about twist, bend, splay).
A file is hostile until checked: every count, name, frame and number is."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from s2h_viewer.errors import InputFileError, reading, require_readable_file
from s2h_viewer.hand import topology as topo
from s2h_viewer.retarget.corrections import Corrections, JointCorrection, OffsetKey

FORMAT, VERSION = "s2h-corrections", 1
SUFFIX = ".corrections.json"
MAX_BYTES = 16 * 1024 ** 2  # a sidecar of every joint keyed at every frame of a long clip is far smaller
MAX_DEGREES = 360.0  # a key's offset: more is a file's mistake, not a correction


@dataclass(frozen=True)
class CorrectionsFile:
    """Corrections and what they were made on: the clip (name, frames, fps), its source, target and method."""

    corrections: Corrections
    clip: str
    frames: int
    fps: float
    source: str
    target: str
    method: str
    part: tuple[int, int] | None = None  # beside a motion export of these frames of the clip (first, last)

    def mismatch(self, clip_frames: int) -> str | None:
        """Why these corrections cannot apply to a clip of ``clip_frames`` frames, or None."""
        if clip_frames != self.frames:
            return (f"its corrections were made on a clip of {self.frames} frames ({self.clip!r}); this one has "
                    f"{clip_frames}")
        return None


def sidecar_path(motion_file: str | Path) -> Path:
    """``<name>.corrections.json`` beside ``motion_file``, its suffix kept: take.glb and take.bvh, exported from
    two retargets, each keep their own (with the stem alone the second export overwrote, or removed, the first's)."""
    motion_file = Path(motion_file)
    return motion_file.with_name(motion_file.name + SUFFIX)


def save_corrections(path: str | Path, file: CorrectionsFile) -> Path:
    """Write ``file`` atomically (temp file, then rename)."""
    from s2h_viewer.io.atomic import atomic_path
    document = {
        "format": FORMAT, "version": VERSION, "clip": file.clip, "frames": file.frames, "fps": file.fps,
        "source": file.source, "target": file.target, "method": file.method,
        **({} if file.part is None else {"part": list(file.part)}),
        "joints": [{"joint": c.name,
                    "keys": [{"frame": k.frame, "start": k.start, "end": k.end,
                              **({} if k.hold is None else {"hold": list(k.hold)}),
                              "rotation_deg": [round(math.degrees(v), 6) for v in k.rotvec]} for k in c.keys]}
                   for c in file.corrections.joints]}
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(document, indent=1) + "\n")
    return Path(path)


def is_corrections_file(path: str | Path) -> bool:
    """True if ``path`` reads as a corrections sidecar (whatever its content's validity): what an export may
    replace or remove beside its motion, never another file."""
    try:
        with open(path, "rb") as stream:
            head = stream.read(4096)
        return f'"format": "{FORMAT}"'.encode() in head
    except OSError:
        return False


def load_corrections(path: str | Path, clip_frames: int | None = None) -> CorrectionsFile:
    """Read and check a corrections sidecar (against a clip of ``clip_frames`` frames, if given: the one it is to
    apply to); one `InputFileError` naming the file and the problem."""
    path = require_readable_file(path, MAX_BYTES)
    with reading(path, "a corrections sidecar"):
        try:
            document = json.loads(path.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise InputFileError(path, f"is not JSON ({exc})") from None
        file = _parse(path, document)
    problem = None if clip_frames is None else file.mismatch(clip_frames)
    if problem is not None:
        raise InputFileError(path, problem)
    return file


def _fail(path: Path, problem: str) -> InputFileError:
    return InputFileError(path, f"is not a valid corrections sidecar: {problem}")


def _integer(path: Path, value, what: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise _fail(path, f"{what} is {value!r}, not a whole number")
    if not low <= value <= high:
        raise _fail(path, f"{what} is {value}, outside {low}..{high}")
    return value


def _text(path: Path, document: dict, key: str) -> str:
    value = document.get(key, "")
    if not isinstance(value, str):
        raise _fail(path, f'"{key}" is {value!r}, not text')
    return value


def _parse(path: Path, document) -> CorrectionsFile:
    if not isinstance(document, dict) or document.get("format") != FORMAT:
        raise _fail(path, f'no "format": "{FORMAT}"')
    if document.get("version") != VERSION:
        raise _fail(path, f"version {document.get('version')!r}; this s2h reads version {VERSION}")
    frames = _integer(path, document.get("frames"), '"frames"', 1, 10 ** 8)
    fps = document.get("fps", 30.0)
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not math.isfinite(fps) or fps <= 0:
        raise _fail(path, f'"fps" is {fps!r}, not a positive number')
    joints = document.get("joints")
    if not isinstance(joints, list):
        raise _fail(path, '"joints" is not a list')
    corrections, seen = [], set()
    for n, entry in enumerate(joints):
        where = f"joints[{n}]"
        if not isinstance(entry, dict):
            raise _fail(path, f"{where} is not an object")
        name = entry.get("joint")
        if name not in topo.ARTICULATED_NAMES:
            raise _fail(path, f"{where}: joint {name!r} is not one of {', '.join(topo.ARTICULATED_NAMES)}")
        if name in seen:
            raise _fail(path, f"{where}: joint {name} is corrected twice")
        seen.add(name)
        keys = entry.get("keys")
        if not isinstance(keys, list) or not keys:
            raise _fail(path, f"{where} ({name}) has no keys")
        parsed = []
        for k, key in enumerate(keys):
            what = f"{where} ({name}) key {k}"
            if not isinstance(key, dict):
                raise _fail(path, f"{what} is not an object")
            frame = _integer(path, key.get("frame"), f"{what} frame", 0, frames - 1)
            start = _integer(path, key.get("start"), f"{what} start", 0, frame)
            end = _integer(path, key.get("end"), f"{what} end", frame, frames - 1)
            hold = key.get("hold")
            if hold is not None:
                if not isinstance(hold, list) or len(hold) != 2:
                    raise _fail(path, f'{what}: "hold" is {hold!r}, not [first, last]')
                hold = (_integer(path, hold[0], f"{what} hold's first frame", start, frame),
                        _integer(path, hold[1], f"{what} hold's last frame", frame, end))
            if parsed and frame <= parsed[-1].frame:
                raise _fail(path, f"{what}: frame {frame} does not follow frame {parsed[-1].frame}")
            rotation = key.get("rotation_deg")
            if not (isinstance(rotation, list) and len(rotation) == 3 and all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in rotation)):
                raise _fail(path, f"{what}: rotation_deg is {rotation!r}, not three finite numbers")
            if math.hypot(*rotation) > MAX_DEGREES:
                raise _fail(path, f"{what}: a turn of {math.hypot(*rotation):.0f} deg (at most {MAX_DEGREES:.0f})")
            parsed.append(OffsetKey(frame, tuple(math.radians(v) for v in rotation), start, end, hold))
        corrections.append(JointCorrection(topo.ARTICULATED_NAMES.index(name), tuple(parsed)))
    part = document.get("part")
    if part is not None:
        if not isinstance(part, list) or len(part) != 2:
            raise _fail(path, f'"part" is {part!r}, not [first, last]')
        first = _integer(path, part[0], '"part" first frame', 0, frames - 1)
        part = (first, _integer(path, part[1], '"part" last frame', first, frames - 1))
    return CorrectionsFile(Corrections(tuple(sorted(corrections, key=lambda c: c.joint))),
                           _text(path, document, "clip"), frames, float(fps), _text(path, document, "source"),
                           _text(path, document, "target"), _text(path, document, "method"), part)
