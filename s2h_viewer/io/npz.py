"""The project's own npz formats for hands and motions (schema-versioned, atomic writes).

Motion npz (schema 2): ``q_tbs`` float32 (T, 15, 4) quaternions (w, x, y, z) in TBS space measured
from the hand's canonical pose (schema 1 measured them from the rig's rest pose: refused, see
``MOTION_SCHEMA_VERSION``),
``fps`` float, ``name`` str, ``hand_name`` str (the hand it is posed on), ``labels`` str (T,)
(gesture held at each frame, "" between gestures), ``meta_json`` (provenance: gesture script, seed), ``schema`` = "s2h-motion", ``schema_version`` = 2.

Hand npz (schema 1): ``name``, ``offsets`` (21, 3), ``rest_frames`` (15, 3, 3), ``rig_frames``
(16, 3, 3), ``radii`` (21,), optional ``mesh_vertices`` (V, 3), ``mesh_faces`` (F, 3),
``mesh_weights`` (V, 16), ``source``, ``meta_json``, ``schema`` = "s2h-hand", ``schema_version`` = 1.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from s2h_viewer.errors import InputFileError, S2HError
from s2h_viewer.hand.model import HandModel, SkinnedMesh
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.atomic import atomic_path

HAND_SCHEMA_VERSION = 1
#: 2: TBS rotations measured from the canonical pose (DESIGN.md section 2); 1 (rest pose) is refused
MOTION_SCHEMA_VERSION = 2
_SCHEMA_VERSIONS = {"s2h-hand": HAND_SCHEMA_VERSION, "s2h-motion": MOTION_SCHEMA_VERSION}


def _open(path: Path, schema: str) -> dict[str, np.ndarray]:
    if not path.exists():
        raise InputFileError(path, "file not found")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise InputFileError(path, f"not a readable npz file ({exc})") from None
    found = str(arrays.get("schema", ""))
    if found != schema:
        raise InputFileError(path, f"not an {schema} file (schema {found or 'missing'})")
    version = int(arrays.get("schema_version", 0))
    current = _SCHEMA_VERSIONS[schema]
    if version > current:
        raise InputFileError(path, f"{schema} schema version {version} is newer than this program reads "
                                   f"({current})")
    if schema == "s2h-motion" and version < current:
        raise InputFileError(path, f"motion saved with schema {version}, whose TBS rotations were measured "
                                   f"from the rig's rest pose, not the canonical pose; re-export it from its "
                                   f"source file (BVH, glTF, FBX) or regenerate it (`make assets`)")
    return arrays


def _require(path: Path, arrays: dict[str, np.ndarray], *keys: str) -> None:
    missing = [k for k in keys if k not in arrays]
    if missing:
        raise InputFileError(path, f"missing field(s): {', '.join(missing)}")


def save_motion(motion: Motion, path: str | Path) -> Path:
    """Write a motion npz atomically."""
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, schema="s2h-motion", schema_version=MOTION_SCHEMA_VERSION, q_tbs=motion.q_tbs,
                            fps=np.float64(motion.fps), name=motion.name, hand_name=motion.hand_name,
                            labels=motion.labels.astype(str), meta_json=json.dumps(motion.meta))
    return path


def load_motion(path: str | Path) -> Motion:
    """Read a motion npz; any problem is an `InputFileError` naming the file."""
    path = Path(path)
    arrays = _open(path, "s2h-motion")
    _require(path, arrays, "q_tbs", "fps")
    try:
        return Motion(q_tbs=arrays["q_tbs"], fps=float(arrays["fps"]), name=str(arrays.get("name", path.stem)),
                      hand_name=str(arrays.get("hand_name", "")),
                      labels=arrays["labels"].astype(object) if "labels" in arrays else None,
                      meta=json.loads(str(arrays.get("meta_json", "{}"))))
    except (S2HError, json.JSONDecodeError) as exc:
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
        np.savez_compressed(fh, **fields)
    return path


def load_hand(path: str | Path) -> HandModel:
    """Read a hand npz; any problem is an `InputFileError` naming the file."""
    path = Path(path)
    arrays = _open(path, "s2h-hand")
    _require(path, arrays, "name", "offsets", "rest_frames", "rig_frames", "radii")
    mesh = None
    if "mesh_vertices" in arrays:
        _require(path, arrays, "mesh_faces", "mesh_weights")
        mesh = SkinnedMesh(vertices=arrays["mesh_vertices"].astype(np.float32),
                           faces=arrays["mesh_faces"].astype(np.int32),
                           weights=arrays["mesh_weights"].astype(np.float32))
    try:
        return HandModel(name=str(arrays["name"]), offsets=arrays["offsets"], rest_frames=arrays["rest_frames"],
                         rig_frames=arrays["rig_frames"], radii=arrays["radii"], mesh=mesh,
                         source=str(arrays.get("source", path)), meta=json.loads(str(arrays.get("meta_json", "{}"))))
    except (S2HError, json.JSONDecodeError) as exc:
        raise InputFileError(path, str(exc)) from None
