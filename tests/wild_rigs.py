"""Rig files of kinds met in the wild, made here from a real rig's skeleton where no such file can be shipped:
Meta hand-tracking skeletons with marker nodes, renamed, mirrored and rescaled variants."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pygltflib

from s2h_viewer.io.files import read_rig_skeleton


def write_gltf_skeleton(path: Path, names: list[str], parents: list[int], positions: np.ndarray,
                        scale: float = 1.0) -> Path:
    """A glTF holding only a node tree: each node translated to its world ``positions`` (rotation identity);
    ``scale`` on a root node above them all (the skeleton then reads ``positions * scale`` in world units)."""
    positions = np.asarray(positions, dtype=float)
    nodes = []
    for i, p in enumerate(parents):
        local = positions[i] - (positions[p] if p >= 0 else 0.0)
        nodes.append(pygltflib.Node(name=names[i], translation=local.tolist(),
                                    children=[c for c, q in enumerate(parents) if q == i]))
    roots = [i for i, p in enumerate(parents) if p < 0]
    nodes.append(pygltflib.Node(name="Armature", scale=[scale] * 3, children=roots))
    gltf = pygltflib.GLTF2(scene=0, scenes=[pygltflib.Scene(nodes=[len(nodes) - 1])], nodes=nodes,
                           asset=pygltflib.Asset(version="2.0"))
    gltf.save(str(path))
    return path


def meta_hand_skeleton(fbx: Path, side: str = "r") -> tuple[list[str], list[int], np.ndarray]:
    """The skeleton of a Meta/Oculus custom hand (``b_r_hand`` ..) in metres, named as Meta's hand-tracking
    meshes are (``b_r_wrist``, ``b_r_index_null`` tips) with the marker nodes they hang on each finger
    (``r_index_finger_tip_marker``, ``..._pad_marker`` beside the tip, ``..._knuckle_marker`` on the proximal)."""
    skeleton = read_rig_skeleton(fbx)
    keep = [i for i, n in enumerate(skeleton.names) if ":b_" in n]
    index = {old: new for new, old in enumerate(keep)}
    names = [skeleton.names[i].split(":")[-1].replace("_ignore", "_null").replace("_hand", "_wrist")
             .replace("b_r_", f"b_{side}_") for i in keep]
    parents = [index.get(int(skeleton.parents[i]), -1) for i in keep]
    positions = skeleton.world[keep, :3, 3]  # metres (the FBX reader applies the file's unit)
    for finger in ("thumb", "index", "middle", "ring", "pinky"):
        tip = names.index(f"b_{side}_{finger}_null")
        distal, proximal = parents[tip], names.index(f"b_{side}_{finger}1")
        for part, at, where in (("tip", distal, 1.0), ("pad", distal, 0.8), ("knuckle", proximal, 0.0)):
            names.append(f"{side}_{finger}_finger_{part}_marker")
            parents.append(at)
            target = tip if part != "knuckle" else proximal
            positions = np.vstack([positions, positions[at] + where * (positions[target] - positions[at])
                                   + (0.002 if part == "pad" else 0.0)])
    return names, parents, positions


def mirrored(positions: np.ndarray) -> np.ndarray:
    """The same skeleton reflected across the world's y-z plane: a left hand from a right one."""
    return positions * np.array([-1.0, 1.0, 1.0])


def rescaled_bvh(source: Path, out: Path, factor: float) -> Path:
    """A BVH in another length unit: every OFFSET and the root's position channels (a frame's first three
    values, as our writer orders them) times ``factor``."""
    hierarchy, motion = source.read_text().split("MOTION\n")

    def scale(match) -> str:
        return "OFFSET " + " ".join(f"{float(v) * factor:.9g}" for v in match.group(1).split())

    hierarchy = re.sub(r"OFFSET ((?:\S+ ){2}\S+)", scale, hierarchy)
    lines = motion.splitlines()
    frames = [" ".join([*(f"{float(v) * factor:.9g}" for v in line.split()[:3]), *line.split()[3:]])
              for line in lines[2:]]
    out.write_text(hierarchy + "MOTION\n" + "\n".join(lines[:2] + frames) + "\n")
    return out


