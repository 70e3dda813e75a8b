"""Contacts between fingertip pads and the palm, measured on the skeleton as capsule gaps.

Sites: the five fingertip pads (a point 60% along the last phalanx, with the interpolated finger
radius) and the palm (the rectangle spanned by the wrist and the four finger knuckles in the
canonical palm frame, thickened by the palm half-thickness). A finger meets the palm with the
nearer of its pad and its tip: in a fist the last phalanx stands on the palm tip first, with every
bend inside the anatomical 90 deg. The thumb meets a finger with the nearest points of their
fingertips, pad to tip (`thumb_pair_gaps`): in a tip pinch the pads 60% along stay 6-9% of the hand
apart while the tips touch. A pair is in contact when the gap
between the surfaces is below ``CONTACT_TOLERANCE`` x hand length (1.5%, DESIGN.md section 5).
Everything is torch and differentiable, so gesture fitting can pull pads together.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import HandPose
from s2h_viewer.hand.model import HandModel

CONTACT_TOLERANCE = 0.015
PAD_FRACTION = 0.6
SITES: tuple[str, ...] = topo.FINGERS + ("palm",)
#: all tip-tip pairs then each tip with the palm: 15 pairs of site names.
CONTACT_PAIRS: tuple[tuple[str, str], ...] = tuple(combinations(topo.FINGERS, 2)) + tuple((f, "palm") for f in topo.FINGERS)
#: the fingertip pad pairs (DESIGN.md section 5's contacts) and the fingertip-palm pairs (our extension)
PAD_PAIRS = slice(0, len(CONTACT_PAIRS) - len(topo.FINGERS))
PALM_PAIRS = slice(len(CONTACT_PAIRS) - len(topo.FINGERS), len(CONTACT_PAIRS))


def pair_index(a: str, b: str) -> int:
    """Index into ``CONTACT_PAIRS`` of an unordered pair of site names."""
    for i, pair in enumerate(CONTACT_PAIRS):
        if {a, b} == set(pair):
            return i
    raise KeyError(f"no contact pair {a!r}-{b!r}; sites are {', '.join(SITES)}")


def pad_centres(positions: torch.Tensor) -> torch.Tensor:
    """(T, 21, 3) -> (T, 5, 3) fingertip pad centres on the bone axis."""
    last = positions[:, topo.TIP_JOINTS - 1]
    tip = positions[:, topo.TIP_JOINTS]
    return last + PAD_FRACTION * (tip - last)


def _palm_box(hand: HandModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Palm frame (3, 3) and the rectangle's lower/upper corners in palm coordinates."""
    frame = hand.palm_frame
    knuckles = hand.rest_positions[topo.KNUCKLE_JOINTS[1:]] @ frame  # index..pinky, palm coords
    lower = np.array([0.15 * knuckles[:, 0].mean(), knuckles[:, 1].min(), 0.0])
    upper = np.array([knuckles[:, 0].mean(), knuckles[:, 1].max(), 0.0])
    return frame, lower, upper


def _pad_radii(hand: HandModel, dtype: torch.dtype) -> tuple[torch.Tensor, torch.Tensor]:
    """(21,) joint radii and (5,) fingertip pad radii of ``hand``."""
    radii = torch.as_tensor(hand.radii, dtype=dtype)
    return radii, radii[topo.TIP_JOINTS - 1] + PAD_FRACTION * (radii[topo.TIP_JOINTS] - radii[topo.TIP_JOINTS - 1])


_PAD_A, _PAD_B = (list(side) for side in zip(*combinations(range(5), 2)))
_N_THUMB_PAIRS = topo.N_FINGERS - 1  # combinations list the thumb's pairs first


