"""Evaluation metrics between a source motion on hand A and its retarget on hand B (DESIGN.md section 5)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.chunks import frame_chunks
from s2h_viewer.hand.kinematics import HandPose, forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.semantics.anatomy import violation_rates
from s2h_viewer.semantics.asm import semantic_matrix
from s2h_viewer.semantics.contacts import (CONTACT_PAIRS, PAD_PAIRS, PALM_PAIRS, contact_precision_recall,
                                           detect_contacts, touching_and_near)
from s2h_viewer.semantics.flexion import SidewaysPeak, sideways_peak, thumb_follow
from s2h_viewer.semantics.signature import (SIDEWAYS_FLEXION, pose_loss_masks, sideways_anywhere, sideways_broken,
                                            sideways_there)
from s2h_viewer.semantics.similarity import masked_cosine
from s2h_viewer.wording import counted

#: frames whose ASMs are built at once when a whole clip is scored ((4096, 20, 29, 3) float64: 57 MiB)
ASM_CHUNK_FRAMES = 4096


def per_joint_cosine(d_source: torch.Tensor, d_target: torch.Tensor) -> torch.Tensor:
    """(T, 20, 29) cosine per ASM cell, NaN where masked: the viewer's heatmap source."""
    cos, valid = masked_cosine(d_source, d_target)
    return torch.where(valid, cos, torch.full_like(cos, float("nan")))


def palm_and_finger_scores(d_source: torch.Tensor, d_target: torch.Tensor) -> tuple[float, float, float]:
    """S_palm (mean cosine over the 9 anchor columns), S_finger (over the 20 finger columns, masked cells
    left out) and the paper-compatible S_finger (the official code's: masked cells count as cosine 0,
    so a hand compared with itself scores 0.95)."""
    cos, valid = masked_cosine(d_source, d_target)
    finger = slice(0, topo.N_FINGER_JOINTS)
    anchors = slice(topo.N_FINGER_JOINTS, None)
    s_palm = cos[..., anchors].sum() / valid[..., anchors].sum()
    s_finger = cos[..., finger].sum() / valid[..., finger].sum()
    return float(s_palm), float(s_finger), float(cos[..., finger].mean())


def joint_position_mse(pose: HandPose, reference: HandPose, hand_length: float) -> float:
    """Mean squared finger-joint position error, positions in units of the hand's length."""
    diff = (pose.finger_positions - reference.finger_positions) / hand_length
    return float(diff.square().sum(-1).mean())


def jitter(pose: HandPose, hand_length: float) -> float:
    """Mean norm of the second difference of finger-joint positions (hand lengths per frame^2)."""
    x = pose.finger_positions / hand_length
    if x.shape[0] < 3:
        return 0.0
    return float((x[2:] - 2 * x[1:-1] + x[:-2]).norm(dim=-1).mean())


