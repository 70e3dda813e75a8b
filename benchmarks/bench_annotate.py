"""Benchmark: TBS solver time per hand (all rays in one query, embree), and for the first hand the
same solve with trimesh's pure-Python intersector in the same run as the baseline (it takes a minute).

    python benchmarks/bench_annotate.py      # or: make bench

Target: < 1 s for a hand of 20k faces or more on 2 CPU cores.
"""

from __future__ import annotations

import time

import trimesh

from timing import median_seconds  # benchmarks/timing.py, beside this script

from s2h_viewer import samples
from s2h_viewer.annotate import solver
from s2h_viewer.io.gltf import load_gltf_hand


def main() -> None:
    hands = samples.load_sample_hands("test") + [load_gltf_hand(samples.ASSETS_DIR / "hands" / "webxr" /
                                                                "generic-hand-right.glb")]
    rays = solver.N_ANGLES * 4 * len(solver.STATIONS_ALONG_BONE) * 15
    print(f"{rays:,} rays per hand; embree through trimesh vs trimesh's pure-Python intersector")
    fast_intersector = solver._ray_intersector
    solver._ray_intersector = lambda mesh: trimesh.ray.ray_triangle.RayMeshIntersector(mesh)
    try:
        t0 = time.perf_counter()
        solver.solve_tbs_frames(hands[0])
        baseline = time.perf_counter() - t0
    finally:
        solver._ray_intersector = fast_intersector
    print(f"baseline: {hands[0].name}, pure-Python rays: {baseline:.1f} s")
    for hand in hands:
        fast = median_seconds(lambda: solver.solve_tbs_frames(hand), 5)
        print(f"{hand.name:20s} {len(hand.mesh.faces):6d} faces: {fast:6.3f} s  ({baseline / fast:5.0f} x faster "
              f"than the baseline; target < 1 s)")


if __name__ == "__main__":
    main()
