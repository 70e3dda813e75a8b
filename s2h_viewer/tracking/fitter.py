"""A recording becomes a source hand and its motion: `fit_recording`.

Steps (DESIGN.md section 9): outlying frames (bones far from their lengths, keypoints that jump away and
back) set aside with the lost ones; keypoints smoothed as their noise asks and gaps filled (`smoothing`);
the palm as a rigid template aligned to every frame (the wrist's path and turn taken out: motions here are
the fingers'); bone lengths as medians; each finger's hinge roll from how it bends; the hand built in its
canonical pose (`skeleton`); TBS angles by IK (`ik`). The residual is the mean distance (mm) from the fitted
joints to the recorded keypoints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.tracking import ik, skeleton, smoothing
from s2h_viewer.tracking.recording import KeypointRecording, right_handed

#: a frame whose bone is off its median length by more than this fraction is an outlier
BONE_TOLERANCE = 0.3
#: a keypoint further than this (and than SPIKE_SIGMAS noise) off the midpoint of its neighbours, and further
#: than they are off theirs, is an outlier (a smooth motion's midpoints are off by half its acceleration)
SPIKE_DISTANCE = 0.015  # metres
SPIKE_SIGMAS = 8.0
#: fingers whose chains are refined as a whole: the thumb, whose base a tracker moves and the fitted palm
#: keeps fixed (the others' bones, aimed from where their parent put them, already meet the keypoints)
REFINED_FINGERS = (0,)
#: candidate rolls (deg) of the thumb's frames and of each finger's (as many of each)
ROLL_STEP_DEG = 2.5
ROLL_SAMPLE = 250  # frames the rolls are judged on (every k-th)
THUMB_ROLLS_DEG = np.arange(40.0, 110.1, ROLL_STEP_DEG)
FINGER_ROLLS_DEG = np.linspace(-25.0, 25.0, len(THUMB_ROLLS_DEG))
HINGE_ROLLS_DEG = np.arange(-10.0, 10.1, 1.0)  # a hinge's roll against the joint above it


@dataclass(eq=False)
class TrackingFit:
    """What fitting a recording gave, for the viewer and the reports (all in the fitted hand's space)."""

    hand: HandModel  # the source hand (right-hand convention, as every HandModel)
    motion: Motion
    keypoints: np.ndarray  # (T, 21, 3) the recorded keypoints in hand space, NaN on lost frames
    palm_rotation: np.ndarray  # (T, 3, 3) hand space -> the recording's axes (the wrist's turn, smoothed)
    wrist: np.ndarray  # (T, 3) the wrist's path in the recording's space (smoothed; filled where lost)
    residual_mm: np.ndarray  # (T,) mean joint distance fit -> keypoints, NaN on lost and outlying frames
    filled: np.ndarray  # (T,) True where the frame was lost or outlying and is interpolated
    lost: np.ndarray  # (T,) True where the recording had no hand
    noise_mm: float  # the tracking noise estimated per coordinate
    notes: list[str]

    def describe(self) -> str:
        """One line for a report: how the fit went."""
        s = self.summary
        return (f"fitted to a {self.motion.n_frames}-frame recording ({self.motion.n_frames - s['lost_frames']} "
                f"tracked): residual {s['residual_mm_mean']} mm mean, {s['residual_mm_max']} mm max; "
                f"{s['filled_frames']} frames filled ({s['lost_frames']} lost, the rest outliers); "
                + "; ".join(self.notes))

    @property
    def summary(self) -> dict:
        """JSON-safe figures for the motion's provenance."""
        r = self.residual_mm[np.isfinite(self.residual_mm)]
        return {"residual_mm_mean": round(float(r.mean()), 3) if len(r) else None,
                "residual_mm_max": round(float(r.max()), 3) if len(r) else None,
                "filled_frames": int(self.filled.sum()), "lost_frames": int(self.lost.sum()),
                "noise_mm": round(float(self.noise_mm), 3), "notes": list(self.notes)}


def _outliers(hand_space: np.ndarray, valid: np.ndarray, sigma: float) -> np.ndarray:
    """(T,) tracked frames that do not fit the rest: a bone off its length, or a keypoint spike."""
    out = np.zeros(len(valid), dtype=bool)
    idx = np.flatnonzero(valid)
    x = hand_space[idx]
    lengths = np.linalg.norm(x - x[:, np.maximum(topo.PARENTS, 0)], axis=-1)[:, 1:]
    median = np.median(lengths, axis=0)
    outlying = (np.abs(lengths - median) > BONE_TOLERANCE * median + 6.0 * sigma).any(1)
    if len(idx) >= 3:  # a keypoint far off the line between its neighbours, and further than they are off theirs
        off = np.linalg.norm(x[1:-1] - 0.5 * (x[:-2] + x[2:]), axis=-1)  # (n - 2, 21)
        padded = np.pad(off, ((1, 1), (0, 0)))
        peak = (off > padded[:-2]) & (off > padded[2:]) & (np.diff(idx, 2) == 0)[:, None]  # no gap between
        outlying[1:-1] |= (peak & (off > max(SPIKE_DISTANCE, SPIKE_SIGMAS * sigma))).any(1)
    out[idx[outlying]] = True
    return out


def _roll_errors(template: np.ndarray, lengths: np.ndarray, sample: np.ndarray, name: str, grid: np.ndarray
                 ) -> np.ndarray:
    """(candidates, 5, 2) each hinge's error (`ik.hinge_errors`) with the joints' frames rolled by ``grid``
    (candidates, 5, 3)."""
    errors = [ik.hinge_errors(ik.solve(skeleton.build_hand(template, lengths, name, rolls), sample, False))
              for rolls in grid]
    return np.where(np.isfinite(errors), errors, np.inf)


def _best(grid: np.ndarray, errors: np.ndarray, current: np.ndarray, level: int | None) -> np.ndarray:
    """(5, 3) rolls: per finger, the candidate with the least error (of both hinges, or of ``level``'s),
    where the candidates differ by more than a degree of error; elsewhere ``current``."""
    e = errors.sum(-1) if level is None else errors[..., level - 1]  # (candidates, 5)
    finite = np.isfinite(e)
    spread = np.where(finite, e, -np.inf).max(0) - np.where(finite, e, np.inf).min(0)
    telling = finite.all(0) & (spread > math.radians(1.0 if level is None else 0.2))
    chosen = grid[np.argmin(e, axis=0), np.arange(topo.N_FINGERS)]
    return np.where(telling[:, None], chosen, current)


def _finger_rolls(template: np.ndarray, lengths: np.ndarray, keypoints: np.ndarray, name: str,
                  thumb_roll: float | None = None) -> np.ndarray:
    """(5, 3) deg: each joint's frame roll about its bone, so that the hinges bend least sideways over (a
    sample of) the frames: a roll per finger on a coarse grid, then a fine one, then each hinge's own
    (the thumb's first joint at ``thumb_roll`` where the recording's axes gave it); the default where a
    finger bends too little to tell."""
    sample = keypoints[:: max(1, len(keypoints) // ROLL_SAMPLE)]
    rolls = np.repeat(np.array(skeleton.DEFAULT_ROLLS_DEG)[:, None], 3, axis=1)
    coarse = np.repeat(np.stack([THUMB_ROLLS_DEG, *[FINGER_ROLLS_DEG] * 4], axis=1)[:, :, None], 3, axis=2)
    rolls = _best(coarse, _roll_errors(template, lengths, sample, name, coarse), rolls, None)
    steps = np.linspace(-ROLL_STEP_DEG, ROLL_STEP_DEG, 11)[:, None, None]
    fine = rolls + steps
    rolls = _best(fine, _roll_errors(template, lengths, sample, name, fine), rolls, None)
    if thumb_roll is not None:
        rolls[0, 0] = thumb_roll
    for level in (1, 2):  # each hinge's own roll, relative to the joint above it
        offsets = np.zeros((len(HINGE_ROLLS_DEG), topo.N_FINGERS, 3))
        offsets[:, :, level:] = HINGE_ROLLS_DEG[:, None, None]
        grid = rolls + offsets
        rolls = _best(grid, _roll_errors(template, lengths, sample, name, grid), rolls, level)
    return rolls


def _thumb_roll_from_axes(axes: np.ndarray, hand: HandModel) -> float:
    """The thumb roll (deg) the recorded thumb CMC axes show (median over frames): the angle its bend axis
    is tilted from across the palm toward the palm, about its own bone."""
    from s2h_viewer.hand.canonical import palm_normal

    normal = palm_normal(hand.rest_positions)
    twist, bend = axes[..., 0], axes[..., 1]  # columns
    across = np.cross(normal, twist)
    across /= np.linalg.norm(across, axis=-1, keepdims=True).clip(1e-12)
    up = np.cross(twist, across)
    roll = np.degrees(np.arctan2(-np.einsum("tc,tc->t", bend, up), np.einsum("tc,tc->t", bend, across)))
    return float(np.median(roll))


def _keep_recorded_contacts(hand: HandModel, q: np.ndarray, keypoints: np.ndarray, use: np.ndarray) -> np.ndarray:
    """``q`` with the fingertip-pad contacts the keypoints show (and only those) held on the fitted hand: where
    the tracker moved a joint the fitted skeleton keeps fixed (a thumb's base, say) the chain alone cannot
    close a pinch (`retarget.contact_fit`, with the keypoints' own pad gaps as the source)."""
    import torch

    from s2h_viewer.retarget.contact_fit import fit_contacts_to_gaps, pad_gaps
    from s2h_viewer.semantics.contacts import pad_pair_gaps

    points = torch.as_tensor(keypoints, dtype=torch.float32)
    recorded = pad_pair_gaps(hand, points).numpy()
    recorded = recorded / hand.hand_length
    if not use.all():  # filled frames: the keypoints there are not recorded ones, the fit stands as it is
        recorded[~use] = pad_gaps(hand, q[~use])
    return fit_contacts_to_gaps(recorded, hand, q)


def fit_recording(recording: KeypointRecording, mesh: bool = True) -> TrackingFit:
    """Fit a source hand and its TBS motion to ``recording`` (see the module docstring); ``mesh`` also skins
    the fitted hand (for the viewer and pictures)."""
    positions, orientations = right_handed(recording)
    lost = ~recording.valid
    tracked = ~lost
    if tracked.sum() < 1:
        raise InputFileError(recording.name, "no frame holds a hand")
    flat = np.nan_to_num(positions).reshape(len(positions), -1)
    sigma = smoothing.estimate_noise(flat, tracked)
    outlying = _outliers(positions, tracked, sigma)
    use = tracked & ~outlying
    if not use.any():
        raise InputFileError(recording.name, f"all {int(tracked.sum())} tracked frames are outliers "
                                             f"(bones that change length, keypoints that jump)")
    if outlying.any():  # re-estimated without them
        sigma = smoothing.estimate_noise(flat, use)
    # smoothed where they were recorded (the wrist's path and turn with the fingers), gaps filled
    weights = use.astype(np.float64)
    lam = smoothing.choose_smoothing(flat, weights, sigma)
    world = smoothing.follow_fast_moves(flat, weights, lam, sigma).reshape(positions.shape)
    template = skeleton.palm_template(world[use])
    rotation = skeleton.align_palm(world, template)
    wrist = world[:, 0]
    smoothed = np.einsum("tca,tjc->tja", rotation, world - wrist[:, None])
    hand_space = np.einsum("tca,tjc->tja", rotation, positions - wrist[:, None])  # NaN where lost
    lengths = skeleton.bone_lengths(smoothed[use])
    thumb_roll = None
    if orientations is not None:  # the recorded thumb axes say how it is rolled
        cmc = np.einsum("tca,tcb->tab", rotation[use], orientations[use, topo.joint_index("thumb_cmc")])
        thumb_roll = _thumb_roll_from_axes(cmc, skeleton.build_hand(template, lengths, recording.name))
    rolls = _finger_rolls(template, lengths, smoothed[use], recording.name, thumb_roll)
    hand = skeleton.build_hand(template, lengths, recording.name, rolls, recording.radii,
                               source=f"{recording.format}:{recording.name}")
    angles = ik.refine_chains(hand, smoothed, ik.solve(hand, smoothed), REFINED_FINGERS)
    q = _keep_recorded_contacts(hand, ik.angles_to_quats(angles), smoothed, use)
    fitted = forward_kinematics(hand, q).positions.numpy().astype(np.float64)
    residual = np.full(len(positions), np.nan)
    residual[use] = np.linalg.norm(fitted[use, 1:] - hand_space[use, 1:], axis=-1).mean(1) * 1000.0
    filled = ~use
    notes = list(recording.notes) + ["hinge rolls (deg; thumb, index, middle, ring, pinky; each knuckle/middle/"
                                     "end joint) " + ", ".join("/".join(f"{r:.0f}" for r in finger)
                                                               for finger in rolls),
                                     f"noise {sigma * 1000:.2f} mm"]
    if recording.side == "left":
        notes.append("left hand: fitted as its mirror image (right-hand convention), as every left hand")
    labels = recording.labels if recording.labels is not None else np.where(filled, "(filled)", "")
    motion = Motion(q_tbs=q, fps=recording.fps, name=recording.name, hand_name=hand.name, labels=labels,
                    meta={"tracked": {"format": recording.format, "side": recording.side}})
    if mesh:
        from s2h_viewer.hand.hand_mesh import build_hand_mesh
        hand.mesh = build_hand_mesh(hand)
    fit = TrackingFit(hand=hand, motion=motion, keypoints=hand_space, palm_rotation=rotation, wrist=wrist,
                      residual_mm=residual, filled=filled,
                      lost=lost, noise_mm=sigma * 1000.0, notes=notes)
    motion.meta["tracked"] |= fit.summary
    motion.fit = fit
    return fit
