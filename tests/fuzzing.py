"""A seeded mutator over the shipped samples and a harness that classifies what each reader does with them.

Each ``mutate_*`` function turns one valid file into a damaged one (bytes: truncations, flips, zeroed
chunks, appended bytes; structure: glTF JSON that lies, npz members of the wrong key, shape or dtype,
NaN/Inf, BVH counts and values, sidecar and joint-map JSON of the wrong types). `classify` runs a
loader on one input and says which of these it did:

- ``ok``: loaded, and everything it returned is finite (a mutation may leave a file valid);
- ``clean``: an `InputFileError`, one line, naming the file;
- ``unclear``: an `InputFileError` with more than one line or without the file's name;
- ``memory``: an `InputFileError` made from a MemoryError (an allocation a check should have stopped);
- ``traceback``: any other exception;
- ``hang``: still running after the time limit;
- ``nan``: loaded, but with NaN or infinite values in what it returned.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import struct
import zipfile
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pygltflib

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.corrections import CorrectionsFile

OUTCOMES = ("ok", "clean", "unclear", "memory", "traceback", "hang", "nan")
BAD_OUTCOMES = ("unclear", "memory", "traceback", "hang", "nan")


# ---------------------------------------------------------------- byte-level mutations (any format)

def truncate(data: bytes, rng: np.random.Generator) -> bytes:
    return data[:int(rng.integers(0, max(len(data), 1)))]


def flip_bytes(data: bytes, rng: np.random.Generator) -> bytes:
    out = bytearray(data)
    for at in rng.integers(0, len(out), size=int(rng.integers(1, 32))):
        out[at] ^= int(rng.integers(1, 256))
    return bytes(out)


def zero_chunk(data: bytes, rng: np.random.Generator) -> bytes:
    out = bytearray(data)
    start = int(rng.integers(0, len(out)))
    length = int(rng.integers(1, max(2, len(out) // 8)))
    out[start:start + length] = bytes(min(length, len(out) - start))
    return bytes(out)


def append_bytes(data: bytes, rng: np.random.Generator) -> bytes:
    return data + rng.bytes(int(rng.integers(1, 4096)))


BYTE_MUTATIONS = (truncate, flip_bytes, zero_chunk, append_bytes)


def mutate_bytes(data: bytes, rng: np.random.Generator) -> tuple[str, bytes]:
    fn = BYTE_MUTATIONS[int(rng.integers(len(BYTE_MUTATIONS)))]
    return fn.__name__, fn(data, rng)


# ---------------------------------------------------------------- npz

def _npz_bytes(arrays: dict[str, np.ndarray]) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def _lying_header(arrays: dict[str, np.ndarray], key: str, shape: tuple) -> bytes:
    """An npz whose member ``key`` declares ``shape`` in its header but holds a few bytes."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, value in arrays.items():
            member = io.BytesIO()
            if name == key:
                np.lib.format.write_array_header_1_0(member, {"descr": "<f4", "fortran_order": False, "shape": shape})
                member.write(b"\0" * 64)
            else:
                np.lib.format.write_array(member, np.asanyarray(value))
            archive.writestr(f"{name}.npy", member.getvalue())
    return buffer.getvalue()


def _poisoned(value: np.ndarray, rng: np.random.Generator, poison: float) -> np.ndarray:
    value = np.array(value, dtype=np.float64, copy=True)
    if value.size:
        value.flat[int(rng.integers(value.size))] = poison
    return value


