"""A pose's signature, what a viewer reads off a hand at a glance: each finger extended, bent or curled;
which fingertips the thumb touches, or whether it stands out to the side (a thumbs-up) where it touches
none, or rests on the curled fingers (horns, a V sign: the thumb holds them down), or lies across the palm (a
four); no finger curling sideways.
A retarget keeps a pose when its signature matches the source's (issue 26: scoring authored poses on real rigs)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import HandPose, forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.semantics.contacts import CONTACT_PAIRS, contact_gaps, pad_centres
from s2h_viewer.semantics.flexion import HINGE_JOINTS, SidewaysPeak, flexion_and_sideways, thumb_across, thumb_out

#: a finger's curl (its MCP, PIP and DIP flexion summed, degrees) below which it reads extended, above
#: which curled; a curl within `CURL_MARGIN` of the source's is kept whatever the words
EXTENDED_BELOW, CURLED_ABOVE, CURL_MARGIN = 70.0, 150.0, 45.0
#: a PIP/DIP flexing at least `SIDEWAYS_FLEXION` and bending more than `SIDEWAYS_LIMIT` sideways reads as
#: a broken finger, unless the source bends as far (+5); a joint flexed less reads its splay, not its hinge
SIDEWAYS_LIMIT, SIDEWAYS_FLEXION = 25.0, 45.0
#: the thumb's fingertip touches a finger's within this gap (hand lengths, `contacts.thumb_pair_gaps`): looser
#: than the contact metric's 1.5%, as authored touches on real rigs leave up to 2.4% (the Godot hand's OK sign 1.3%,
#: Pinch Tight 2.3%), and the nearest pose that does not touch is a pinch around a flat object at 5.0%
THUMB_TOUCH = 0.035
THUMB_PAIRS = tuple(i for i, pair in enumerate(CONTACT_PAIRS) if "thumb" in pair and "palm" not in pair)
#: a thumb pointing further out to its side than this (degrees, `semantics.flexion.thumb_out`) reads as out (a
#: thumbs-up, a shaka: the authored ones 40-52), one pointing less than `THUMB_IN_BELOW` as in (the Meta hand's
#: copied shaka: 9 deg, its thumb in front of the palm; 24 still lies there, the character's 32 stands out); a
#: retarget loses the thumb out where its thumb is in and the source's out. Only that way: rigs hold their thumbs 20
#: deg apart at rest, and one held further out than the source's changes no gesture. Read only where the source's
#: thumb touches no fingertip: a touch says where a thumb is.
THUMB_OUT_ABOVE, THUMB_IN_BELOW = 35.0, 25.0
#: the thumb rests on a bent or curled finger where its tip's pad lies within `THUMB_ON` hand lengths of the
#: finger's first two bones (MCP to PIP to DIP, their axes): the authored horns, V sign and fists hold it 0.08-0.11
#: from the curled middle or ring, their open poses 0.2 and more. A retarget lets go of it where its thumb lies
#: further than `THUMB_ON_MARGIN` beyond the source's from every finger the source's rests on (thicker fingers
#: part axes by a few hundredths): ASRN onto the RPM avatar held it 0.19-0.27 from them in the horns, and a
#: viewer saw the thumb off the fingers where kept read 1.000. Read only where the source's thumb touches no
#: fingertip: a touch says where a thumb is.
THUMB_ON, THUMB_ON_MARGIN = 0.13, 0.08
#: the thumb lies across the palm where its tip is this far past the index knuckle toward the pinky's (palm widths,
#: `semantics.flexion.thumb_across`): the authored Sign 4 (a four) 0.60, its Pinch Middle 0.39, the sample clips'
#: four and letters B and S 0.8-1.1. A retarget lets it go where its thumb lies `THUMB_ACROSS_MARGIN` less far across:
#: TBS Copy and ASRN held Sign 4's at the palm's side (-0.37 to 0.11 on six real rigs; 0.16 and 0.32 on the mitten).
#: Read only where the source's thumb touches no fingertip and rests on no bent finger: those say where it is.
THUMB_ACROSS_FROM, THUMB_ACROSS_MARGIN = 0.45, 0.3


@dataclass(frozen=True)
class PoseSignature:
    """One frame's signature: curl (4,) degrees of index..pinky, thumb-tip contacts (4,) with index..pinky,
    the worst sideways flexion (degrees, NaN if nothing curls)."""

    curl: np.ndarray
    thumb_contacts: np.ndarray
    sideways: float
    sideways_joint: str = ""  # the PIP/DIP bending the most sideways ("ring_dip"), "" if none flexes enough
    thumb_out: float = 0.0  # degrees the thumb points out to its side (`semantics.flexion.thumb_out`)
    #: (4,) hand lengths from the thumb's tip to index..pinky's first two bones (`thumb_rest_distances`)
    thumb_rest: np.ndarray = None  # type: ignore[assignment]
    thumb_across: float = 0.0  # palm widths its tip lies across the palm (`semantics.flexion.thumb_across`)
    #: (4,) hand lengths from the thumb's fingertip to index..pinky's (`contacts.thumb_pair_gaps`): a touch under
    #: `THUMB_TOUCH`, looser than the contact metric's (what the words of a lost or invented touch give)
    thumb_gaps: np.ndarray = None  # type: ignore[assignment]

    @property
    def states(self) -> list[str]:
        return ["extended" if c < EXTENDED_BELOW else "curled" if c > CURLED_ABOVE else "bent" for c in self.curl]


#: per finger index..pinky, its chain of joints from the wrist to the tip: what a curl sums the bends of
CURL_CHAINS: list[list[int]] = [[0, *range(1 + 4 * f, 5 + 4 * f)] for f in range(1, topo.N_FINGERS)]


def sideways_broken(degrees: float, source_degrees: float) -> bool:
    """A clip's worst sideways bend read as a broken finger: past `SIDEWAYS_LIMIT` and past the source's own (NaN:
    it curls no finger) + 5; the red of the viewer's Sideways cell and of a batch's row."""
    return bool(degrees > max(SIDEWAYS_LIMIT, np.nan_to_num(source_degrees) + 5.0))


def finger_curls(positions: np.ndarray) -> np.ndarray:
    """(T, 4) curl in degrees of index..pinky: the angles between consecutive bones from the wrist-to-MCP
    line to the tip, summed."""
    bones = np.diff(positions[:, CURL_CHAINS], axis=2)
    bones /= np.maximum(np.linalg.norm(bones, axis=-1, keepdims=True), 1e-12)
    cos = np.clip((bones[:, :, :-1] * bones[:, :, 1:]).sum(-1), -1.0, 1.0)
    return np.degrees(np.arccos(cos)).sum(-1)


def thumb_rest_distances(positions: torch.Tensor, hand_length: float) -> torch.Tensor:
    """(T, 4) hand lengths from the thumb tip's pad centre to each of index..pinky's proximal and middle bones
    (the nearer of the two segments MCP-PIP, PIP-DIP): where the thumb rests on a curled finger, it is near. With
    gradients (the contact fit pulls a thumb back onto the fingers)."""
    tip = pad_centres(positions)[:, 0]
    out = []
    for f in range(1, topo.N_FINGERS):
        mcp = 1 + 4 * f
        nearest = []
        for a, b in ((mcp, mcp + 1), (mcp + 1, mcp + 2)):
            start, along = positions[:, a], positions[:, b] - positions[:, a]
            share = (((tip - start) * along).sum(1) / (along * along).sum(1).clamp(min=1e-12)).clamp(0.0, 1.0)
            nearest.append((start + share[:, None] * along - tip).norm(dim=1))
        out.append(torch.minimum(*nearest))
    return torch.stack(out, 1) / hand_length


def thumb_resting(curl: np.ndarray, rest: np.ndarray, touches: np.ndarray) -> np.ndarray:
    """(T, 4) bool from (T, 4) curls (degrees), rest distances and thumb-tip touches: the bent or curled fingers
    the thumb rests on (`THUMB_ON`), on frames where it touches no fingertip."""
    return (rest < THUMB_ON) & (curl >= EXTENDED_BELOW) & ~np.asarray(touches).any(-1, keepdims=True)


def thumb_rest_lost(source_curl: np.ndarray, source_rest: np.ndarray, target_rest: np.ndarray,
                    source_touches: np.ndarray) -> np.ndarray:
    """(T,) bool from (T, 4) curls and rest distances: where the source's thumb rests on a bent or curled finger
    (`thumb_resting`), and the target's lies more than `THUMB_ON_MARGIN` further from each."""
    resting = thumb_resting(source_curl, source_rest, source_touches)
    off = (target_rest - source_rest) > THUMB_ON_MARGIN
    return resting.any(-1) & (off | ~resting).all(-1)


