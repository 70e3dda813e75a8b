"""Contact fit: close on the target the fingertip-pad contacts the source has, and open those it lacks,
changing a retarget only around the frames where the two disagree (beyond the paper); and keep the
thumb at the fingertips the source's thumb is at (the pose signature's looser touch, `thumb_touch_loss`).

A network trained on procedural hands brings pads close on a hand it never saw, but not always within
the 1.5% tolerance that makes a touch (DESIGN.md section 5). This pass takes its output as given and
optimises a correction of the TBS Euler angles on the frames where a pad pair is touching on one hand and
apart on the other (or the thumb at a fingertip, `gaps_disagree`, a finger bent sideways, a thumb the source
holds out to its side held in, `semantics.signature.thumb_out_lost`, or one off the curled fingers or not across
the palm where the source's rests on them or lies across it), and on
``reach`` frames either side, where the correction fades to zero (a smoothness term ties each run's ends to
zero): elsewhere the retarget is returned bit for bit. Loss: the contact term
(`semantics.contacts.contact_loss`), L_ana on what the correction adds to the angles' excess (a twist the
network or the source's frames put there is not undone: "untwisting" a Godot fist's pinky knuckle opened it
22 deg), smoothness, a pull to the network's pose (harder on the thumb's CMC, most on its lift, and the CMC
stepped at a share of the others' rate, its swing across the palm slowest, so a finger and the thumb's hinges come
to a touch before the metacarpal leaves the path the source's takes), a curl term (no finger's curl moved further from the
source's than the signature's margin allows: a bent ring finger curled to meet the thumb is a pose lost), a
thumb-out term (a thumb the source holds out to its side, a thumbs-up's, brought out as far: on the Meta hand,
whose rest thumb lies along the fingers, the network held it in front of the palm), a thumb-rest term (a thumb the
source rests on its curled fingers, the horns' and the V sign's, brought back onto them: the network lifted it off
on every real rig), a thumb-across term (a thumb the source folds across the palm, a four's, brought back
across: the network left it at the palm's side on every real rig; its metacarpal stays slowed, as swinging it for
one pose made the thumb follow the source's less), a palm term (a fingertip on the palm in the source and in the
retarget or TBS Copy stays or comes there: closing the thumb's touches lifted the ring finger off the palm in fists,
and the network left the mitten avatar's index finger off it), and a sideways term: no
flexed PIP/DIP bent more than `SIDEWAYS_FREE` out of the curl plane (on the Godot hand, opening the ring-pinky
touch of fists bent the pinky DIP 45 deg sideways without it). The angles are read with the twist within +-90
deg (`quat_to_tbs_euler_past_lock`): a knuckle of a fist bent past 90 read as twisted 160 deg, and the anatomy
term "untwisted" it. Every
angle the fit moves stays within its limits, or no further out than the retarget's or the source's: each step is
projected there (L_ana alone let it twist and splay knuckles to close a touch). All runs of a clip are
optimised together in one batch, a bounded number of frames at a time; frames whose touches still disagree, or
whose thumb is still off the curled fingers or short of across the palm, are fitted once more with the thumb free
to go there (its metacarpal's swing still slowed), and those whose thumb is still not at the source's fingertips a
third time with that swing free too.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import torch

from s2h_viewer.hand.chunks import frame_chunks
from s2h_viewer.hand.kinematics import joint_positions
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.rotations import quat_to_tbs_euler_past_lock, tbs_euler_to_quat
from s2h_viewer.hand.topology import N_FINGERS
from s2h_viewer.retarget.progress import report, stage
from s2h_viewer.retarget.threads import torch_threads
from s2h_viewer.semantics.anatomy import angle_excess, clamp_angles, limits_reaching
from s2h_viewer.semantics.contacts import CONTACT_TOLERANCE, contact_loss, pad_pair_gaps, palm_gaps
from s2h_viewer.semantics.flexion import hinge_flexion_and_alignment, thumb_across, thumb_out
from s2h_viewer.semantics.signature import (CURL_CHAINS, CURL_MARGIN, SIDEWAYS_FLEXION, SIDEWAYS_LIMIT,
                                            THUMB_ACROSS_MARGIN, THUMB_ON_MARGIN, THUMB_OUT_ABOVE, THUMB_PAIRS,
                                            THUMB_TOUCH, finger_curls, frame_sideways, thumb_across_lost,
                                            thumb_out_lost, thumb_rest_distances, thumb_rest_lost, thumb_resting)

#: the thumb-to-fingertip pairs, as indices into the pad pairs (the thumb's come first in both)
_THUMB = list(THUMB_PAIRS)


def _thumb_at_tips(gaps):
    """(F, 4) bool from (F, 10) pad gaps (numpy or torch): the thumb at each fingertip, the signature's looser touch."""
    return gaps[:, _THUMB] < THUMB_TOUCH


