"""Benchmark and report: the TBS solver on real third-party rigs loaded without a joint map.

    python benchmarks/bench_real_rigs.py      # or: make bench

One row per rig: recognised scheme and side (and where the side came from), faces, solver time (median
of 5), the worst angle between the bend axes of neighbouring joints of one finger (target <= 20 deg),
and the joints the solver flags for review.
"""

from __future__ import annotations

import numpy as np

from timing import median_seconds  # benchmarks/timing.py, beside this script

from s2h_viewer.annotate.solver import solve_tbs_frames
from s2h_viewer.hand import topology as topo
from s2h_viewer.io.files import RigOptions, load_hand_file
from s2h_viewer.samples import ASSETS_DIR

RIGS = [("real/godot_hand_r.gltf", None), ("real/godot_hand_l.gltf", None), ("real/human-female.glb", "right"),
        ("real/human-female.glb", "left"), ("webxr/generic-hand-right.glb", None),
        ("webxr/generic-hand-left.glb", None)]


def worst_bend_axis_spread(frames: np.ndarray) -> float:
    """Degrees: the largest angle between the bend axes of neighbouring joints of one finger."""
    y = frames[:, :, 1].reshape(topo.N_FINGERS, 3, 3)
    cos = np.abs(np.einsum("fki,fki->fk", y[:, :-1], y[:, 1:]))
    return float(np.degrees(np.arccos(np.clip(cos, 0.0, 1.0))).max())


def main() -> None:
    print("| Rig | --side | Scheme | Side (from) | Faces | Solver (s) | Worst bend-axis spread (deg) | Flagged |")
    print("|---|---|---|---|---:|---:|---:|---|")
    for rig, side in RIGS:
        hand = load_hand_file(ASSETS_DIR / "hands" / rig, RigOptions(side=side))
        seconds = median_seconds(lambda: solve_tbs_frames(hand), 5)
        solution = solve_tbs_frames(hand)
        flagged = ", ".join(topo.ARTICULATED_NAMES[j] for j in np.flatnonzero(solution.needs_review)) or "none"
        print(f"| {rig} | {side or '-'} | {hand.meta['rig_scheme']} | {hand.meta['side']} ({hand.meta['side_from']}) "
              f"| {len(hand.mesh.faces)} | {seconds:.3f} | {worst_bend_axis_spread(solution.frames):.1f} | {flagged} |")


if __name__ == "__main__":
    main()