def signatures(hand: HandModel, q_tbs: np.ndarray) -> list[PoseSignature]:
    """The signature of every frame of ``q_tbs`` (T, 15, 4) on ``hand``."""
    with torch.no_grad():
        pose = forward_kinematics(hand, torch.as_tensor(np.asarray(q_tbs), dtype=torch.float64))
    positions = pose.positions.numpy()
    gaps = contact_gaps(hand, pose).numpy()[:, list(THUMB_PAIRS)]
    contacts = gaps < THUMB_TOUCH * hand.hand_length
    gaps = gaps / hand.hand_length
    curls = finger_curls(positions)
    out = np.degrees(thumb_out(pose.positions).numpy())
    flexion, sideways = flexion_and_sideways(positions)
    sideways = np.where(flexion >= SIDEWAYS_FLEXION, sideways, np.nan)
    none = np.isnan(sideways).all(axis=1)
    which = np.argmax(np.nan_to_num(sideways, nan=-1.0), axis=1)
    worst = np.where(none, np.nan, np.nan_to_num(sideways, nan=-1.0)[np.arange(len(which)), which])
    rest = thumb_rest_distances(pose.positions, hand.hand_length).numpy()
    across = thumb_across(pose.positions).numpy()
    return [PoseSignature(curls[t], contacts[t], float(worst[t]), "" if none[t] else HINGE_JOINTS[which[t]][0],
                          float(out[t]), rest[t], float(across[t]), gaps[t]) for t in range(len(positions))]


