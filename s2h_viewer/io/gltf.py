"""glTF 2.0 / GLB: rigged hands in, animations in and out (pygltflib).

- `load_gltf_hand`: the skinned mesh and skeleton of a hand, or of one hand of a full-body character.
- `load_gltf_motion`: an animation's bone rotations as a `Motion` on a hand loaded from the same rig.
- `save_gltf_motion`: a GLB that opens in Blender with the avatar: the hand's own source file with the
  motion added as an animation, or, for hands made here, the skinned hand written out with it; the
  hand's TBS frames go beside it as its sidecar, since the ray solver's frames of the reopened file
  (a few degrees off, or unlike frames set by hand) would read other TBS rotations back.
"""

from __future__ import annotations

import functools
import hashlib
import json
import re
from pathlib import Path

import numpy as np
import pygltflib
from scipy.spatial.transform import Rotation, Slerp

from s2h_viewer.errors import InputFileError, reading, require_readable_file
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rig_mapping import RigMapping
from s2h_viewer.io.annotation import hand_side, refuse_foreign_sidecar, save_hand_frames
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.io.gltf_json import DecodedGLTF2
from s2h_viewer.io.rig import (RigMesh, RigSkeleton, bone_indices, build_hand, motion_from_world_rotations,
                               recognise, rotation_part, world_rotations_from_motion)
from s2h_viewer.io.rig_gltf import node_rotations, rig_document

_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
GLTF_SUFFIXES = (".glb", ".gltf", ".vrm")
BINARY_SUFFIXES = (".glb", ".vrm")  # binary glTF (a VRM avatar is one, with a VRM extension)
_VRM_FINGER = {"thumb": "Thumb", "index": "Index", "middle": "Middle", "ring": "Ring", "pinky": "Little"}
#: VRM humanoid bone suffixes of the three articulated levels: (fingers, thumb)
VRM0_LEVELS = (("Proximal", "Intermediate", "Distal"), ("Proximal", "Intermediate", "Distal"))
VRM1_LEVELS = (("Proximal", "Intermediate", "Distal"), ("Metacarpal", "Proximal", "Distal"))


#: bounds on what a file may declare, checked before anything is allocated
MAX_NODES = 100_000
MAX_ACCESSOR_ELEMENTS = 20_000_000
MAX_MESH_VERTICES = 2_000_000
#: frames x animated nodes resampled from one animation (float64 3 x 3 each: about 1.4 GiB)
MAX_ANIMATION_SAMPLES = 20_000_000


def _index(path: Path, value, table: list | None, what: str) -> int:
    """``value`` as an index into ``table``, or an `InputFileError` naming ``what``."""
    size = len(table or [])
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < size:
        raise InputFileError(path, f"{what} refers to entry {value!r} of {size}")
    return value


