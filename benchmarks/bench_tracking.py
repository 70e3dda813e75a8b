"""Benchmark: fitting a hand and its motion to a 10,000-frame tracking recording (goal, issue 24: >= 1,000
frames/s on this 2-core machine), and its stages, in this run:

    python benchmarks/bench_tracking.py      # or: make bench

The recording is the shipped motions on a procedural hand, repeated to 10,000 frames, with 3 mm noise, 2%
of frames lost and 0.5% spikes, written as MediaPipe landmarks and as WebXR joint poses. Reported as
frames/s, and as a ratio against a baseline timed in the same run: one forward-kinematics pass of the
fitted hand over the same frames (what any method costs per frame at least).
"""

from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch

from timing import median_seconds  # benchmarks/timing.py, beside this script

from s2h_viewer import samples
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.mediapipe_hand import save_mediapipe_hand
from s2h_viewer.io.recordings import read_recording
from s2h_viewer.io.webxr_hand import save_webxr_hand
from s2h_viewer.tracking.fitter import fit_recording
from s2h_viewer.tracking.synthetic import synthetic_recording

FRAMES = 10_000


def long_motion() -> Motion:
    clips = samples.load_sample_motions()
    q = np.concatenate([c.q_tbs for c in clips])
    q = np.concatenate([q] * (FRAMES // len(q) + 1))[:FRAMES]
    return Motion(q_tbs=q, fps=30.0, name="long", hand_name="iris")


def main() -> None:
    torch.set_num_threads(2)
    hand = samples.load_sample_hand("iris")
    recording = synthetic_recording(hand, long_motion(), noise_mm=3.0, lost=0.02, spikes=0.005, seed=0)
    with tempfile.TemporaryDirectory() as tmp:
        mediapipe = save_mediapipe_hand(Path(tmp) / "long_mediapipe.json", recording, "Left")
        webxr = save_webxr_hand(Path(tmp) / "long_webxr.json", recording)
        read_mp = median_seconds(lambda: read_recording(mediapipe), 3)
        read_wx = median_seconds(lambda: read_recording(webxr), 3)
        loaded_mp, loaded_wx = read_recording(mediapipe), read_recording(webxr)
    fit = fit_recording(loaded_mp, mesh=False)
    fk = median_seconds(lambda: forward_kinematics(fit.hand, fit.motion.q_tbs), 5)
    fit_mp = median_seconds(lambda: fit_recording(replace(loaded_mp, notes=[]), mesh=False), 3)
    fit_wx = median_seconds(lambda: fit_recording(replace(loaded_wx, notes=[]), mesh=False), 3)
    fit_mesh = median_seconds(lambda: fit_recording(replace(loaded_mp, notes=[]), mesh=True), 1)
    print(f"tracking fit, {FRAMES} frames (3 mm noise, {int(fit.lost.sum())} lost, {int(fit.filled.sum())} filled; "
          f"residual {np.nanmean(fit.residual_mm):.2f} mm mean)")
    print(f"  baseline: FK of the fitted hand     {FRAMES / fk:10.0f} frames/s")
    for label, seconds in (("read MediaPipe JSON", read_mp), ("read WebXR JSON", read_wx),
                           ("fit (MediaPipe landmarks)", fit_mp), ("fit (WebXR joint poses)", fit_wx),
                           ("fit + skin the fitted hand", fit_mesh), ("read + fit (MediaPipe)", read_mp + fit_mp)):
        print(f"  {label:34s} {FRAMES / seconds:10.0f} frames/s   {seconds / fk:7.1f} x the baseline's time")
    print(f"  goal >= 1000 frames/s for the fit: {'met' if FRAMES / fit_mp >= 1000 else 'NOT met'}")


if __name__ == "__main__":
    main()
