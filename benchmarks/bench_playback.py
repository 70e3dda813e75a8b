"""Benchmark: compare-mode playback off screen, source + 4 target hands, frames/s and one frame's
cost split into skinning and rendering. Baselines in the same run: full meshes (25k+ faces) for the
display meshes (10k faces) the viewer draws, and pyvista's default lighting and face drawing for
the viewer's one light and back-face culling.

    python benchmarks/bench_playback.py      # or: make bench

Uses the same scene code as the app's viewport (`render.compare_scene`) in an off-screen plotter.
"""

from __future__ import annotations

import time

import pyvista as pv

from s2h_viewer import samples
from s2h_viewer.render.compare_scene import DISPLAY_FACES, grid_layout, populate
from s2h_viewer.retarget.comparison import build_comparison

FRAMES = 120
REPEATS = 3  # this machine's timings wander by +-20%; each figure is the median run


def playback(comparison, display_faces: int | None, size=(1400, 900),
             plain: bool = False, repeats: int = REPEATS) -> tuple[float, float, int, float]:
    """(skinning s/frame, rendering s/frame, fewest faces of a drawn hand, CPU s/frame of this process, all
    threads: the load on a shared machine changes it less than the wall time) of the median of ``repeats`` runs."""
    runs = sorted((playback_once(comparison, display_faces, size, plain) for _ in range(repeats)),
                  key=lambda r: sum(r[:2]))
    return runs[len(runs) // 2]


def playback_once(comparison, display_faces: int | None, size, plain: bool) -> tuple[float, float, int, float]:
    """(skinning s/frame, rendering s/frame, fewest faces of a drawn hand, CPU s/frame) over FRAMES frames;
    ``plain``: pyvista's defaults instead of the viewer's choices (five-light kit, back faces drawn)."""
    plotter = pv.Plotter(off_screen=True, window_size=size, **grid_layout(comparison))
    plotter.render_window.SetMultiSamples(0)
    hands, _ = populate(plotter, comparison, display_faces=display_faces)
    if plain:
        plotter.enable_lightkit()  # replaces each subplot's lights
        for hand in hands:
            hand.mesh_actor.prop.culling = "none"
    plotter.show(auto_close=False)
    skin = render = 0.0
    cpu = time.process_time()
    for frame in range(FRAMES):
        t0 = time.perf_counter()
        for hand in hands:
            hand.show(frame)
        t1 = time.perf_counter()
        plotter.render()
        skin, render = skin + t1 - t0, render + time.perf_counter() - t1
    cpu = time.process_time() - cpu
    plotter.close()
    return skin / FRAMES, render / FRAMES, min(len(h.hand.mesh.faces) for h in hands), cpu / FRAMES


def main() -> None:
    hands = {h.name: h for h in samples.load_sample_hands()}
    motion = next(m for m in samples.load_sample_motions() if m.name == "gestures")
    targets = [hands[n] for n in samples.hand_names("test")]
    comparison = build_comparison(motion, hands[motion.hand_name], targets, ["tbs_copy"])
    print(f"source + {len(targets)} targets (TBS Copy), {FRAMES} frames, 1400 x 900, off screen, no MSAA, "
          f"median of {REPEATS} runs")
    rates = []
    for label, faces in (("full meshes (baseline)", None), ("display meshes", DISPLAY_FACES)):
        skin, render, fewest, _ = playback(comparison, faces)
        rates.append(1 / (skin + render))
        print(f"{label:24s} >= {fewest:6d} faces/hand: {rates[-1]:5.1f} frames/s "
              f"(skinning {skin * 1000:5.1f} ms + rendering {render * 1000:5.1f} ms per frame)")
    print(f"display meshes: {rates[1] / rates[0]:.1f} x the baseline's frame rate (target >= 30 frames/s)")
    skin, render, _, _ = playback(comparison, DISPLAY_FACES, plain=True)
    print(f"display meshes, pyvista's five-light kit and back faces drawn: {1 / (skin + render):5.1f} frames/s "
          f"(rendering {render * 1000:5.1f} ms; the viewer's one light + culling: {rates[1] * (skin + render):.1f} x)")
    skin, render, _, _ = playback(comparison, DISPLAY_FACES, size=(1024, 640))
    print(f"display meshes at 1024 x 640: {1 / (skin + render):5.1f} frames/s ({1 / (skin + render) / rates[1]:.1f} x the "
          f"1400 x 900 rate)")


if __name__ == "__main__":
    main()
