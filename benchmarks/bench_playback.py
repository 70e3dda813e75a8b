"""Benchmark: compare-mode playback off screen, 4 target hands, frames/s and one frame's cost split
into skinning and rendering; the full 25k-face meshes are the baseline for the display meshes.

    python benchmarks/bench_playback.py      # or: make bench

Draws what `widgets.compare_view` draws per frame (skin every hand, colour it by ASM error, render
one window of subplots, no multisampling) without Qt, so it runs with no display (EGL).
"""

from __future__ import annotations

import time

import numpy as np
import pyvista as pv

from s2h_viewer import samples
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.skinning import skin_vertices
from s2h_viewer.render.scene import display_hand, to_view
from s2h_viewer.retarget.comparison import build_comparison

DISPLAY_FACES = 10_000  # as widgets.compare_view.DISPLAY_FACES (not imported: that module needs Qt)
FRAMES = 60


def playback(comparison, lighten: bool, size=(1400, 900)) -> tuple[float, float, int]:
    """(skinning s/frame, rendering s/frame, faces per hand) over FRAMES frames."""
    hands = [(comparison.source, comparison.source_pose, None)] + [(r.target, r.pose, r.joint_error)
                                                                    for r in comparison.results]
    shown = [(display_hand(h, DISPLAY_FACES) if lighten else h, pose, err) for h, pose, err in hands]
    plotter = pv.Plotter(off_screen=True, shape=(1, len(shown)), window_size=size, border=False)
    plotter.render_window.SetMultiSamples(0)
    meshes = []
    for i, (hand, pose, err) in enumerate(shown):
        plotter.subplot(0, i)
        faces = np.hstack([np.full((len(hand.mesh.faces), 1), 3), hand.mesh.faces]).astype(np.int64)
        mesh = pv.PolyData(to_view(hand, skin_vertices(hand, pose, 0)), faces)
        mesh["error"] = np.zeros(mesh.n_points)
        plotter.add_mesh(mesh, scalars="error", clim=(0, 0.1), show_scalar_bar=False)
        meshes.append(mesh)
    plotter.show(auto_close=False)
    skin = render = 0.0
    for frame in range(FRAMES):
        t0 = time.perf_counter()
        for mesh, (hand, pose, err) in zip(meshes, shown):
            mesh.points = to_view(hand, skin_vertices(hand, pose, frame))
            if err is not None:
                per_rotating = np.zeros(topo.N_ROTATING)
                per_rotating[1:] = np.nan_to_num(err[frame, topo.ARTICULATED_JOINTS - 1])
                mesh["error"] = hand.mesh.weights @ per_rotating
        t1 = time.perf_counter()
        plotter.render()
        skin, render = skin + t1 - t0, render + time.perf_counter() - t1
    plotter.close()
    return skin / FRAMES, render / FRAMES, min(len(h.mesh.faces) for h, _, _ in shown)


def main() -> None:
    hands = {h.name: h for h in samples.load_sample_hands()}
    motion = next(m for m in samples.load_sample_motions() if m.name == "gestures")
    targets = [hands[n] for n in samples.hand_names("test")]
    comparison = build_comparison(motion, hands[motion.hand_name], targets, ["tbs_copy"])
    print(f"source + {len(targets)} targets, {FRAMES} frames, 1400 x 900, off screen")
    results = {}
    for label, lighten in (("full meshes (baseline)", False), (f"display meshes", True)):
        skin, render, faces = playback(comparison, lighten)
        results[label] = skin + render
        print(f"{label:24s} >= {faces:6d} faces/hand: {1 / (skin + render):5.1f} frames/s "
              f"(skinning {skin * 1000:5.1f} ms + rendering {render * 1000:5.1f} ms per frame)")
    base, light = results.values()
    print(f"display meshes: {base / light:.1f} x the baseline's frame rate (target >= 30 frames/s)")


if __name__ == "__main__":
    main()