def _gap_words(gap: float) -> str:
    """A fingertip gap in hand lengths, in words: "0.185 hand lengths apart", or "pressed 0.012 into each other"
    where the pads overlap (a gap below 0: "the source's -0.012 hand lengths apart" read as a typo)."""
    return f"{gap:.3f} hand lengths apart" if gap >= 0.0 else f"pressed {-gap:.3f} into each other"


def differences(source: PoseSignature, target: PoseSignature) -> list[str]:
    """What the target loses of the source's signature, in words (empty: kept)."""
    out = []
    for f, (a, b, sa, sb) in enumerate(zip(source.curl, target.curl, source.states, target.states)):
        if sa != sb and abs(a - b) > CURL_MARGIN:
            out.append(f"{topo.FINGERS[f + 1]} {sb}, not {sa}")
    for f, (a, b) in enumerate(zip(source.thumb_contacts, target.thumb_contacts)):
        if a != b:
            # a touch, not a contact: the scores' contacts (and the view's links) are the metric's 1.5%, this 3.5%
            out.append(f"thumb-{topo.FINGERS[f + 1]} touch {'lost' if a else 'invented'} (fingertips "
                       f"{_gap_words(target.thumb_gaps[f])}, the source's {_gap_words(source.thumb_gaps[f])})")
    if thumb_out_lost(source.thumb_out, target.thumb_out, source.thumb_contacts.any()):
        out.append(f"thumb not out to its side ({target.thumb_out:.0f} deg, the source: {source.thumb_out:.0f})")
    if thumb_rest_lost(source.curl[None], source.thumb_rest[None], target.thumb_rest[None],
                       source.thumb_contacts[None])[0]:
        fingers = np.flatnonzero(thumb_resting(source.curl[None], source.thumb_rest[None],
                                               source.thumb_contacts[None])[0])
        names = ", ".join(topo.FINGERS[f + 1] for f in fingers)
        them = "it" if len(fingers) == 1 else "them"
        out.append(f"thumb off the {names} ({target.thumb_rest[fingers].min():.2f} hand lengths from {them}; the "
                   f"source's: {source.thumb_rest[fingers].min():.2f})")
    if thumb_across_lost(source.curl[None], source.thumb_rest[None], source.thumb_contacts[None],
                         np.array([source.thumb_across]), np.array([target.thumb_across]))[0]:
        out.append(f"thumb not across the palm (its tip {_across_words(target.thumb_across)}; the source's "
                   f"{_across_words(source.thumb_across)})")
    if sideways_broken(target.sideways, source.sideways):
        joint = target.sideways_joint.replace("_", " ").replace("pip", "PIP").replace("dip", "DIP")
        source_deg = "no joint flexed enough" if np.isnan(source.sideways) else f"{source.sideways:.0f}"
        out.append(f"{joint} bends {target.sideways:.0f} deg sideways (the source: {source_deg})")
    return out


def _across_words(across: float) -> str:
    """Where a thumb tip lies along the palm's width (`flexion.thumb_across`): "0.46 of the palm's width across it,
    past the index knuckle", "0.29 of the palm's width outside the index knuckle" (a fresh-eyes user read "-0.29 of
    its width past the index knuckle" as nonsense)."""
    if across >= 0.0:
        return f"{across:.2f} of the palm's width across it, past the index knuckle"
    return f"{-across:.2f} of the palm's width outside the index knuckle"