def _numbers(path: Path, value, length: int, what: str) -> np.ndarray:
    """``value`` as ``length`` finite floats, or an `InputFileError` naming ``what``."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputFileError(path, f"{what} is not a list of numbers") from None
    if array.shape != (length,) or not np.isfinite(array).all():
        raise InputFileError(path, f"{what} must be {length} finite numbers")
    return array


GLB_HEADER_BYTES = 12


def _check_glb_header(path: Path) -> None:
    """Refuse, in words a user can act on, a GLB that is not one, whose size is not what its header says
    (shorter: cut off; longer: changed after it was written, as a text-mode transfer does), or whose chunks
    do not fit in it or hold no JSON."""
    size = path.stat().st_size
    with open(path, "rb") as f:
        header = f.read(GLB_HEADER_BYTES)
        if len(header) < GLB_HEADER_BYTES or header[:4] != b"glTF":
            raise InputFileError(path, f"not a GLB file: it does not start with a GLB header ({size} bytes)")
        declared = int.from_bytes(header[8:12], "little")
        if size < declared:
            raise InputFileError(path, f"truncated GLB: its header declares {declared} bytes, the file has {size} "
                                       f"(an interrupted download or copy?)")
        if size > declared:
            raise InputFileError(path, f"damaged GLB: its header declares {declared} bytes, the file has {size} "
                                       f"(changed after it was written: a text-mode transfer or a line-ending "
                                       f"conversion does this)")
        chunk = f.read(8)
        length = int.from_bytes(chunk[:4], "little") if len(chunk) == 8 else -1
        if len(chunk) < 8 or chunk[4:8] != b"JSON":
            raise InputFileError(path, "damaged GLB: its first chunk is not the JSON chunk")
        if GLB_HEADER_BYTES + 8 + length > size:
            raise InputFileError(path, f"damaged GLB: its JSON chunk declares {length} bytes, past the end of the "
                                       f"file ({size} bytes)")
        text = f.read(length)
    try:
        json.loads(text.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise InputFileError(path, f"damaged GLB: its JSON chunk is not UTF-8 text (byte {exc.start} of "
                                   f"{length})") from None
    except json.JSONDecodeError as exc:
        raise InputFileError(path, f"damaged GLB: its JSON chunk is not valid JSON (at character {exc.pos}: "
                                   f"{exc.msg})") from None


#: extensions whose data s2h cannot decode: a file that requires one is refused, naming it, never misread
COMPRESSION_EXTENSIONS = {"EXT_meshopt_compression": "meshopt", "KHR_draco_mesh_compression": "Draco"}


def _refuse_compressed(path: Path, gltf: pygltflib.GLTF2) -> None:
    """An `InputFileError` for a file whose buffers or meshes are compressed with an extension it requires
    (without the requirement, the uncompressed fallback data is there and is what is read)."""
    required = [e for e in (gltf.extensionsRequired or []) if e in COMPRESSION_EXTENSIONS]
    if required:
        kinds = " and ".join(f"{COMPRESSION_EXTENSIONS[e]} ({e})" for e in required)
        raise InputFileError(path, f"its meshes are {kinds} compressed, which s2h does not decode; write it "
                                   f"uncompressed (gltfpack -i FILE -o OUT.glb -noq, or a Blender re-export without "
                                   f"compression) and open that")


def read_document(path: str | Path) -> "_Document":
    """The parsed file, read once while its bytes stay the same (under the name given): one hand and its motions
    read a file three to five times over (its rig, its animations as the hinges' evidence, each animation), and
    a parse of the 35 poses takes 0.1 s (`io.gltf_json`; pygltflib's own decoding took 6 s), hashing them
    milliseconds. Readers only: a writer edits its own."""
    path = require_readable_file(Path(path))
    try:
        digest = hashlib.blake2b(path.read_bytes(), digest_size=16)
        if path.suffix.lower() not in BINARY_SUFFIXES:  # its buffers may be files beside it
            for beside in sorted(path.parent.glob("*.bin")):
                stat = beside.stat()
                digest.update(f"{beside.name} {stat.st_size} {stat.st_mtime_ns}".encode())
    except OSError:
        return _Document(path)  # unreadable: its own error
    return _parsed(str(path), digest.hexdigest())


@functools.lru_cache(maxsize=4)
def _parsed(path: str, digest: str) -> "_Document":
    return _Document(Path(path))


class _Document:
    """A parsed glTF with its binary data in one blob, and the scene graph at rest."""

    def __init__(self, path: Path):
        self.path = require_readable_file(path)
        binary = self.path.suffix.lower() in BINARY_SUFFIXES
        if binary:
            _check_glb_header(self.path)
        try:
            self.gltf = DecodedGLTF2.load_binary(str(path)) if binary else DecodedGLTF2.load(str(path))
            if self.gltf is None:
                raise ValueError("empty file")
            self.gltf.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)
        except FileNotFoundError:
            raise InputFileError(path, "file not found") from None
        except Exception as exc:  # pygltflib raises many types on damaged input
            raise InputFileError(path, f"not a readable glTF/GLB file ({type(exc).__name__}: {exc})") from None
        self.blob = self.gltf.binary_blob() or b""
        _refuse_compressed(self.path, self.gltf)
        nodes = self.gltf.nodes or []
        if len(nodes) > MAX_NODES:
            raise InputFileError(path, f"has {len(nodes)} nodes, over the limit of {MAX_NODES}")
        self.names = [str(n.name) if n.name else f"node{i}" for i, n in enumerate(nodes)]
        self.parents = np.full(len(nodes), -1)
        for i, node in enumerate(nodes):
            for child in node.children or []:
                child = _index(path, child, nodes, f"node {i}'s child")
                if self.parents[child] >= 0:
                    raise InputFileError(path, f"node {self.names[child]!r} has two parents "
                                               f"({self.names[self.parents[child]]!r}, {self.names[i]!r})")
                self.parents[child] = i
        self._refuse_cycles()
        self.order = self._parents_first()
        self.local = (np.stack([_local_matrix(path, i, n) for i, n in enumerate(nodes)]) if nodes
                      else np.zeros((0, 4, 4)))
        self.world = self.local.copy()
        for i in self.order:
            if self.parents[i] >= 0:
                self.world[i] = self.world[self.parents[i]] @ self.local[i]

    def _refuse_cycles(self) -> None:
        """Bones whose parents lead back to themselves: one clear error naming the loop."""
        for start in range(len(self.parents)):
            path, node = [], start
            while node >= 0 and node not in path and len(path) <= len(self.parents):
                path.append(node)
                node = self.parents[node]
            if node >= 0:
                loop = path[path.index(node):] + [node]
                raise InputFileError(self.path, "bones form a cycle (" + " -> ".join(self.names[n] for n in loop)
                                     + "): a skeleton must be a tree; fix the parenting in the authoring tool")

    def humanoid_map(self) -> dict[str, dict[str, str]] | None:
        """VRM 0.x / 1.0 humanoid bones of each hand as side -> canonical joint -> node name, None if not VRM."""
        extensions = self.gltf.extensions or {}
        if "VRMC_vrm" in extensions:
            bones = {k: v.get("node") for k, v in extensions["VRMC_vrm"].get("humanoid", {}).get("humanBones",
                                                                                                  {}).items()}
            levels = VRM1_LEVELS
        elif "VRM" in extensions:
            bones = {b.get("bone"): b.get("node") for b in extensions["VRM"].get("humanoid", {}).get("humanBones", [])}
            levels = VRM0_LEVELS
        else:
            return None
        out = {}
        for side in ("right", "left"):
            joints = {}
            for joint, vrm_bone in [("wrist", "Hand")] + [(f"{f}_{lv}", f"{_VRM_FINGER[f]}{part}")
                                                         for f in topo.FINGERS
                                                         for lv, part in zip(topo.FINGER_LEVELS[f],
                                                                             levels[f == "thumb"])]:
                node = bones.get(f"{side}{vrm_bone}")
                if isinstance(node, int) and 0 <= node < len(self.names):
                    joints[joint] = self.names[node]
            if "wrist" in joints:
                out[side] = joints
        return out or None

    def _parents_first(self) -> list[int]:
        """Nodes ordered parents first; an `InputFileError` if the hierarchy has a cycle."""
        depth = np.full(len(self.parents), -1)
        for start in range(len(self.parents)):
            chain, node = [], start
            while node >= 0 and depth[node] < 0:
                if len(chain) > len(self.parents):
                    raise InputFileError(self.path, f"node hierarchy has a cycle through node {start}")
                chain.append(node)
                node = self.parents[node]
            base = depth[node] if node >= 0 else -1
            for k, n in enumerate(reversed(chain)):
                depth[n] = base + 1 + k
        return [int(i) for i in np.argsort(depth, kind="stable")]

    def accessor(self, index, what: str = "accessor") -> np.ndarray:
        """(count, width) data of accessor ``index``, checked against the bytes really there first."""
        path = self.path
        index = _index(path, index, self.gltf.accessors, what)
        acc = self.gltf.accessors[index]
        label = f"accessor {index} ({what})"
        if acc.componentType not in _DTYPES or acc.type not in _WIDTH:
            raise InputFileError(path, f"{label} has unknown type {acc.type!r}/{acc.componentType!r}")
        dtype = np.dtype(_DTYPES[acc.componentType])
        width = _WIDTH[acc.type]
        count = acc.count
        if isinstance(count, bool) or not isinstance(count, int) or not 0 < count <= MAX_ACCESSOR_ELEMENTS:
            raise InputFileError(path, f"{label} declares {count!r} elements; this program reads 1 to "
                                       f"{MAX_ACCESSOR_ELEMENTS}")
        if acc.bufferView is None:
            return np.zeros((count, width), dtype=np.float64)
        view = self.gltf.bufferViews[_index(path, acc.bufferView, self.gltf.bufferViews, f"{label}'s bufferView")]
        element = dtype.itemsize * width
        view_start, view_length = view.byteOffset or 0, view.byteLength
        start = acc.byteOffset or 0
        stride = view.byteStride or element
        if not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0
                   for v in (view_start, view_length, start, stride)):
            raise InputFileError(path, f"{label}: byte offsets, lengths and strides must be non-negative integers")
        if stride < element:
            raise InputFileError(path, f"{label}: byte stride {stride} is smaller than its {element}-byte element")
        if view_start + view_length > len(self.blob):
            raise InputFileError(path, f"bufferView {acc.bufferView} ends at byte {view_start + view_length}, past "
                                       f"the {len(self.blob)} bytes of binary data")
        needed = start + stride * (count - 1) + element
        if needed > view_length:
            raise InputFileError(path, f"{label} needs {needed} bytes of its {view_length}-byte bufferView "
                                       f"({count} elements)")
        raw = np.frombuffer(self.blob, dtype=np.uint8, count=needed - start, offset=view_start + start)
        rows = np.lib.stride_tricks.as_strided(raw, (count, element), (stride, 1))
        data = rows.copy().view(dtype).reshape(count, width)
        if dtype.kind == "f" and not np.isfinite(data).all():
            raise InputFileError(path, f"{label} contains NaN or infinite values")
        if acc.normalized and dtype.kind in "iu":
            data = data.astype(np.float64) / np.iinfo(dtype).max
        return data


def _local_matrix(path: Path, index: int, node: pygltflib.Node) -> np.ndarray:
    what = f"node {index}"
    if node.matrix:
        return _numbers(path, node.matrix, 16, f"{what}'s matrix").reshape(4, 4).T  # column-major in the file
    m = np.eye(4)
    if node.rotation:
        xyzw = _numbers(path, node.rotation, 4, f"{what}'s rotation")
        if np.linalg.norm(xyzw) < 1e-6:
            raise InputFileError(path, f"{what}'s rotation is a zero quaternion")
        m[:3, :3] = Rotation.from_quat(xyzw).as_matrix()  # glTF stores (x, y, z, w)
    if node.scale:
        m[:3, :3] = m[:3, :3] * _numbers(path, node.scale, 3, f"{what}'s scale")
    if node.translation:
        m[:3, 3] = _numbers(path, node.translation, 3, f"{what}'s translation")
    return m


def _skinned_mesh(doc: _Document) -> RigMesh | None:
    """All skinned triangle primitives of the file, posed at rest, as one mesh."""
    parts, n_vertices = [], 0
    path, gltf = doc.path, doc.gltf
    for index, node in enumerate(gltf.nodes):
        if node.mesh is None or node.skin is None:
            continue
        skin = gltf.skins[_index(path, node.skin, gltf.skins, f"node {index}'s skin")]
        mesh = gltf.meshes[_index(path, node.mesh, gltf.meshes, f"node {index}'s mesh")]
        if not skin.joints:
            raise InputFileError(path, f"skin {node.skin} has no joints")
        joints = np.array([_index(path, j, gltf.nodes, f"skin {node.skin}'s joint") for j in skin.joints])
        if skin.inverseBindMatrices is not None:
            inverse_bind = doc.accessor(skin.inverseBindMatrices, f"skin {node.skin}'s inverse bind matrices")
            if inverse_bind.shape != (len(joints), 16):
                raise InputFileError(path, f"skin {node.skin} has {len(joints)} joints and {len(inverse_bind)} "
                                           f"inverse bind matrices of {inverse_bind.shape[1]} values")
            inverse_bind = inverse_bind.astype(np.float64).reshape(-1, 4, 4).transpose(0, 2, 1)
        else:
            inverse_bind = np.broadcast_to(np.eye(4), (len(joints), 4, 4))
        skinning = doc.world[joints] @ inverse_bind  # (J, 4, 4)
        for p, prim in enumerate(mesh.primitives or []):
            if prim.mode not in (None, 4) or prim.attributes.JOINTS_0 is None:
                continue
            what = f"mesh {node.mesh} primitive {p}"
            if prim.attributes.POSITION is None or prim.attributes.WEIGHTS_0 is None:
                raise InputFileError(path, f"{what} has joints but no positions or weights")
            v = doc.accessor(prim.attributes.POSITION, f"{what} positions").astype(np.float64)
            j = doc.accessor(prim.attributes.JOINTS_0, f"{what} joints").astype(np.int64)
            w = doc.accessor(prim.attributes.WEIGHTS_0, f"{what} weights").astype(np.float64)
            if v.shape[1] != 3 or j.shape != w.shape or len(j) != len(v):
                raise InputFileError(path, f"{what}: {len(v)} positions of {v.shape[1]} values, {len(j)} joint and "
                                           f"{len(w)} weight entries")
            n_vertices += len(v)
            if n_vertices > MAX_MESH_VERTICES:
                raise InputFileError(path, f"skinned meshes have more than {MAX_MESH_VERTICES} vertices")
            if j.min(initial=0) < 0 or j.max(initial=0) >= len(joints):
                raise InputFileError(doc.path, f"mesh {node.mesh} skins vertices to joint {j.max()} of a "
                                               f"{len(joints)}-joint skin")
            if np.any(w < 0):
                raise InputFileError(path, f"{what} has negative skin weights")
            if prim.indices is not None:
                faces = doc.accessor(prim.indices, f"{what} indices")
                if faces.shape[1] != 1 or faces.dtype.kind not in "iu" or len(faces) % 3:
                    raise InputFileError(path, f"{what}: indices must be integers, three per triangle")
                faces = faces.reshape(-1, 3).astype(np.int64)
            elif len(v) % 3:
                raise InputFileError(path, f"{what}: {len(v)} vertices without indices is not a triangle list")
            else:
                faces = np.arange(len(v)).reshape(-1, 3)
            if faces.max(initial=0) >= len(v):
                raise InputFileError(path, f"{what}: a triangle uses vertex {int(faces.max())} of {len(v)}")
            w = w / np.maximum(w.sum(axis=1, keepdims=True), 1e-12)
            blend = np.einsum("vk,vkab->vab", w, skinning[j])
            posed = np.einsum("vab,vb->va", blend[:, :3, :3], v) + blend[:, :3, 3]
            parts.append((posed, faces, joints[j], w))
    if not parts:
        return None
    offsets = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
    return RigMesh(np.concatenate([p[0] for p in parts]), np.concatenate([p[1] + o for p, o in zip(parts, offsets)]),
                   np.concatenate([p[2] for p in parts]), np.concatenate([p[3] for p in parts]))


def _recognise(doc: _Document, side: str | None, scheme: str | None, joint_map: dict[str, str] | None) -> RigMapping:
    if not doc.gltf.nodes:
        raise InputFileError(doc.path, "has no nodes (no skeleton)")
    return recognise(RigSkeleton(doc.names, doc.world, doc.parents), doc.path, side, scheme, joint_map,
                     doc.humanoid_map() if joint_map is None and scheme is None else None)


def load_gltf_hand(path: str | Path, side: str | None = None, scheme: str | None = None,
                   joint_map: dict[str, str] | None = None, name: str | None = None, unit: str | None = None,
                   hinges_from: str | Path | None = None) -> HandModel:
    """The hand of a glTF/GLB file (a lone hand or one hand of a character), annotated, as a right hand.
    ``side`` None: the side the names say, else the one geometry says (see `rig_recognition`); ``unit`` None:
    metres where the hand is plausible in them, else a guess (`io.units`). The solver's frames are checked
    against the hinges of the file's own animations, or of ``hinges_from``'s (`annotate.hinges`)."""
    with reading(path, "a glTF hand"):
        doc = read_document(path)
        mapping = _recognise(doc, side, scheme, joint_map)
        skeleton = RigSkeleton(doc.names, doc.world, doc.parents)
        evidence = hinges_from or (doc.path if doc.gltf.animations else None)
        return build_hand(doc.path, skeleton, mapping, _skinned_mesh(doc), name, unit, hinge_evidence=evidence)


def list_gltf_animations(path: str | Path) -> list[tuple[str, float]]:
    """(name, duration in seconds) of each animation of the file, in file order."""
    with reading(path, "a glTF file's animations"):
        doc = read_document(path)
        out = []
        for i, anim in enumerate(doc.gltf.animations or []):
            ends = [float(_rotation_track(doc, anim, c, f"animation {i} channel {k}")[0][-1])
                    for k, c in enumerate(anim.channels or []) if c.target is not None and c.target.path == "rotation"]
            out.append((anim.name or f"animation {i}", max(ends, default=0.0)))
        return out


def pick_animation(names: list[str], wanted: str | int | None, path: Path, what: str = "animation") -> int:
    """Index of ``wanted`` (a name, or an index as int or digits) among ``names``; clear error if absent."""
    if not names:
        raise InputFileError(path, f"has no {what}s")
    if wanted is None:
        return 0
    if isinstance(wanted, int) or str(wanted).isdigit():
        index = int(wanted)
        if not 0 <= index < len(names):
            raise InputFileError(path, f"has {len(names)} {what}s (0-{len(names) - 1}); no {what} {index}")
        return index
    if wanted in names:
        return names.index(wanted)
    raise InputFileError(path, f"has no {what} named {wanted!r}; it has {', '.join(repr(n) for n in names)}")


#: animation names exporters write when a person named nothing ("Take 001", "mixamo.com", "Armature|Action.001",
#: "Animation_0"): a clip so named is called by its file's name (captions, export names, the batch report)
_UNNAMED = re.compile(r"((armature|root|scene)\|)?(take|animation|anim|action|clip|default take|mixamo\.com)"
                      r"([ ._|-]*(\d+|layer\d*))*", re.IGNORECASE)


def clip_name(name: str | None, path: Path, index: int = 0) -> str:
    """What a clip read from animation ``name`` (number ``index``) of ``path`` is called: its own name, or the file's
    (with the animation's number where the file has others) where the exporter's default stands in for one."""
    name = (name or "").strip()
    if name and not _UNNAMED.fullmatch(name):
        return name
    return path.stem if index == 0 else f"{path.stem}_{index}"


def _rotation_track(doc: _Document, anim, channel, label: str) -> tuple[np.ndarray, np.ndarray]:
    """(times, xyzw) of a rotation channel: times finite and strictly increasing, quaternions non-zero."""
    path = doc.path
    sampler = anim.samplers[_index(path, channel.sampler, anim.samplers, f"{label}'s sampler")]
    times = doc.accessor(sampler.input, f"{label} times")
    values = doc.accessor(sampler.output, f"{label} rotations")
    if times.shape[1] != 1 or values.shape[1] != 4:
        raise InputFileError(path, f"{label}: times must be scalars and rotations 4-vectors")
    times, values = times[:, 0].astype(np.float64), values.astype(np.float64)
    per_key = 3 if sampler.interpolation == "CUBICSPLINE" else 1
    if len(values) != per_key * len(times):
        raise InputFileError(path, f"{label}: sampler has {len(times)} times and {len(values)} rotations")
    if per_key == 3:
        values = values.reshape(len(times), 3, 4)[:, 1]
    if np.any(times < 0) or np.any(np.diff(times) <= 0):
        raise InputFileError(path, f"{label}: key times must be non-negative and strictly increasing")
    if np.any(np.linalg.norm(values, axis=1) < 1e-6):
        raise InputFileError(path, f"{label}: zero quaternion among its rotations")
    return times, values


def load_gltf_motion(path: str | Path, hand: HandModel, animation: str | int | None = None, fps: float = 30.0
                     ) -> Motion:
    """Animation ``animation`` (name or index; the first by default) of the file, resampled at ``fps``, as
    finger rotations on ``hand`` (a hand loaded from the same rig, or any rig with the same bone names)."""
    with reading(path, "a glTF animation"):
        return _load_motion(read_document(path), hand, animation, fps)


def load_every_gltf_animation(path: str | Path, hand: HandModel, fps: float = 30.0) -> list[Motion]:
    """Every animation of the file in file order, as `load_gltf_motion` reads each, the file parsed once."""
    with reading(path, "a glTF animation"):
        doc = read_document(path)
        return [_load_motion(doc, hand, k, fps) for k in range(len(doc.gltf.animations or []))]


def _load_motion(doc: _Document, hand: HandModel, animation: str | int | None, fps: float) -> Motion:
    animations = doc.gltf.animations or []
    animation = pick_animation([a.name or f"animation {i}" for i, a in enumerate(animations)], animation, doc.path)
    anim = animations[animation]
    rotating = bone_indices(doc.names, hand, doc.path)
    needed = sorted({a for r in rotating for a in _ancestors(doc, r)})  # the bones whose rotations matter
    tracks = {}
    end = 0.0
    for c, channel in enumerate(anim.channels or []):
        if channel.target is None or channel.target.path != "rotation" or channel.target.node is None:
            continue
        node = _index(doc.path, channel.target.node, doc.names, f"animation {animation} channel {c}'s node")
        if node in needed:
            tracks[node] = _rotation_track(doc, anim, channel, f"animation {animation} channel {c}")
            end = max(end, float(tracks[node][0][-1]))
    n_frames = int(round(end * fps)) + 1
    if n_frames * len(needed) > MAX_ANIMATION_SAMPLES:
        raise InputFileError(doc.path, f"animation {animation} lasts {end:.4g} s: {n_frames} frames x {len(needed)} "
                                       f"bones is over the limit of {MAX_ANIMATION_SAMPLES} bone-frames")
    t = np.arange(n_frames) / fps
    local_rest = rotation_part(doc.local)
    world_rot: dict[int, np.ndarray] = {}
    needed_set = set(needed)
    for i in doc.order:  # parents first
        if i in needed_set:
            local = (_sample_rotations(*tracks[i], t) if i in tracks
                     else np.broadcast_to(local_rest[i], (n_frames, 3, 3)))
            parent = doc.parents[i]
            world_rot[i] = local if parent < 0 else world_rot[parent] @ local
    return motion_from_world_rotations(hand, np.stack([world_rot[r] for r in rotating], axis=1), fps, doc.path,
                                       clip_name(anim.name, doc.path, animation))


def _ancestors(doc: _Document, node: int) -> list[int]:
    """``node`` and every node above it."""
    chain = []
    while node >= 0:
        chain.append(node)
        node = doc.parents[node]
    return chain


def _sample_rotations(times: np.ndarray, xyzw: np.ndarray, t: np.ndarray) -> np.ndarray:
    rotations = Rotation.from_quat(xyzw / np.linalg.norm(xyzw, axis=1, keepdims=True))
    if len(times) == 1:
        return np.broadcast_to(rotations.as_matrix(), (len(t), 3, 3))
    return Slerp(times, rotations)(np.clip(t, times[0], times[-1])).as_matrix()


def _append(gltf: pygltflib.GLTF2, blob: bytearray, data: np.ndarray, accessor_type: str,
            component: int, target: int | None = None, with_bounds: bool = False) -> int:
    """Append ``data`` to ``blob`` as a new bufferView and accessor; returns the accessor index."""
    while len(blob) % 4:
        blob.append(0)
    raw = np.ascontiguousarray(data).tobytes()
    gltf.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(raw), target=target))
    blob.extend(raw)
    flat = data.reshape(len(data), -1)
    accessor = pygltflib.Accessor(bufferView=len(gltf.bufferViews) - 1, componentType=component, count=len(data),
                                  type=accessor_type)
    if with_bounds:
        accessor.min, accessor.max = flat.min(axis=0).tolist(), flat.max(axis=0).tolist()
    gltf.accessors.append(accessor)
    return len(gltf.accessors) - 1


def _add_animation(gltf: pygltflib.GLTF2, blob: bytearray, motion: Motion, node_rotations: dict[int, np.ndarray]) -> None:
    times = (np.arange(motion.n_frames) / motion.fps).astype(np.float32)[:, None]
    t_acc = _append(gltf, blob, times, "SCALAR", pygltflib.FLOAT, with_bounds=True)
    anim = pygltflib.Animation(name=motion.name or "retargeted", channels=[], samplers=[])
    for node, matrices in node_rotations.items():
        xyzw = Rotation.from_matrix(matrices).as_quat().astype(np.float32)
        anim.samplers.append(pygltflib.AnimationSampler(input=t_acc, output=_append(gltf, blob, xyzw, "VEC4",
                                                                                    pygltflib.FLOAT),
                                                        interpolation="LINEAR"))
        anim.channels.append(pygltflib.AnimationChannel(sampler=len(anim.samplers) - 1,
                                                        target=pygltflib.AnimationChannelTarget(node=node,
                                                                                                path="rotation")))
    gltf.animations.append(anim)


def _save_glb(gltf: pygltflib.GLTF2, blob: bytearray, path: Path) -> None:
    gltf.buffers = [pygltflib.Buffer(byteLength=len(blob))]
    gltf.set_binary_blob(bytes(blob))
    with atomic_path(path) as tmp:
        gltf.save_binary(str(tmp))


def save_gltf_motion(path: str | Path, motion: Motion, hand: HandModel) -> Path:
    """Write ``motion`` on ``hand`` as a GLB: the hand's glTF source with the animation added when it has
    one (so the avatar opens animated in Blender), an FBX source's rig and mesh rebuilt as glTF
    (`io.rig_gltf`), else the hand itself, skinned, with the animation. The
    hand's TBS frames go beside it as its annotation sidecar, so that it reads back with the same TBS
    rotations; a sidecar of another file under that name is refused, before anything is written."""
    path = Path(path)
    refuse_foreign_sidecar(path, hand_side(hand))
    source = Path(hand.source)
    from_rig = source.exists() and "rig_joints" in hand.meta
    if from_rig and source.suffix.lower() in GLTF_SUFFIXES:
        doc = _Document(source)
        gltf, blob = doc.gltf, bytearray(doc.blob)
        rotations = _source_node_rotations(doc, hand, motion)
    elif from_rig and source.suffix.lower() == ".fbx":  # the avatar's own rig, rebuilt as glTF
        from s2h_viewer.io.fbx import _read
        skeleton, mesh, _ = _read(source)
        blob = bytearray()
        gltf = rig_document(skeleton, mesh, source.stem, lambda g, data, kind, component, target, bounds: _append(
            g, blob, data, kind, component, target, bounds))
        rotations = node_rotations(skeleton, hand, motion, world_rotations_from_motion(hand, motion))
    else:
        gltf, blob, rotations = _hand_document(hand, motion)
    _add_animation(gltf, blob, motion, rotations)
    _save_glb(gltf, blob, path)
    return save_hand_frames(path, hand, hand.rig_frames[0].T)  # the file loads in its wrist bone's frame


def _source_node_rotations(doc: _Document, hand: HandModel, motion: Motion) -> dict[int, np.ndarray]:
    """Local rotations over time of the source file's mapped bones playing ``motion`` (wrist held at rest)."""
    return node_rotations(RigSkeleton(doc.names, doc.world, doc.parents), hand, motion,
                          world_rotations_from_motion(hand, motion))


def _hand_document(hand: HandModel, motion: Motion) -> tuple[pygltflib.GLTF2, bytearray, dict[int, np.ndarray]]:
    """A glTF of a hand made here: 21 joint nodes in a chain per finger (project names), the skinned mesh."""
    gltf = pygltflib.GLTF2(asset=pygltflib.Asset(generator="s2h-viewer", version="2.0"), scene=0, nodes=[],
                           scenes=[], meshes=[], skins=[], accessors=[], bufferViews=[], animations=[])
    blob = bytearray()
    articulated = topo.ARTICULATED_OF_JOINT.copy()
    articulated[topo.TIP_JOINTS] = articulated[topo.TIP_JOINTS - 1]  # a tip node turns with its DIP
    rotating_of_joint = articulated + 1  # the wrist's -1 becomes rotating index 0
    world_rot = hand.rig_frames[rotating_of_joint]
    positions = hand.rest_positions
    for j, name in enumerate(topo.JOINT_NAMES):
        parent = topo.PARENTS[j]
        parent_rot = world_rot[parent] if parent >= 0 else np.eye(3)
        local = parent_rot.T @ world_rot[j]
        offset = parent_rot.T @ (positions[j] - positions[parent]) if parent >= 0 else np.zeros(3)
        gltf.nodes.append(pygltflib.Node(name=name, rotation=Rotation.from_matrix(local).as_quat().tolist(),
                                         translation=offset.tolist(), children=[]))
        if parent >= 0:
            gltf.nodes[parent].children.append(j)
    world = np.tile(np.eye(4), (topo.N_JOINTS, 1, 1))
    world[:, :3, :3], world[:, :3, 3] = world_rot, positions
    scene_nodes = [0]
    if hand.mesh is not None:
        mesh = hand.mesh
        import trimesh  # only here: reading a rig does not pay for it

        normals = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).vertex_normals.astype(np.float32)
        top = np.argsort(-mesh.weights, axis=1)[:, :4]
        weights = np.take_along_axis(mesh.weights, top, axis=1)
        weights = (weights / weights.sum(axis=1, keepdims=True)).astype(np.float32)
        attributes = pygltflib.Attributes(
            POSITION=_append(gltf, blob, mesh.vertices.astype(np.float32), "VEC3", pygltflib.FLOAT,
                             pygltflib.ARRAY_BUFFER, with_bounds=True),
            NORMAL=_append(gltf, blob, normals, "VEC3", pygltflib.FLOAT, pygltflib.ARRAY_BUFFER),
            JOINTS_0=_append(gltf, blob, topo.ROTATING_JOINTS[top].astype(np.uint16), "VEC4",
                             pygltflib.UNSIGNED_SHORT, pygltflib.ARRAY_BUFFER),
            WEIGHTS_0=_append(gltf, blob, weights, "VEC4", pygltflib.FLOAT, pygltflib.ARRAY_BUFFER))
        indices = _append(gltf, blob, mesh.faces.astype(np.uint32).reshape(-1, 1), "SCALAR",
                          pygltflib.UNSIGNED_INT, pygltflib.ELEMENT_ARRAY_BUFFER)
        gltf.meshes.append(pygltflib.Mesh(name=f"{hand.name}_skin", primitives=[
            pygltflib.Primitive(attributes=attributes, indices=indices, mode=4)]))
        inverse_bind = np.linalg.inv(world).transpose(0, 2, 1).astype(np.float32)  # column-major
        gltf.skins.append(pygltflib.Skin(joints=list(range(topo.N_JOINTS)), skeleton=0,
                                         inverseBindMatrices=_append(gltf, blob, inverse_bind, "MAT4",
                                                                     pygltflib.FLOAT)))
        gltf.nodes.append(pygltflib.Node(name=f"{hand.name}_mesh", mesh=0, skin=0))
        scene_nodes.append(len(gltf.nodes) - 1)
    gltf.scenes.append(pygltflib.Scene(name=hand.name, nodes=scene_nodes))
    gltf.extras = {"s2h_hand": json.dumps({"name": hand.name, "source": hand.source})}
    hand_rot = world_rotations_from_motion(hand, motion)
    node_rotations = {int(j): hand_rot[:, rotating_of_joint[topo.PARENTS[j]]].transpose(0, 2, 1) @ hand_rot[:, r]
                      for r, j in enumerate(topo.ROTATING_JOINTS) if r}
    return gltf, blob, node_rotations
