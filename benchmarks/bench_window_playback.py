"""Benchmark: playback in the real window (needs an X display; under Xvfb that is software OpenGL
plus Qt composing the window), against the same scene rendered off screen in the same run.

    xvfb-run -a -s "-screen 0 1600x1000x24" python benchmarks/bench_window_playback.py

The window: the default samples (source + 2 targets x TBS Copy, ASRN), 1400 x 900, played for
8 s; frames/s counts the frames the timeline advanced (it never skips frames).
"""

from __future__ import annotations

import time

from bench_playback import playback  # this folder is on sys.path when the script runs
from s2h_viewer.app.scripted import scripted_window, wait_for
from s2h_viewer.render.compare_scene import DISPLAY_FACES

SECONDS = 8.0


def main() -> None:
    with scripted_window() as window:
        wait_for(seconds=1.0)
        viewport = (window.view.interactor.width(), window.view.interactor.height())
        start, t0 = window.timeline.frame, time.perf_counter()
        window.timeline.set_playing(True)
        wait_for(seconds=SECONDS)
        window.timeline.set_playing(False)
        in_window = (window.timeline.frame - start) / (time.perf_counter() - t0)
        comparison = window.comparison
    skin, render, _ = playback(comparison, DISPLAY_FACES, size=viewport)
    off_screen = 1 / (skin + render)
    print(f"{len(comparison.results)} retargets + source, viewport {viewport[0]} x {viewport[1]}")
    print(f"off screen (baseline): {off_screen:5.1f} frames/s (skinning {skin * 1000:4.1f} ms + rendering "
          f"{render * 1000:4.1f} ms)")
    print(f"in the window:         {in_window:5.1f} frames/s ({in_window / off_screen:.2f} x off screen; the rest "
          f"of {1000 / in_window:.0f} ms a frame is Qt composing the window and the X server copy)")


if __name__ == "__main__":
    main()