@dataclass(frozen=True)
class ContactFitConfig:
    steps: int = 90
    learning_rate: float = 0.03
    contact_weight: float = 2e3
    anatomy_weight: float = 10.0
    smoothness_weight: float = 100.0
    prior_weight: float = 1.0  # pull toward the network's pose: the degrees of freedom contacts leave free stay put
    sideways_weight: float = 1e3  # no flexed PIP/DIP bent sideways past `SIDEWAYS_FREE`
    thumb_prior_weight: float = 5.0  # the thumb CMC pulled this much harder: fingers move to the thumb first
    thumb_lift_weight: float = 10.0  # and its splay (the metacarpal's lift out of the palm plane) this much more
    #: the thumb's MCP and IP pulled this much harder: with its twists and splays held within the limits, the fit
    #: reached the fingertips by bending them away from the network's (the robot's IP followed the poses' at 0.67,
    #: the mitten avatar's left at 0.88); so 0.75 and 0.93 (before the third pass), the poses kept, the touches the
    #: same within 0.02
    thumb_hinge_prior_weight: float = 3.0
    #: the thumb CMC's angles move at this share of the other joints' rate (Adam's steps), so the fingers and the
    #: thumb's own hinges reach a touch before its metacarpal swings away from the source's path: ASRN's thumb
    #: followed the authored poses' at 0.59-0.91 (its CMC across the palm), 0.69-0.93 so; 0.1 lost pad touches
    thumb_cmc_rate: float = 0.2
    #: and its bend, the metacarpal's swing across the palm, at this share of the CMC's rate, in both passes: the
    #: poses' rig reaches the ring and pinky tips with its metacarpal where it rests and its MCP bent, and a fit
    #: that swung it there 14-52 deg instead read as a thumb not following (0.74-0.94); reaching with the lift and
    #: the hinges, 0.80-0.93, the same touches
    thumb_cmc_bend_rate: float = 0.1
    curl_weight: float = 1e3  # no finger's curl moved further from the source's than `CURL_FREE` (`_curl_excess`)
    thumb_out_weight: float = 1e3  # the thumb out to its side as the source's (`_thumb_out_allowed`)
    thumb_rest_weight: float = 1e3  # the thumb back on the curled fingers the source's rests on (`_thumb_resting`)
    thumb_across_weight: float = 1e3  # the thumb back across the palm where the source's lies across it (a four)
    palm_weight: float = 1e4  # a fingertip on the palm where the source's is and the retarget's or TBS Copy's was
    reach: int = 4  # frames either side of a disagreement over which the correction fades in and out
    batch_frames: int = 4096  # frames optimised at once (memory of one batch)


#: a flexed PIP/DIP may bend sideways this far (radians) before the fit's sideways term acts: the signature's
#: limit less a margin
SIDEWAYS_FREE = np.radians(SIDEWAYS_LIMIT - 5.0)


def _sideways_excess(positions: torch.Tensor) -> torch.Tensor:
    """(F, 8) how far each PIP/DIP's curl-axis alignment (`hinge_flexion_and_alignment`) drops below that of a
    `SIDEWAYS_FREE` sideways bend, counted in full from `SIDEWAYS_FLEXION` on, fading in over the 20 deg below."""
    flexion, alignment = hinge_flexion_and_alignment(positions)
    weight = ((flexion - np.radians(SIDEWAYS_FLEXION - 20.0)) / np.radians(20.0)).clamp(0.0, 1.0)
    return weight * torch.relu(float(np.cos(SIDEWAYS_FREE)) - alignment)


