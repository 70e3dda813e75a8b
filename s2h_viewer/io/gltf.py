"""glTF 2.0 / GLB: rigged hands in, animations in and out (pygltflib).

- `load_gltf_hand`: the skinned mesh and skeleton of a hand, or of one hand of a full-body character.
- `load_gltf_motion`: an animation's bone rotations as a `Motion` on a hand loaded from the same rig.
- `save_gltf_motion`: a GLB that opens in Blender with the avatar: the hand's own source file with the
  motion added as an animation, or, for hands made here, the skinned hand written out with it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pygltflib
import trimesh
from scipy.spatial.transform import Rotation, Slerp

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rig_mapping import RigMapping
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.io.rig import (RigMesh, RigSkeleton, bone_indices, build_hand, motion_from_world_rotations,
                               recognise, rotation_part, world_rotations_from_motion)

_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
GLTF_SUFFIXES = (".glb", ".gltf")
_VRM_FINGER = {"thumb": "Thumb", "index": "Index", "middle": "Middle", "ring": "Ring", "pinky": "Little"}
#: VRM humanoid bone suffixes of the three articulated levels: (fingers, thumb)
VRM0_LEVELS = (("Proximal", "Intermediate", "Distal"), ("Proximal", "Intermediate", "Distal"))
VRM1_LEVELS = (("Proximal", "Intermediate", "Distal"), ("Metacarpal", "Proximal", "Distal"))


class _Document:
    """A parsed glTF with its binary data in one blob, and the scene graph at rest."""

    def __init__(self, path: Path):
        self.path = path
        try:
            self.gltf = pygltflib.GLTF2().load(str(path))
            if self.gltf is None:
                raise ValueError("empty file")
            self.gltf.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)
        except FileNotFoundError:
            raise InputFileError(path, "file not found") from None
        except Exception as exc:  # pygltflib raises many types on damaged input
            raise InputFileError(path, f"not a readable glTF/GLB file ({type(exc).__name__}: {exc})") from None
        self.blob = self.gltf.binary_blob() or b""
        nodes = self.gltf.nodes
        self.names = [n.name or f"node{i}" for i, n in enumerate(nodes)]
        self.parents = np.full(len(nodes), -1)
        for i, node in enumerate(nodes):
            for child in node.children or []:
                if not 0 <= child < len(nodes):
                    raise InputFileError(path, f"node {self.names[i]!r} has a child {child} that does not exist")
                if self.parents[child] >= 0:
                    raise InputFileError(path, f"node {self.names[child]!r} has two parents "
                                               f"({self.names[self.parents[child]]!r}, {self.names[i]!r})")
                self.parents[child] = i
        self._refuse_cycles()
        self.order = self._parents_first()
        self.local = np.stack([_local_matrix(n) for n in nodes]) if nodes else np.zeros((0, 4, 4))
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
        order, seen = [], set()
        for start in range(len(self.parents)):
            chain = []
            node = start
            while node >= 0 and node not in seen:
                chain.append(node)
                seen.add(node)
                node = self.parents[node]
            order.extend(reversed(chain))
        return order

    def accessor(self, index: int) -> np.ndarray:
        acc = self.gltf.accessors[index]
        dtype = np.dtype(_DTYPES[acc.componentType])
        width = _WIDTH[acc.type]
        if acc.bufferView is None:
            return np.zeros((acc.count, width), dtype=np.float64)
        view = self.gltf.bufferViews[acc.bufferView]
        start = (view.byteOffset or 0) + (acc.byteOffset or 0)
        stride = view.byteStride or dtype.itemsize * width
        try:
            raw = np.frombuffer(self.blob, dtype=np.uint8, count=stride * (acc.count - 1) + dtype.itemsize * width,
                                offset=start)
        except ValueError:
            raise InputFileError(self.path, f"accessor {index} reaches past the end of the binary data") from None
        rows = np.lib.stride_tricks.as_strided(raw, (acc.count, dtype.itemsize * width), (stride, 1))
        data = rows.copy().view(dtype).reshape(acc.count, width)
        if acc.normalized and dtype.kind in "iu":
            data = data.astype(np.float64) / np.iinfo(dtype).max
        return data


def _local_matrix(node: pygltflib.Node) -> np.ndarray:
    if node.matrix:
        return np.array(node.matrix, dtype=np.float64).reshape(4, 4).T  # column-major in the file
    m = np.eye(4)
    if node.rotation:
        m[:3, :3] = Rotation.from_quat(node.rotation).as_matrix()  # glTF stores (x, y, z, w)
    if node.scale:
        m[:3, :3] = m[:3, :3] * np.asarray(node.scale)
    if node.translation:
        m[:3, 3] = node.translation
    return m


def _skinned_mesh(doc: _Document) -> RigMesh | None:
    """All skinned triangle primitives of the file, posed at rest, as one mesh."""
    parts = []
    for node in doc.gltf.nodes:
        if node.mesh is None or node.skin is None:
            continue
        skin = doc.gltf.skins[node.skin]
        joints = np.asarray(skin.joints)
        if skin.inverseBindMatrices is not None:
            inverse_bind = doc.accessor(skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
        else:
            inverse_bind = np.broadcast_to(np.eye(4), (len(joints), 4, 4))
        skinning = doc.world[joints] @ inverse_bind  # (J, 4, 4)
        for prim in doc.gltf.meshes[node.mesh].primitives:
            if prim.mode not in (None, 4) or prim.attributes.JOINTS_0 is None:
                continue
            v = doc.accessor(prim.attributes.POSITION).astype(np.float64)
            j = doc.accessor(prim.attributes.JOINTS_0).astype(np.int64)
            w = doc.accessor(prim.attributes.WEIGHTS_0).astype(np.float64)
            if j.max(initial=0) >= len(joints):
                raise InputFileError(doc.path, f"mesh {node.mesh} skins vertices to joint {j.max()} of a "
                                               f"{len(joints)}-joint skin")
            faces = (doc.accessor(prim.indices).reshape(-1, 3) if prim.indices is not None
                     else np.arange(len(v)).reshape(-1, 3))
            w = w / np.maximum(w.sum(axis=1, keepdims=True), 1e-12)
            blend = np.einsum("vk,vkab->vab", w, skinning[j])
            posed = np.einsum("vab,vb->va", blend[:, :3, :3], v) + blend[:, :3, 3]
            parts.append((posed, faces.astype(np.int64), joints[j], w))
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
                   joint_map: dict[str, str] | None = None, name: str | None = None) -> HandModel:
    """The hand of a glTF/GLB file (a lone hand or one hand of a character), annotated, as a right hand.
    ``side`` None: the side the names say, else the one geometry says (see `rig_recognition`)."""
    doc = _Document(Path(path))
    mapping = _recognise(doc, side, scheme, joint_map)
    skeleton = RigSkeleton(doc.names, doc.world, doc.parents)
    return build_hand(doc.path, skeleton, mapping, _skinned_mesh(doc), name)


def list_gltf_animations(path: str | Path) -> list[tuple[str, float]]:
    """(name, duration in seconds) of each animation of the file, in file order."""
    doc = _Document(Path(path))
    out = []
    for i, anim in enumerate(doc.gltf.animations or []):
        ends = [float(doc.accessor(anim.samplers[c.sampler].input)[-1, 0]) for c in anim.channels
                if doc.gltf.accessors[anim.samplers[c.sampler].input].count]
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


def load_gltf_motion(path: str | Path, hand: HandModel, animation: str | int | None = None, fps: float = 30.0
                     ) -> Motion:
    """Animation ``animation`` (name or index; the first by default) of the file, resampled at ``fps``, as
    finger rotations on ``hand`` (a hand loaded from the same rig, or any rig with the same bone names)."""
    doc = _Document(Path(path))
    animations = doc.gltf.animations or []
    animation = pick_animation([a.name or f"animation {i}" for i, a in enumerate(animations)], animation, doc.path)
    anim = animations[animation]
    rotating = bone_indices(doc.names, hand, doc.path)
    tracks = {}
    end = 0.0
    for channel in anim.channels:
        if channel.target.path != "rotation" or channel.target.node is None:
            continue
        sampler = anim.samplers[channel.sampler]
        times = doc.accessor(sampler.input)[:, 0].astype(np.float64)
        values = doc.accessor(sampler.output).astype(np.float64)
        if sampler.interpolation == "CUBICSPLINE":
            values = values.reshape(len(times), 3, 4)[:, 1]
        if len(times) == 0 or len(values) != len(times):
            raise InputFileError(doc.path, f"animation {animation}: sampler {channel.sampler} has "
                                           f"{len(times)} times and {len(values)} rotations")
        if not np.isfinite(values).all():
            raise InputFileError(doc.path, f"animation {animation}: NaN or infinite rotations on node "
                                           f"{doc.names[channel.target.node]!r}")
        tracks[channel.target.node] = (times, values)
        end = max(end, float(times[-1]))
    n_frames = int(round(end * fps)) + 1
    t = np.arange(n_frames) / fps
    local_rot = np.broadcast_to(rotation_part(doc.local), (n_frames, len(doc.names), 3, 3)).copy()
    for node, (times, values) in tracks.items():
        local_rot[:, node] = _sample_rotations(times, values, t)
    world_rot = local_rot.copy()
    for i in doc.order:
        if doc.parents[i] >= 0:
            world_rot[:, i] = world_rot[:, doc.parents[i]] @ local_rot[:, i]
    name = anim.name or f"{doc.path.stem}_{animation}"
    return motion_from_world_rotations(hand, world_rot[:, rotating], fps, doc.path, name)


def _sample_rotations(times: np.ndarray, xyzw: np.ndarray, t: np.ndarray) -> np.ndarray:
    norms = np.linalg.norm(xyzw, axis=1, keepdims=True)
    if np.any(norms < 1e-6):
        raise ValueError("zero quaternion in an animation")
    rotations = Rotation.from_quat(xyzw / norms)
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
    one (so the avatar opens animated in Blender), else the hand itself, skinned, with the animation."""
    path = Path(path)
    source = Path(hand.source)
    if source.suffix.lower() in GLTF_SUFFIXES and source.exists() and "rig_joints" in hand.meta:
        doc = _Document(source)
        gltf, blob = doc.gltf, bytearray(doc.blob)
        node_rotations = _source_node_rotations(doc, hand, motion)
    else:
        gltf, blob, node_rotations = _hand_document(hand, motion)
    _add_animation(gltf, blob, motion, node_rotations)
    _save_glb(gltf, blob, path)
    return path


