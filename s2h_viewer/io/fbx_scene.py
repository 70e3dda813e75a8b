"""The ufbx half of FBX reading, run in a child process: ``python -m s2h_viewer.io.fbx_scene IN OUT [FPS]``.

ufbx 0.0.5 caches one Python wrapper per scene object without owning it, so a wrapper that Python
frees is later handed out again and crashes the interpreter (``Scene.free`` does the same). Freeing
them at all is unsafe: the scene and its wrappers, dropped when `read_scene` returned, crashed the
process at random (signal 11 in about 1 read in 12 of a Blender-exported FBX: Python's teardown order
of a frame's locals decides whether a wrapper outlives the scene it points into). So every wrapper
fetched is kept in ``keep``, the scene and ``keep`` are never freed (`_NEVER_FREED`), and the process
leaves with ``os._exit`` once the arrays are written; the whole read happens in a process of its own,
so any crash left becomes an error message, never a dead application.
Imports numpy, scipy and ufbx only (fast to start).
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np
import ufbx
from scipy.spatial.transform import Rotation

#: frames x bones evaluated for one take (each a ufbx call): bounds the read's time and memory
MAX_TAKE_SAMPLES = 5_000_000
#: every scene read and the wrappers fetched from it, held until the process exits (see the module docstring)
_NEVER_FREED: list = []


def _matrix(m) -> np.ndarray:
    out = np.eye(4)
    for c, column in enumerate((m.c0, m.c1, m.c2, m.c3)):
        out[:3, c] = (column.x, column.y, column.z)
    return out


def _mesh(nodes: list, names: dict[str, int], keep: list) -> dict[str, np.ndarray]:
    parts = []
    for node in nodes:
        mesh = node.mesh
        keep.append(mesh)
        if mesh is None:
            continue
        deformers = list(mesh.skin_deformers)
        keep.extend(deformers)
        if not deformers:
            continue
        to_world = _matrix(node.geometry_to_world)
        positions = np.array([(v.x, v.y, v.z) for v in mesh.vertices], dtype=np.float64)
        positions = positions @ to_world[:3, :3].T + to_world[:3, 3]
        corner = np.array(list(mesh.vertex_indices), dtype=np.int64)
        faces = []
        for face in list(mesh.faces):  # fan-triangulate polygons
            idx = corner[face.index_begin:face.index_begin + face.num_indices]
            faces.extend((idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1))
        influences = [[] for _ in range(len(positions))]
        clusters = list(deformers[0].clusters)
        keep.extend(clusters)
        for cluster in clusters:
            bone_node = cluster.bone_node
            keep.append(bone_node)
            if bone_node is None:
                continue
            bone = names[bone_node.name]
            for v, w in zip(list(cluster.vertices), list(cluster.weights)):
                influences[v].append((bone, w))
        width = max(1, max(len(i) for i in influences))
        index = np.zeros((len(positions), width), dtype=np.int64)
        weight = np.zeros((len(positions), width))
        for v, inf in enumerate(influences):
            for k, (b, w) in enumerate(inf):
                index[v, k], weight[v, k] = b, w
        parts.append((positions, np.array(faces, dtype=np.int64).reshape(-1, 3), index, weight))
    if not parts:
        return {}
    width = max(p[2].shape[1] for p in parts)
    pad = [(p[2], p[3]) if p[2].shape[1] == width else
           (np.pad(p[2], ((0, 0), (0, width - p[2].shape[1]))), np.pad(p[3], ((0, 0), (0, width - p[3].shape[1]))))
           for p in parts]
    offsets = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
    return {"mesh_vertices": np.concatenate([p[0] for p in parts]),
            "mesh_faces": np.concatenate([p[1] + o for p, o in zip(parts, offsets)]),
            "mesh_bone_index": np.concatenate([i for i, _ in pad]),
            "mesh_bone_weight": np.concatenate([w for _, w in pad])}


def _takes(scene, nodes: list, parents: np.ndarray, fps: float, keep: list
           ) -> list[tuple[str, np.ndarray, float]]:
    takes = []
    stacks = list(scene.anim_stacks)
    keep.extend(stacks)
    for stack in stacks:
        anim = stack.anim
        keep.append(anim)
        duration = stack.time_end - stack.time_begin
        if not np.isfinite(duration) or duration * fps * len(nodes) > MAX_TAKE_SAMPLES:
            raise ValueError(f"take {stack.name!r} lasts {duration:.4g} s: over the limit of {MAX_TAKE_SAMPLES} "
                             f"bone-frames ({len(nodes)} bones at {fps:g} fps)")
        n_frames = int(round(duration * fps)) + 1
        if n_frames < 2:
            continue
        local = np.empty((n_frames, len(nodes), 3, 3))
        for f in range(n_frames):
            t = stack.time_begin + f / fps
            for i, node in enumerate(nodes):
                q = ufbx.evaluate_transform(anim, node, t).rotation
                local[f, i] = Rotation.from_quat((q.x, q.y, q.z, q.w)).as_matrix()
        world = local.copy()
        for i in range(len(nodes)):  # ufbx lists parents before children
            if parents[i] >= 0:
                world[:, i] = world[:, parents[i]] @ local[:, i]
        takes.append((stack.name, world, fps))
    return takes


def _bind_pose(scene, world: np.ndarray, parents: np.ndarray, index: dict[int, int], keep: list) -> np.ndarray:
    """Rest world matrices: the file's bind pose where it has one (a file saved mid-animation stores
    the animated pose in its nodes), a bone outside it following its parent at the stored offset."""
    bind = {}
    poses = list(scene.poses)
    keep.extend(poses)
    for pose in poses:
        if pose.is_bind_pose:
            bone_poses = list(pose.bone_poses)
            keep.extend(bone_poses)
            for bone_pose in bone_poses:
                node = bone_pose.bone_node
                keep.append(node)
                if node is not None and node.typed_id in index:
                    bind[index[node.typed_id]] = _matrix(bone_pose.bone_to_world)
    if not bind:
        return world
    rest = world.copy()
    for i in range(len(world)):  # parents come first
        if i in bind:
            rest[i] = bind[i]
        elif parents[i] >= 0:
            rest[i] = rest[parents[i]] @ np.linalg.inv(world[parents[i]]) @ world[i]
    return rest


def read_scene(path: str, fps: float) -> dict[str, np.ndarray]:
    """Everything s2h needs from an FBX file, as arrays (names as JSON); raises on unreadable files."""
    scene = ufbx.load_file(path, target_unit_meters=1.0, ignore_embedded=True)
    keep = list(scene.nodes)
    _NEVER_FREED.append((scene, keep))
    nodes = [n for n in keep if not n.is_root]
    names = [n.name for n in nodes]
    index = {n.typed_id: i for i, n in enumerate(nodes)}
    parent_nodes = [n.parent for n in nodes]
    parents = np.array([-1 if p is None else index.get(p.typed_id, -1) for p in parent_nodes], dtype=np.int64)
    world = np.stack([_matrix(n.node_to_world) for n in nodes]) if nodes else np.zeros((0, 4, 4))
    world = _bind_pose(scene, world, parents, index, keep)
    arrays = {"names_json": np.array(json.dumps(names)), "parents": parents, "world": world,
              **_mesh(nodes, {n: i for i, n in enumerate(names)}, keep)}
    takes = _takes(scene, nodes, parents, fps, keep)
    arrays["take_names_json"] = np.array(json.dumps([name for name, _, _ in takes]))
    for t, (_, rotations, _) in enumerate(takes):
        arrays[f"take_{t}"] = rotations
    return arrays


def main(argv: list[str]) -> int:
    source, out, fps = argv[0], argv[1], float(argv[2]) if len(argv) > 2 else 30.0
    try:
        arrays = read_scene(source, fps)
    except Exception as exc:  # ufbx.Error and its many subclasses: reported to the parent on stderr
        print(f"{type(exc).__name__}: {exc}".replace("\n", " "), file=sys.stderr)
        return 3
    with open(out, "wb") as fh:
        np.savez(fh, **arrays)
    return 0


if __name__ == "__main__":
    code = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # no teardown: nothing of ufbx is ever freed (see the module docstring)