#: a finger's curl may move this far (radians) from the source's before the fit's curl term acts: the
#: signature's margin less 10 deg
CURL_FREE = np.radians(CURL_MARGIN - 10.0)


def pose_curls(positions: torch.Tensor) -> torch.Tensor:
    """(F, 4) radians: `semantics.signature.finger_curls` of (F, 21, 3) positions, with gradients (atan2 of the
    bones' cross and dot: no arccos, whose slope is infinite at a straight finger)."""
    bones = positions[:, CURL_CHAINS].diff(dim=2)
    a, b = bones[:, :, :-1], bones[:, :, 1:]
    cross = (torch.linalg.cross(a, b).square().sum(-1) + 1e-12).sqrt()
    return torch.atan2(cross, (a * b).sum(-1)).sum(-1)


def _curl_excess(curls: torch.Tensor, source_curls: torch.Tensor, start_curls: torch.Tensor) -> torch.Tensor:
    """(F, 4) how far each finger's curl is from the source's beyond `CURL_FREE`, or beyond where the retarget
    had it, if further: the fit may not turn a bent finger curled to meet the thumb (Pinch Ring's ring)."""
    allowed = torch.clamp((start_curls - source_curls).abs(), min=float(CURL_FREE))
    return torch.relu((curls - source_curls).abs() - allowed)


#: how far (radians) the fit may leave the thumb pointing less out to its side than the source's, where the source's
#: is out (`semantics.signature.THUMB_OUT_ABOVE`), touches no fingertip and the retarget's is in (allowed 15 deg
#: short, the Meta hand's thumbs-up stood out at 37 deg, the source's 52: barely a thumbs-up)
THUMB_OUT_FREE = np.radians(5.0)


def _thumb_out_allowed(source_out: torch.Tensor, start_out: torch.Tensor, source_gaps: torch.Tensor
                       ) -> tuple[torch.Tensor, torch.Tensor]:
    """(F,) radians the thumb may point less out to its side (`semantics.flexion.thumb_out`) than the source's:
    `THUMB_OUT_FREE` where the retarget lost the source's thumb out (a thumbs-up's thumb in front of the Meta hand's
    palm: `semantics.signature.thumb_out_lost`), as far as the retarget had it elsewhere (the fit does not make it
    worse); unbounded where the source's thumb is not out or touches a fingertip (the touch terms place it). And
    (F,) bool: where it was lost."""
    touches = _thumb_at_tips(source_gaps).any(-1)
    source_deg = np.degrees(source_out.numpy())
    lost = torch.as_tensor(thumb_out_lost(source_deg, np.degrees(start_out.numpy()), touches.numpy()))
    allowed = torch.where(lost, torch.full_like(start_out, float(THUMB_OUT_FREE)),
                          torch.clamp(source_out - start_out, min=float(THUMB_OUT_FREE)))
    free = touches | torch.as_tensor(source_deg <= THUMB_OUT_ABOVE)
    return torch.where(free, torch.full_like(allowed, float("inf")), allowed), lost


def _thumb_resting(source: SourceFrames, source_gaps: torch.Tensor) -> torch.Tensor:
    """(F, 4) bool: the fingers the source's thumb rests on (`semantics.signature.THUMB_ON`, bent or curled), where
    it touches no fingertip: the fit keeps the target's thumb within half the signature's margin of them (ASRN lifted
    it 0.2-0.4 hand lengths off the authored horns' and V sign's curled fingers on every real rig)."""
    return torch.as_tensor(thumb_resting(np.degrees(source.curls.numpy()), source.thumb_rest.numpy(),
                                         _thumb_at_tips(source_gaps).numpy()))


#: a fingertip the fit keeps on the palm stays within this share of the contact tolerance of it
PALM_HOLD = 0.8


