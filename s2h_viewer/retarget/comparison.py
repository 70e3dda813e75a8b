"""What the compare view shows, computed once per clip: each method's motion on each target, its FK,
and its ASM error against the source (per joint and per cell, every frame) and clip scores.

Pure computation (no Qt): the app runs `build_comparison` off the GUI thread and only draws.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from s2h_viewer.hand.kinematics import HandPose, forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.retarget.corrections import Corrections, corrected_motion
from s2h_viewer.retarget.methods import METHODS, retarget
from s2h_viewer.retarget.progress import report, stage
from s2h_viewer.semantics.asm import semantic_matrix
from s2h_viewer.semantics.metrics import RetargetScores, per_joint_cosine, score_retarget
from s2h_viewer.semantics.signature import pose_differences


@dataclass
class MethodResult:
    """One method's retarget onto one target hand (with a person's corrections on top, if any)."""

    method: str
    target: HandModel
    motion: Motion
    pose: HandPose  # FK of every frame (float32, no grad)
    cell_error: np.ndarray  # (T, 20, 29) 1 - cosine per ASM cell, NaN where masked
    scores: RetargetScores
    corrections: Corrections = field(default_factory=Corrections)  # applied to ``motion`` (and all above)
    #: per pose the clip holds (`semantics.signature.held_poses`) that the retarget loses, what it loses, in words
    #: ("Horns": ["thumb off the middle, ring (...)"]); empty for a clip of no poses or one that keeps them all
    poses_lost: dict[str, list[str]] = field(default_factory=dict)
    poses_held: int = 0  # how many poses the clip holds
    base: "MethodResult | None" = None  # the method's own retarget, before the corrections (None: this is it)

    @property
    def name(self) -> str:
        """'TBS Copy -> iris': how every message names the retarget."""
        return f"{METHODS[self.method].label} -> {self.target.name}"

    @property
    def uncorrected(self) -> "MethodResult":
        return self.base if self.base is not None else self

    @property
    def joint_error(self) -> np.ndarray:
        """(T, 20) 1 - mean cosine over each finger joint's ASM row: the heatmap colour per joint."""
        return np.nanmean(self.cell_error, axis=-1)

    @property
    def frame_error(self) -> np.ndarray:
        """(T,) mean ASM error over every unmasked cell: the error curve under the timeline."""
        return np.nan_to_num(np.nanmean(self.cell_error.reshape(len(self.cell_error), -1), axis=-1))


@dataclass
class Comparison:
    source: HandModel
    motion: Motion
    source_pose: HandPose
    results: list[MethodResult]  # targets x methods, target-major

    @property
    def n_frames(self) -> int:
        return self.motion.n_frames


def distinct_name(hand: HandModel, others: Iterable[HandModel]) -> str:
    """``hand``'s name, or where one of ``others`` (the other targets) has it, that name with what tells the hand
    apart from them: its side ("human-female (left)"), else its file's format ("r (fbx)"), else a number ("iris #2").
    Both hands of a character, or two exports of one avatar, read as one name twice in every cell, row and file
    name."""
    others = list(others)
    taken = {other.name for other in others}
    if hand.name not in taken:
        return hand.name
    alike = [other for other in others if other.name == hand.name]
    side = hand.meta.get("side")
    suffix = _format(hand)
    tellers = [f"{hand.name} ({side})" if side and all(o.meta.get("side") != side for o in alike) else "",
               f"{hand.name} ({suffix})" if suffix and all(_format(o) != suffix for o in alike) else ""]
    tellers += [f"{hand.name} #{k}" for k in range(2, len(others) + 3)]
    return next(name for name in tellers if name and name not in taken)


def _format(hand: HandModel) -> str:
    """The suffix of the file ``hand`` was read from, lower case ("fbx"); "" where none."""
    return Path(hand.source).suffix.lstrip(".").lower() if hand.source else ""


