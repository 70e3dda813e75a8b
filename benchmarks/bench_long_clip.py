"""Benchmark: peak memory and time of `s2h retarget` on long clips (10k, 100k, 1M frames by default).

    python benchmarks/bench_long_clip.py [--method asrn] [--frames 10000,100000,1000000] [--dir /tmp/s2h-long]

Each clip is the shipped gestures motion tiled to length and saved as a motion npz; the CLI runs in
a child process under ``/usr/bin/time -v`` (Debian package ``time``). Memory should be flat beyond the
clip's own arrays (input and output rotations: 2 x T x 15 x 4 float32, plus labels), time linear.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

from s2h_viewer import samples
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.npz import save_motion


def make_clip(n_frames: int, folder: Path) -> Path:
    path = folder / f"long_{n_frames}.npz"
    if not path.exists():
        base = next(m for m in samples.load_sample_motions() if m.name == "gestures")
        reps = -(-n_frames // base.n_frames)
        motion = Motion(q_tbs=np.tile(base.q_tbs, (reps, 1, 1))[:n_frames], fps=base.fps, name=f"long_{n_frames}",
                        hand_name=base.hand_name, labels=np.tile(base.labels, reps)[:n_frames])
        save_motion(motion, path)
    return path


def measure(clip: Path, method: str, out: Path) -> tuple[float, float, float]:
    """(peak resident MiB, wall seconds, CPU seconds) of one CLI retarget."""
    done = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-m", "s2h_viewer.cli", "retarget", "--quiet",
                           "--motion", str(clip), "--target", "juniper", "--method", method, "--out", str(out)],
                          capture_output=True, text=True, check=True)
    peak_kib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr).group(1))
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", done.stderr).group(1)
    seconds = sum(float(part) * 60 ** k for k, part in enumerate(reversed(wall.split(":"))))
    cpu = sum(float(re.search(rf"{kind} time \(seconds\): (\S+)", done.stderr).group(1)) for kind in ("User", "System"))
    return peak_kib / 1024, seconds, cpu


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--method", default="asrn")
    parser.add_argument("--frames", default="10000,100000,1000000")
    parser.add_argument("--dir", default="/tmp/s2h-long")
    args = parser.parse_args()
    folder = Path(args.dir)
    folder.mkdir(parents=True, exist_ok=True)
    print("| frames | peak RSS (MiB) | rotations in+out (MiB) | peak - rotations (MiB) | wall (s) | CPU (s) | "
          "CPU us/frame |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for n_frames in (int(f) for f in args.frames.split(",")):
        clip = make_clip(n_frames, folder)
        peak, seconds, cpu = measure(clip, args.method, folder / f"out_{n_frames}.npz")
        arrays = 2 * n_frames * 15 * 4 * 4 / 1024 ** 2
        print(f"| {n_frames:,} | {peak:,.0f} | {arrays:,.0f} | {peak - arrays:,.0f} | {seconds:.1f} | {cpu:.1f} | "
              f"{1e6 * cpu / n_frames:.1f} |", flush=True)


if __name__ == "__main__":
    main()