def thumb_across_lost(source_curl: np.ndarray, source_rest: np.ndarray, source_touches: np.ndarray,
                      source_across: np.ndarray, target_across: np.ndarray) -> np.ndarray:
    """(T,) bool: the source's thumb lies across the palm (`THUMB_ACROSS_FROM`), touching no fingertip and resting on
    no bent finger, and the target's `THUMB_ACROSS_MARGIN` less far across; from (T, 4) curls, rest distances and
    thumb touches and (T,) `thumb_across` readings."""
    free = ~np.asarray(source_touches).any(-1) & ~thumb_resting(source_curl, source_rest, source_touches).any(-1)
    return free & (source_across >= THUMB_ACROSS_FROM) & (target_across < source_across - THUMB_ACROSS_MARGIN)


def thumb_out_lost(source_deg, target_deg, source_touches):
    """Whether the source's thumb is out to its side (`THUMB_OUT_ABOVE`) and the target's in (`THUMB_IN_BELOW`),
    the source's touching no fingertip: floats or arrays of degrees (`semantics.flexion.thumb_out`) and of whether
    the source's thumb touches a fingertip."""
    return ((np.asarray(source_deg) > THUMB_OUT_ABOVE) & (np.asarray(target_deg) < THUMB_IN_BELOW)
            & ~np.asarray(source_touches))


