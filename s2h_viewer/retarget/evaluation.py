"""`s2h evaluate`: retarget sample motions onto held-out hands with each method and score the results.

Ground truth for MSE: each sample motion records the gesture script and seed it was synthesised
from, so the same performance can be re-synthesised on the target hand with its contacts fitted
(`motions.synthesis.resynthesize`): what a semantically perfect retarget would produce.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.motions.synthesis import resynthesize
from s2h_viewer.retarget.methods import METHODS, retarget
from s2h_viewer.semantics.metrics import RetargetScores, score_retarget

METRICS = ("mse", "s_palm", "s_finger", "contact_precision", "contact_recall", "violation_rate", "jitter")
HEADERS = {"mse": "MSE", "s_palm": "S_palm", "s_finger": "S_finger", "contact_precision": "Contact P",
           "contact_recall": "Contact R", "violation_rate": "Violations", "jitter": "Jitter"}


@dataclass
class EvaluationRow:
    method: str
    motion: str
    source: str
    target: str
    scores: RetargetScores


def evaluate(motions: list[Motion], hands: dict[str, HandModel], targets: list[str], methods: list[str],
             progress: Callable[[str], None] | None = None) -> list[EvaluationRow]:
    """Score every (motion, target hand, method); a motion's source hand is ``hands[motion.hand_name]``."""
    rows = []
    for motion in motions:
        if motion.hand_name not in hands:
            raise KeyError(f"motion {motion.name!r} is posed on unknown hand {motion.hand_name!r}")
        source = hands[motion.hand_name]
        for target_name in targets:
            target = hands[target_name]
            reference = resynthesize(motion, target)
            for method in methods:
                if progress:
                    progress(f"{motion.name} -> {target_name} ({method})")
                result = retarget(motion, source, target, method)
                scores = score_retarget(source, motion.q_tbs, target, result.q_tbs,
                                        reference.q_tbs if reference is not None else None)
                rows.append(EvaluationRow(method, motion.name, source.name, target_name, scores))
    return rows


def summarise(rows: list[EvaluationRow]) -> dict[str, dict[str, float]]:
    """Per method, the mean of each metric over all rows (MSE over rows that have a reference)."""
    out: dict[str, dict[str, float]] = {}
    for method in dict.fromkeys(r.method for r in rows):
        mine = [r.scores.as_dict() for r in rows if r.method == method]
        out[method] = {m: float(np.mean([s[m] for s in mine if s[m] is not None]))
                       if any(s[m] is not None for s in mine) else float("nan") for m in METRICS}
    return out


def format_markdown(summary: dict[str, dict[str, float]]) -> str:
    """The summary as a Markdown table, one row per method."""
    lines = ["| Method | " + " | ".join(HEADERS[m] for m in METRICS) + " |",
             "|---|" + "---:|" * len(METRICS)]
    for method, values in summary.items():
        label = METHODS[method].label if method in METHODS else method
        cells = [f"{values[m]:.5f}" if m in ("mse", "jitter") else f"{values[m]:.3f}" for m in METRICS]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_results(rows: list[EvaluationRow], summary: dict[str, dict[str, float]], out_dir: str | Path) -> list[Path]:
    """Per-row CSV and the Markdown summary, each written atomically."""
    out_dir = Path(out_dir)
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["method", "motion", "source", "target", *METRICS])
    for r in rows:
        s = r.scores.as_dict()
        writer.writerow([r.method, r.motion, r.source, r.target, *("" if s[m] is None else s[m] for m in METRICS)])
    written = []
    for name, text in (("evaluation.csv", buffer.getvalue()), ("evaluation.md", format_markdown(summary) + "\n")):
        with atomic_path(out_dir / name) as tmp:
            tmp.write_text(text)
        written.append(out_dir / name)
    return written
