"""Make the FBX test rigs under assets/hands/fbx/ with Blender's own FBX writer (Blender as a module).

    python -m venv /tmp/bpyenv && /tmp/bpyenv/bin/pip install bpy==5.0.1   # Python 3.11, ~370 MB
    .venv/bin/s2h retarget --motion assets/motions/counting.npz --target kale --method tbs_copy --out /tmp/kale.glb
    /tmp/bpyenv/bin/python scripts/make_fbx_samples.py /tmp/kale.glb assets/hands/fbx

Writes ``mixamo_right_hand.fbx`` (bones renamed to Mixamo's ``mixamorig:RightHand...``, the mesh
decimated to about 3,000 faces, the counting motion as its take) and ``four_finger_hand.fbx`` (the
same rig with the pinky removed, no take, to test the 5-finger check). s2h itself only reads FBX
(ufbx); this script is not run by the tests.
"""

import sys
from pathlib import Path

import bpy

MIXAMO = {"wrist": "RightHand"}
for finger, mixamo in (("thumb", "Thumb"), ("index", "Index"), ("middle", "Middle"), ("ring", "Ring"),
                       ("pinky", "Pinky")):
    levels = ("cmc", "mcp", "ip", "tip") if finger == "thumb" else ("mcp", "pip", "dip", "tip")
    for i, level in enumerate(levels):
        MIXAMO[f"{finger}_{level}"] = f"RightHand{mixamo}{i + 1}"


def load(glb: Path) -> bpy.types.Object:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.fps = 30  # before the import, which places keys by the scene's frame rate
    bpy.ops.import_scene.gltf(filepath=str(glb))
    armature = next(o for o in bpy.context.scene.objects if o.type == "ARMATURE")
    for bone in armature.data.bones:
        if bone.name in MIXAMO:
            bone.name = f"mixamorig:{MIXAMO[bone.name]}"
    for obj in bpy.context.scene.objects:
        if obj.type == "MESH":
            for group in obj.vertex_groups:
                if group.name in MIXAMO:
                    group.name = f"mixamorig:{MIXAMO[group.name]}"
    for obj in list(bpy.context.scene.objects):
        if obj.type == "MESH" and not obj.data.vertices or obj.name.startswith("Icosphere"):
            bpy.data.objects.remove(obj)  # the importer's bone display shapes
        elif obj.type == "MESH":
            decimate = obj.modifiers.new("decimate", "DECIMATE")
            decimate.ratio = 0.12
    return armature


def export(path: Path, animated: bool) -> None:
    bpy.ops.export_scene.fbx(filepath=str(path), add_leaf_bones=False, bake_anim=animated,
                             use_armature_deform_only=True, use_mesh_modifiers=True)
    print(f"wrote {path} ({path.stat().st_size} bytes)")


def main() -> None:
    glb, out = Path(sys.argv[1]), Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    load(glb)
    export(out / "mixamo_right_hand.fbx", animated=True)

    armature = load(glb)
    bpy.context.view_layer.objects.active = armature
    bpy.ops.object.mode_set(mode="EDIT")
    for bone in list(armature.data.edit_bones):
        if "Pinky" in bone.name:
            armature.data.edit_bones.remove(bone)
    bpy.ops.object.mode_set(mode="OBJECT")
    export(out / "four_finger_hand.fbx", animated=False)


if __name__ == "__main__":
    main()
