"""Issue 22's tables: every real rig file (assets/hands/real, ../shared/real-rigs) and the variants made from them
(tests/wild_rigs.py) through `s2h rig`, `s2h annotate` and `s2h retarget` on each hand, full bodies annotated
and retargeted in either order; then each file read 20 times in a row by its reader, the outcomes counted.

    python scripts/wild_files_table.py [--shared ../shared] [--reads 20]
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
GESTURES = ROOT / "assets" / "motions" / "gestures.npz"
REAL = (".glb", ".gltf", ".vrm", ".fbx", ".bvh")


def s2h(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "s2h_viewer.cli", *argv], capture_output=True, text=True, cwd=ROOT,
                          timeout=600)


def made_variants(folder: Path) -> list[Path]:
    """The kinds of the issue no shipped file is an example of, made from real rigs (see tests/wild_rigs.py)."""
    import pygltflib

    from s2h_viewer.io.files import save_motion_file
    from s2h_viewer.io.npz import load_motion
    from s2h_viewer.samples import load_sample_hand
    from wild_rigs import meta_hand_skeleton, mirrored, per_dof_bvh, rescaled_bvh, write_gltf_skeleton
    oculus = ROOT / "assets/hands/real/r_hand_skeletal_lowres.fbx"
    names, parents, positions = meta_hand_skeleton(oculus)
    out = [write_gltf_skeleton(folder / "meta_markers_r.gltf", names, parents, positions),
           write_gltf_skeleton(folder / "meta_markers_r_mirrored.gltf", names, parents, mirrored(positions))]
    left = meta_hand_skeleton(oculus, "l")
    out.append(write_gltf_skeleton(folder / "meta_markers_l.gltf", left[0], left[1], mirrored(left[2])))
    out.append(write_gltf_skeleton(folder / "meta_scaled_roots.gltf", names, parents, positions * 100.0, 0.01))
    motion = load_motion(GESTURES)
    bvh = save_motion_file(folder / "hand_cm.bvh", motion, load_sample_hand(motion.hand_name))
    out += [bvh, rescaled_bvh(bvh, folder / "hand_dm.bvh", 0.1), rescaled_bvh(bvh, folder / "hand_in.bvh", 1 / 2.54),
            per_dof_bvh(bvh, folder / "hand_per_dof.bvh")]
    robot = pygltflib.GLTF2().load_binary(str(ROOT / "assets/hands/real/debug_robot.vrm"))
    robot.extensionsUsed = [*(robot.extensionsUsed or []), "EXT_meshopt_compression"]
    robot.extensionsRequired = ["EXT_meshopt_compression"]
    robot.save_binary(str(folder / "robot_meshopt.vrm"))
    out.append(folder / "robot_meshopt.vrm")
    return out


def sides_of(path: Path) -> list[str | None]:
    """Both hands of a character whose names mark both, else the one hand (None: as recognised)."""
    from s2h_viewer.hand.rig_mapping import sides_named
    from s2h_viewer.io.files import read_rig_skeleton
    try:
        named = sides_named(read_rig_skeleton(path).names)
    except Exception:  # a file the readers refuse: one row, its refusal
        return [None]
    return ["right", "left"] if named == {"right", "left"} else [None]


def rig_summary(done: subprocess.CompletedProcess) -> str:
    if done.returncode != 0:
        return done.stderr.strip().splitlines()[-1][:110] if done.stderr.strip() else f"rc {done.returncode}"
    head = done.stdout.splitlines()[0].split(": ", 1)[1]
    return head.replace(" scheme", "").replace(" hand (side from", ",").split("), confidence")[0]


def table(files: list[Path], work: Path) -> None:
    print("| file | hand | scheme, side, side from | rig | annotate | retarget | annotated first, then the other "
          "retargeted |")
    print("|---|---|---|---:|---:|---:|---|")
    for path in files:
        for side in sides_of(path):
            flag = ["--side", side] if side else []
            rig = s2h("rig", str(path), *flag)
            annotate = s2h("annotate", str(path), *flag)
            out = work / f"{path.stem}_{side}.glb"
            retarget = s2h("retarget", "--motion", str(GESTURES), "--target", str(path), *flag, "--method",
                           "tbs_copy", "--out", str(out), "--quiet")
            order = ""
            if side:  # save this hand's frames on a copy, then retarget onto the other hand of it
                other = "left" if side == "right" else "right"
                copy = work / f"order_{side}" / path.name
                copy.parent.mkdir(exist_ok=True)
                shutil.copy(path, copy)
                saved = s2h("annotate", str(copy), "--side", side, "--save")
                then = s2h("retarget", "--motion", str(GESTURES), "--target", str(copy), "--side", other,
                           "--method", "tbs_copy", "--out", str(work / "order.glb"), "--quiet")
                order = f"annotate --save {side}: {saved.returncode}, retarget {other}: {then.returncode}"
            print(f"| {path.name} | {side or '-'} | {rig_summary(rig)} | {rig.returncode} | {annotate.returncode} | "
                  f"{retarget.returncode} | {order} |", flush=True)


READS = """
import hashlib, sys
from s2h_viewer.io.files import load_hand_file
for _ in range({reads}):
    try:
        hand = load_hand_file(sys.argv[1])
        print(hashlib.sha256(hand.rest_positions.tobytes() + hand.rest_frames.tobytes()).hexdigest()[:12], flush=True)
    except Exception as exc:
        print(f"refused: {{exc}}"[:80], flush=True)
"""


def reads(files: list[Path], n: int) -> None:
    print(f"\n| file | reads | outcomes (distinct) | process exit |\n|---|---:|---|---:|")
    for path in files:
        done = subprocess.run([sys.executable, "-c", READS.format(reads=n), str(path)], capture_output=True,
                              text=True, cwd=ROOT, timeout=1800)
        lines = done.stdout.splitlines()
        outcomes = {line: lines.count(line) for line in lines}
        shown = "; ".join(f"{k} x{v}" for k, v in outcomes.items())
        print(f"| {path.name} | {len(lines)} | {len(outcomes)}: {shown} | {done.returncode} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", default=str(ROOT.parent / "shared"))
    parser.add_argument("--reads", type=int, default=20)
    args = parser.parse_args()
    shipped = sorted(p for p in (ROOT / "assets/hands/real").iterdir() if p.suffix.lower() in REAL)
    shared = Path(args.shared) / "real-rigs"
    extra = sorted(p for p in shared.iterdir() if p.suffix.lower() in REAL and not (ROOT / "assets/hands/real" /
                                                                                     p.name).exists()) \
        if shared.is_dir() else []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        files = shipped + extra + made_variants(work)
        table(files, work)
        reads(files, args.reads)


if __name__ == "__main__":
    main()
