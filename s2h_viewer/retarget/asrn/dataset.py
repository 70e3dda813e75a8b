"""Training data: random gesture scripts (and, for the shipped ASRN, clips through random key poses over
the whole pose space: `motions.pose_space`) performed by each training hand, cut into windows of
``TrainConfig.window`` frames.

Pairs are drawn per batch: one target hand B; with probability ``p_same`` every window comes from B
itself (the supervised case, A = B), otherwise from the other training hands. Each clip keeps its
source's contact gaps (in hand lengths), from which the contact loss knows which pairs touch.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.procedural import generate_hand
from s2h_viewer.motions.gestures import GESTURES
from s2h_viewer.motions.pose_space import random_pose_motion
from s2h_viewer.motions.synthesis import fit_library, synthesize
from s2h_viewer.retarget.asrn.features import source_features, target_static
from s2h_viewer.semantics.contacts import contact_gaps


@dataclass
class Clip:
    hand: int  # index into TrainingSet.hands
    q: torch.Tensor  # (T, 15, 4)
    features: torch.Tensor  # (T, F)
    gaps: torch.Tensor  # (T, 15) contact gaps on the source hand, in its hand lengths


@dataclass
class TrainingSet:
    kind: str
    hands: list[HandModel]
    statics: list[tuple[torch.Tensor, torch.Tensor]]
    clips: list[Clip]

    @property
    def n_frames(self) -> int:
        return sum(len(c.q) for c in self.clips)


@dataclass
class Batch:
    target: int  # hand index of B
    same: bool  # A == B for every window
    features: torch.Tensor  # (N, W, F)
    q_source: torch.Tensor  # (N, W, 15, 4)
    source_gaps: torch.Tensor  # (N, W, 15) contact gaps on each window's source hand, in its hand lengths


EXTRA_HAND_FIRST_SEED = 10_000  # far from the shipped hands' seeds (100..), so no test hand is regenerated


def extra_training_hands(count: int, seed: int = 0) -> list[HandModel]:
    """``count`` unnamed procedural hands (no mesh), realistic and stylised in turn, to widen the
    variety of shapes the network sees beyond the 8 shipped training hands."""
    first = EXTRA_HAND_FIRST_SEED + 1000 * seed
    return [generate_hand(first + i, with_mesh=False, style=("realistic", "stylised")[i % 2]) for i in range(count)]


def build_training_set(kind: str, hands: list[HandModel], scripts_per_hand: int = 6, gestures_per_script: int = 10,
                       seed: int = 0, progress: Callable[[str], None] | None = None,
                       pose_scripts_per_hand: int = 0) -> TrainingSet:
    """Each hand performs ``scripts_per_hand`` random gesture scripts and ``pose_scripts_per_hand`` clips
    through random key poses, ``gestures_per_script`` keys each (contacts fitted to that hand). The random
    poses draw from their own seeded stream, so the gesture clips are the same with or without them."""
    rng = np.random.default_rng(seed)
    pose_rng = np.random.default_rng([seed, 1])
    names = list(GESTURES)
    clips = []

    def add(h: int, hand: HandModel, motion) -> None:
        q = torch.as_tensor(motion.q_tbs)
        with torch.no_grad():
            gaps = contact_gaps(hand, forward_kinematics(hand, q), thumb_tips=False) / hand.hand_length  # pads
        clips.append(Clip(h, q, source_features(kind, hand, motion.q_tbs), gaps.float()))

    for h, hand in enumerate(hands):
        if progress:
            progress(f"fitting the gesture library to {hand.name}")
        fitted = fit_library(hand)
        for s in range(scripts_per_hand):
            script = list(rng.choice(names, gestures_per_script, replace=False))
            add(h, hand, synthesize(script, hand, seed=int(rng.integers(1 << 31)), fitted=fitted))
        for s in range(pose_scripts_per_hand):
            add(h, hand, random_pose_motion(hand, gestures_per_script, seed=int(pose_rng.integers(1 << 31))))
    return TrainingSet(kind, hands, [target_static(h) for h in hands], clips)


def sample_batch(data: TrainingSet, rng: np.random.Generator, size: int, window: int, p_same: float) -> Batch:
    """``size`` random windows for one random target hand."""
    target = int(rng.integers(len(data.hands)))
    same = bool(rng.random() < p_same)
    pool = [c for c in data.clips if (c.hand == target) == same]
    feats, qs, gaps = [], [], []
    for _ in range(size):
        clip = pool[int(rng.integers(len(pool)))]
        start = int(rng.integers(len(clip.q) - window + 1))
        feats.append(clip.features[start:start + window])
        qs.append(clip.q[start:start + window])
        gaps.append(clip.gaps[start:start + window])
    return Batch(target, same, torch.stack(feats), torch.stack(qs), torch.stack(gaps))
