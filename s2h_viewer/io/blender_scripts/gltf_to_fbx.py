"""Run by Blender's Python: ``python gltf_to_fbx.py IN.glb OUT.fbx FPS``: the GLB imported as Blender's File >
Import does, then written as FBX with its animation baked at FPS, no leaf bones added."""

import sys

import bpy


def main(source: str, out: str, fps: int) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.fps, bpy.context.scene.render.fps_base = fps, 1.0
    bpy.ops.import_scene.gltf(filepath=source)
    armature = next(o for o in bpy.context.scene.objects if o.type == "ARMATURE")
    action = armature.animation_data.action if armature.animation_data else None
    if action is not None:
        start, end = action.frame_range
        bpy.context.scene.frame_start, bpy.context.scene.frame_end = int(round(start)), int(round(end))
    bpy.ops.export_scene.fbx(filepath=out, add_leaf_bones=False, bake_anim=True, bake_anim_use_all_actions=False,
                             bake_anim_use_nla_strips=False, bake_anim_simplify_factor=0.0)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]))
