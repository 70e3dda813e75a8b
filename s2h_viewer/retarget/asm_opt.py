"""ASM-Opt: per-sequence gradient optimisation of the target's TBS rotations (DESIGN.md section 6).

Variables: a correction of the per-joint TBS Euler angles (twist, bend, splay) on every
``keyframe_step``-th frame and on the frames either side of every change in the source's contacts (a
touch shorter than the step must not fall between keyframes), added to the warm start (TBS Copy) and interpolated
linearly in between, so the warm start's detail is kept and the loss is evaluated on the keyframes
only. Loss: -L_sem (match the source's ASM) + L_ana (stay anatomical) +
temporal smoothness of the correction + a contact term that goes beyond the paper: pairs touching in
the source are pulled to touch on the target and pairs apart are kept apart, gaps measured in each
hand's own length. The anatomy term is taken on the angles themselves (smooth past a 90 deg bend; the warm
start read with the twist within +-90 deg, so a knuckle bent past 90 is a bend, not a twisted finger) and
the result's bends are clamped into their limits. Long clips go in overlapping chunks,
cross-faded at the seams (`retarget.windows`). No training.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rotations import quat_to_tbs_euler_past_lock, tbs_euler_to_quat
from s2h_viewer.retarget.contact_fit import fit_contacts
from s2h_viewer.retarget.methods import on_target, register
from s2h_viewer.retarget.progress import report, stage
from s2h_viewer.retarget.threads import torch_threads
from s2h_viewer.retarget.windows import stream_windows
from s2h_viewer.semantics.anatomy import angle_loss, clamp_bends
from s2h_viewer.semantics.asm import semantic_matrix, semantic_matrix_by_axis
from s2h_viewer.semantics.contacts import CONTACT_TOLERANCE, contact_gaps, contact_loss
from s2h_viewer.semantics.similarity import SourceSemantics


@dataclass(frozen=True)
class AsmOptConfig:
    steps: int = 60
    learning_rate: float = 0.02
    keyframe_step: int = 3
    semantic_weight: float = 5.0
    anatomy_weight: float = 10.0
    smoothness_weight: float = 20.0
    contact_weight: float = 2e3
    prior_weight: float = 0.01  # pull toward the warm start (TBS Copy), keeps the unconstrained DOF put
    repair_steps: int = 15  # steps on the frames between keys that lost a source contact, keyed, alone
    chunk: int = 2048  # frames optimised together; a longer clip goes in chunks (memory of one chunk). A step
    # costs mostly per-op overhead, so one long chunk is faster than several short ones
    chunk_overlap: int = 64  # frames two chunks share, cross-faded so there is no seam


def keyframes(n_frames: int, step: int) -> np.ndarray:
    """Every ``step``-th frame index, and the last frame."""
    return np.unique(np.r_[np.arange(0, n_frames, step), n_frames - 1])


def contact_keyframes(touching: np.ndarray, step: int) -> np.ndarray:
    """`keyframes`, and the frames either side of every change in the source's contacts ((T, pairs) bools):
    a touch shorter than the step still lands on keys (its first frame, and the frame after it ends),
    while a long hold is keyed every ``step`` frames like the rest of the clip.

    Keying every contact frame instead put the keys one frame apart over long holds (781 keys for
    1,000 frames of the sample clips, 334 on the grid), where the smoothness term, a second difference
    over consecutive keys, holds each frame far more loosely: jitter rose, pads the source keeps apart
    were closed on the WebXR hand (contact precision 0.57 on its counting clip, 1.00 with keys at the
    changes) and every step cost twice as much."""
    changes = np.flatnonzero((touching[1:] != touching[:-1]).any(-1)) + 1
    return np.union1d(keyframes(len(touching), step), np.r_[changes - 1, changes])


def interpolate_keys(values: torch.Tensor, keys: np.ndarray, n_frames: int) -> torch.Tensor:
    """(K, ...) values at frames ``keys`` (increasing, first 0, last ``n_frames - 1``) -> (n_frames, ...)
    linearly interpolated between them."""
    if len(keys) == 1:
        return values[:1].expand(n_frames, *values.shape[1:])
    frames = np.arange(n_frames)
    left = np.clip(np.searchsorted(keys, frames, side="right") - 1, 0, len(keys) - 2)
    t = (frames - keys[left]) / (keys[left + 1] - keys[left])
    t = torch.as_tensor(t, dtype=values.dtype).reshape(-1, *[1] * (values.ndim - 1))
    return values[left] + t * (values[left + 1] - values[left])


def optimise_asm(source_q: np.ndarray, source_hand: HandModel, target_hand: HandModel,
                 initial_q: np.ndarray | None = None, config: AsmOptConfig = AsmOptConfig()) -> np.ndarray:
    """(T, 15, 4) target TBS rotations whose ASM matches the source's: each chunk of `AsmOptConfig.chunk`
    frames optimised on its own (batched over its frames), chunks cross-faded over ``chunk_overlap``
    frames, so memory stays that of one chunk however long the clip."""
    source_q = np.asarray(source_q, dtype=np.float32)
    initial_q = source_q if initial_q is None else np.asarray(initial_q, dtype=np.float32)
    n_frames = len(source_q)
    chunk = min(config.chunk, n_frames)
    out = np.empty_like(source_q)

    def run(starts: list[int], first: int, end: int) -> np.ndarray:
        return np.stack([_optimise_chunk(source_q[s:s + chunk], source_hand, target_hand, initial_q[s:s + chunk],
                                         config) for s in starts])

    def finish(first: int, end: int, angles: np.ndarray) -> None:
        out[first:end] = tbs_euler_to_quat(torch.as_tensor(angles, dtype=torch.float32)).numpy()

    stream_windows(n_frames, chunk, min(config.chunk_overlap, chunk - 1), run, finish, windows_per_batch=1)
    return out


def _optimise_chunk(source_q: np.ndarray, source_hand: HandModel, target_hand: HandModel, initial_q: np.ndarray,
                    config: AsmOptConfig) -> np.ndarray:
    """(T, 15, 3) optimised TBS Euler angles of one chunk, warm-started from ``initial_q``; batched over
    its keyframes."""
    with torch_threads(1):
        return _optimise_keyframes(source_q, source_hand, target_hand, initial_q, config)


@dataclass(frozen=True)
class _Keyed:
    """What the loss compares on a set of keyframes: the warm start's angles, the source's semantics and gaps."""

    keys: np.ndarray
    start: torch.Tensor  # (K, 15, 3)
    source: SourceSemantics
    source_gaps: torch.Tensor  # (K, 15) in hand lengths


def _optimise_keyframes(source_q: np.ndarray, source_hand: HandModel, target_hand: HandModel,
                        initial_q: np.ndarray, config: AsmOptConfig) -> np.ndarray:
    """`_optimise_chunk` on the current thread settings.

    After the steps, frames between two touching keys where the source touches and the interpolated
    result does not (inside a long hold the warm start can drift apart) become keys too,
    and `AsmOptConfig.repair_steps` more steps move those alone (moving every key again lowered the
    semantics and the precision on the WebXR hands)."""
    n_frames = len(source_q)
    with torch.no_grad():
        src_pose = forward_kinematics(source_hand, torch.as_tensor(source_q, dtype=torch.float32))
        source_gaps = contact_gaps(source_hand, src_pose) / source_hand.hand_length
        touching = source_gaps < CONTACT_TOLERANCE
        source = SourceSemantics.of(semantic_matrix(src_pose))
        start = quat_to_tbs_euler_past_lock(torch.as_tensor(initial_q, dtype=torch.float32))

    def at(keys: np.ndarray) -> _Keyed:
        return _Keyed(keys, start[keys], SourceSemantics(source.directions[keys], source.weights[keys]),
                      source_gaps[keys])

    keyed = at(contact_keyframes(touching.numpy(), config.keyframe_step))
    correction = _descend(keyed, target_hand, torch.zeros(len(keyed.keys), *start.shape[1:]), config,
                          config.steps)
    lost = _lost_between_keys(target_hand, start + interpolate_keys(correction, keyed.keys, n_frames), touching,
                              keyed.keys)
    if len(lost):
        keys = np.union1d(keyed.keys, lost)
        correction = interpolate_keys(correction, keyed.keys, n_frames)[keys]
        keyed = at(keys)
        correction = _descend(keyed, target_hand, correction, config, config.repair_steps,
                              free=torch.as_tensor(np.isin(keys, lost))[:, None, None])
    with torch.no_grad():
        return clamp_bends(start + interpolate_keys(correction, keyed.keys, n_frames)).numpy()


def _descend(keyed: _Keyed, target_hand: HandModel, correction: torch.Tensor, config: AsmOptConfig, steps: int,
             free: torch.Tensor | None = None) -> torch.Tensor:
    """``correction`` (K, 15, 3) after ``steps`` of Adam on `_loss`, only the keys where ``free`` (K, 1, 1)
    is True moving if it is given (the repair, reported as the chunk's end)."""
    correction = correction.detach().clone().requires_grad_()
    optimiser = torch.optim.Adam([correction], lr=config.learning_rate)
    for step in range(steps):
        report(1.0 if free is not None else step / steps)  # progress, and where a cancel stops it
        loss = _loss(keyed, target_hand, correction, config)
        optimiser.zero_grad()
        loss.backward()
        if free is not None:
            correction.grad.mul_(free)
        optimiser.step()
    return correction.detach()


def _lost_between_keys(target_hand: HandModel, angles: torch.Tensor, touching: torch.Tensor,
                       keys: np.ndarray) -> np.ndarray:
    """Frames between keys where the source touches ((T, pairs) bools) and the target in ``angles``
    (T, 15, 3) does not, though it does on the keys either side: contacts the interpolation lost (not
    those the target cannot make at all, as a fist onto the WebXR hand's palm)."""
    with torch.no_grad():
        gaps = contact_gaps(target_hand, forward_kinematics(target_hand, tbs_euler_to_quat(angles)))
    target_touching = (gaps < CONTACT_TOLERANCE * target_hand.hand_length).numpy()
    left = np.clip(np.searchsorted(keys, np.arange(len(angles)), side="right") - 1, 0, len(keys) - 1)
    right = np.clip(left + 1, 0, len(keys) - 1)
    lost = touching.numpy() & ~target_touching & target_touching[keys[left]] & target_touching[keys[right]]
    return np.setdiff1d(np.flatnonzero(lost.any(-1)), keys)


def _loss(keyed: _Keyed, target_hand: HandModel, correction: torch.Tensor, config: AsmOptConfig) -> torch.Tensor:
    """ASM-Opt's loss on the keyframes for the correction (K, 15, 3) of the warm start's angles."""
    angles = keyed.start + correction
    pose = forward_kinematics(target_hand, tbs_euler_to_quat(angles))
    sem = keyed.source.similarity_by_axis(semantic_matrix_by_axis(pose))
    gaps = contact_gaps(target_hand, pose) / target_hand.hand_length
    contact = contact_loss(gaps, keyed.source_gaps)
    smooth = (correction[2:] - 2 * correction[1:-1] + correction[:-2]).square().sum((-1, -2)).mean() \
        if len(correction) > 2 else correction.new_zeros(())
    anatomy = angle_loss(angles)
    return (-config.semantic_weight * sem + config.anatomy_weight * anatomy
            + config.smoothness_weight * smooth + config.contact_weight * contact
            + config.prior_weight * correction.square().sum((-1, -2)).mean())


@register("asm_opt", "ASM-Opt", "optimise the target pose per clip to match the source's semantics (no training), "
                                "its pad contacts then fitted to the source's")
def retarget_asm_opt(motion: Motion, source_hand: HandModel, target_hand: HandModel) -> Motion:
    with stage(0.0, 0.9, "optimise"):
        q = optimise_asm(motion.q_tbs, source_hand, target_hand)
    with stage(0.9, 1.0, "contact fit"):
        # the ASM pulls pads near each other where they only come close (the WebXR left hand: precision
        # 0.62 on the counting clip); the contact fit opens them, as it does for ASRN (1.00)
        q = fit_contacts(motion.q_tbs, source_hand, target_hand, q)
    return on_target(motion, target_hand, q, "asm_opt")