@dataclass
class RetargetScores:
    """One retargeted clip's scores; ``mse`` only where a paired ground truth exists; a contact score over no
    contacts is NaN (`contact_precision_recall`)."""

    s_palm: float
    s_finger: float
    s_finger_paper: float  # the official code's S_finger (zero diagonal counted), for the paper's Table 1
    contact_precision: float  # fingertip pad pairs (DESIGN.md section 5)
    contact_recall: float
    palm_contact_recall: float  # fingertips on the palm (our extension; a fist's, say)
    violation_rate: float
    jitter: float
    mse: float | None = None
    #: the retarget's worst sideways flexion at its tightest curls (`semantics.flexion`), degrees (NaN: no
    #: finger curls), where it is ("ring_dip@212") and the source's own figure, for comparison
    sideways_deg: float = float("nan")
    sideways_at: str = ""
    source_sideways_deg: float = float("nan")
    #: the source's sideways bend at that joint and frame (NaN: it flexes too little there to have an axis)
    source_sideways_there: float = float("nan")
    #: the worst sideways bend of a PIP/DIP flexed 45 deg or more anywhere (`signature.sideways_anywhere`: the
    #: viewer's sideways curve's peak, which the tightest curls may leave out) and where it is
    sideways_anywhere_deg: float = float("nan")
    sideways_anywhere_at: str = ""
    #: the source's sideways bend at that joint and frame (the authored Sign 3 bends the pinky PIP 64 there itself)
    source_sideways_anywhere_there: float = float("nan")
    #: share of frames whose signature (`semantics.signature.loss_masks`: each finger extended, bent or curled,
    #: the thumb's touches, a thumb out to its side where the source's is, no finger bending sideways, no invented
    #: pad contact) is the source's: it drops where
    #: one finger is visibly wrong, which the clip-wide S_finger averages away
    signature_kept: float = float("nan")
    #: frames where the retarget makes a contact (any of the 15 pairs) the source does not come near
    #: (`contacts.touching_and_near`), and per pair invented, most frames first: its name, frames and first frame
    #: (("thumb-middle", 30, 120), ...): a fix that invents a pair on frames already counted shows there
    invented_contacts: int = 0
    invented_pairs: tuple[tuple[str, int, int], ...] = ()
    #: the least correlation, over the thumb's angles that move in the source (the CMC's two, the MCP's and IP's
    #: bends), of an angle with the source's (`semantics.flexion.thumb_follow`; NaN: the source's thumb stays
    #: still) and that angle ("thumb_ip", "thumb_cmc_lift")
    thumb_follow: float = float("nan")
    thumb_follow_at: str = ""
    #: the source's own violation rate: a clip authored past the limits (the authored poses' 0.625) keeps past
    #: them on any target, and a retarget's figure reads against it
    source_violation_rate: float = float("nan")
    #: the violations the retarget adds: (frame, joint) angles further outside the limits than the source's own
    #: (`semantics.anatomy.violation_rates`; the same as ``violation_rate`` where the source keeps within them)
    added_violation_rate: float = float("nan")

    def as_dict(self) -> dict:
        return asdict(self)

    def sideways_words(self, pose_at=lambda frame: "") -> str:
        """The worst sideways bend in words, with the source's there and the curve's peak where that is worse:
        "pinky PIP bends 59 deg sideways at frame 557, at that joint's tightest curls (the source bends 38 there; 38 at
        its own tightest curls); at any PIP/DIP flexed 45 deg or more: pinky PIP bends 85 deg sideways at frame 560
        (Sign 3), where the source bends 64".
        ``pose_at(frame)``: the pose held there, as " (Sign 3)", or "" (`Motion.held_at`)."""
        if np.isnan(self.sideways_deg):
            return "no finger curls (no sideways flexion to measure)"
        joint, _, frame = self.sideways_at.partition("@")
        there = ("the source does not flex it there" if np.isnan(self.source_sideways_there)
                 else f"the source bends {self.source_sideways_there:.0f} there")
        text = (f"{SidewaysPeak(self.sideways_deg, joint, int(frame)).describe()}{pose_at(int(frame))}, at that "
                f"joint's tightest curls ({there}; {self.source_sideways_deg:.0f} at its own tightest curls)")
        if self.sideways_anywhere_deg > self.sideways_deg + 0.5:
            joint, _, frame = self.sideways_anywhere_at.partition("@")
            text += (f"; at any PIP/DIP flexed {SIDEWAYS_FLEXION:.0f} deg or more: "
                     f"{SidewaysPeak(self.sideways_anywhere_deg, joint, int(frame)).describe()}{pose_at(int(frame))}, "
                     + ("where the source does not flex it" if np.isnan(self.source_sideways_anywhere_there)
                        else f"where the source bends {self.source_sideways_anywhere_there:.0f}"))
        return text

    def invented_words(self, listed: int = 5) -> str:
        """The frames with a contact the source does not make, and per pair (the first ``listed``) on how many frames
        from which: "22 frames with a contact the source does not make: index-palm on 22 frames (from 120)"."""
        pairs = self.invented_pairs
        if not self.invented_contacts:
            return "no contact the source does not make"
        named = ", ".join(f"{pair} on {counted(frames, 'frame')} (from {first})" for pair, frames, first in pairs[:listed])
        more = f", {len(pairs) - listed} more" if len(pairs) > listed else ""
        return f"{counted(self.invented_contacts, 'frame')} with a contact the source does not make: {named}{more}"

    @property
    def sideways_broken(self) -> bool:
        """Its worst sideways bend past the signature's limit and past the source's own + 5 (drawn red)."""
        return sideways_broken(self.sideways_deg, self.source_sideways_deg)


def score_retarget(source_hand: HandModel, source_q: np.ndarray | torch.Tensor, target_hand: HandModel,
                   target_q: np.ndarray | torch.Tensor, reference_q: np.ndarray | torch.Tensor | None = None
                   ) -> RetargetScores:
    """All metrics of one retarget: semantics against the source, MSE against ``reference_q`` if given."""
    return score_retarget_frames(source_hand, source_q, target_hand, target_q, reference_q)[0]