def mutate_npz(data: bytes, rng: np.random.Generator) -> tuple[str, bytes]:
    """A damaged copy of an npz: a byte mutation, or a member of the wrong key, shape, dtype or value."""
    with np.load(io.BytesIO(data)) as loaded:
        arrays = {k: loaded[k] for k in loaded.files}
    keys = sorted(arrays)
    key = keys[int(rng.integers(len(keys)))]
    value = arrays[key]
    kind = int(rng.integers(16))
    if kind == 0:
        return mutate_bytes(data, rng)
    if kind == 1:
        del arrays[key]
        return f"drop {key}", _npz_bytes(arrays)
    if kind == 2:
        arrays[key] = np.array(["not", "numbers"])
        return f"strings as {key}", _npz_bytes(arrays)
    if kind == 3:
        shape = tuple(int(s) for s in rng.integers(0, 5, size=int(rng.integers(0, 4))))
        arrays[key] = np.ones(shape)
        return f"{key} of shape {shape}", _npz_bytes(arrays)
    if kind == 4 and value.dtype.kind == "f":
        arrays[key] = _poisoned(value, rng, [np.nan, np.inf, -np.inf, 1e308][int(rng.integers(4))])
        return f"NaN/Inf in {key}", _npz_bytes(arrays)
    if kind == 5 and "fps" in arrays:
        arrays["fps"] = np.array([0.0, -30.0, np.nan, np.inf, 1e-300][int(rng.integers(5))])
        return f"fps {arrays['fps']}", _npz_bytes(arrays)
    if kind == 6 and "q_tbs" in arrays:
        q = arrays["q_tbs"].copy()
        q[int(rng.integers(len(q))), int(rng.integers(15))] = 0.0
        arrays["q_tbs"] = q
        return "zero quaternion", _npz_bytes(arrays)
    if kind == 7 and "q_tbs" in arrays:
        arrays["q_tbs"] = arrays["q_tbs"][:1]
        arrays.pop("labels", None)
        return "one frame", _npz_bytes(arrays)
    if kind == 8:
        arrays["meta_json"] = np.array(["[]", "5", '"x"', "[" * 100_000 + "]" * 100_000, "{not json", "null"]
                                       [int(rng.integers(6))])
        return "bad meta_json", _npz_bytes(arrays)
    if kind == 9 and value.ndim:
        return f"{key} header claims 10^9 rows", _lying_header(arrays, key, (10 ** 9, *value.shape[1:]))
    if kind == 10:
        arrays["schema_version"] = np.array([99, -1, "one"][int(rng.integers(3))])
        return "schema_version", _npz_bytes(arrays)
    if kind == 11 and "mesh_faces" in arrays:
        faces = arrays["mesh_faces"].copy()
        faces.flat[int(rng.integers(faces.size))] = [-1, 10 ** 6][int(rng.integers(2))]
        arrays["mesh_faces"] = faces
        return "face index out of range", _npz_bytes(arrays)
    if kind == 12 and "labels" in arrays:
        arrays["labels"] = arrays["labels"][: len(arrays["labels"]) // 2]
        return "labels of the wrong length", _npz_bytes(arrays)
    if kind == 13:
        arrays[key] = value.astype(np.complex64) if value.dtype.kind in "fiu" else np.zeros(3, dtype=bool)
        return f"{key} as complex/bool", _npz_bytes(arrays)
    if kind == 14 and "mesh_weights" in arrays:
        arrays["mesh_weights"] = arrays["mesh_weights"] * 3.0
        return "skin weights not summing to 1", _npz_bytes(arrays)
    return mutate_bytes(data, rng)


# ---------------------------------------------------------------- glTF / GLB

def _glb_bytes(gltf: pygltflib.GLTF2) -> bytes:
    """A GLB of ``gltf``'s JSON and binary blob as they are (even where they lie about each other)."""
    text = gltf.to_json(separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    blob = gltf.binary_blob() or b""
    blob += b"\0" * (-len(blob) % 4)
    chunks = (struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(blob), b"BIN\0") + blob)
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def _accessor_region(gltf: pygltflib.GLTF2, index: int) -> tuple[int, int]:
    acc = gltf.accessors[index]
    view = gltf.bufferViews[acc.bufferView]
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    return start, start + min(view.byteLength - (acc.byteOffset or 0), 4 * 16 * acc.count)


def mutate_gltf(data: bytes, rng: np.random.Generator) -> tuple[str, bytes]:
    """A damaged copy of a GLB: a byte mutation, JSON that lies (counts, indices, offsets, types,
    transforms, a cyclic hierarchy) or binary data poisoned with NaN, huge, zero or reversed values."""
    kind = int(rng.integers(12))
    if kind == 0:
        return mutate_bytes(data, rng)
    gltf = pygltflib.GLTF2.load_from_bytes(data)
    pick = lambda table: int(rng.integers(len(table)))  # noqa: E731
    huge = [0, -1, 10 ** 9, 3 * 10 ** 7, 2 ** 40, "12", 1.5, None]
    if kind == 1:
        acc = gltf.accessors[pick(gltf.accessors)]
        acc.count = huge[int(rng.integers(len(huge)))]
        what = f"accessor count {acc.count!r}"
    elif kind == 2:
        acc = gltf.accessors[pick(gltf.accessors)]
        attr, value = [("byteOffset", -4), ("byteOffset", 10 ** 9), ("byteOffset", 3), ("componentType", 5130),
                       ("componentType", "x"), ("type", "MAT4"), ("type", "VEC2"), ("type", "X"),
                       ("bufferView", 999), ("bufferView", -1)][int(rng.integers(10))]
        setattr(acc, attr, value)
        what = f"accessor {attr} {value!r}"
    elif kind == 3:
        view = gltf.bufferViews[pick(gltf.bufferViews)]
        attr, value = [("byteOffset", 10 ** 9), ("byteOffset", -8), ("byteLength", 2 ** 40), ("byteLength", 0),
                       ("byteLength", 1), ("byteStride", 1), ("byteStride", 10 ** 6), ("buffer", 7)][int(rng.integers(8))]
        setattr(view, attr, value)
        what = f"bufferView {attr} {value!r}"
    elif kind == 4:
        node = gltf.nodes[pick(gltf.nodes)]
        index = gltf.nodes.index(node)
        choice = int(rng.integers(8))
        if choice == 0:
            node.children = (node.children or []) + [99_999]
        elif choice == 1:
            node.children = (node.children or []) + [index]
        elif choice == 2:  # a cycle: the node becomes a child of its own child
            if node.children:
                gltf.nodes[node.children[0]].children = (gltf.nodes[node.children[0]].children or []) + [index]
        elif choice == 3:
            node.rotation = [0.0, 0.0, 0.0, 0.0]
        elif choice == 4:
            node.rotation = [float("nan"), 0.0, 0.0, 1.0]
        elif choice == 5:
            node.rotation = ["a", "b", "c", "d"]
        elif choice == 6:
            node.matrix = [1.0] * 15
        else:
            node.translation = [1e308, 1e308, 1e308]
        what = f"node {index} mutation {choice}"
    elif kind == 5 and gltf.skins:
        skin = gltf.skins[0]
        if rng.integers(2):
            skin.joints = list(skin.joints) + [99_999]
            what = "skin joint out of range"
        else:
            skin.inverseBindMatrices = [99_999, 0][int(rng.integers(2))]
            what = f"inverseBindMatrices -> {skin.inverseBindMatrices}"
    elif kind == 6 and gltf.meshes:
        prim = gltf.meshes[0].primitives[0]
        attr = ["indices", "POSITION", "JOINTS_0", "WEIGHTS_0"][int(rng.integers(4))]
        other = pick(gltf.accessors)
        if attr == "indices":
            prim.indices = other
        else:
            setattr(prim.attributes, attr, other)
        what = f"primitive {attr} -> accessor {other}"
    elif kind == 7 and gltf.animations:
        anim = gltf.animations[0]
        choice = int(rng.integers(5))
        if choice == 0:
            anim.channels[pick(anim.channels)].target.node = 99_999
        elif choice == 1:
            anim.channels[pick(anim.channels)].sampler = 999
        elif choice == 2:
            sampler = anim.samplers[pick(anim.samplers)]
            sampler.input, sampler.output = sampler.output, sampler.input
        elif choice == 3:
            anim.samplers[pick(anim.samplers)].interpolation = "CUBICSPLINE"
        else:
            anim.samplers[pick(anim.samplers)].input = pick(gltf.accessors)
        what = f"animation mutation {choice}"
    elif kind in (8, 9, 10):  # poison the binary data of one accessor
        blob = bytearray(gltf.binary_blob())
        index = pick(gltf.accessors)
        start, end = _accessor_region(gltf, index)
        floats = np.frombuffer(bytes(blob[start:end - (end - start) % 4]), dtype=np.float32).copy()
        if len(floats):
            poison = [np.nan, np.inf, 3e38, 0.0][int(rng.integers(4))] if kind != 10 else None
            if poison is None:  # key times reversed, or every value zero (zero quaternions)
                floats = floats[::-1].copy() if rng.integers(2) else np.zeros_like(floats)
            else:
                floats[rng.integers(0, len(floats), size=int(rng.integers(1, 8)))] = poison
            blob[start:start + 4 * len(floats)] = floats.tobytes()
        gltf.set_binary_blob(bytes(blob))
        what = f"accessor {index} data poisoned"
    else:
        gltf.accessors[pick(gltf.accessors)].count = 10 ** 9
        what = "accessor count 10^9"
    return what, _glb_bytes(gltf)


# ---------------------------------------------------------------- BVH

def mutate_bvh(data: bytes, rng: np.random.Generator) -> tuple[str, bytes]:
    """A damaged copy of a BVH: bytes, or NaN/Inf/1e308 values, lying frame counts, bad frame times,
    wrong channel counts, missing braces or garbage tokens."""
    kind = int(rng.integers(8))
    if kind == 0:
        return mutate_bytes(data, rng)
    lines = data.decode().splitlines()
    motion = next(i for i, line in enumerate(lines) if line.startswith("MOTION"))
    if kind == 1:
        row = int(rng.integers(motion + 3, len(lines)))
        values = lines[row].split()
        values[int(rng.integers(len(values)))] = ["nan", "inf", "-inf", "1e308", "-1e308", "abc"][int(rng.integers(6))]
        lines[row] = " ".join(values)
        what = "bad value"
    elif kind == 2:
        n = int(lines[motion + 1].split()[1])
        lines[motion + 1] = f"Frames: {[n + 1, n - 1, 0, -5, 10 ** 12, 'many'][int(rng.integers(6))]}"
        what = lines[motion + 1]
    elif kind == 3:
        lines[motion + 2] = f"Frame Time: {['0', '-0.03', 'nan', 'inf', '1e-300'][int(rng.integers(5))]}"
        what = lines[motion + 2]
    elif kind == 4:
        rows = [i for i, line in enumerate(lines[:motion]) if "CHANNELS" in line]
        row = rows[int(rng.integers(len(rows)))]
        parts = lines[row].split()
        parts[1] = str([7, -1, 2, 10 ** 9][int(rng.integers(4))])
        lines[row] = " ".join(parts)
        what = "channel count"
    elif kind == 5:
        rows = [i for i, line in enumerate(lines[:motion]) if line.strip() in ("{", "}")]
        del lines[rows[int(rng.integers(len(rows)))]]
        what = "missing brace"
    elif kind == 6:
        row = int(rng.integers(1, motion))
        lines.insert(row, ["Garbage", "OFFSET nan 0 0", "JOINT", "End", "{", "CHANNELS 3 Wrotation Xrotation Yrotation"]
                     [int(rng.integers(6))])
        what = "garbage token"
    else:
        del lines[motion:]
        what = "no MOTION"
    return what, ("\n".join(lines) + "\n").encode()


# ---------------------------------------------------------------- JSON (sidecars, joint maps)

def _wrong_type(rng: np.random.Generator):
    return [5, "text", [], {}, None, True, 1e308, [[1, 2], [3]], float("nan"), -1][int(rng.integers(10))]


def mutate_json(data: bytes, rng: np.random.Generator) -> tuple[str, bytes]:
    """A damaged copy of a JSON document: bytes, a value of the wrong type anywhere in it, zero or NaN
    matrices, deep nesting, a list or number at the top."""
    kind = int(rng.integers(6))
    if kind == 0:
        return mutate_bytes(data, rng)
    if kind == 1:
        return "deep nesting", ("[" * 100_000 + "]" * 100_000).encode()
    if kind == 2:
        return "top-level non-object", json.dumps(_wrong_type(rng)).encode()
    document = json.loads(data)
    paths = list(_json_paths(document))
    where = paths[int(rng.integers(len(paths)))]
    parent = document
    for key in where[:-1]:
        parent = parent[key]
    if kind == 3:
        parent[where[-1]] = _wrong_type(rng)
        what = f"{'/'.join(map(str, where))} of a wrong type"
    elif kind == 4:
        frames = [p for p in paths if p[-1] == "frame"]
        target = document
        for key in (frames[int(rng.integers(len(frames)))] if frames else where)[:-1]:
            target = target[key]
        target["frame" if frames else where[-1]] = [[[0, 0, 0]] * 3, [[float("nan")] * 3] * 3,
                                                    [[1, 0, 0], [0, 1, 0], [0, 0, -1]]][int(rng.integers(3))]
        what = "bad frame matrix"
    else:
        del parent[where[-1]]
        what = f"{'/'.join(map(str, where))} removed"
    return what, json.dumps(document).encode()


def _json_paths(value, prefix: tuple = ()) -> Iterator[tuple]:
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for key, child in items:
        yield (*prefix, key)
        yield from _json_paths(child, (*prefix, key))


# ---------------------------------------------------------------- classifying a loader's outcome

class Hang(Exception):
    """The time limit passed."""


@contextlib.contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Raise `Hang` in this (main) thread after ``seconds``."""
    def expired(signum, frame):
        raise Hang()
    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _finite(result) -> bool:
    """Whether every number in a loader's result (a hand, a motion, or a tuple of them) is finite."""
    if isinstance(result, tuple):
        return all(_finite(r) for r in result if r is not None)
    if isinstance(result, HandModel):
        arrays = [result.offsets, result.rest_frames, result.rig_frames, result.radii]
        if result.mesh is not None:
            arrays += [result.mesh.vertices, result.mesh.weights]
        return all(np.isfinite(a).all() for a in arrays)
    if isinstance(result, Motion):
        return bool(np.isfinite(result.q_tbs).all() and np.isfinite(result.fps) and result.fps > 0)
    if isinstance(result, CorrectionsFile):
        return all(np.isfinite(k.rotvec).all() for c in result.corrections.joints for k in c.keys)
    raise TypeError(f"unexpected loader result {type(result).__name__}")


def classify(load: Callable[[], object], path: Path, seconds: float = 30.0) -> tuple[str, str]:
    """(outcome, detail) of running ``load`` on the damaged file ``path`` (see the module docstring)."""
    try:
        with time_limit(seconds):
            result = load()
    except Hang:
        return "hang", f"over {seconds} s"
    except InputFileError as exc:
        message = str(exc)
        if isinstance(exc.__cause__, MemoryError):
            return "memory", message
        if "\n" in message or path.name not in message:
            return "unclear", message
        return "clean", message
    except Exception as exc:  # noqa: BLE001 - the point: any other exception is a defect
        return "traceback", f"{type(exc).__name__}: {exc}"[:300]
    return ("ok", "") if _finite(result) else ("nan", "loaded with NaN or infinite values")


@dataclass
class Tally:
    """Outcomes per reader, with one example of each bad outcome."""

    counts: dict[str, Counter] = field(default_factory=dict)
    examples: list[str] = field(default_factory=list)

    def add(self, reader: str, what: str, outcome: str, detail: str) -> None:
        self.counts.setdefault(reader, Counter())[outcome] += 1
        if outcome in BAD_OUTCOMES:
            self.examples.append(f"{reader} [{what}] {outcome}: {detail}")

    def bad(self) -> int:
        return sum(c[o] for c in self.counts.values() for o in BAD_OUTCOMES)

    def table(self) -> str:
        rows = ["| reader | inputs | " + " | ".join(OUTCOMES) + " |", "|---|---:|" + "---:|" * len(OUTCOMES)]
        for reader, counts in self.counts.items():
            rows.append(f"| {reader} | {sum(counts.values())} | " + " | ".join(str(counts[o]) for o in OUTCOMES) + " |")
        total = sum((c for c in self.counts.values()), Counter())
        rows.append(f"| all | {sum(total.values())} | " + " | ".join(str(total[o]) for o in OUTCOMES) + " |")
        return "\n".join(rows)


def unreadable_supported() -> bool:
    """chmod 000 stops a reader only for a user other than root."""
    return os.geteuid() != 0
