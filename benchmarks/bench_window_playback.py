"""Benchmark: playback in the real window (needs an X display; under Xvfb that is software OpenGL),
against the same scene rendered off screen in the same run, and the cost of adding one method.

    xvfb-run -a -s "-screen 0 1600x1000x24" python benchmarks/bench_window_playback.py [--rounds 7] [--no-asm-opt]

The window: the default samples (source + 2 targets x TBS Copy, ASRN), 1400 x 900. Playback runs
against the clock, so at 1x it can never draw more than the clip's 30 frames/s: the window's drawing
rate is measured at 4x (120 frames/s asked for: it draws as fast as it can and drops the rest),
counting the renders the view really made, beside the CPU time per drawn frame (all threads of this
process; on a shared machine the load moves it less than the wall time). While playing the window
draws each skin with `PLAYING_FACES` faces: the off-screen rate of the same scene (those skins, a
viewport of the window's size) is timed right after each window round, with the window open and idle,
so that both see the same load: rounds are short (SECONDS of playing, one off-screen run of `bench_playback.FRAMES`
frames) because this machine's speed wanders within minutes, and the ratio of each round and their
median are printed. The window poses
the next frame's skins on a worker thread while it draws the current one (the share of frames shown so
is printed); off screen poses each in line, as `s2h render` does. Then the 1x
rate, the off-screen rate with the paused skins (`DISPLAY_FACES`), the grid built again (its skins' lighter
meshes kept, against decimating them again, in the same run), and ASM-Opt ticked in the Methods
menu, timed until the grid shows it (only ASM-Opt's two retargets are computed: the rest is cached).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from bench_playback import playback  # this folder is on sys.path when the script runs
from s2h_viewer.app.scripted import scripted_window, wait_for
from s2h_viewer.render import scene
from s2h_viewer.render.compare_scene import DISPLAY_FACES, PLAYING_FACES
from s2h_viewer.widgets.timeline import SPEEDS

SECONDS = 3.0


def load() -> str:
    return "load {:.1f} {:.1f} {:.1f}".format(*os.getloadavg())


def drawn_rate(window, speed: float) -> tuple[float, float, float, float]:
    """(frames drawn per second, clip frames advanced per second, CPU seconds per drawn frame, share of the
    frames shown whose skins were posed ahead on the worker thread) while playing at ``speed``."""
    drawn: list[float] = []
    ahead, here = window.view.prefetched, window.view.posed_here

    def count() -> None:
        drawn.append(time.perf_counter())

    window.view.drawn.connect(count)
    window.timeline.speed.setCurrentIndex(SPEEDS.index(speed))
    window.timeline.set_frame(0)
    t0, cpu = time.perf_counter(), time.process_time()
    window.timeline.set_playing(True)
    wait_for(seconds=SECONDS)
    window.timeline.set_playing(False)
    elapsed, cpu = time.perf_counter() - t0, time.process_time() - cpu
    advanced = window.timeline.frame  # no loop wrap in SECONDS at 1x; at 4x only the draw rate is used
    window.view.drawn.disconnect(count)
    ahead, here = window.view.prefetched - ahead, window.view.posed_here - here
    return len(drawn) / elapsed, advanced / elapsed, cpu / max(1, len(drawn)), ahead / max(1, ahead + here)


def off_screen(comparison, faces: int, viewport: tuple[int, int],
               repeats: int = 1) -> tuple[float, float, float, float]:
    """(frames/s, skinning s/frame, rendering s/frame, CPU s/frame) off screen, median of ``repeats`` of
    `bench_playback`'s runs."""
    skin, render, _, cpu = playback(comparison, faces, size=viewport, repeats=repeats)
    return 1 / (skin + render), skin, render, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7, help="window / off-screen pairs timed (default 7)")
    parser.add_argument("--no-asm-opt", action="store_true", help="skip timing ASM-Opt's addition")
    args = parser.parse_args()
    with scripted_window() as window:
        wait_for(seconds=1.0)
        viewport = (window.view.interactor.width(), window.view.interactor.height())
        comparison = window.comparison
        print(f"{len(comparison.results)} retargets + source, viewport {viewport[0]} x {viewport[1]}, widget "
              f"{type(window.view.interactor).__module__}.{type(window.view.interactor).__name__}; skins of "
              f"{PLAYING_FACES} faces while playing, in the window (drawing flat out, 4x) and off screen")
        ratios, cpu_ratios = [], []
        for round_ in range(1, args.rounds + 1):
            before = load()
            fast, _, fast_cpu, ahead = drawn_rate(window, 4.0)
            off, skin, render, off_cpu = off_screen(comparison, PLAYING_FACES, viewport)
            ratios.append(fast / off)
            cpu_ratios.append(off_cpu / fast_cpu)
            print(f"round {round_}: window {fast:5.1f} frames/s (CPU {fast_cpu * 1000:4.1f} ms/frame, {ahead:.0%} of "
                  f"frames posed ahead), off screen "
                  f"{off:5.1f} frames/s (skinning {skin * 1000:4.1f} + rendering {render * 1000:4.1f} ms; CPU "
                  f"{off_cpu * 1000:4.1f} ms/frame): window / off screen {ratios[-1]:.2f} x, CPU per frame off "
                  f"screen / window {cpu_ratios[-1]:.2f} [{before} -> {load()}]", flush=True)
        print(f"window / off screen, median of {args.rounds} rounds: {statistics.median(ratios):.2f} x frames/s, "
              f"{statistics.median(cpu_ratios):.2f} x CPU per frame (target >= 0.8 x and >= 30 frames/s)")
        real, advanced, _, _ = drawn_rate(window, 1.0)
        print(f"in the window at 1x: {real:5.1f} frames/s drawn, the clip advanced {advanced:5.1f} frames/s "
              f"(real time: {comparison.motion.fps:g})")
        paused, _, _, paused_cpu = off_screen(comparison, DISPLAY_FACES, viewport, repeats=3)
        print(f"off screen, the paused skins ({DISPLAY_FACES} faces): {paused:5.1f} frames/s "
              f"(CPU {paused_cpu * 1000:4.1f} ms/frame) [{load()}]")
        rebuilds = []
        for decimated in (False, True):  # the grid built again (a method ticked, a clip opened): skins decimated
            if not decimated:  # afresh, as before their lighter meshes were kept, then kept
                scene._LIGHTER.clear()
            t0 = time.perf_counter()
            window.view.set_comparison(comparison)
            rebuilds.append(time.perf_counter() - t0)
        print(f"grid built again: {rebuilds[1]:.2f} s with the skins' lighter meshes kept, {rebuilds[0]:.2f} s "
              f"decimating them again: {rebuilds[0] / rebuilds[1]:.2f} x [{load()}]")
        if args.no_asm_opt:
            return
        computed = len(window.compare.queue.computed)
        t0 = time.perf_counter()
        window.method_actions["asm_opt"].trigger()
        wait_for(window.comparison_ready, seconds=900)
        add_asm_opt = time.perf_counter() - t0
        added = [f"{k.method}" for k in window.compare.queue.computed[computed:]]
        print(f"adding ASM-Opt to the default scene: {add_asm_opt:5.1f} s, computed only: {', '.join(added)}")


if __name__ == "__main__":
    main()
