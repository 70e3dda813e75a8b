"""`s2h annotate` output: per hand and finger, the solver's angle error against ground truth (procedural
hands know their true frames) or, for real hands, its confidence and what to review."""

from __future__ import annotations

import numpy as np

from s2h_viewer.annotate.solver import TbsSolution, frame_angle_errors
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel

WITHIN_DEGREES = 10.0


def has_true_frames(hand: HandModel) -> bool:
    """Procedural hands carry the frames they were generated with; loaded rigs carry solved ones."""
    return hand.source.startswith("procedural") and "annotation" not in hand.meta


def annotation_report(results: list[tuple[HandModel, TbsSolution, float]], against_truth: bool) -> str:
    """A Markdown table, one row per hand, and the solver's diagnostics under it."""
    truth = against_truth and all(has_true_frames(h) for h, _, _ in results)
    if truth:
        header = ("| Hand | Faces | " + " | ".join(f"{f.capitalize()} mean/max" for f in topo.FINGERS)
                  + f" | Within {WITHIN_DEGREES:.0f} deg | Time (s) |")
    else:
        header = "| Hand | Faces | " + " | ".join(f"{f.capitalize()} confidence" for f in topo.FINGERS) + \
                 " | To review | Time (s) |"
    lines = [header, "|---|---:|" + "---:|" * (len(topo.FINGERS) + 2)]
    all_errors, notes = [], []
    for hand, solution, seconds in results:
        faces = len(hand.mesh.faces) if hand.mesh is not None else 0
        if truth:
            errors = frame_angle_errors(solution.frames, hand.rest_frames)
            all_errors.append(errors)
            cells = [f"{e.mean():.1f} / {e.max():.1f}" for e in errors.reshape(topo.N_FINGERS, 3)]
            tail = f"{np.mean(errors <= WITHIN_DEGREES):.0%}"
        else:
            cells = [f"{c.min():.2f}" for c in solution.confidence.reshape(topo.N_FINGERS, 3)]
            review = [topo.ARTICULATED_NAMES[j] for j in np.flatnonzero(solution.needs_review)]
            tail = ", ".join(review) or "none"
        lines.append(f"| {hand.name} | {faces} | " + " | ".join(cells) + f" | {tail} | {seconds:.2f} |")
        notes.extend(f"{hand.name}: {d}" for d in solution.diagnostics)
    if truth:
        errors = np.concatenate(all_errors)
        lines.append(f"\nAll {len(errors)} joints: mean {errors.mean():.1f} deg, max {errors.max():.1f} deg, "
                     f"{np.mean(errors <= WITHIN_DEGREES):.1%} within {WITHIN_DEGREES:.0f} deg")
    elif against_truth:
        lines.append("\n(no ground truth: only procedural hands know their true frames; showing confidence)")
    if notes:
        lines.append("\n" + "\n".join(notes))
    return "\n".join(lines)