def held_poses(labels: np.ndarray) -> list[tuple[str, int]]:
    """(label, middle frame) of each run of frames with one non-empty label: the poses a clip holds."""
    out, start = [], 0
    for t in range(1, len(labels) + 1):
        if t == len(labels) or labels[t] != labels[start]:
            if labels[start]:
                out.append((str(labels[start]), (start + t - 1) // 2))
            start = t
    return out


def lost_pose_lines(lost: dict[str, list[str]], labels: np.ndarray) -> list[tuple[str, list[str]]]:
    """Per pose lost (`pose_differences`' non-empty entries), its name with the frame it is held at (the middle of
    its run, `held_poses`), "Sign 3 (frame 571)", and what it loses: a user goes there (they had only the name)."""
    frames = dict(held_poses(labels))
    return [(f"{name} (frame {frames[name]})" if name in frames else name, what) for name, what in lost.items()]


def pose_differences(source_hand: HandModel, source_q: np.ndarray, target_hand: HandModel, target_q: np.ndarray,
                     labels: np.ndarray) -> dict[str, list[str]]:
    """Per held pose of the clip (`held_poses`), what the retarget loses of its signature (empty: kept)."""
    poses = held_poses(labels)
    frames = [t for _, t in poses]
    src = signatures(source_hand, np.asarray(source_q)[frames])
    tgt = signatures(target_hand, np.asarray(target_q)[frames])
    return {name: differences(a, b) for (name, _), a, b in zip(poses, src, tgt)}


#: bits of `loss_masks`: finger states (index..pinky), thumb-tip touches (index..pinky), sideways, a pad
#: contact (the metric's 1.5% tolerance) the source does not make, the thumb out to its side or not, the thumb
#: resting on the curled fingers or not, the thumb across the palm or not
STATE_BITS, TOUCH_BITS, SIDEWAYS_BIT, INVENTED_BIT, THUMB_OUT_BIT, THUMB_REST_BIT = 0, 4, 8, 9, 10, 11
THUMB_ACROSS_BIT = 12


def sideways_anywhere(positions: np.ndarray) -> SidewaysPeak:
    """The worst sideways bend of a PIP/DIP flexed past `SIDEWAYS_FLEXION` in any frame of (T, 21, 3) positions: the
    peak of the viewer's sideways curve (`frame_sideways`), which the clip's figure (`flexion.sideways_peak`, at each
    joint's tightest curls) may leave out: TBS Copy of the authored poses onto the VRM robot bends the pinky PIP 85
    deg sideways in Sign 3, where the clip's figure read 59 (a fresh-eyes user found the curve's peak beside it)."""
    read = _flexed_sideways(positions)
    frame, joint = np.unravel_index(int(np.argmax(read)), read.shape)
    if read[frame, joint] < 0.0:
        return SidewaysPeak(float("nan"))
    return SidewaysPeak(float(read[frame, joint]), HINGE_JOINTS[joint][0], int(frame))


def sideways_there(positions: np.ndarray, where: str) -> float:
    """Degrees joint and frame ``where`` ("pinky_pip@557", a `SidewaysPeak.where`) bend sideways in (T, 21, 3)
    positions (the source's, say, where a retarget bends the most); NaN where that joint flexes too little to
    have an axis, or ``where`` is empty."""
    joint, _, frame = where.partition("@")
    if not joint:
        return float("nan")
    _, sideways = flexion_and_sideways(np.asarray(positions)[int(frame):int(frame) + 1])
    return float(sideways[0, [name for name, _ in HINGE_JOINTS].index(joint)])


def _flexed_sideways(positions: np.ndarray) -> np.ndarray:
    """(T, 8) degrees each PIP/DIP (`HINGE_JOINTS`) bends sideways where it flexes past `SIDEWAYS_FLEXION`, -1
    elsewhere, from (T, 21, 3) positions: the bends the signature reads."""
    flexion, sideways = flexion_and_sideways(positions)
    return np.where(flexion >= SIDEWAYS_FLEXION, np.nan_to_num(sideways, nan=-1.0), -1.0)


def frame_sideways(positions: np.ndarray) -> np.ndarray:
    """(T,) degrees: each frame's worst sideways bend of the PIP/DIP joints flexed past `SIDEWAYS_FLEXION`, 0 where
    none is (the signature's sideways part, and the viewer's sideways curve), from (T, 21, 3) positions."""
    return _flexed_sideways(positions).max(axis=1).clip(min=0.0)


def _frame_features(hand: HandModel, pose: HandPose
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(T, 4) curls, (T, 4) thumb touches, (T,) `frame_sideways`, (T, 10) pad contacts at the metric's tolerance,
    (T,) degrees the thumb points out to its side, (T, 4) `thumb_rest_distances`, (T,) `thumb_across`."""
    from s2h_viewer.semantics.contacts import CONTACT_TOLERANCE, PAD_PAIRS
    with torch.no_grad():
        gaps = contact_gaps(hand, pose).numpy() / hand.hand_length
        out = np.degrees(thumb_out(pose.positions).numpy())
        rest = thumb_rest_distances(pose.positions, hand.hand_length).numpy()
        across = thumb_across(pose.positions).numpy()
    positions = pose.positions.numpy()
    return (finger_curls(positions), gaps[:, list(THUMB_PAIRS)] < THUMB_TOUCH, frame_sideways(positions),
            gaps[:, PAD_PAIRS] < CONTACT_TOLERANCE, out, rest, across)


def loss_masks(source_hand: HandModel, source_q: np.ndarray, target_hand: HandModel, target_q: np.ndarray
               ) -> np.ndarray:
    """(T,) int: per frame, a bit for each part of the source's signature the target loses (`differences`,
    frame by frame), and `INVENTED_BIT` for a pad contact the source does not make."""
    with torch.no_grad():
        poses = [forward_kinematics(hand, torch.as_tensor(np.asarray(q), dtype=torch.float64))
                 for hand, q in ((source_hand, source_q), (target_hand, target_q))]
    return pose_loss_masks(source_hand, poses[0], target_hand, poses[1])


def pose_loss_masks(source_hand: HandModel, source_pose: HandPose, target_hand: HandModel, target_pose: HandPose
                    ) -> np.ndarray:
    """`loss_masks` from FK already done (float64 poses): scoring a retarget has both."""
    src_curl, src_touch, src_side, src_pads, src_out, src_rest, src_across = _frame_features(source_hand,
                                                                                             source_pose)
    tgt_curl, tgt_touch, tgt_side, tgt_pads, tgt_out, tgt_rest, tgt_across = _frame_features(target_hand,
                                                                                             target_pose)

    def states(curl: np.ndarray) -> np.ndarray:
        return np.where(curl < EXTENDED_BELOW, 0, np.where(curl > CURLED_ABOVE, 2, 1))

    state_lost = (states(src_curl) != states(tgt_curl)) & (np.abs(src_curl - tgt_curl) > CURL_MARGIN)
    mask = (state_lost * (1 << (STATE_BITS + np.arange(4)))).sum(-1)
    mask += ((src_touch != tgt_touch) * (1 << (TOUCH_BITS + np.arange(4)))).sum(-1)
    mask += (tgt_side > np.maximum(SIDEWAYS_LIMIT, src_side + 5.0)) * (1 << SIDEWAYS_BIT)
    mask += (tgt_pads & ~src_pads).any(-1) * (1 << INVENTED_BIT)
    mask += thumb_out_lost(src_out, tgt_out, src_touch.any(-1)) * (1 << THUMB_OUT_BIT)
    mask += thumb_rest_lost(src_curl, src_rest, tgt_rest, src_touch) * (1 << THUMB_REST_BIT)
    mask += thumb_across_lost(src_curl, src_rest, src_touch, src_across, tgt_across) * (1 << THUMB_ACROSS_BIT)
    return mask.astype(int)