def _minimal_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking direction ``a`` to direction ``b``."""
    from scipy.spatial.transform import Rotation
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    axis = np.cross(a, b)
    angle = np.arctan2(np.linalg.norm(axis), a @ b)
    return Rotation.from_rotvec(axis / max(np.linalg.norm(axis), 1e-12) * angle).as_matrix()


def per_dof_bvh(source: Path, out: Path) -> Path:
    """Optical finger mocap's way of writing a hand BVH (made from one of ours, ZXY channels): upper-case
    names, a joint per degree of freedom (``INDEX_MCP_FE`` turning Z and X, then ``INDEX_MCP_AA`` at the same
    point turning Y; the thumb CMC too), zero-length End Sites for tips, and a zero pose that is no hand pose
    (every finger and the thumb straight along the palm); the frames move every joint where the source's do."""
    from scipy.spatial.transform import Rotation

    from s2h_viewer.io.bvh import read_bvh
    clip = read_bvh(source)
    n, parents = len(clip.names), clip.parents
    local = np.tile(np.eye(3), (len(clip.frames), n, 1, 1))
    column, roots = 0, {}
    for j, chans in enumerate(clip.channels):
        if any(c.endswith("position") for c in chans):
            roots[j] = clip.frames[:, column:column + 3]
        rot = [(c[0], column + k) for k, c in enumerate(chans) if c.endswith("rotation")]
        if rot:
            local[:, j] = Rotation.from_euler("".join(a for a, _ in rot), clip.frames[:, [c for _, c in rot]],
                                              degrees=True).as_matrix()
        column += len(chans)
    rest = np.zeros((n, 3))
    for j, p in enumerate(parents):
        rest[j] = rest[p] + clip.offsets[j] if p >= 0 else clip.offsets[j]
    wrist = 0
    forward = rest[clip.names.index("middle_mcp")] - rest[wrist]
    forward /= np.linalg.norm(forward)
    offsets = clip.offsets.copy()
    for j, p in enumerate(parents):
        if p > wrist:  # a finger's bones (and tips) straight along the palm
            offsets[j] = np.linalg.norm(clip.offsets[j]) * forward
    turn = np.tile(np.eye(3), (n, 1, 1))
    for j in range(n):
        kids = [c for c in range(n) if parents[c] == j]
        if j != wrist and len(kids) == 1:
            turn[j] = _minimal_rotation(offsets[kids[0]], clip.offsets[kids[0]])
    new_local = local.copy()
    for j, p in enumerate(parents):
        if p >= 0:
            new_local[:, j] = turn[p].T @ local[:, j] @ turn[j]
    lines, data = ["HIERARCHY"], []

    def write(j: int, depth: int) -> None:
        pad, name = "  " * depth, clip.names[j].upper()
        kids = [c for c in range(n) if parents[c] == j]
        off = offsets[j]
        if not clip.channels[j]:  # an End Site: zero length, as such mocap writes it
            lines.extend([f"{pad}End Site", f"{pad}{{", f"{pad}  OFFSET 0 0 0", f"{pad}}}"])
            return
        euler = Rotation.from_matrix(new_local[:, j]).as_euler("ZXY", degrees=True)
        two_dof = name.endswith("_MCP") and not name.startswith("THUMB") or name == "THUMB_CMC"
        root = parents[j] < 0
        head = f"{pad}{'ROOT' if root else 'JOINT'} {name if root else name + '_FE'}"
        chans = (["Xposition", "Yposition", "Zposition"] if root else []) + ["Zrotation", "Xrotation"]
        lines.extend([head, f"{pad}{{", f"{pad}  OFFSET {off[0]:.9f} {off[1]:.9f} {off[2]:.9f}"])
        if two_dof:
            lines.append(f"{pad}  CHANNELS 2 Zrotation Xrotation")
            lines.extend([f"{pad}  JOINT {name}_AA", f"{pad}  {{", f"{pad}    OFFSET 0 0 0",
                          f"{pad}    CHANNELS 1 Yrotation"])
            data.append(euler)
            inner = depth + 2
        else:
            chans.append("Yrotation")
            lines.append(f"{pad}  CHANNELS {len(chans)} {' '.join(chans)}")
            data.append(np.concatenate([roots[j], euler], axis=1) if root else euler)
            inner = depth + 1
        for kid in kids:
            write(kid, inner)
        if two_dof:
            lines.append(f"{pad}  }}")
        lines.append(f"{pad}}}")

    write(wrist, 0)
    table = np.concatenate(data, axis=1)
    motion = [f"Frames: {len(table)}", f"Frame Time: {clip.frame_time:.7f}"]
    motion += [" ".join(f"{v:.6f}" for v in row) for row in table]
    out.write_text("\n".join(lines + ["MOTION"] + motion) + "\n")
    return out


