"""Benchmark: playback in the real window (needs an X display; under Xvfb that is software OpenGL),
against the same scene rendered off screen in the same run, and the cost of adding one method.

    xvfb-run -a -s "-screen 0 1600x1000x24" python benchmarks/bench_window_playback.py

The window: the default samples (source + 2 targets x TBS Copy, ASRN), 1400 x 900. Playback runs
against the clock, so at 1x it can never draw more than the clip's 30 frames/s: the window's drawing
rate is measured at 4x (120 frames/s asked for: it draws as fast as it can and drops the rest),
counting the renders the view really made. Then ASM-Opt is ticked in the Methods menu and timed until
the grid shows it (only ASM-Opt's two retargets are computed: the rest is cached).
"""

from __future__ import annotations

import time

from bench_playback import playback  # this folder is on sys.path when the script runs
from s2h_viewer.app.scripted import scripted_window, wait_for
from s2h_viewer.render.compare_scene import DISPLAY_FACES
from s2h_viewer.widgets.timeline import SPEEDS

SECONDS = 6.0


def drawn_rate(window, speed: float) -> tuple[float, float]:
    """(frames drawn per second, clip frames advanced per second) while playing at ``speed``."""
    drawn: list[float] = []

    def count() -> None:
        drawn.append(time.perf_counter())

    window.view.drawn.connect(count)
    window.timeline.speed.setCurrentIndex(SPEEDS.index(speed))
    window.timeline.set_frame(0)
    t0 = time.perf_counter()
    window.timeline.set_playing(True)
    wait_for(seconds=SECONDS)
    window.timeline.set_playing(False)
    elapsed = time.perf_counter() - t0
    advanced = window.timeline.frame  # no loop wrap in 6 s at 1x; at 4x only the draw rate is used
    window.view.drawn.disconnect(count)
    return len(drawn) / elapsed, advanced / elapsed


def main() -> None:
    with scripted_window() as window:
        wait_for(seconds=1.0)
        viewport = (window.view.interactor.width(), window.view.interactor.height())
        widget = type(window.view.interactor).__module__
        fast, _ = drawn_rate(window, 4.0)
        real, advanced = drawn_rate(window, 1.0)
        comparison = window.comparison
        computed = len(window.compare.queue.computed)
        t0 = time.perf_counter()
        window.method_actions["asm_opt"].trigger()
        wait_for(window.comparison_ready, seconds=900)
        add_asm_opt = time.perf_counter() - t0
        added = [f"{k.method}" for k in window.compare.queue.computed[computed:]]
    skin, render, _ = playback(comparison, DISPLAY_FACES, size=viewport)
    off_screen = 1 / (skin + render)
    print(f"{len(comparison.results)} retargets + source, viewport {viewport[0]} x {viewport[1]}, widget {widget}")
    print(f"off screen (baseline):      {off_screen:5.1f} frames/s (skinning {skin * 1000:4.1f} ms + rendering "
          f"{render * 1000:4.1f} ms)")
    print(f"in the window, drawing flat out (4x): {fast:5.1f} frames/s drawn ({fast / off_screen:.2f} x off screen)")
    print(f"in the window at 1x: {real:5.1f} frames/s drawn, the clip advanced {advanced:5.1f} frames/s "
          f"(real time: {comparison.motion.fps:g})")
    print(f"adding ASM-Opt to the default scene: {add_asm_opt:5.1f} s, computed only: {', '.join(added)}")


if __name__ == "__main__":
    main()
