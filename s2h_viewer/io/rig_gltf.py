"""A GLB of a rig read from a format s2h cannot write (FBX): the rig's own nodes, names, hierarchy and rest pose,
its skinned mesh, and the hand's bones animated, so that a retarget onto an FBX avatar opens in Blender, Unity
or Unreal as that avatar.

Each node's local transform is its rest world matrix relative to its parent's (translation, rotation, scale);
the skin binds every node at its rest world matrix; the mesh keeps four influences a vertex (glTF's
``JOINTS_0``/``WEIGHTS_0``), the strongest, renormalised.
"""

from __future__ import annotations

import numpy as np
import pygltflib
from scipy.spatial.transform import Rotation

from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.rig import RigMesh, RigSkeleton, rotation_part

#: influences a vertex keeps in glTF (one JOINTS_0 / WEIGHTS_0 pair)
INFLUENCES = 4


def parents_first(parents: np.ndarray) -> list[int]:
    """Node indices ordered so that each comes after its parent."""
    depth = np.zeros(len(parents), dtype=int)
    for i in range(len(parents)):
        node, d = i, 0
        while parents[node] >= 0 and d <= len(parents):
            node, d = parents[node], d + 1
        depth[i] = d
    return [int(i) for i in np.argsort(depth, kind="stable")]


def _local_matrices(skeleton: RigSkeleton) -> np.ndarray:
    """(N, 4, 4) each node's rest transform relative to its parent."""
    local = skeleton.world.copy()
    for i, p in enumerate(skeleton.parents):
        if p >= 0:
            local[i] = np.linalg.inv(skeleton.world[p]) @ skeleton.world[i]
    return local


def rig_nodes(skeleton: RigSkeleton) -> list[pygltflib.Node]:
    """The rig's nodes with their rest transforms (a scale only where it is not one)."""
    local = _local_matrices(skeleton)
    rotation = rotation_part(local)
    nodes = []
    for i, name in enumerate(skeleton.names):
        scale = np.einsum("ij,ij->j", rotation[i], local[i, :3, :3])  # along the node's own axes
        node = pygltflib.Node(name=name, translation=local[i, :3, 3].tolist(),
                              rotation=Rotation.from_matrix(rotation[i]).as_quat().tolist(),
                              children=[int(c) for c in np.flatnonzero(skeleton.parents == i)])
        if not np.allclose(scale, 1.0, atol=1e-9):
            node.scale = scale.tolist()
        nodes.append(node)
    return nodes


def node_rotations(skeleton: RigSkeleton, hand: HandModel, motion: Motion, world_rotations: np.ndarray
                   ) -> dict[int, np.ndarray]:
    """Local rotations over time (T, 3, 3) of the rig's articulated hand bones playing ``motion``, the wrist and
    every other node at rest; ``world_rotations`` are the hand's 16 bone frames over time in hand space
    (`io.rig.world_rotations_from_motion`)."""
    from s2h_viewer.hand import topology as topo
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    rotating = {lookup[hand.meta["rig_joints"][topo.JOINT_NAMES[j]]]: r for r, j in enumerate(topo.ROTATING_JOINTS)}
    wrist = next(node for node, r in rotating.items() if r == 0)
    rest = rotation_part(skeleton.world)
    local_rest = rotation_part(_local_matrices(skeleton))
    world = np.broadcast_to(rest, (motion.n_frames, *rest.shape)).copy()
    for i in parents_first(skeleton.parents):
        if i in rotating:
            world[:, i] = rest[wrist] @ world_rotations[:, rotating[i]]
        elif skeleton.parents[i] >= 0:
            world[:, i] = world[:, skeleton.parents[i]] @ local_rest[i]
    out = {}
    for node, r in rotating.items():
        if r:
            parent = skeleton.parents[node]
            out[node] = world[:, node] if parent < 0 else world[:, parent].transpose(0, 2, 1) @ world[:, node]
    return out


def rig_document(skeleton: RigSkeleton, mesh: RigMesh | None, name: str, append
                 ) -> pygltflib.GLTF2:
    """A glTF of the rig at rest, skinned where it has a mesh; ``append(gltf, data, type, component, target,
    with_bounds)`` adds a buffer view and accessor (`io.gltf._append`) and returns the accessor's index."""
    gltf = pygltflib.GLTF2(asset=pygltflib.Asset(generator="s2h-viewer", version="2.0"), scene=0,
                           nodes=rig_nodes(skeleton), scenes=[], meshes=[], skins=[], accessors=[], bufferViews=[],
                           animations=[])
    roots = [int(i) for i in np.flatnonzero(skeleton.parents < 0)]
    if mesh is not None and len(mesh.faces):
        top = np.argsort(-mesh.bone_weight, axis=1, kind="stable")[:, :INFLUENCES]
        weights = np.take_along_axis(mesh.bone_weight, top, axis=1)
        joints = np.take_along_axis(mesh.bone_index, top, axis=1)
        if weights.shape[1] < INFLUENCES:
            pad = ((0, 0), (0, INFLUENCES - weights.shape[1]))
            weights, joints = np.pad(weights, pad), np.pad(joints, pad)
        weights = (weights / np.maximum(weights.sum(axis=1, keepdims=True), 1e-12)).astype(np.float32)
        attributes = pygltflib.Attributes(
            POSITION=append(gltf, mesh.vertices.astype(np.float32), "VEC3", pygltflib.FLOAT, pygltflib.ARRAY_BUFFER,
                            True),
            JOINTS_0=append(gltf, joints.astype(np.uint16), "VEC4", pygltflib.UNSIGNED_SHORT,
                            pygltflib.ARRAY_BUFFER, False),
            WEIGHTS_0=append(gltf, weights, "VEC4", pygltflib.FLOAT, pygltflib.ARRAY_BUFFER, False))
        indices = append(gltf, mesh.faces.astype(np.uint32).reshape(-1, 1), "SCALAR", pygltflib.UNSIGNED_INT,
                         pygltflib.ELEMENT_ARRAY_BUFFER, False)
        gltf.meshes.append(pygltflib.Mesh(name=f"{name}_skin", primitives=[
            pygltflib.Primitive(attributes=attributes, indices=indices, mode=4)]))
        inverse_bind = np.linalg.inv(skeleton.world).transpose(0, 2, 1).astype(np.float32)  # column-major
        gltf.skins.append(pygltflib.Skin(joints=list(range(len(skeleton.names))),
                                         inverseBindMatrices=append(gltf, inverse_bind, "MAT4", pygltflib.FLOAT,
                                                                    None, False)))
        gltf.nodes.append(pygltflib.Node(name=f"{name}_mesh", mesh=0, skin=0))
        roots.append(len(gltf.nodes) - 1)
    gltf.scenes.append(pygltflib.Scene(name=name, nodes=roots))
    return gltf
