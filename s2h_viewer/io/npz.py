"""The project's own npz formats for hands and motions (schema-versioned, atomic writes).

Motion npz (schema 2): ``q_tbs`` float32 (T, 15, 4) quaternions (w, x, y, z) in TBS space measured
from the hand's canonical pose (schema 1 measured them from the rig's rest pose: refused, see
``MOTION_SCHEMA_VERSION``),
``fps`` float, ``name`` str, ``hand_name`` str (the hand it is posed on), ``labels`` str (T,)
(gesture held at each frame, "" between gestures), ``meta_json`` (provenance: gesture script, seed), ``schema`` = "s2h-motion", ``schema_version`` = 2.

Hand npz (schema 1): ``name``, ``offsets`` (21, 3), ``rest_frames`` (15, 3, 3), ``rig_frames``
(16, 3, 3), ``radii`` (21,), optional ``mesh_vertices`` (V, 3), ``mesh_faces`` (F, 3),
``mesh_weights`` (V, 16), ``source``, ``meta_json``, ``schema`` = "s2h-hand", ``schema_version`` = 1.

Reading checks every member against a table (`MOTION_FIELDS`, `HAND_FIELDS`: kind, shape, required)
from the npy headers, before any array is decompressed, so a file that lies about its sizes costs
nothing; a new field is one line in the table.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from s2h_viewer.errors import InputFileError, S2HError, reading, require_readable_file
from s2h_viewer.hand.chunks import frame_chunks, nonfinite_frames
from s2h_viewer.hand.model import HandModel, SkinnedMesh
from s2h_viewer.hand.motion import Motion, shared_labels
from s2h_viewer.io.atomic import atomic_path

HAND_SCHEMA_VERSION = 1
#: 2: TBS rotations measured from the canonical pose (DESIGN.md section 2); 1 (rest pose) is refused
MOTION_SCHEMA_VERSION = 2
_SCHEMA_VERSIONS = {"s2h-hand": HAND_SCHEMA_VERSION, "s2h-motion": MOTION_SCHEMA_VERSION}
#: longest motion read (about 46 hours at 30 fps): a clip's arrays stay a few GiB at most
MAX_CLIP_FRAMES = 5_000_000
#: shortest motion read: one frame is a pose, not a motion
MIN_CLIP_FRAMES = 2
#: largest hand mesh read
MAX_MESH_VERTICES = 2_000_000
MAX_MESH_FACES = 4_000_000
#: longest string field (names, provenance JSON)
MAX_TEXT_CHARS = 1_000_000
#: deepest nesting accepted in ``meta_json``
MAX_JSON_DEPTH = 32
#: bytes of a member decompressed and converted at once while reading
READ_CHUNK_BYTES = 4 * 1024 ** 2
#: how a motion's members are held once read: rotations float32, labels one shared string per label
MOTION_LOAD_AS = {"q_tbs": (np.float32, None), "labels": (object, shared_labels)}


@dataclass(frozen=True)
class Field:
    """One npz member: its kind ("float", "int", "text"), shape (ints fixed, letters shared sizes such as
    the frame count T; () a scalar) and whether it must be there."""

    kind: str
    shape: tuple = ()
    required: bool = False


_KINDS = {"float": "fiu", "int": "iu", "text": "U"}
#: bounds on the shared sizes named in shapes
_SIZE_LIMITS = {"T": (MIN_CLIP_FRAMES, MAX_CLIP_FRAMES, "frames"), "V": (3, MAX_MESH_VERTICES, "mesh vertices"),
                "F": (1, MAX_MESH_FACES, "mesh faces")}

_COMMON_FIELDS = {"schema": Field("text", required=True), "schema_version": Field("int"), "name": Field("text"),
                  "meta_json": Field("text")}
MOTION_FIELDS = {**_COMMON_FIELDS, "q_tbs": Field("float", ("T", 15, 4), True), "fps": Field("float", (), True),
                 "hand_name": Field("text"), "labels": Field("text", ("T",))}
HAND_FIELDS = {**_COMMON_FIELDS, "name": Field("text", required=True), "offsets": Field("float", (21, 3), True),
               "rest_frames": Field("float", (15, 3, 3), True), "rig_frames": Field("float", (16, 3, 3), True),
               "radii": Field("float", (21,), True), "mesh_vertices": Field("float", ("V", 3)),
               "mesh_faces": Field("int", ("F", 3)), "mesh_weights": Field("float", ("V", 16)), "source": Field("text")}
_MESH_KEYS = ("mesh_vertices", "mesh_faces", "mesh_weights")


def _header(archive: zipfile.ZipFile, member: str) -> tuple[tuple, np.dtype]:
    """Shape and dtype an npy member declares, read without decompressing the array."""
    with archive.open(member) as fh:
        version = np.lib.format.read_magic(fh)
        shape, _, dtype = (np.lib.format.read_array_header_1_0(fh) if version == (1, 0)
                           else np.lib.format.read_array_header_2_0(fh))
    return shape, dtype


def _check_field(path: Path, key: str, field: Field, shape: tuple, dtype: np.dtype, sizes: dict[str, int]) -> None:
    if dtype.kind not in _KINDS[field.kind] or dtype.hasobject:
        raise InputFileError(path, f"field {key} holds {dtype} values, expected {field.kind}")
    if field.kind == "text" and dtype.itemsize // 4 > MAX_TEXT_CHARS:
        raise InputFileError(path, f"field {key} is longer than {MAX_TEXT_CHARS} characters")
    expected = tuple(sizes.get(d, d) for d in field.shape)
    described = "(" + ", ".join(map(str, field.shape)) + ("," if len(field.shape) == 1 else "") + ")"
    if len(shape) != len(expected):
        raise InputFileError(path, f"field {key} has shape {shape}, expected {described}")
    for actual, want in zip(shape, expected):
        if isinstance(want, str):
            low, high, what = _SIZE_LIMITS[want]
            if not low <= actual <= high:
                raise InputFileError(path, f"field {key} has {actual} {what}; this program reads {low} to {high}")
            sizes[want] = actual
        elif actual != want:
            raise InputFileError(path, f"field {key} has shape {shape}, expected {described}")


def _open(path: Path, schema: str, fields: dict[str, Field], load_as: dict[str, tuple] | None = None
          ) -> dict[str, np.ndarray]:
    """The members of ``path`` named in ``fields``, each checked against its entry before it is read;
    ``load_as[key]`` = (dtype, convert) reads that member as ``dtype``, passing each chunk through ``convert``."""
    load_as = load_as or {}
    require_readable_file(path)
    try:
        with zipfile.ZipFile(path) as archive:
            members = {m[:-4]: m for m in archive.namelist() if m.endswith(".npy")}
            if "schema" not in members:
                raise InputFileError(path, f"not an {schema} file (schema missing)")
            _check_field(path, "schema", fields["schema"], *_header(archive, members["schema"]), {})
            with archive.open(members["schema"]) as fh:
                found = str(np.lib.format.read_array(fh, allow_pickle=False))
            if found != schema:
                raise InputFileError(path, f"not an {schema} file (schema {found or 'missing'})")
            missing = [k for k, f in fields.items() if f.required and k not in members]
            if missing:
                raise InputFileError(path, f"missing field(s): {', '.join(missing)}")
            sizes: dict[str, int] = {}
            for key, field in fields.items():
                if key in members:
                    _check_field(path, key, field, *_header(archive, members[key]), sizes)
            arrays = {k: _read(archive, members[k], *load_as.get(k, (None, None))) for k in fields if k in members}
    except InputFileError:
        raise
    except Exception as exc:  # zipfile, zlib, the npy header parser: many types on damaged input
        raise InputFileError(path, f"not a readable npz file ({type(exc).__name__}: {exc})") from exc
    version = int(arrays.get("schema_version", 0))
    current = _SCHEMA_VERSIONS[schema]
    if version > current:
        raise InputFileError(path, f"{schema} schema version {version} is newer than this program reads "
                                   f"({current})")
    if schema == "s2h-motion" and version < current:
        raise InputFileError(path, f"motion saved with schema {version}, whose TBS rotations were measured "
                                   f"from the rig's rest pose, not the canonical pose; re-export it from its "
                                   f"source file (BVH, glTF, FBX) or regenerate it (`make assets`)")
    for key, value in arrays.items():
        if value.dtype.kind != "f":
            continue
        n_bad, first_bad = nonfinite_frames(np.atleast_1d(value))
        if n_bad and fields[key].shape[:1] == ("T",):
            raise InputFileError(path, f"field {key} has NaN or infinite values in {n_bad} frames "
                                       f"(first at frame {first_bad})")
        if n_bad:
            raise InputFileError(path, f"field {key} contains NaN or infinite values")
    return arrays


def _read(archive: zipfile.ZipFile, member: str, dtype=None, convert=None) -> np.ndarray:
    """One npy member as ``dtype`` (default: its own), its rows decompressed, converted and copied a chunk
    at a time, so a clip is never held twice (as stored and as wanted)."""
    with archive.open(member) as fh:
        version = np.lib.format.read_magic(fh)
        shape, fortran, stored = (np.lib.format.read_array_header_1_0(fh) if version == (1, 0)
                                  else np.lib.format.read_array_header_2_0(fh))
        if fortran or not shape:  # scalars, and column-major arrays no writer of ours makes: whole
            size = stored.itemsize * int(np.prod(shape))
            data = fh.read(size)
            if len(data) < size:
                raise ValueError(f"member {member} ends before its {size} bytes")
            whole = np.frombuffer(data, stored).reshape(shape, order="F" if fortran else "C")
            return whole.astype(dtype or stored) if convert is None else convert(whole)
        out = np.empty(shape, dtype or stored)
        row_bytes = stored.itemsize * int(np.prod(shape[1:]))
        rows = max(1, READ_CHUNK_BYTES // max(row_bytes, 1))
        for first in range(0, shape[0], rows):
            end = min(first + rows, shape[0])
            data = fh.read((end - first) * row_bytes)
            if len(data) < (end - first) * row_bytes:
                raise ValueError(f"member {member} ends after {first} of its {shape[0]} rows")
            chunk = np.frombuffer(data, stored).reshape(end - first, *shape[1:])
            out[first:end] = chunk if convert is None else convert(chunk)
        if fh.read(1):
            raise ValueError(f"member {member} holds more data than its header declares")
    return out


def _meta(path: Path, arrays: dict[str, np.ndarray]) -> dict:
    """``meta_json`` as a dict (an object in JSON), at most `MAX_JSON_DEPTH` deep."""
    text = str(arrays.get("meta_json", "{}"))
    if bracket_depth(text) > MAX_JSON_DEPTH:
        raise InputFileError(path, f"meta_json is nested deeper than {MAX_JSON_DEPTH} levels")
    try:
        meta = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputFileError(path, f"meta_json is not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise InputFileError(path, f"meta_json holds a JSON {type(meta).__name__}, expected an object")
    return meta


def bracket_depth(text: str) -> int:
    """Deepest bracket nesting in ``text`` (strings included: only an upper bound, cheap and recursion-free)."""
    depth = deepest = 0
    for char in text:
        if char in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif char in "]}":
            depth -= 1
    return deepest


def save_motion(motion: Motion, path: str | Path) -> Path:
    """Write a motion npz atomically."""
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        _write(fh, dict(schema="s2h-motion", schema_version=MOTION_SCHEMA_VERSION, q_tbs=motion.q_tbs,
                        fps=np.float64(motion.fps), name=motion.name, hand_name=motion.hand_name,
                        labels=motion.labels, meta_json=json.dumps(motion.meta)))
    return path


def _write(fh, members: dict) -> None:
    """A compressed npz of ``members`` (what ``np.savez_compressed`` writes), streamed a chunk of rows at a
    time: neither the rotations nor the labels (an object array of strings, written as fixed-width text)
    are ever copied whole."""
    with zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED, allowZip64=True) as archive:
        for key, value in members.items():
            value = np.asanyarray(value)
            with archive.open(f"{key}.npy", "w", force_zip64=True) as member:
                if value.ndim == 0:
                    np.lib.format.write_array(member, value, allow_pickle=False)
                    continue
                stored = value.dtype
                if stored == object:
                    width = max(max(len(str(v)) for v in set(value[first:end].tolist()))
                                for first, end in frame_chunks(len(value)))
                    stored = np.dtype(f"<U{max(width, 1)}")
                np.lib.format.write_array_header_1_0(member, {"descr": np.lib.format.dtype_to_descr(stored),
                                                              "fortran_order": False, "shape": value.shape})
                for first, end in frame_chunks(len(value)):
                    member.write(np.ascontiguousarray(value[first:end], dtype=stored).data)


def load_motion(path: str | Path) -> Motion:
    """Read a motion npz; any problem is an `InputFileError` naming the file."""
    path = Path(path)
    with reading(path, "an s2h motion"):
        arrays = _open(path, "s2h-motion", MOTION_FIELDS, MOTION_LOAD_AS)
        if float(arrays["fps"]) <= 0:
            raise InputFileError(path, f"frame rate {float(arrays['fps'])} is not positive")
        try:
            return Motion(q_tbs=arrays["q_tbs"], fps=float(arrays["fps"]), name=str(arrays.get("name", path.stem)),
                          hand_name=str(arrays.get("hand_name", "")),
                          labels=arrays.get("labels"),
                          meta=_meta(path, arrays))
        except S2HError as exc:
            raise InputFileError(path, str(exc)) from None


def save_hand(hand: HandModel, path: str | Path) -> Path:
    """Write a hand npz atomically (mesh included when present)."""
    path = Path(path)
    fields = dict(schema="s2h-hand", schema_version=HAND_SCHEMA_VERSION, name=hand.name, offsets=hand.offsets,
                  rest_frames=hand.rest_frames, rig_frames=hand.rig_frames, radii=hand.radii, source=hand.source,
                  meta_json=json.dumps(hand.meta))
    if hand.mesh is not None:
        fields.update(mesh_vertices=hand.mesh.vertices, mesh_faces=hand.mesh.faces, mesh_weights=hand.mesh.weights)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        _write(fh, fields)
    return path


def load_hand(path: str | Path) -> HandModel:
    """Read a hand npz; any problem is an `InputFileError` naming the file."""
    path = Path(path)
    with reading(path, "an s2h hand"):
        arrays = _open(path, "s2h-hand", HAND_FIELDS)
        mesh = None
        present = [k for k in _MESH_KEYS if k in arrays]
        if present and len(present) < len(_MESH_KEYS):
            raise InputFileError(path, f"missing field(s): {', '.join(k for k in _MESH_KEYS if k not in arrays)}")
        if present:
            mesh = SkinnedMesh(vertices=arrays["mesh_vertices"].astype(np.float32),
                               faces=arrays["mesh_faces"].astype(np.int32),
                               weights=arrays["mesh_weights"].astype(np.float32))
        if np.any(arrays["radii"] <= 0):
            raise InputFileError(path, "radii must be positive")
        try:
            return HandModel(name=str(arrays["name"]), offsets=arrays["offsets"], rest_frames=arrays["rest_frames"],
                             rig_frames=arrays["rig_frames"], radii=arrays["radii"], mesh=mesh,
                             source=str(arrays.get("source", path)), meta=_meta(path, arrays))
        except S2HError as exc:
            raise InputFileError(path, str(exc)) from None
