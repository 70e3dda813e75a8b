"""Benchmark: peak memory and time of `s2h retarget` on long clips (10k, 100k, 1M frames by default).

    python -m benchmarks.bench_long_clip [--method asrn] [--frames 10000,100000,1000000] [--dir /tmp/s2h-long]

Each clip is the shipped gestures motion tiled to length and saved as a motion npz; the CLI runs in
a child process under ``/usr/bin/time -v`` (Debian package ``time``). "arrays" is what the clip itself
must hold: input and output rotations (2 x T x 15 x 4 float32) and the per-frame labels (one reference
each, shared by input and output). Memory should be flat beyond the arrays (the last column the same at
every length), time linear: the seconds per 100k frames beyond the start-up (imports, loading the
network: the time of a 1,000-frame clip) the same at every length. The machine's load is printed beside
the table: wall times are only comparable under the same load (CPU times less so).
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

from s2h_viewer import samples
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.npz import save_motion

#: bytes the clip's own arrays take per frame: input and output rotations, one label reference
ARRAY_BYTES_PER_FRAME = 2 * 15 * 4 * 4 + 8
#: the clip whose run measures the start-up (everything but the per-frame work)
STARTUP_FRAMES = 1000


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
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"s2h retarget failed on {clip}:\n{done.stderr[-2000:]}")
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
    print(f"s2h retarget --method {args.method}; load average before: {os.getloadavg()[0]:.2f}")
    _, start_wall, start_cpu = measure(make_clip(STARTUP_FRAMES, folder), args.method,
                                       folder / f"out_{args.method}_{STARTUP_FRAMES}.npz")
    print(f"start-up ({STARTUP_FRAMES:,}-frame clip): wall {start_wall:.1f} s, CPU {start_cpu:.1f} s")
    print("| frames | wall (s) | wall s / 100k frames | beyond start-up: wall s / 100k | CPU (s) | "
          "beyond start-up: CPU s / 100k | peak RSS (MiB) | arrays (MiB) | peak - arrays (MiB) |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n_frames in (int(f) for f in args.frames.split(",")):
        clip = make_clip(n_frames, folder)
        peak, seconds, cpu = measure(clip, args.method, folder / f"out_{args.method}_{n_frames}.npz")
        arrays = n_frames * ARRAY_BYTES_PER_FRAME / 1024 ** 2
        per_100k = 1e5 / (n_frames - STARTUP_FRAMES)
        print(f"| {n_frames:,} | {seconds:.1f} | {1e5 * seconds / n_frames:.2f} | "
              f"{(seconds - start_wall) * per_100k:.2f} | {cpu:.1f} | {(cpu - start_cpu) * per_100k:.2f} | "
              f"{peak:,.0f} | {arrays:,.0f} | {peak - arrays:,.0f} |", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