def _on_palm_around(hand: HandModel, poses: tuple[np.ndarray, ...], frames: np.ndarray, reach: int) -> np.ndarray:
    """(T, 5) bool: the fingertips on the palm (the metric's tolerance) in any of ``poses`` ((T, 15, 4) rotations
    each) in the runs the fit changes (``reach`` frames around the true ``frames``), False elsewhere. The fit keeps
    those the source has there too: closing a thumb's touch, it lifted the ring finger off the palm in the fists of
    the gestures clip on the robot and the mitten avatar (the ring fingertip's palm recall 1.00 -> 0.52, TBS Copy's
    1.00)."""
    out = np.zeros((len(frames), N_FINGERS), dtype=bool)
    around = np.zeros(len(frames), dtype=bool)
    for first, end in runs_around(frames, reach):
        around[first:end] = True
    fitted = np.flatnonzero(around)
    for first, end in frame_chunks(len(fitted)):
        idx = fitted[first:end]
        for q_tbs in poses:
            with torch.no_grad():
                gaps = palm_gaps(hand, joint_positions(hand, torch.as_tensor(q_tbs[idx], dtype=torch.float32)))
            out[idx] |= gaps.numpy() < CONTACT_TOLERANCE * hand.hand_length
    return out


def _pose_pad_gaps(hand: HandModel, positions: torch.Tensor) -> torch.Tensor:
    """(T, 10) fingertip-pad gaps of a posed hand in units of its length (what the fit compares)."""
    return pad_pair_gaps(hand, positions) / hand.hand_length


def pad_gaps(hand: HandModel, q_tbs: np.ndarray) -> np.ndarray:
    """(T, 10) fingertip-pad gaps in units of the hand's length."""
    with torch.no_grad():
        return _pose_pad_gaps(hand, joint_positions(hand, torch.as_tensor(q_tbs, dtype=torch.float32))).numpy()


def disagreement(source_hand: HandModel, source_q: np.ndarray, target_hand: HandModel, target_q: np.ndarray
                 ) -> np.ndarray:
    """(T,) bool: frames where some pad pair touches on one hand and not on the other (`gaps_disagree`), the
    target bends a finger sideways past the signature's limit and the source does not, or holds in the thumb the
    source holds out to its side (one bool per frame is all that is kept of a long clip's gaps)."""
    out = np.empty(len(source_q), dtype=bool)
    for first, end in frame_chunks(len(source_q)):
        source_gaps = pad_gaps(source_hand, source_q[first:end])
        out[first:end] = gaps_disagree(source_gaps, pad_gaps(target_hand, target_q[first:end]))
        out[first:end] |= _shape_lost(source_hand, source_q[first:end], target_hand, target_q[first:end],
                                      _thumb_at_tips(source_gaps).any(-1))
    return out


def _shape_lost(source_hand: HandModel, source_q: np.ndarray, target_hand: HandModel, target_q: np.ndarray,
                source_touches: np.ndarray) -> np.ndarray:
    """(T,) bool: the target's worst flexed PIP/DIP bends sideways past `SIDEWAYS_LIMIT` and past the source's + 5,
    or its thumb is not out to its side where the source's is, or off the curled fingers the source's rests on, or
    not across the palm where the source's lies across it, and touches no fingertip (the signature's rules,
    `semantics.signature`)."""
    with torch.no_grad():
        positions = [joint_positions(hand, torch.as_tensor(q, dtype=torch.float64))
                     for hand, q in ((source_hand, source_q), (target_hand, target_q))]
        rest = [thumb_rest_distances(p, hand.hand_length).numpy() for p, hand in zip(positions, (source_hand,
                                                                                                target_hand))]
    sideways = [frame_sideways(p.numpy()) for p in positions]
    out = [np.degrees(thumb_out(p).numpy()) for p in positions]
    curls = finger_curls(positions[0].numpy())
    return ((sideways[1] > np.maximum(SIDEWAYS_LIMIT, sideways[0] + 5.0)) | thumb_out_lost(*out, source_touches)
            | thumb_rest_lost(curls, *rest, source_touches[:, None])
            | thumb_across_lost(curls, rest[0], source_touches[:, None], *(thumb_across(p).numpy() for p in positions)))


