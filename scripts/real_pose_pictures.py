"""Issue 26's pictures: fist, point, OK, pinch and thumbs-up of the authored Godot poses on every real rig,
TBS Copy and ASRN side by side (one PNG per pose and group of rigs), off screen.

    python scripts/real_pose_pictures.py OUT_DIR [--shared ../shared] [--methods tbs_copy,asrn] [--poses "Sign 3,Horns"]

``--poses`` names other authored poses to picture instead (the file named after the pose).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from s2h_viewer.io.files import RigOptions, load_hand_file, load_motion_file
from s2h_viewer.render.compare_scene import render_comparison
from s2h_viewer.retarget.comparison import build_comparison, with_distinct_names
from s2h_viewer.semantics.signature import held_poses

ROOT = Path(__file__).resolve().parents[1]
POSES = ROOT / "assets/motions/real/godot_hand_poses_r.gltf"
#: the picture's name -> the authored pose shown
SHOWN = {"fist": "Grip", "point": "Sign_Point", "ok": "OK", "pinch": "Pinch Tight", "thumbs_up": "Thumb"}
#: rigs per picture (file under assets/hands or ../shared/real-rigs, side)
GROUPS = {"lone_hands": (("real/godot_hand_r.gltf", None), ("r_hand_skeletal_lowres.fbx", None),
                         ("webxr/generic-hand-right.glb", None)),
          "characters": (("real/human-female.glb", "right"), ("real/RPM_Template_Mesh_XR.glb", "right"),
                         ("real/godot_hand_l.gltf", None)),
          "vrm_avatars": (("real/debug_robot.vrm", "right"), ("real/cryptovoxels.vrm", "right"),
                          ("real/cryptovoxels.vrm", "left"))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--shared", type=Path, default=ROOT.parent / "shared")
    parser.add_argument("--methods", default="tbs_copy,asrn")
    parser.add_argument("--poses", help=f"authored poses to picture, comma-separated (default: {', '.join(SHOWN.values())})")
    args = parser.parse_args()
    shown = ({pose.lower().replace(" ", "_"): pose for pose in args.poses.split(",")} if args.poses else SHOWN)
    rig = load_hand_file(ROOT / "assets/motions/real/godot_hand_r_posed_rig.gltf", RigOptions(hinges_from=POSES))
    motion, source = load_motion_file(POSES, rig, RigOptions(animation="all"))
    starts = dict(held_poses(motion.labels))
    unknown = [pose for pose in shown.values() if pose not in starts]
    if unknown:
        parser.error(f"no such pose: {', '.join(unknown)} (the file holds {', '.join(starts)})")
    args.out.mkdir(parents=True, exist_ok=True)
    for group, rigs in GROUPS.items():
        targets = []
        for file, side in rigs:
            path = ROOT / "assets/hands" / file
            path = path if path.exists() else args.shared / "real-rigs" / file
            if path.exists():
                targets.append(load_hand_file(path, RigOptions(side=side)))
        comparison = build_comparison(motion, source, with_distinct_names(targets), args.methods.split(","))
        for name, pose in shown.items():
            frame = starts[pose]  # the middle of its held frames
            print(render_comparison(comparison, args.out / f"{name}_{group}.png", frame=frame, size=(1600, 1000)))


if __name__ == "__main__":
    main()