def _accessor_floats(gltf: pygltflib.GLTF2, blob: bytearray, index: int, width: int) -> np.ndarray:
    """Accessor ``index``'s float32 values, ``width`` per element, as a writable view into ``blob``: tightly packed
    or interleaved with other attributes (the bufferView's stride, as the Ready Player Me avatar stores its vertices).
    A sparse accessor gives its stored values; one with neither (all zeros: the avatar's morph targets) gives none."""
    accessor = gltf.accessors[index]
    count, view_index, offset = accessor.count, accessor.bufferView, accessor.byteOffset
    if accessor.sparse is not None:
        assert accessor.bufferView is None, "a sparse accessor over stored values is not handled here"
        values = accessor.sparse.values
        count, view_index, offset = accessor.sparse.count, values.bufferView, values.byteOffset
    if view_index is None:
        return np.zeros((0, width), dtype="<f4")
    view = gltf.bufferViews[view_index]
    start = (view.byteOffset or 0) + (offset or 0)
    stride = view.byteStride or 4 * width
    return np.ndarray((count, width), dtype="<f4", buffer=blob, offset=start, strides=(stride, 4))


def _load(source: Path) -> pygltflib.GLTF2:
    """A glTF by its bytes, not its suffix: a .vrm is a binary glTF that pygltflib reads as JSON by its name."""
    with open(source, "rb") as file:
        binary = file.read(4) == b"glTF"
    return pygltflib.GLTF2().load_binary(str(source)) if binary else pygltflib.GLTF2().load_json(str(source))


def rerolled_glb(source: Path, out: Path, degrees: float, pattern: str = r"(?i)thumb|index|middle|ring|pinky|little"
                 ) -> Path:
    """The same skinned avatar with every finger bone (a skin joint whose name matches ``pattern`` and that has a
    child) rolled ``degrees`` about its bone: its rest rotation turned, its children and its inverse bind matrix
    turned back, so the skin and the pose are the same and only the bones' local axes differ (as two exporters,
    or two riggers' roll settings, leave them). Animations are dropped (their keys hold the old axes)."""
    from scipy.spatial.transform import Rotation

    gltf = _load(source)
    gltf.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)  # a .gltf's embedded buffers into one blob
    blob = bytearray(gltf.binary_blob())
    skin = gltf.skins[0]
    stored = _accessor_floats(gltf, blob, skin.inverseBindMatrices, 16)
    ibm = stored.reshape(-1, 4, 4).transpose(0, 2, 1).astype(np.float64)
    for slot, n in enumerate(skin.joints):
        node = gltf.nodes[n]
        if not re.search(pattern, node.name or "") or not node.children:
            continue
        child = gltf.nodes[node.children[0]]
        direction = np.asarray(child.translation or [0.0, 0.0, 0.0], dtype=float)
        if np.linalg.norm(direction) < 1e-9:
            continue
        roll = Rotation.from_rotvec(np.radians(degrees) * direction / np.linalg.norm(direction))
        node.rotation = (Rotation.from_quat(node.rotation or [0.0, 0.0, 0.0, 1.0]) * roll).as_quat().tolist()
        for c in node.children:
            kid = gltf.nodes[c]
            kid.translation = roll.inv().apply(kid.translation or [0.0, 0.0, 0.0]).tolist()
            kid.rotation = (roll.inv() * Rotation.from_quat(kid.rotation or [0.0, 0.0, 0.0, 1.0])).as_quat().tolist()
        turn = np.eye(4)
        turn[:3, :3] = roll.inv().as_matrix()
        ibm[slot] = turn @ ibm[slot]
    stored[:] = ibm.transpose(0, 2, 1).reshape(-1, 16)
    gltf.animations = []
    gltf.set_binary_blob(bytes(blob))
    gltf.save_binary(str(out))
    return out


def centimetre_glb(source: Path, out: Path) -> Path:
    """The same skinned avatar as an exporter working in centimetres writes it: every node's translation, every
    mesh position and the inverse bind matrices' translations 100 times larger, under a new root node scaled 0.01
    (as Blender's and Maya's FBX-to-glTF exports of a cm scene leave it). In world units it is the same avatar.
    Animations are dropped (their translation keys would need the same factor)."""
    gltf = _load(source)
    gltf.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)
    blob = bytearray(gltf.binary_blob())

    for node in gltf.nodes:
        if node.translation:
            node.translation = [100.0 * v for v in node.translation]
        if node.matrix:
            node.matrix = [v * 100.0 if i in (12, 13, 14) else v for i, v in enumerate(node.matrix)]
    positions = {p.attributes.POSITION for mesh in gltf.meshes for p in mesh.primitives}
    positions |= {t.get("POSITION") if isinstance(t, dict) else getattr(t, "POSITION", None)
                  for mesh in gltf.meshes for p in mesh.primitives for t in (p.targets or [])}  # morph offsets too
    for index in sorted(i for i in positions if i is not None):
        _accessor_floats(gltf, blob, index, 3)[:] *= 100.0
        accessor = gltf.accessors[index]
        if accessor.min and accessor.max:
            accessor.min, accessor.max = [100.0 * v for v in accessor.min], [100.0 * v for v in accessor.max]
    for skin in gltf.skins:
        _accessor_floats(gltf, blob, skin.inverseBindMatrices, 16)[:, 12:15] *= 100.0  # column-major: translation last
    scene = gltf.scenes[gltf.scene or 0]
    gltf.nodes.append(pygltflib.Node(name="Centimetres", scale=[0.01] * 3, children=list(scene.nodes)))
    scene.nodes = [len(gltf.nodes) - 1]
    gltf.animations = []
    gltf.set_binary_blob(bytes(blob))
    gltf.save_binary(str(out))
    return out