def gaps_disagree(source_gaps: np.ndarray, target_gaps: np.ndarray) -> np.ndarray:
    """(T,) bool from (T, 10) pad gaps: some pair touches (the metric's tolerance) on one hand and not on the
    other, or the thumb is at a fingertip (the signature's looser `THUMB_TOUCH`) on one and not on the other."""
    pads = (source_gaps < CONTACT_TOLERANCE) != (target_gaps < CONTACT_TOLERANCE)
    thumb = _thumb_at_tips(source_gaps) != _thumb_at_tips(target_gaps)
    return pads.any(-1) | thumb.any(-1)


def thumb_touch_loss(gaps: torch.Tensor, source_gaps: torch.Tensor) -> torch.Tensor:
    """Mean over frames of the squared misses of the thumb-to-fingertip gaps (F, 10 pad gaps) against the
    signature's `THUMB_TOUCH`: a thumb at a fingertip in the source (a pinch's 2%, under it but no pad
    contact) is kept under 0.8 times it, one away from it beyond 1.2 times it. Without it, opening a thumb
    the network had pressed onto the index (a pad contact the source does not make) let it fly off."""
    near = _thumb_at_tips(source_gaps)
    gap = gaps[:, _THUMB]
    miss = torch.where(near, torch.relu(gap - 0.8 * THUMB_TOUCH), torch.relu(1.2 * THUMB_TOUCH - gap))
    return miss.square().sum(-1).mean()


def runs_around(frames: np.ndarray, reach: int) -> list[tuple[int, int]]:
    """(first, end) runs of the frames within ``reach`` of a true frame of ``frames`` ((T,) bool); runs
    closer than two frames are merged."""
    runs: list[tuple[int, int]] = []
    for f in np.flatnonzero(frames):
        first, end = max(f - reach, 0), min(f + reach + 1, len(frames))
        if runs and first <= runs[-1][1] + 2:
            runs[-1] = (runs[-1][0], end)
        else:
            runs.append((int(first), int(end)))
    return runs


def fit_contacts(source_q: np.ndarray, source_hand: HandModel, target_hand: HandModel, target_q: np.ndarray,
                 config: ContactFitConfig = ContactFitConfig()) -> np.ndarray:
    """(T, 15, 4) ``target_q`` with its pad contacts made to agree with the source's, changed only in runs
    around the frames where they disagree (progress through `retarget.progress`). A float32 ``target_q``
    is changed in place (a long clip's rotations are not copied)."""
    source_q = np.asarray(source_q)
    out = np.asarray(target_q, dtype=np.float32)
    frames = disagreement(source_hand, source_q, target_hand, out)
    # before any pass moves them; and where TBS Copy (the source's own TBS rotations) has them there
    on_palm = _on_palm_around(target_hand, (out, source_q), frames, config.reach)

    def source_at(idx: np.ndarray) -> SourceFrames:
        with torch.no_grad():
            positions = joint_positions(source_hand, torch.as_tensor(source_q[idx], dtype=torch.float32))
            source_on_palm = palm_gaps(source_hand, positions).numpy() < CONTACT_TOLERANCE * source_hand.hand_length
            # read as the target's
            return SourceFrames(_pose_pad_gaps(source_hand, positions), pose_curls(positions), thumb_out(positions),
                                thumb_rest_distances(positions, source_hand.hand_length), thumb_across(positions),
                                quat_to_tbs_euler_past_lock(torch.as_tensor(source_q[idx], dtype=torch.float32)),
                                torch.as_tensor(source_on_palm & on_palm[idx]))
    return _fit_frames(out, frames, source_at, target_hand, config)


def fit_contacts_to_gaps(source_gaps: np.ndarray, hand: HandModel, q_tbs: np.ndarray,
                         config: ContactFitConfig = ContactFitConfig()) -> np.ndarray:
    """(T, 15, 4) ``q_tbs`` on ``hand`` with its pad contacts made to agree with ``source_gaps`` (T, 10), pad
    gaps in hand lengths measured elsewhere (a tracked hand's keypoints, say), as `fit_contacts` does."""
    out = np.asarray(q_tbs, dtype=np.float32)
    frames = np.zeros(len(out), dtype=bool)
    for first, end in frame_chunks(len(out)):
        frames[first:end] = gaps_disagree(source_gaps[first:end], pad_gaps(hand, out[first:end]))
    return _fit_frames(out, frames, lambda idx: SourceFrames(torch.as_tensor(source_gaps[idx])), hand, config)


