"""Scripts Blender's own Python runs (`io.blender`): they import bpy and nothing of s2h_viewer."""