def score_retarget_frames(source_hand: HandModel, source_q: np.ndarray | torch.Tensor, target_hand: HandModel,
                          target_q: np.ndarray | torch.Tensor, reference_q: np.ndarray | torch.Tensor | None = None
                          ) -> tuple[RetargetScores, np.ndarray]:
    """`score_retarget`'s scores and the (T,) mean ASM error per frame (the error curve; its argmax is the
    worst frame). The ASMs are built a chunk of frames at a time, so a long clip's memory stays one chunk's."""
    with torch.no_grad():
        src_pose = forward_kinematics(source_hand, torch.as_tensor(np.asarray(source_q), dtype=torch.float64))
        tgt_q = torch.as_tensor(np.asarray(target_q), dtype=torch.float64)
        tgt_pose = forward_kinematics(target_hand, tgt_q)
        (s_palm, s_finger, s_finger_paper), frame_error = _asm_agreement(src_pose, tgt_pose)
        src_contacts, src_near = touching_and_near(source_hand, src_pose)
        tgt_contacts = detect_contacts(target_hand, tgt_pose)
        precision, recall = contact_precision_recall(src_contacts[:, PAD_PAIRS], tgt_contacts[:, PAD_PAIRS])
        palm_recall = contact_precision_recall(src_contacts[:, PALM_PAIRS], tgt_contacts[:, PALM_PAIRS])[1]
        mse = None
        if reference_q is not None:
            ref = forward_kinematics(target_hand, torch.as_tensor(np.asarray(reference_q), dtype=torch.float64))
            mse = joint_position_mse(tgt_pose, ref, target_hand.hand_length)
        peak = sideways_peak(tgt_pose.positions.numpy())
        anywhere = sideways_anywhere(tgt_pose.positions.numpy())
        kept = pose_loss_masks(source_hand, src_pose, target_hand, tgt_pose) == 0
        invented = tgt_contacts & ~src_near  # where the source's pair is apart, not nearly touching
        follow = {name: c for name, c in thumb_follow(src_pose.positions.numpy(), tgt_pose.positions.numpy()).items()
                  if not np.isnan(c)}
        worst_thumb = min(follow, key=follow.get, default="")
        source_violations, target_violations, added_violations = violation_rates(np.asarray(source_q), tgt_q)
        scores = RetargetScores(s_palm=s_palm, s_finger=s_finger, s_finger_paper=s_finger_paper,
                                contact_precision=precision, contact_recall=recall, palm_contact_recall=palm_recall,
                                violation_rate=target_violations, jitter=jitter(tgt_pose, target_hand.hand_length),
                                mse=mse, sideways_deg=peak.degrees, sideways_at=peak.where,
                                source_sideways_deg=sideways_peak(src_pose.positions.numpy()).degrees,
                                source_sideways_there=sideways_there(src_pose.positions.numpy(), peak.where),
                                sideways_anywhere_deg=anywhere.degrees, sideways_anywhere_at=anywhere.where,
                                source_sideways_anywhere_there=sideways_there(src_pose.positions.numpy(),
                                                                              anywhere.where),
                                signature_kept=float(kept.mean()), invented_contacts=int(invented.any(-1).sum()),
                                invented_pairs=invented_by_pair(invented),
                                thumb_follow=follow.get(worst_thumb, float("nan")), thumb_follow_at=worst_thumb,
                                source_violation_rate=source_violations, added_violation_rate=added_violations)
        return scores, frame_error


def invented_by_pair(invented: np.ndarray) -> tuple[tuple[str, int, int], ...]:
    """Per pair a (T, 15) invented-contact mask holds, most frames first: its name, frames and first frame."""
    counts = invented.sum(0)
    return tuple(("-".join(CONTACT_PAIRS[pair]), int(counts[pair]), int(np.argmax(invented[:, pair])))
                 for pair in np.argsort(-counts, kind="stable") if counts[pair])


def _asm_agreement(src_pose: HandPose, tgt_pose: HandPose) -> tuple[tuple[float, float, float], np.ndarray]:
    """`palm_and_finger_scores` over the whole clip and the (T,) mean ASM error per frame, summed chunk by chunk."""
    finger, anchors = slice(0, topo.N_FINGER_JOINTS), slice(topo.N_FINGER_JOINTS, None)
    sums = np.zeros(5)  # palm cosines, palm cells, finger cosines, finger cells, finger cells counting masked
    n_frames = src_pose.positions.shape[0]
    frame_error = np.zeros(n_frames)
    for first, end in frame_chunks(n_frames, ASM_CHUNK_FRAMES):
        cos, valid = masked_cosine(semantic_matrix(_frames(src_pose, first, end)),
                                   semantic_matrix(_frames(tgt_pose, first, end)))
        sums += [float(cos[..., anchors].sum()), float(valid[..., anchors].sum()), float(cos[..., finger].sum()),
                 float(valid[..., finger].sum()), cos[..., finger].numel()]
        cells = valid.flatten(1).sum(-1)
        error = ((1.0 - cos) * valid).flatten(1).sum(-1) / cells.clamp_min(1)
        frame_error[first:end] = error.numpy()
    return (float(sums[0] / sums[1]), float(sums[2] / sums[3]), float(sums[2] / sums[4])), frame_error


def _frames(pose: HandPose, first: int, end: int) -> HandPose:
    return HandPose(pose.positions[first:end], pose.frames[first:end])