@dataclass(frozen=True)
class SourceFrames:
    """What the fit matches on some frames of the source: (F, 10) pad gaps in hand lengths, (F, 4) finger curls,
    (F,) how far the thumb points out to its side (radians) and (F, 4) how far its tip lies from each finger's first
    two bones (hand lengths; None where not known, as of a tracked hand's gaps)."""

    gaps: torch.Tensor
    curls: torch.Tensor | None = None
    thumb_out: torch.Tensor | None = None
    thumb_rest: torch.Tensor | None = None  # (F, 4) `semantics.signature.thumb_rest_distances`
    thumb_across: torch.Tensor | None = None  # (F,) palm widths, `semantics.flexion.thumb_across`
    angles: torch.Tensor | None = None  # (F, 15, 3) its TBS angles: the fit may reach as far past the limits
    #: (F, 5) bool: fingertips on the palm here and in the retarget the fit starts from or in TBS Copy (the source's
    #: TBS rotations on the target), which it keeps or brings there
    palm_held: torch.Tensor | None = None


def _fit_frames(out: np.ndarray, disagree: np.ndarray, source_at, hand: HandModel, config: ContactFitConfig
                ) -> np.ndarray:
    """The fit of `fit_contacts` on the runs around the ``disagree`` frames; ``source_at(frames)``: the source's
    `SourceFrames` there. Frames whose touches still disagree after it, where the fingers could not reach a thumb
    held near its path, or whose thumb is still off the curled fingers or short of across the palm, are fitted again
    with the thumb pulled and stepped like any joint but for its metacarpal's swing across the palm (the VRM robot's
    pad recall: 0.28 with the first pass alone); those whose thumb is then still not at the fingertips the source's is
    at, a third time with that swing too as fast (the robot, held within the joint limits, lost Sign 3 and Ring from
    the left-hand pose file without it: its thumb lies 0.7 palm widths further out than the source's)."""
    with stage(0.0, 0.8):
        left, _ = _fit_pass(out, disagree, source_at, hand, config)
    if (config.thumb_prior_weight, config.thumb_lift_weight) != (1.0, 1.0) and left.any():
        with stage(0.8, 0.9):
            # half the steps: a handful of frames, from where the first pass left them
            again = dataclasses.replace(config, thumb_prior_weight=1.0, thumb_lift_weight=1.0, thumb_cmc_rate=1.0,
                                        steps=config.steps // 2)
            _, thumb_lost = _fit_pass(out, left, source_at, hand, again)
        if config.thumb_cmc_bend_rate != 1.0 and thumb_lost.any():
            with stage(0.9, 1.0):
                _fit_pass(out, thumb_lost, source_at, hand, dataclasses.replace(again, thumb_cmc_bend_rate=1.0))
    report(1.0)
    return out


def _fit_pass(out: np.ndarray, disagree: np.ndarray, source_at, hand: HandModel, config: ContactFitConfig
              ) -> tuple[np.ndarray, np.ndarray]:
    """One pass of `_fit_frames`, in place: (T,) bool, the frames whose touches disagree after it (or whose thumb
    is off the curled fingers or short of across the palm), and (T,) bool, those whose thumb is not at the
    fingertips the source's is at (the signature's looser touch: a pose lost)."""
    left = np.zeros(len(out), dtype=bool)
    thumb_lost = np.zeros(len(out), dtype=bool)
    batches = _batches(runs_around(disagree, config.reach), config.batch_frames)
    for i, batch in enumerate(batches):
        frames = np.concatenate([np.arange(a, b) for a, b in batch])
        source = source_at(frames)
        with stage(i / len(batches), (i + 1) / len(batches)), torch_threads(1):
            out[frames] = _fit_runs(out[frames], source, [b - a for a, b in batch], hand, config)
        with torch.no_grad():
            positions = joint_positions(hand, torch.as_tensor(out[frames], dtype=torch.float32))
            gaps = _pose_pad_gaps(hand, positions).numpy()
        left[frames] = (gaps_disagree(source.gaps.numpy(), gaps) | _thumb_left(source, hand, positions)
                        ) & disagree[frames]
        thumb_lost[frames] = (_thumb_at_tips(source.gaps.numpy()) != _thumb_at_tips(gaps)).any(-1) & disagree[frames]
    return left, thumb_lost


def _thumb_left(source: SourceFrames, hand: HandModel, positions: torch.Tensor) -> np.ndarray:
    """(F,) bool: frames whose thumb (``positions``, (F, 21, 3)) is still off the curled fingers the source's rests
    on, or not across the palm where the source's lies across it (none where the source frames do not say where
    its thumb is)."""
    if source.thumb_rest is None:
        return np.zeros(len(positions), dtype=bool)
    with torch.no_grad():
        rest = thumb_rest_distances(positions, hand.hand_length).numpy()
        across = thumb_across(positions).numpy()
    curls, touches = np.degrees(source.curls.numpy()), _thumb_at_tips(source.gaps).numpy()
    return (thumb_rest_lost(curls, source.thumb_rest.numpy(), rest, touches)
            | thumb_across_lost(curls, source.thumb_rest.numpy(), touches, source.thumb_across.numpy(), across))


def _batches(runs: list[tuple[int, int]], batch_frames: int) -> list[list[tuple[int, int]]]:
    """Runs grouped so a group holds at most ``batch_frames`` frames; a longer run is cut into pieces (each
    piece's correction fades to zero at the cut: rare, a disagreement thousands of frames long)."""
    pieces = [(a, min(a + batch_frames, end)) for first, end in runs for a in range(first, end, batch_frames)]
    batches: list[list[tuple[int, int]]] = []
    size = batch_frames
    for piece in pieces:
        length = piece[1] - piece[0]
        if size + length > batch_frames:
            batches.append([])
            size = 0
        batches[-1].append(piece)
        size += length
    return batches


def _fit_runs(q: np.ndarray, source_frames: SourceFrames, lengths: list[int], hand: HandModel,
              config: ContactFitConfig) -> np.ndarray:
    """(F, 15, 4) rotations of the concatenated runs (``lengths`` frames each) after the fit."""
    source = source_frames.gaps
    with torch.no_grad():
        start = quat_to_tbs_euler_past_lock(torch.as_tensor(q, dtype=torch.float32))
        start_excess = angle_excess(start)  # what the retarget already has is not the fit's to undo
        # every angle stays within its limits, or no further out than the retarget's or the source's: the fit adds
        # no violation (L_ana alone let it twist and splay knuckles and the thumb MCP, 1-3% of the poses' angles)
        low, high = limits_reaching(start, *([] if source_frames.angles is None else [source_frames.angles]))
        start_positions = joint_positions(hand, torch.as_tensor(q, dtype=torch.float32))
        start_curls = pose_curls(start_positions)
        rate = torch.ones(len(q), *start.shape[1:])
        rate[:, 0] = config.thumb_cmc_rate
        rate[:, 0, 1] *= config.thumb_cmc_bend_rate
        if source_frames.thumb_out is not None:
            out_allowed, out_lost = _thumb_out_allowed(source_frames.thumb_out, thumb_out(start_positions), source)
            rate[out_lost, 0] = 1.0  # a thumb to bring out to its side turns at its metacarpal: not slowed
        if source_frames.thumb_rest is not None:
            resting = _thumb_resting(source_frames, source)
        if source_frames.thumb_across is not None:
            across_lost = torch.as_tensor(thumb_across_lost(
                np.degrees(source_frames.curls.numpy()), source_frames.thumb_rest.numpy(), _thumb_at_tips(source).numpy(),
                source_frames.thumb_across.numpy(), thumb_across(start_positions).numpy()))
        out_term = source_frames.thumb_out is not None and bool(torch.isfinite(out_allowed).any())
        rest_term = source_frames.thumb_rest is not None and bool(resting.any())
        across_term = source_frames.thumb_across is not None and bool(across_lost.any())
        palm_term = source_frames.palm_held is not None and bool(source_frames.palm_held.any())
    # each run's correction sits between two zero frames: second differences across them tie its ends
    # to zero, and no difference spans two runs
    offsets = np.cumsum([0] + [n + 2 for n in lengths[:-1]])
    slots = torch.as_tensor(np.concatenate([o + 1 + np.arange(n) for o, n in zip(offsets, lengths)]))
    padded_len = int(offsets[-1] + lengths[-1] + 2)
    correction = torch.zeros(len(q), *start.shape[1:], requires_grad=True)
    prior_scale = torch.ones(start.shape[1:])  # (joint, twist/bend/splay)
    prior_scale[0] = config.thumb_prior_weight  # the thumb CMC
    # its splay, the lift: a thumb lifted to meet a fingertip the source's reaches lying in the palm plane read
    # as not following (the gestures onto the mitten avatar: lift 0.71; 0.82 with it, the touches the same)
    prior_scale[0, 2] *= config.thumb_lift_weight
    prior_scale[1:3] *= config.thumb_hinge_prior_weight  # the thumb's MCP and IP
    optimiser = torch.optim.Adam([correction], lr=config.learning_rate)
    # Adam steps every angle alike whatever the gradient's scale, so the prior's weights alone set only where the
    # fit ends, not which joints it moves first: the CMC's angles are stepped at a share of the others' rate (`rate`)
    for step in range(config.steps):
        report(step / config.steps)  # and where a cancel stops the fit
        delta = correction * rate
        angles = start + delta
        positions = joint_positions(hand, tbs_euler_to_quat(angles))
        gaps = _pose_pad_gaps(hand, positions)
        padded = delta.new_zeros(padded_len, *delta.shape[1:]).index_copy(0, slots, delta)
        smooth = (padded[2:] - 2 * padded[1:-1] + padded[:-2]).square().sum((-1, -2)).mean()
        loss = (config.contact_weight * (contact_loss(gaps, source) + thumb_touch_loss(gaps, source))
                + config.anatomy_weight * torch.relu(angle_excess(angles) - start_excess).square().sum((-1, -2)).mean()
                + config.smoothness_weight * smooth
                + config.prior_weight * (delta.square() * prior_scale).sum((-1, -2)).mean()
                + config.sideways_weight * _sideways_excess(positions).square().sum(-1).mean())
        if source_frames.curls is not None:
            loss = loss + config.curl_weight * _curl_excess(pose_curls(positions), source_frames.curls,
                                                            start_curls).square().sum(-1).mean()
        # a term no frame of the batch needs is left out (it adds exact zeros, to the loss and to every gradient)
        if out_term:
            miss = torch.relu(source_frames.thumb_out - thumb_out(positions) - out_allowed)
            loss = loss + config.thumb_out_weight * miss.square().mean()
        if rest_term:
            miss = torch.relu(thumb_rest_distances(positions, hand.hand_length) - source_frames.thumb_rest
                              - 0.75 * THUMB_ON_MARGIN)
            loss = loss + config.thumb_rest_weight * (miss * resting).square().sum(-1).mean()
        if across_term:
            miss = torch.relu(source_frames.thumb_across - 0.5 * THUMB_ACROSS_MARGIN - thumb_across(positions))
            loss = loss + config.thumb_across_weight * (miss * across_lost).square().mean()
        if palm_term:
            miss = torch.relu(palm_gaps(hand, positions) / hand.hand_length - PALM_HOLD * CONTACT_TOLERANCE)
            loss = loss + config.palm_weight * (miss * source_frames.palm_held).square().sum(-1).mean()
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        with torch.no_grad():  # projected: the next step starts within the limits
            correction.copy_((clamp_angles(start + correction * rate, low, high) - start) / rate)
    with torch.no_grad():
        return tbs_euler_to_quat(start + correction * rate).numpy()
