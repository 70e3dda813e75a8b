"""Benchmark: playback in the real window (needs an X display; under Xvfb that is software OpenGL),
against the same scene rendered off screen in the same run, and the cost of adding one method.

    xvfb-run -a -s "-screen 0 1600x1000x24" python benchmarks/bench_window_playback.py

The window: the default samples (source + 2 targets x TBS Copy, ASRN), 1400 x 900. Playback runs
against the clock, so at 1x it can never draw more than the clip's 30 frames/s: the window's drawing
rate is measured at 4x (120 frames/s asked for: it draws as fast as it can and drops the rest),
counting the renders the view really made, beside the CPU time per drawn frame (all threads of this
process; on a shared machine the load moves it less than the wall time). While playing the window
draws each skin with `PLAYING_FACES` faces and paused with `DISPLAY_FACES`: the off-screen baseline is
timed with both, in a viewport of the window's size. Then ASM-Opt is ticked in the Methods menu and timed
until the grid shows it (only ASM-Opt's two retargets are computed: the rest is cached).
"""

from __future__ import annotations

import os
import time

from bench_playback import playback  # this folder is on sys.path when the script runs
from s2h_viewer.app.scripted import scripted_window, wait_for
from s2h_viewer.render.compare_scene import DISPLAY_FACES, PLAYING_FACES
from s2h_viewer.widgets.timeline import SPEEDS

SECONDS = 6.0


def load() -> str:
    return "load {:.1f} {:.1f} {:.1f}".format(*os.getloadavg())


def drawn_rate(window, speed: float) -> tuple[float, float, float]:
    """(frames drawn per second, clip frames advanced per second, CPU seconds per drawn frame) while
    playing at ``speed``."""
    drawn: list[float] = []

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
    advanced = window.timeline.frame  # no loop wrap in 6 s at 1x; at 4x only the draw rate is used
    window.view.drawn.disconnect(count)
    return len(drawn) / elapsed, advanced / elapsed, cpu / max(1, len(drawn))


def main() -> None:
    with scripted_window() as window:
        wait_for(seconds=1.0)
        viewport = (window.view.interactor.width(), window.view.interactor.height())
        widget = type(window.view.interactor).__module__
        window_load = load()
        fast, _, fast_cpu = drawn_rate(window, 4.0)
        real, advanced, _ = drawn_rate(window, 1.0)
        comparison = window.comparison
        computed = len(window.compare.queue.computed)
        t0 = time.perf_counter()
        window.method_actions["asm_opt"].trigger()
        wait_for(window.comparison_ready, seconds=900)
        add_asm_opt = time.perf_counter() - t0
        added = [f"{k.method}" for k in window.compare.queue.computed[computed:]]
    off_load = load()
    off = {faces: playback(comparison, faces, size=viewport) for faces in (PLAYING_FACES, DISPLAY_FACES)}
    rate = {faces: 1 / (skin + render) for faces, (skin, render, _, _) in off.items()}
    print(f"{len(comparison.results)} retargets + source, viewport {viewport[0]} x {viewport[1]}, widget {widget}")
    for faces, (skin, render, fewest, cpu) in off.items():
        print(f"off screen, skins of {faces} faces: {rate[faces]:5.1f} frames/s (skinning {skin * 1000:4.1f} ms + "
              f"rendering {render * 1000:4.1f} ms; CPU {cpu * 1000:4.1f} ms/frame) [{off_load}]")
    print(f"in the window, drawing flat out (4x), skins of {PLAYING_FACES} faces while playing: {fast:5.1f} frames/s "
          f"drawn, CPU {fast_cpu * 1000:4.1f} ms/frame [{window_load}]")
    print(f"  window / off screen, the same skins ({PLAYING_FACES} faces): {fast / rate[PLAYING_FACES]:.2f} x; "
          f"against the paused skins ({DISPLAY_FACES} faces): {fast / rate[DISPLAY_FACES]:.2f} x; "
          f"off-screen CPU / window CPU per frame: {off[PLAYING_FACES][3] / fast_cpu:.2f}")
    print(f"in the window at 1x: {real:5.1f} frames/s drawn, the clip advanced {advanced:5.1f} frames/s "
          f"(real time: {comparison.motion.fps:g})")
    print(f"adding ASM-Opt to the default scene: {add_asm_opt:5.1f} s, computed only: {', '.join(added)}")


if __name__ == "__main__":
    main()