def mirrored_glb(source: Path, out: Path) -> Path:
    """The same avatar reflected across its y-z plane, as a modeller's "mirror" makes a right hand of a left one:
    node translations and mesh positions and normals with x negated, rotations reflected ((x, y, z, w) ->
    (x, -y, -z, w)), inverse bind matrices conjugated by the reflection, triangles wound the other way so their
    normals still point out, and the sides in the node names swapped (``Thumb_Proximal_L`` -> ``_R``, ``hand_l``
    -> ``hand_r``, ``Left`` -> ``Right``). Animations are dropped (their keys would need the same reflection)."""
    gltf = _load(source)
    swap = {"l": "r", "r": "l", "L": "R", "R": "L", "Left": "Right", "Right": "Left", "left": "right", "right": "left"}
    for node in gltf.nodes:
        if node.name:
            node.name = re.sub(r"(?<=[_.\-])[lLrR](?=$|[_.\-])|Left|Right|left|right", lambda m: swap[m.group(0)],
                               node.name)
    gltf.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)  # a .gltf's embedded buffers into one blob
    blob = bytearray(gltf.binary_blob())
    flip = np.diag([-1.0, 1.0, 1.0, 1.0])
    for node in gltf.nodes:
        if node.translation:
            node.translation = [-node.translation[0], *node.translation[1:]]
        if node.rotation:
            x, y, z, w = node.rotation
            node.rotation = [x, -y, -z, w]
        if node.matrix:
            node.matrix = (flip @ np.asarray(node.matrix).reshape(4, 4).T @ flip).T.reshape(-1).tolist()
    vectors = {i for mesh in gltf.meshes for p in mesh.primitives
               for i in (p.attributes.POSITION, p.attributes.NORMAL) if i is not None}
    for index in sorted(vectors):
        _accessor_floats(gltf, blob, index, 3)[:, 0] *= -1.0
        accessor = gltf.accessors[index]
        if accessor.min and accessor.max:
            accessor.min, accessor.max = [-accessor.max[0], *accessor.min[1:]], [-accessor.min[0], *accessor.max[1:]]
    for mesh in gltf.meshes:
        for primitive in mesh.primitives:
            accessor = gltf.accessors[primitive.indices]
            view = gltf.bufferViews[accessor.bufferView]
            dtype = {5121: "<u1", 5123: "<u2", 5125: "<u4"}[accessor.componentType]
            start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
            size = np.dtype(dtype).itemsize * accessor.count
            triangles = np.frombuffer(bytes(blob[start:start + size]), dtype=dtype).reshape(-1, 3)
            blob[start:start + size] = triangles[:, ::-1].astype(dtype).tobytes()
    for skin in gltf.skins:
        stored = _accessor_floats(gltf, blob, skin.inverseBindMatrices, 16)
        ibm = np.stack([flip @ m.reshape(4, 4).T @ flip for m in stored.astype(np.float64)]).transpose(0, 2, 1)
        stored[:] = ibm.reshape(-1, 16)
    gltf.animations = []
    gltf.set_binary_blob(bytes(blob))
    gltf.save_binary(str(out))
    return out


def rested_in_pose_gltf(source: Path, out: Path, animation: str) -> Path:
    """A skeleton-only glTF pose file (buffers in data URIs) whose nodes rest in its ``animation``'s first key, as an
    exporter that bakes a key into the nodes leaves a clip: the animations are the same, only the rest moves."""
    import base64

    gltf = _load(source)
    uri = gltf.buffers[0].uri
    blob = bytearray(base64.b64decode(uri.split(",", 1)[1]))
    chosen = next(a for a in gltf.animations if a.name == animation)
    for channel in chosen.channels:
        if channel.target.path not in ("rotation", "translation"):
            continue
        width = 4 if channel.target.path == "rotation" else 3
        keys = _accessor_floats(gltf, blob, chosen.samplers[channel.sampler].output, width)
        setattr(gltf.nodes[channel.target.node], channel.target.path, keys[0].astype(float).tolist())
    gltf.save(str(out))
    return out
