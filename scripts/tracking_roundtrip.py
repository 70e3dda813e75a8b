"""Round trip of the tracking fit where the truth is known: each shipped motion on each procedural hand
becomes keypoints (`tracking.synthetic`), is fitted, and the fit is compared with the truth. Prints a
markdown table (issue 24's "must show"); `tests/test_tracking.py` asserts the same on a few of them.

Run: .venv/bin/python scripts/tracking_roundtrip.py [--noise MM] [--lost FRACTION] [--spikes FRACTION]
"""

from __future__ import annotations

import argparse

import numpy as np

from s2h_viewer import samples
from s2h_viewer.tracking.accuracy import compare_with_truth
from s2h_viewer.tracking.fitter import fit_recording
from s2h_viewer.tracking.synthetic import synthetic_recording


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--noise", type=float, default=0.0, help="RMS 3D keypoint noise, mm")
    parser.add_argument("--lost", type=float, default=0.0)
    parser.add_argument("--spikes", type=float, default=0.0)
    args = parser.parse_args()
    print(f"noise {args.noise} mm RMS, lost {args.lost:.0%}, spikes {args.spikes:.0%}\n")
    print("| hand | motion | joints mean / max mm | finger TBS mean / max deg | thumb TBS mean deg (CMC MCP IP) "
          "| jitter / truth | residual mm | filled |")
    print("|---|---|---|---|---|---|---|---|")
    rows = []
    for i, hand in enumerate(samples.load_sample_hands()):
        for motion in samples.load_sample_motions():
            recording = synthetic_recording(hand, motion, args.noise, args.lost, args.spikes, seed=i)
            fit = fit_recording(recording, mesh=False)
            c = compare_with_truth(fit, hand, motion, seed=i)
            rows.append(c)
            print(f"| {hand.name} | {motion.name} | {c.position_mm_mean:.2f} / {c.position_mm_max:.2f} | "
                  f"{c.finger_deg_mean:.2f} / {c.finger_deg_max:.2f} | "
                  + " ".join(f"{x:.1f}" for x in c.thumb_deg_mean)
                  + f" | {c.jitter_ratio:.2f} | {np.nanmean(fit.residual_mm):.2f} | {int(fit.filled.sum())} |")
    worst = {k: max(getattr(r, k) for r in rows) for k in ("position_mm_mean", "position_mm_max", "finger_deg_mean",
                                                             "finger_deg_max", "jitter_ratio")}
    print("\nworst over all: " + ", ".join(f"{k} {v:.2f}" for k, v in worst.items()))


if __name__ == "__main__":
    main()
