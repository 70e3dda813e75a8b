"""The real WebXR recording (iwer's relaxed / pinch / point) and the same frames as MediaPipe landmarks,
retargeted with TBS Copy and ASRN onto every real rig: does each pose keep its signature (each finger
extended, half or curled; the thumb-index touch)? Prints a markdown table and writes one picture per pose
(every rig, both methods) to --out. Issue 24's "must show"; real files are test data only.

Run: .venv/bin/python scripts/tracking_signatures.py [--rigs DIR ...] [--out DIR]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from s2h_viewer.errors import S2HError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.io.files import RigOptions, load_hand_file, load_motion_file
from s2h_viewer.io.mediapipe_hand import save_mediapipe_hand
from s2h_viewer.io.recordings import read_recording
from s2h_viewer.retarget import retarget
from s2h_viewer.samples import ASSETS_DIR
from s2h_viewer.semantics.contacts import detect_contacts, pair_index
from s2h_viewer.tracking.recording import KeypointRecording

RECORDING = ASSETS_DIR / "recordings" / "webxr_hand_poses_right.json"
POSES = ("relaxed", "pinch", "point")
RIGS = [(ASSETS_DIR / "hands" / "real" / "godot_hand_r.gltf", None), (ASSETS_DIR / "hands" / "real" /
        "godot_hand_l.gltf", None), (ASSETS_DIR / "hands" / "real" / "human-female.glb", "right"),
        (ASSETS_DIR / "hands" / "real" / "human-female.glb", "left"),
        (ASSETS_DIR / "hands" / "real" / "r_hand_skeletal_lowres.fbx", None),
        (ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb", None),
        (ASSETS_DIR / "hands" / "webxr" / "generic-hand-left.glb", None)]
SHARED = Path(__file__).resolve().parents[2] / "shared" / "real-rigs"
SHARED_RIGS = [("RPM_Template_Mesh_XR.glb", "right"), ("RPM_Template_Mesh_XR.glb", "left"),
               ("l_hand_skeletal_lowres.fbx", None)]


def finger_states(hand, q: np.ndarray) -> list[str]:
    """Per finger: extended (tip to knuckle over 90% of the finger's length), curled (under 65%), else half."""
    p = forward_kinematics(hand, q[None]).positions[0].numpy()
    states = []
    for f in range(topo.N_FINGERS):
        joints = [1 + 4 * f + k for k in range(4)]
        length = sum(np.linalg.norm(p[b] - p[a]) for a, b in zip(joints, joints[1:]))
        reach = np.linalg.norm(p[joints[-1]] - p[joints[0]]) / length
        states.append("E" if reach > 0.9 else "C" if reach < 0.65 else "h")
    return states


def signature(hand, motion, frame: int) -> str:
    touching = detect_contacts(hand, forward_kinematics(hand, motion.q_tbs[frame:frame + 1]))[0]
    return "".join(finger_states(hand, motion.q_tbs[frame])) + (" +pinch" if touching[pair_index("thumb", "index")]
                                                                else "")


def as_mediapipe(out: Path) -> Path:
    """The recording's frames as MediaPipe world landmarks would give them: about the hand's centre, in a
    camera's axes (x right, y down, z away: a half turn about x), the label for a mirrored image."""
    webxr = read_recording(RECORDING)
    centred = webxr.positions - webxr.positions.mean(1, keepdims=True)
    camera = np.diag([1.0, -1.0, -1.0])
    landmarks = KeypointRecording(centred @ camera.T, webxr.fps, webxr.side, "mediapipe", "mediapipe-hand",
                                  labels=webxr.labels)
    return save_mediapipe_hand(out / "webxr_hand_poses_as_mediapipe.json", landmarks, handedness="Left")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="tracking_signatures", help="folder for the pictures")
    parser.add_argument("--no-pictures", dest="pictures", action="store_false")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rigs = list(RIGS) + [(SHARED / name, side) for name, side in SHARED_RIGS if (SHARED / name).exists()]
    sources = {"WebXR": load_motion_file(RECORDING), "MediaPipe": load_motion_file(as_mediapipe(out))}
    frames = {}
    motion = sources["WebXR"][0]
    for pose in POSES:
        held = np.flatnonzero(motion.labels == pose)
        frames[pose] = int(held[len(held) // 2])
    print("signature: thumb index middle ring pinky, E extended / h half / C curled; +pinch: thumb-index touch\n")
    print("| source | target | method | " + " | ".join(POSES) + " | kept |")
    print("|---|---|---|" + "---|" * (len(POSES) + 1))
    targets = []
    for kind, (motion, source) in sources.items():
        want = {pose: signature(source, motion, frames[pose]) for pose in POSES}
        print(f"| {kind} | (fitted source) | | " + " | ".join(want.values()) + " | |")
        for path, side in rigs:
            try:
                target = load_hand_file(path, RigOptions(side=side))
            except S2HError as exc:
                print(f"| {kind} | {path.name} {side or ''} | | refused: {exc} |")
                continue
            if kind == "WebXR":
                targets.append(target)
            for method in ("tbs_copy", "asrn"):
                result = retarget(motion, source, target, method)
                got = {pose: signature(target, result, frames[pose]) for pose in POSES}
                kept = sum(got[p] == want[p] for p in POSES)
                print(f"| {kind} | {target.name}{f' ({side})' if side else ''} | {method} | " + " | ".join(
                    g if g == want[p] else f"**{g}**" for p, g in got.items()) + f" | {kept}/{len(POSES)} |")
    if args.pictures:
        from s2h_viewer.render.compare_scene import ViewOptions, render_comparison
        from s2h_viewer.retarget.comparison import build_comparison

        motion, source = sources["WebXR"]
        comparison = build_comparison(motion, source, targets, ["tbs_copy", "asrn"])
        for pose, frame in frames.items():
            path = render_comparison(comparison, out / f"{pose}.png", frame=frame, size=(1000, 2200),
                                     options=ViewOptions(camera="palm", contacts=True))
            print(f"wrote {path}")


if __name__ == "__main__":
    main()
