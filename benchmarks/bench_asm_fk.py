"""Benchmark: batched torch FK + ASM against the plain per-frame numpy loop, in the same run.

    python benchmarks/bench_asm_fk.py [--frames 10000] [--reference-frames 10000]   # or: make bench

Prints frames/s of each and their ratio (target: batched >= 50x the loop), plus the skinning
cost per frame that the viewer pays, against a per-joint accumulation loop. Timings are medians
of several repeats; nothing here is asserted, so CI never depends on machine speed. Large tensors
go on huge pages as in the app (`s2h_viewer/__init__.py`); ``THP_MEM_ALLOC_ENABLE=0`` measures 4 kB pages.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import s2h_viewer  # noqa: F401  first: it sets how torch allocates large tensors, before torch is imported

import numpy as np
import torch

from timing import median_seconds  # benchmarks/timing.py, beside this script

from s2h_viewer import samples
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.skinning import skin_vertices, skinning_transforms
from s2h_viewer.semantics.asm import semantic_matrix
from s2h_viewer.semantics.reference import asm_sequence


def skin_per_joint_loop(hand, pose) -> np.ndarray:
    """Baseline skinning: accumulate each joint's transformed vertices, one joint at a time."""
    transforms = skinning_transforms(hand, pose)
    v = hand.mesh.vertices.astype(np.float64)
    out = np.zeros_like(v)
    for j in range(topo.N_ROTATING):
        out += hand.mesh.weights[:, j:j + 1] * (v @ transforms[j, :, :3].T + transforms[j, :, 3])
    return out


def median_cpu_seconds(fn, repeats: int) -> float:
    """Median process CPU time of ``fn``: with one thread, what it costs on a core that others share too."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=10_000)
    parser.add_argument("--reference-frames", type=int, default=10_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()

    hand = samples.load_sample_hand("birch")
    clips = np.concatenate([m.q_tbs for m in samples.load_sample_motions()])
    q = np.resize(clips, (args.frames, 15, 4)).astype(np.float32)
    q32 = torch.as_tensor(q)
    print(f"machine: {platform.processor() or platform.machine()}, torch {torch.__version__}, "
          f"{torch.get_num_threads()} threads (OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')}, "
          f"THP_MEM_ALLOC_ENABLE={os.environ.get('THP_MEM_ALLOC_ENABLE')}); "
          f"hand {hand.name}, {args.frames} frames; load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")

    def batched():
        with torch.no_grad():
            return semantic_matrix(forward_kinematics(hand, q32))

    def fk_only():
        with torch.no_grad():
            return forward_kinematics(hand, q32)

    t_batched = median_seconds(batched, args.repeats)
    t_fk = median_seconds(fk_only, args.repeats)
    n_ref = min(args.reference_frames, args.frames)
    t0, c0 = time.perf_counter(), time.process_time()
    reference = asm_sequence(hand, q[:n_ref].astype(np.float64))
    t_ref, c_ref = time.perf_counter() - t0, time.process_time() - c0
    c_batched = median_cpu_seconds(batched, args.repeats)
    error = np.abs(batched().numpy()[:n_ref] - reference).max()

    fps_batched = args.frames / t_batched
    fps_ref = n_ref / t_ref
    print(f"FK + ASM, batched torch float32 : {fps_batched:12,.0f} frames/s  ({t_batched * 1e3:.1f} ms for "
          f"{args.frames}; FK alone {t_fk * 1e3:.1f} ms)")
    print(f"FK + ASM, per-frame numpy loop  : {fps_ref:12,.0f} frames/s  ({t_ref:.2f} s for {n_ref})")
    print(f"ratio batched / loop            : {fps_batched / fps_ref:12.1f} x   (target >= 50 x); "
          f"max |difference| {error:.1e} palm lengths; load average now {os.getloadavg()[0]:.2f}")
    print(f"in CPU time (all threads)       : batched {args.frames / c_batched:,.0f} frames/s, loop "
          f"{n_ref / c_ref:,.0f} frames/s, ratio {(args.frames / c_batched) / (n_ref / c_ref):.1f} x "
          f"(steadier than wall time on a shared machine with one thread)")

    pose = forward_kinematics(hand, torch.as_tensor(q[:1], dtype=torch.float64))
    t_skin = median_seconds(lambda: skin_vertices(hand, pose), 20)
    t_loop = median_seconds(lambda: skin_per_joint_loop(hand, pose), 20)
    print(f"skinning {len(hand.mesh.vertices)} vertices: blended {t_skin * 1e3:.2f} ms/frame, per-joint loop "
          f"{t_loop * 1e3:.2f} ms/frame, ratio {t_loop / t_skin:.1f} x")


if __name__ == "__main__":
    main()