def with_distinct_names(hands: Iterable[HandModel], others: Iterable[HandModel] = ()) -> list[HandModel]:
    """``hands`` in order, each named apart from ``others`` and from those before it (`distinct_name`); hands of
    one name among ``hands`` that are each of another side are all named by it ("human-female (right)", "(left)":
    with the right one's name bare, a fresh-eyes user could not tell which it was). A renamed hand is a copy, the
    one given is left as it is."""
    hands = list(hands)
    sides: dict[str, list[str | None]] = {}
    for hand in hands:
        sides.setdefault(hand.name, []).append(hand.meta.get("side"))
    named = list(others)
    out = []
    for hand in hands:
        alike = sides[hand.name]
        by_side = len(alike) > 1 and None not in alike and len(set(alike)) == len(alike)
        name = f"{hand.name} ({hand.meta['side']})" if by_side else hand.name
        if name in {other.name for other in named}:
            name = distinct_name(hand, named)
        out.append(hand if name == hand.name else dataclasses.replace(hand, name=name))
        named.append(out[-1])
    return out


def source_semantics(motion: Motion, source: HandModel) -> tuple[HandPose, torch.Tensor]:
    """FK and ASM of the clip on its source hand: what every retarget is measured against."""
    with torch.no_grad():
        source_pose = forward_kinematics(source, motion.q_tbs)
        return source_pose, semantic_matrix(source_pose)


def compute_result(motion: Motion, source: HandModel, source_asm: torch.Tensor, target: HandModel,
                   method: str) -> MethodResult:
    """One method's retarget onto one target, measured; reports progress (``retarget.progress``)."""
    with stage(0.0, 0.9):
        moved = retarget(motion, source, target, method)
    report(0.9)
    result = _measured(motion, source, source_asm, target, method, moved)
    report(1.0)
    return result


def _measured(motion: Motion, source: HandModel, source_asm: torch.Tensor, target: HandModel, method: str,
              moved: Motion) -> MethodResult:
    """``moved`` (``motion`` retargeted onto ``target``) with its FK, ASM error and scores against the source."""
    with torch.no_grad():
        pose = forward_kinematics(target, moved.q_tbs)
        cell_error = 1.0 - per_joint_cosine(source_asm, semantic_matrix(pose)).numpy()
    scores = score_retarget(source, motion.q_tbs, target, moved.q_tbs)
    poses = pose_differences(source, motion.q_tbs, target, moved.q_tbs, motion.labels) if motion.labels.any() else {}
    return MethodResult(method, target, moved, pose, cell_error, scores,
                        poses_lost={name: what for name, what in poses.items() if what}, poses_held=len(poses))


def corrected_result(result: MethodResult, corrections: Corrections, motion: Motion, source: HandModel,
                     source_asm: torch.Tensor) -> MethodResult:
    """The method's retarget under ``result`` (before any correction) with ``corrections`` applied, measured
    again against the source (``motion`` on ``source``, its ASM ``source_asm``); no corrections: that retarget."""
    base = result.uncorrected
    if not corrections:
        return base
    measured = _measured(motion, source, source_asm, base.target, base.method, corrected_motion(base.motion, corrections))
    return dataclasses.replace(measured, corrections=corrections, base=base)


def build_comparison(motion: Motion, source: HandModel, targets: list[HandModel], methods: list[str]) -> Comparison:
    """Retarget ``motion`` onto every target with every method, each an equal stage of the progress
    (``retarget.progress``), named "method -> target"."""
    source_pose, source_asm = source_semantics(motion, source)
    jobs = [(target, method) for target in targets for method in methods]
    results = []
    for i, (target, method) in enumerate(jobs):
        with stage(i / len(jobs), (i + 1) / len(jobs), f"{method} -> {target.name}"):
            results.append(compute_result(motion, source, source_asm, target, method))
    report(1.0, "done")
    return Comparison(source, motion, source_pose, results)


def target_ids(comparison: Comparison) -> list[int]:
    """The comparison's targets (ids), in its rows' order."""
    return list(dict.fromkeys(id(r.target) for r in comparison.results))


def target_page(comparison: Comparison, page: int, rows: int) -> tuple[Comparison, int]:
    """The comparison of targets ``page * rows`` to ``page * rows + rows - 1`` (the grid's page ``page`` of
    ``rows`` targets), and the index in ``comparison.results`` of its first result."""
    shown = set(target_ids(comparison)[page * rows:(page + 1) * rows])
    indices = [i for i, r in enumerate(comparison.results) if id(r.target) in shown]
    return (Comparison(comparison.source, comparison.motion, comparison.source_pose,
                       [comparison.results[i] for i in indices]), indices[0] if indices else 0)
