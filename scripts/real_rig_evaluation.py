"""Issue 26's tables: every method onto every real rig, on the authored poses of assets/motions/real
(held one by one, `s2h evaluate --animation all`) and on the shipped gestures clip: poses whose signature
is kept, contact precision, violations, the worst sideways flexion at the tightest curls; and how closely the
thumb follows the source's on a motion made of those poses that moves it (`THUMB_EXERCISE`).

    python scripts/real_rig_evaluation.py [--methods tbs_copy,dm,asrn] [--shared ../shared] [--side left] [--no-hinges]

The source is the rig the poses were authored on (the right hand's), its frames checked against the hinges of
the poses themselves (`--hinges-from`; `--no-hinges`: the solver's alone); `--side left` takes the left-hand
pose file on its own skeleton (it has no mesh: palm-plane frames and the hinges).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from s2h_viewer import samples
from s2h_viewer.io.files import RigOptions, load_hand_file, load_motion_file
from s2h_viewer.motions.pose_clip import pose_sequence
from s2h_viewer.retarget.evaluation import evaluate
from s2h_viewer.semantics.signature import held_poses

ROOT = Path(__file__).resolve().parents[1]
#: (file under real-rigs/ or assets/hands/, side or None for a lone hand)
RIGS = (("real/godot_hand_r.gltf", None), ("real/godot_hand_l.gltf", None), ("real/human-female.glb", "right"),
        ("real/human-female.glb", "left"), ("real/RPM_Template_Mesh_XR.glb", "right"), ("real/RPM_Template_Mesh_XR.glb", "left"),
        ("r_hand_skeletal_lowres.fbx", None), ("l_hand_skeletal_lowres.fbx", None),
        ("webxr/generic-hand-right.glb", None), ("webxr/generic-hand-left.glb", None),
        ("real/debug_robot.vrm", "right"), ("real/debug_robot.vrm", "left"),
        ("real/cryptovoxels.vrm", "right"), ("real/cryptovoxels.vrm", "left"))

#: the authored poses the thumb exercise goes through (`pose_sequence`): its tip to each fingertip and back, the
#: thumbs-up, a grip, across the palm (Sign 4), out (Surfer): the poses clip's thumb barely moves between most of
#: its poses (its CMC across the palm: 72-76 deg on 33 of 35), so its correlations are made by two or three
THUMB_EXERCISE = ("Default", "Pinch Tight", "Default", "Pinch Middle", "Default", "Pinch Ring", "Default", "Thumb",
                  "Grip", "Sign 4", "Surfer", "Default", "OK", "Pinky", "Default")
#: the rest pose's name in each pose file (the left hand's calls it "Default pose")
REST_NAMES = ("Default", "Default pose")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--methods", default="tbs_copy,dm,asrn")
    parser.add_argument("--shared", default=str(ROOT.parent / "shared"))
    parser.add_argument("--side", choices=("right", "left"), default="right", help="which hand's pose file")
    parser.add_argument("--no-hinges", action="store_true", help="the source rig's frames without the poses' hinges")
    args = parser.parse_args()
    shared = Path(args.shared)
    methods = args.methods.split(",")
    pose_file = ROOT / f"assets/motions/real/godot_hand_poses_{args.side[0]}.gltf"
    rig = None
    if args.side == "right":
        rig = load_hand_file(ROOT / "assets/motions/real/godot_hand_r_posed_rig.gltf",
                             RigOptions(hinges_from=None if args.no_hinges else pose_file))
    poses, performer = load_motion_file(pose_file, rig, RigOptions(animation="all"))
    gestures = next(m for m in samples.load_sample_motions() if m.name.startswith("gestures"))
    hands = {performer.name: performer, gestures.hand_name: samples.load_sample_hand(gestures.hand_name)}
    labels = []
    for file, side in RIGS:
        path = ROOT / "assets/hands" / file if (ROOT / "assets/hands" / file).exists() else shared / "real-rigs" / file
        if not path.exists():
            continue
        label = f"{Path(file).name}" + (f" ({side})" if side else "")
        hand = load_hand_file(path, RigOptions(side=side))
        hand.name = label
        hands[label] = hand
        labels.append(label)
    print(f"source: {pose_file.name} on {performer.source or performer.name} ({performer.meta.get('annotation')})")
    print("| rig | method | poses kept (of 35) | contact P (poses) | violations (poses) | violations added (poses) "
          "| sideways max, poses "
          "| thumb follows, poses | thumb follows, thumb exercise | sideways max, gestures | S_finger, gestures |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    pose_rows = evaluate([poses], hands, labels, methods)
    rest = next(name for name in REST_NAMES if name in {pose for pose, _ in held_poses(poses.labels)})
    exercise = pose_sequence(poses, [rest if name == "Default" else name for name in THUMB_EXERCISE], "thumb exercise",
                             hold=10, blend=15)
    exercise_rows = evaluate([exercise], hands, labels, methods)
    gesture_rows = evaluate([gestures], hands, labels, methods)
    for p, e, g in zip(pose_rows, exercise_rows, gesture_rows):
        kept = sum(not lost for lost in p.poses.values())
        print(f"| {p.target} | {p.method} | {kept} | {p.scores.contact_precision:.2f} | {p.scores.violation_rate:.3f} "
              f"| {p.scores.added_violation_rate:.3f} | {p.scores.sideways_deg:.0f} "
              f"| {p.scores.thumb_follow:.2f} ({p.scores.thumb_follow_at}) "
              f"| {e.scores.thumb_follow:.2f} ({e.scores.thumb_follow_at}) "
              f"| {g.scores.sideways_deg:.0f} ({g.scores.sideways_at}) "
              f"| {g.scores.s_finger:.3f} |", flush=True)
    print()
    for p in pose_rows:
        lost = {name: what for name, what in p.poses.items() if what}
        print(f"- {p.target}, {p.method}: " + ("; ".join(f"{n}: {', '.join(w)}" for n, w in lost.items()) or "all kept"))


if __name__ == "__main__":
    main()
