"""Benchmark: `s2h batch` against a shell loop over `s2h retarget`, 1 against 2 workers, and a worker's peak
memory on a 100,000-frame clip, all measured in this run.

    python benchmarks/bench_batch.py      # or: make bench

The same 3 clips x 5 targets x 2 methods (30 tasks) each way. The loop pays a process start per task; the
batch pays one cluster start, and does more per task (scores, the worst frame's picture, unless
--no-pictures). Tasks per minute over the whole run, and for the batch also after its start-up (the cluster
up and its workers' imports done). Goals (issue 23): batch >= 5 x the loop, 2 workers >= 1.7 x 1.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import s2h_viewer  # noqa: F401  first: it sets how torch allocates large tensors, before torch is imported

import numpy as np

from s2h_viewer.batch.cluster import local_cluster
from s2h_viewer.batch.plan import TaskOptions
from s2h_viewer.batch.runner import BatchConfig, run_batch
from s2h_viewer.io.npz import load_motion, save_motion
from s2h_viewer.samples import ASSETS_DIR

MOTIONS = [str(ASSETS_DIR / "motions" / f"{name}.npz") for name in ("gestures", "counting", "fingerspelling")]
TARGETS = ["iris", "laurel", "juniper", "kale", str(ASSETS_DIR / "hands" / "real" / "godot_hand_r.gltf")]
METHODS = ["tbs_copy", "asrn"]
S2H = [sys.executable, "-m", "s2h_viewer.cli"]


def shell_loop(out: Path) -> float:
    """Seconds for one `s2h retarget` process per task, one after another (what a shell loop does)."""
    start = time.perf_counter()
    for motion in MOTIONS:
        for target in TARGETS:
            for method in METHODS:
                name = f"{Path(motion).stem}_{Path(target).stem}_{method}.glb"
                subprocess.run([*S2H, "retarget", "--motion", motion, "--target", target, "--method", method,
                                "--out", str(out / name), "--quiet"], check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def batch(out: Path, workers: int, pictures: bool) -> tuple[float, float]:
    """(whole seconds, seconds after start-up) of the 30 tasks on a LocalCluster of ``workers``."""
    result = run_batch(BatchConfig(MOTIONS, TARGETS, METHODS, str(out), TaskOptions(render=pictures),
                                   workers=workers), show_progress=False)
    assert not result.failed, result.failed[:1]
    return result.seconds, result.seconds - result.startup_seconds


def _peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def long_clip_peak(folder: Path, frames: int) -> dict[str, float]:
    """A worker's peak resident memory (MiB) before and after retargeting a ``frames``-frame clip, per method."""
    clip = load_motion(MOTIONS[0])
    long = clip.__class__(q_tbs=np.resize(clip.q_tbs, (frames, 15, 4)), name="long", hand_name=clip.hand_name,
                          fps=clip.fps)
    path = save_motion(long, folder / "long.npz")
    peaks = {}
    with local_cluster(1) as cluster:
        from distributed import Client
        with Client(cluster) as client:
            from s2h_viewer.batch.cluster import warm_up
            client.run(warm_up)
            peaks["after imports"] = next(iter(client.run(_peak_rss_mib).values()))
            for method in METHODS:
                result = run_batch(BatchConfig([str(path)], ["iris"], [method], str(folder / method),
                                               TaskOptions(format="npz", render=False),
                                               scheduler=cluster.scheduler_address), show_progress=False)
                assert not result.failed, result.failed[:1]
                peaks[method] = next(iter(client.run(_peak_rss_mib).values()))
    return peaks


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--long-frames", type=int, default=100_000)
    parser.add_argument("--no-loop", action="store_true", help="skip the shell loop (5 minutes here)")
    args = parser.parse_args()
    n = len(MOTIONS) * len(TARGETS) * len(METHODS)
    print(f"{n} tasks ({len(MOTIONS)} clips x {len(TARGETS)} targets x {len(METHODS)} methods); load average "
          f"{os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        loop = float("nan") if args.no_loop else shell_loop(tmp / "loop")
        print(f"shell loop over s2h retarget : {loop:6.1f} s  {60 * n / loop:6.1f} tasks/min  (baseline)")
        results = {}
        for workers, pictures in ((2, False), (2, True), (1, True)):
            whole, steady = batch(tmp / f"batch{workers}{pictures}", workers, pictures)
            results[workers, pictures] = (whole, steady)
            print(f"s2h batch, {workers} worker{'s' if workers > 1 else ' '}, {'pictures' if pictures else 'no pictures'}"
                  f"{'' if pictures else '   '} : {whole:6.1f} s  {60 * n / whole:6.1f} tasks/min  "
                  f"({loop / whole:.1f} x the loop; after start-up {60 * n / steady:6.1f} tasks/min)")
        (w2, s2), (w1, s1) = results[2, True], results[1, True]
        print(f"2 workers / 1 worker (pictures): {w1 / w2:.2f} x over the whole run, {s1 / s2:.2f} x after "
              f"start-up (goal >= 1.7)")
        print(f"batch (2 workers, no pictures) / shell loop: {loop / results[2, False][0]:.1f} x (goal >= 5)")
        peaks = long_clip_peak(tmp, args.long_frames)
        print(f"worker peak memory, {args.long_frames:,}-frame clip onto iris: "
              + ", ".join(f"{k} {v:,.0f} MiB" for k, v in peaks.items()))


if __name__ == "__main__":
    main()