def pad_pair_gaps(hand: HandModel, positions: torch.Tensor, thumb_tips: bool = True) -> torch.Tensor:
    """(T, 10) surface gaps in metres of the fingertip pad pairs (``CONTACT_PAIRS[PAD_PAIRS]``) of (T, 21, 3)
    joint positions: what the contact fit, run at every step, needs of `contact_gaps`. The thumb's four pairs
    (the first) are `thumb_pair_gaps`; ``thumb_tips=False``: pad centre to pad centre as for the others, the
    gesture library's labelled touches ("which pads touch", DESIGN.md section 7) that the sample motions and the
    networks' training data were made with."""
    pads = pad_centres(positions)
    radii, pad_r = _pad_radii(hand, pads.dtype)
    if not thumb_tips:
        return (pads[:, _PAD_A] - pads[:, _PAD_B]).norm(dim=-1) - pad_r[_PAD_A] - pad_r[_PAD_B]
    a, b = _PAD_A[_N_THUMB_PAIRS:], _PAD_B[_N_THUMB_PAIRS:]
    fingers = (pads[:, a] - pads[:, b]).norm(dim=-1) - pad_r[a] - pad_r[b]
    return torch.cat([_thumb_tip_gaps(positions, pads, radii, pad_r), fingers], -1)


def thumb_pair_gaps(hand: HandModel, positions: torch.Tensor) -> torch.Tensor:
    """(T, 4) surface gaps in metres of the thumb's fingertip with each finger's (index .. pinky): the nearest
    approach of the capsules from each pad centre to where its tip joint's cap ends (radii interpolated between
    the pad's and the tip's). A tip pinch (Oculus's pinch clip, the authored Pinch Tight) touches at the tips,
    with the pads still apart; fingertip pads side by side (two fingers) are measured pad to pad as before."""
    pads = pad_centres(positions)
    return _thumb_tip_gaps(positions, pads, *_pad_radii(hand, positions.dtype))


def _thumb_tip_gaps(positions: torch.Tensor, pads: torch.Tensor, radii: torch.Tensor, pad_r: torch.Tensor
                    ) -> torch.Tensor:
    """`thumb_pair_gaps` from the pads and radii `pad_pair_gaps` has already worked out."""
    tip_r = radii[topo.TIP_JOINTS]
    reach = positions[:, topo.TIP_JOINTS] - pads
    length = reach.norm(dim=-1, keepdim=True)
    ends = pads + reach * (1.0 - torch.minimum(tip_r[:, None], 0.5 * length) / length)  # the cap ends at the tip
    distance, along_thumb, along_finger = _nearest_approach(pads[:, :1], ends[:, :1], pads[:, 1:], ends[:, 1:])
    thumb_r = pad_r[0] + along_thumb * (tip_r[0] - pad_r[0])
    finger_r = pad_r[1:] + along_finger * (tip_r[1:] - pad_r[1:])
    return distance - thumb_r - finger_r


