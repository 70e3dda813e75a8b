"""Benchmark: retargeting speed of each method on a 1,000-frame clip, against TBS Copy in the same run.

    python benchmarks/bench_retarget.py      # or: make bench

ASRN/DM: frames per second including FK + features + sliding windows (target >= 2,000 frames/s on
2 CPU cores). ASM-Opt: seconds per 100 frames. Each as a ratio to TBS Copy measured here and now.
"""

from __future__ import annotations

import argparse
import os
import time

import s2h_viewer  # noqa: F401  first: it sets how torch allocates large tensors, before torch is imported

import numpy as np
import torch

from timing import median_seconds  # benchmarks/timing.py, beside this script

from s2h_viewer import samples
from s2h_viewer.hand.motion import Motion
from s2h_viewer.retarget import retarget


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--methods", default="dm,asrn,asm_opt", help="comma-separated, beside TBS Copy")
    args = parser.parse_args()
    methods = args.methods.split(",")
    hands = {h.name: h for h in samples.load_sample_hands()}
    clips = samples.load_sample_motions()
    q = np.resize(np.concatenate([m.q_tbs for m in clips]), (1000, 15, 4))
    motion = Motion(q_tbs=q, name="bench", hand_name="birch")
    source, target = hands["birch"], hands["juniper"]
    print(f"torch {torch.__version__}, {torch.get_num_threads()} threads (OMP_NUM_THREADS="
          f"{os.environ.get('OMP_NUM_THREADS', 'unset')}); 1000 frames birch -> juniper; load average "
          f"{os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    base = median_seconds(lambda: retarget(motion, source, target, "tbs_copy"), 20)
    print(f"TBS Copy : {1000 / base:12,.0f} frames/s")
    for method in [m for m in ("dm", "asrn") if m in methods]:
        t = median_seconds(lambda: retarget(motion, source, target, method), 5)
        print(f"{method.upper():8s} : {1000 / t:12,.0f} frames/s  ({t / base:.1f} x the time of TBS Copy; "
              f"target >= 2,000 frames/s)")
    if "asm_opt" in methods:
        c0 = time.process_time()
        t = median_seconds(lambda: retarget(motion, source, target, "asm_opt"), 1)
        cpu = (time.process_time() - c0) / 2  # the warm-up run and the timed one
        print(f"ASM-Opt  : {t / 10:12.2f} s per 100 frames ({t / base:,.0f} x the time of TBS Copy; CPU time "
              f"{cpu / 10:.2f} s per 100 frames; target <= 0.2 s); load average now {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
