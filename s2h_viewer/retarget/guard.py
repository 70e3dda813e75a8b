"""The guard (part of ASRN, issue 26): a learned retarget may not lose, frame by frame, what a simpler
retarget of the same clip keeps. Where the candidate loses a part of the source's signature (a finger
extended or curled, a thumb-tip touch, a thumb out to its side, no finger bent sideways: `semantics.signature`)
or makes a pad contact the source does not, and the fallback does not lose it, the result is blended into the
fallback there, fading over `REACH` frames either side so no frame pops.

Why a guard and not only more training: a network trained on procedural hands meets real rigs and real
poses it never saw (the Godot poses: fists that put the thumb on the middle fingertip, shaka and horns
with a ring finger bent sideways); TBS Copy keeps most of those poses by construction, so it is a floor
the method can check itself against at run time, frame by frame, with the signature a viewer reads.
"""

from __future__ import annotations

import numpy as np

from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.rotations import slerp
from s2h_viewer.semantics.signature import loss_masks

#: frames either side of a guarded frame over which the blend fades in and out
REACH = 4


def guarded(source_hand: HandModel, source_q: np.ndarray, target_hand: HandModel, candidate_q: np.ndarray,
            fallback_q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T, 15, 4) ``candidate_q`` blended into ``fallback_q`` on the frames where it loses a part of the
    source's signature that the fallback keeps, and loses nothing the fallback loses
    (`semantics.signature.loss_masks`); and the (T,) blend weight (0: the candidate's frame, 1: the
    fallback's). A blended frame that loses anything the candidate's frame kept (a fade between two poses)
    is undone: the guard never adds a loss."""
    candidate = np.asarray(candidate_q, dtype=np.float32)
    fallback = np.asarray(fallback_q, dtype=np.float32)
    cand = loss_masks(source_hand, source_q, target_hand, candidate)
    base = loss_masks(source_hand, source_q, target_hand, fallback)
    worse = ((cand & ~base) != 0) & ((base & ~cand) == 0)
    weight = fade(worse, REACH)
    out = candidate.copy()
    blended = np.flatnonzero(weight > 0)
    if len(blended):
        out[blended] = slerp(candidate[blended], fallback[blended], weight[blended])
        mixed = loss_masks(source_hand, np.asarray(source_q)[blended], target_hand, out[blended])
        undo = blended[(mixed & ~cand[blended]) != 0]
        out[undo], weight[undo] = candidate[undo], 0.0
    return out, weight


def fade(frames: np.ndarray, reach: int) -> np.ndarray:
    """(T,) 1 on the true frames of ``frames``, falling linearly to 0 over ``reach`` frames either side."""
    distance = np.full(len(frames), np.inf)
    hits = np.flatnonzero(frames)
    if len(hits):
        index = np.arange(len(frames))
        nearest = np.searchsorted(hits, index).clip(0, len(hits) - 1)
        before = (nearest - 1).clip(0)
        distance = np.minimum(np.abs(index - hits[nearest]), np.abs(index - hits[before]))
    return np.clip(1.0 - distance / (reach + 1), 0.0, 1.0)