def _nearest_approach(p0: torch.Tensor, p1: torch.Tensor, q0: torch.Tensor, q1: torch.Tensor
                      ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Distance between segments p0-p1 and q0-q1 (..., 3; neither of length 0) at their nearest points, and
    where those lie along each (0 .. 1): the clamped closed form (Ericson, Real-Time Collision Detection 5.1.9)."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e = (d1 * d1).sum(-1), (d2 * d2).sum(-1)
    b, c, f = (d1 * d2).sum(-1), (d1 * r).sum(-1), (d2 * r).sum(-1)
    across = a * e - b * b  # 0 for parallel segments: start from p0
    s = torch.where(across > 1e-12 * a * e, (b * f - c * e) / across.clamp_min(1e-30), torch.zeros_like(a)).clamp(0, 1)
    t = (b * s + f) / e
    s = torch.where(t < 0, (-c / a).clamp(0, 1), torch.where(t > 1, ((b - c) / a).clamp(0, 1), s))
    t = t.clamp(0, 1)
    nearest = (p0 + s[..., None] * d1) - (q0 + t[..., None] * d2)
    return nearest.norm(dim=-1), s, t


def contact_gaps(hand: HandModel, pose: HandPose, thumb_tips: bool = True) -> torch.Tensor:
    """(T, 15) surface gaps in metres for ``CONTACT_PAIRS`` (negative = interpenetrating); ``thumb_tips`` as in
    `pad_pair_gaps`."""
    return torch.cat([pad_pair_gaps(hand, pose.positions, thumb_tips), palm_gaps(hand, pose.positions)], -1)


def palm_gaps(hand: HandModel, positions: torch.Tensor) -> torch.Tensor:
    """(T, 5) surface gaps in metres of each fingertip with the palm (``CONTACT_PAIRS[PALM_PAIRS]``) of (T, 21, 3)
    joint positions: the nearer of its pad and its tip to the palm's thickened rectangle."""
    dtype = positions.dtype
    radii, pad_r = _pad_radii(hand, dtype)
    frame, lower, upper = (torch.as_tensor(a, dtype=dtype) for a in _palm_box(hand))

    def palm_gap(points: torch.Tensor, point_r: torch.Tensor) -> torch.Tensor:
        local = points @ frame
        nearest = torch.maximum(torch.minimum(local, upper), lower)
        return (local - nearest).norm(dim=-1) - point_r - radii[0]

    return torch.minimum(palm_gap(pad_centres(positions), pad_r), palm_gap(positions[:, topo.TIP_JOINTS],
                                                                           radii[topo.TIP_JOINTS]))


def contact_loss(gaps: torch.Tensor, source_gaps: torch.Tensor, tolerance: float = CONTACT_TOLERANCE) -> torch.Tensor:
    """Mean over frames of the summed squared misses, both gaps (..., 15) in each hand's lengths: pairs
    touching in the source are pulled under half the tolerance, pairs apart kept beyond 1.2 times it
    (margins either side of the threshold, so the detected contacts agree and not only the loss)."""
    touching = source_gaps < tolerance
    miss = torch.where(touching, torch.relu(gaps - 0.5 * tolerance), torch.relu(1.2 * tolerance - gaps))
    return miss.square().sum(-1).mean()


def detect_contacts(hand: HandModel, pose: HandPose, tolerance: float = CONTACT_TOLERANCE) -> np.ndarray:
    """(T, 15) bool: pairs whose gap is under ``tolerance`` x hand length."""
    gaps = contact_gaps(hand, pose).detach().cpu().numpy()
    return gaps < tolerance * hand.hand_length


#: a pair the source holds within this many times the tolerance is near touching: a retarget that closes it makes
#: no contact the source "does not make" (the gestures clip's fingertips 1.5-2.2% of the hand from the palm, closed
#: to 0.5-0.9% onto iris, read as 24 frames of invented contacts beside a contact precision of 1.000)
NEAR_FACTOR = 2.0


def touching_and_near(hand: HandModel, pose: HandPose) -> tuple[np.ndarray, np.ndarray]:
    """(T, 15) bool each, from one reading of the gaps: pairs in contact (`detect_contacts`), and pairs within
    `NEAR_FACTOR` x the tolerance (touching or nearly: a retarget closing them invents nothing)."""
    gaps = contact_gaps(hand, pose).detach().cpu().numpy()  # metres, compared as `detect_contacts` does
    return gaps < CONTACT_TOLERANCE * hand.hand_length, gaps < NEAR_FACTOR * CONTACT_TOLERANCE * hand.hand_length


def contact_precision_recall(source: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """Precision and recall of the target's contacts against the source's ((T, 15) bools).

    A ratio over no contacts is undefined and NaN, not a perfect score: precision when the target makes
    no contact (a retarget that never touches is not precise), recall when the source makes none.
    """
    true_pos = np.logical_and(source, target).sum()
    precision = true_pos / target.sum() if target.sum() else np.nan
    recall = true_pos / source.sum() if source.sum() else np.nan
    return float(precision), float(recall)
