"""`s2h evaluate`: retarget sample motions onto held-out hands with each method and score the results.

Families: a target of the same style as the source (realistic or stylised proportions) is
"same-family", as the paper's Mixamo-to-Mixamo pairs; a realistic-to-stylised one is "cross-family".

Ground truth for MSE: each sample motion records the gesture script and seed it was synthesised
from, so the same performance can be re-synthesised on the target hand with its contacts fitted
(`motions.synthesis.resynthesize`): what a semantically perfect retarget would produce.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.motions.synthesis import resynthesize
from s2h_viewer.retarget.methods import METHODS, retarget
from s2h_viewer.retarget.progress import report, stage
from s2h_viewer.semantics.metrics import RetargetScores, score_retarget
from s2h_viewer.semantics.signature import pose_differences

METRICS = ("mse", "s_palm", "s_finger", "s_finger_paper", "contact_precision", "contact_recall",
           "palm_contact_recall", "violation_rate", "source_violation_rate", "added_violation_rate",
           "jitter", "sideways_deg", "source_sideways_deg", "thumb_follow")
#: the table's columns, as the paper's Table 1: (header, family the rows are averaged over, metric);
#: "S_finger (paper)" is the official code's figure (zero diagonal counted), comparable with the paper's
COLUMNS = (("Same MSE", "same", "mse"), ("Same S_palm", "same", "s_palm"), ("Same S_finger", "same", "s_finger"),
           ("Same S_finger (paper)", "same", "s_finger_paper"),
           ("Cross MSE", "cross", "mse"), ("Cross S_palm", "cross", "s_palm"), ("Cross S_finger", "cross", "s_finger"),
           ("Cross S_finger (paper)", "cross", "s_finger_paper"),
           ("Contact P", "all", "contact_precision"), ("Contact R", "all", "contact_recall"),
           ("Palm R", "all", "palm_contact_recall"),
           ("Violations", "all", "violation_rate"), ("Violations added", "all", "added_violation_rate"),
           ("Jitter", "all", "jitter"),
           ("Sideways max (deg)", "all", "sideways_deg"), ("Poses kept", "all", "poses_kept"),
           ("Thumb follows (corr)", "all", "thumb_follow"))
#: columns summarised by their largest row, not the mean: the worst finger is what a user sees
WORST_OF = ("sideways_deg",)


@dataclass
class EvaluationRow:
    method: str
    motion: str
    source: str
    target: str
    family: str  # "same" or "cross"
    scores: RetargetScores
    #: per pose the clip holds (labelled frames, `semantics.signature.held_poses`), what the retarget loses
    #: of its signature (an empty list: kept); empty for a clip without labels
    poses: dict[str, list[str]] = field(default_factory=dict)

    @property
    def poses_kept(self) -> float:
        """Share of the clip's held poses whose signature the retarget keeps (NaN: the clip holds none)."""
        return sum(not lost for lost in self.poses.values()) / len(self.poses) if self.poses else float("nan")


def hand_family(hand: HandModel) -> str:
    """The style a hand was generated with ("realistic" for hands from elsewhere)."""
    return hand.meta.get("params", {}).get("style", "realistic")


def evaluate(motions: list[Motion], hands: dict[str, HandModel], targets: list[str], methods: list[str]
             ) -> list[EvaluationRow]:
    """Score every (motion, target hand, method), each an equal stage of the progress (`retarget.progress`);
    a motion's source hand is ``hands[motion.hand_name]``."""
    total = len(motions) * len(targets) * len(methods)
    rows = []
    for motion in motions:
        if motion.hand_name not in hands:
            raise KeyError(f"motion {motion.name!r} is posed on unknown hand {motion.hand_name!r}")
        source = hands[motion.hand_name]
        for target_name in targets:
            target = hands[target_name]
            reference = resynthesize(motion, target)
            family = "same" if hand_family(source) == hand_family(target) else "cross"
            for method in methods:
                with stage(len(rows) / total, (len(rows) + 1) / total, f"{motion.name} -> {target_name} ({method})"):
                    result = retarget(motion, source, target, method)
                    scores = score_retarget(source, motion.q_tbs, target, result.q_tbs,
                                            reference.q_tbs if reference is not None else None)
                    poses = pose_differences(source, motion.q_tbs, target, result.q_tbs, motion.labels)
                report((len(rows) + 1) / total)
                rows.append(EvaluationRow(method, motion.name, source.name, target_name, family, scores, poses))
    return rows


def summarise(rows: list[EvaluationRow]) -> dict[str, dict[str, float]]:
    """Per method, each column of ``COLUMNS``: the mean (the largest for ``WORST_OF``) over the rows of its family that have the score (not
    None, not NaN: a contact score over no contacts is undefined, not 0 or 1), NaN if none has it."""
    out: dict[str, dict[str, float]] = {}
    for method in dict.fromkeys(r.method for r in rows):
        out[method] = {}
        for header, family, metric in COLUMNS:
            values = [_metric(r, metric) for r in rows if r.method == method and family in ("all", r.family)]
            values = [v for v in values if v is not None and not np.isnan(v)]
            aggregate = np.max if metric in WORST_OF else np.mean
            out[method][header] = float(aggregate(values)) if values else float("nan")
    return out


def _metric(row: EvaluationRow, metric: str) -> float | None:
    return row.poses_kept if metric == "poses_kept" else row.scores.as_dict()[metric]


def format_markdown(summary: dict[str, dict[str, float]]) -> str:
    """The summary as a Markdown table, one row per method; "n/a" where no row had the score."""
    lines = ["| Method | " + " | ".join(h for h, _, _ in COLUMNS) + " |", "|---|" + "---:|" * len(COLUMNS)]
    for method, values in summary.items():
        label = METHODS[method].label if method in METHODS else method
        cells = ["n/a" if np.isnan(values[h]) else f"{values[h]:.5f}" if m in ("mse", "jitter") else
                 f"{values[h]:.1f}" if m in WORST_OF else
                 f"{values[h]:.3f}" for h, _, m in COLUMNS]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_results(rows: list[EvaluationRow], summary: dict[str, dict[str, float]], out_dir: str | Path) -> list[Path]:
    """Per-row CSV (an empty cell where a row has no score: no MSE without ground truth, a contact score
    over no contacts) and the Markdown summary, each written atomically."""
    out_dir = Path(out_dir)
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["method", "motion", "source", "target", "family", *METRICS, "sideways_at",
                     "sideways_anywhere_deg", "sideways_anywhere_at", "thumb_follow_at", "poses_kept", "poses_lost"])
    for r in rows:
        s = r.scores.as_dict()
        writer.writerow([r.method, r.motion, r.source, r.target, r.family,
                         *("" if s[m] is None or np.isnan(s[m]) else s[m] for m in METRICS), s["sideways_at"],
                         "" if np.isnan(s["sideways_anywhere_deg"]) else s["sideways_anywhere_deg"],
                         s["sideways_anywhere_at"], s["thumb_follow_at"], "" if np.isnan(r.poses_kept) else r.poses_kept,
                         "; ".join(f"{name}: {', '.join(lost)}" for name, lost in r.poses.items() if lost)])
    written = []
    for name, text in (("evaluation.csv", buffer.getvalue()), ("evaluation.md", format_markdown(summary) + "\n")):
        with atomic_path(out_dir / name) as tmp:
            tmp.write_text(text)
        written.append(out_dir / name)
    return written
