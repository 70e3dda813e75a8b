"""Blender (bpy) script: a character as a Blender user makes one with Rigify, written to glTF or FBX for a game engine.

Rigify's human meta-rig is generated into its control rig (``DEF-``, ``ORG-``, ``MCH-`` bones); a mesh of
tubes round each hand's deform bones (finger sections wider than deep, as a hand's) is skinned to them, and the
rig and mesh are exported with deform bones only, as Blender's exporters are used for Unity, Unreal and Godot.
Used by tests/test_rigify_rigs.py to read a rig from Blender's own tools.

    .venv-blender/bin/python scripts/rigify_hands.py OUT.glb|OUT.fbx [OUT.glb|OUT.fbx ...]

The character is made once and written to each file named (Rigify's generation takes most of the run).
"""

from __future__ import annotations

import sys

import bpy  # first: Blender's own modules (addon_utils, bmesh, mathutils) come with it
import addon_utils  # noqa: I001
import bmesh
import numpy as np
from mathutils import Matrix

#: a finger bone's tube: radius (m) at its head, and how deep (back to pad) it is for its width
FINGER_RADIUS, DEPTH_SHARE = 0.0085, 0.75
PALM_RADIUS = 0.012


def hand_bones(rig) -> list:
    """The deform bones of both hands: wrist, palm (metacarpal) and finger bones."""
    return [b for b in rig.data.bones if b.use_deform and b.name.startswith(("DEF-f_", "DEF-thumb", "DEF-palm",
                                                                                 "DEF-hand"))]


def tube_mesh(rig, bones: list) -> bpy.types.Object:
    """One tube per bone along it (a ball at each finger joint), in the rig's rest pose."""
    bm = bmesh.new()
    world = rig.matrix_world
    for bone in bones:
        finger = not bone.name.startswith(("DEF-palm", "DEF-hand"))
        radius = FINGER_RADIUS if finger else PALM_RADIUS
        cone = bmesh.ops.create_cone(bm, cap_ends=True, segments=16, radius1=radius,
                                     radius2=radius * (0.85 if finger else 1.0), depth=bone.length)
        # the cone lies along z about the origin: along the bone's y from its head, shallower along the bone's z
        place = (world @ bone.matrix_local @ Matrix.Translation((0.0, bone.length / 2, 0.0))
                 @ Matrix.Rotation(-np.pi / 2, 4, "X") @ Matrix.Diagonal((1.0, DEPTH_SHARE, 1.0, 1.0)))
        bmesh.ops.transform(bm, matrix=place, verts=cone["verts"])
        if finger:
            ball = bmesh.ops.create_uvsphere(bm, u_segments=12, v_segments=8, radius=radius * 0.95)
            bmesh.ops.transform(bm, matrix=world @ bone.matrix_local @ Matrix.Diagonal((1.0, 1.0, DEPTH_SHARE, 1.0)),
                                verts=ball["verts"])
    mesh = bpy.data.meshes.new("Hands")
    bm.to_mesh(mesh)
    obj = bpy.data.objects.new("Hands", mesh)
    bpy.context.collection.objects.link(obj)
    return obj


def skin_to_nearest_bones(obj, rig, bones: list) -> None:
    """Each vertex weighted to its two nearest bones (inverse fourth power of the distance to their segments); an
    Armature modifier on the rig (Blender's heat weighting fails on overlapping tubes)."""
    world = rig.matrix_world
    heads = np.array([world @ b.head_local for b in bones])
    tails = np.array([world @ b.tail_local for b in bones])
    groups = [obj.vertex_groups.new(name=b.name) for b in bones]
    along = tails - heads
    for vertex in obj.data.vertices:
        p = np.array(vertex.co)
        t = np.clip(((p - heads) * along).sum(1) / np.maximum((along * along).sum(1), 1e-12), 0.0, 1.0)
        distance = np.linalg.norm(p - (heads + t[:, None] * along), axis=1)
        nearest = np.argsort(distance)[:2]
        weights = 1.0 / np.maximum(distance[nearest], 1e-4) ** 4
        for k, w in zip(nearest, weights / weights.sum()):
            groups[k].add([vertex.index], float(w), "REPLACE")
    obj.modifiers.new("Armature", "ARMATURE").object = rig
    obj.parent = rig


def main(outs: list[str]) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("rigify", default_set=True)
    bpy.ops.object.armature_human_metarig_add()
    metarig = bpy.context.object
    bpy.ops.pose.rigify_generate()
    rig = bpy.data.objects["rig"]
    bpy.data.objects.remove(metarig)
    bones = hand_bones(rig)
    hands = tube_mesh(rig, bones)
    skin_to_nearest_bones(hands, rig, bones)
    bpy.ops.object.select_all(action="DESELECT")
    hands.select_set(True)
    rig.select_set(True)
    for out in outs:
        if out.endswith(".fbx"):
            bpy.ops.export_scene.fbx(filepath=out, use_selection=True, use_armature_deform_only=True,
                                     add_leaf_bones=False)
        else:
            bpy.ops.export_scene.gltf(filepath=out, use_selection=True, export_def_bones=True,
                                      export_animations=False)


if __name__ == "__main__":
    main(sys.argv[1:])