def _source_node_rotations(doc: _Document, hand: HandModel, motion: Motion) -> dict[int, np.ndarray]:
    """Local rotations over time of the source file's mapped bones playing ``motion`` (wrist held at rest)."""
    lookup = {n: i for i, n in enumerate(doc.names)}
    rotating = {lookup[hand.meta["rig_joints"][topo.JOINT_NAMES[j]]]: r for r, j in enumerate(topo.ROTATING_JOINTS)}
    wrist_world = rotation_part(doc.world[next(n for n, r in rotating.items() if r == 0)])
    hand_rot = world_rotations_from_motion(hand, motion)  # (T, 16, 3, 3) in hand space
    world = np.broadcast_to(rotation_part(doc.world), (motion.n_frames, len(doc.names), 3, 3)).copy()
    local_rest = rotation_part(doc.local)
    for i in doc.order:
        if i in rotating:
            world[:, i] = wrist_world @ hand_rot[:, rotating[i]]
        elif doc.parents[i] >= 0:
            world[:, i] = world[:, doc.parents[i]] @ local_rest[i]
    out = {}
    for node, r in rotating.items():
        if r == 0:
            continue
        parent = doc.parents[node]
        out[node] = world[:, node] if parent < 0 else world[:, parent].transpose(0, 2, 1) @ world[:, node]
    return out


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
