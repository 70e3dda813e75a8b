"""How close a fit is to the truth it was recorded from (synthetic recordings: `tracking.synthetic`).

Positions are compared where they were recorded (the fitted hand placed by the fit's palm turn and wrist
path). Angles are compared as the same physical rotation: a fitted and a true joint rotation are each
measured in their own hand's canonical TBS frame, and those frames differ by a constant turn (how each
hand's frames are rolled about its bones), so the truth is conjugated into the fitted hand's frames first.
The thumb's canonical direction is a convention of the fit (keypoints cannot show a rest pose), so its
angles are listed apart."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rotations import quat_to_matrix
from s2h_viewer.semantics.metrics import jitter
from s2h_viewer.tracking.fitter import TrackingFit
from s2h_viewer.tracking.synthetic import placed_joints


@dataclass(frozen=True)
class FitAccuracy:
    position_mm_mean: float  # fitted joints vs true joints, where they were recorded
    position_mm_max: float
    finger_deg_mean: float  # the 12 finger joints' TBS rotations vs the truth's
    finger_deg_max: float
    thumb_deg_mean: tuple[float, float, float]  # thumb CMC, MCP, IP (see the module docstring)
    jitter_ratio: float  # the fit's jitter over the truth's


def compare_with_truth(fit: TrackingFit, hand: HandModel, motion: Motion, seed: int) -> FitAccuracy:
    """Compare ``fit`` of a recording that `synthetic_recording` made from ``motion`` on ``hand`` with
    ``seed`` (of either side: a left one is fitted as the right hand it mirrors) with that truth."""
    clean, _ = placed_joints(hand, motion, seed)
    fitted = forward_kinematics(fit.hand, fit.motion.q_tbs).positions.numpy().astype(np.float64)
    placed = fit.wrist[:, None] + np.einsum("tab,tjb->tja", fit.palm_rotation, fitted)
    error = np.linalg.norm(placed[:, 1:] - clean[:, 1:], axis=-1) * 1000.0
    true_frames = hand.palm_frame.T @ hand.canonical_frames
    fit_frames = fit.hand.palm_frame.T @ fit.hand.canonical_frames
    offset = np.einsum("jba,jbc->jac", fit_frames, true_frames)  # C_fit^T C_true
    truth = quat_to_matrix(torch.as_tensor(motion.q_tbs, dtype=torch.float64)).numpy()
    expected = offset @ truth @ offset.transpose(0, 2, 1)
    got = quat_to_matrix(torch.as_tensor(fit.motion.q_tbs, dtype=torch.float64)).numpy()
    cos = (np.einsum("tjab,tjab->tj", expected, got) - 1.0) / 2.0
    angle = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    truth_jitter = jitter(forward_kinematics(hand, motion.q_tbs), hand.hand_length)
    fit_jitter = jitter(forward_kinematics(fit.hand, fit.motion.q_tbs), fit.hand.hand_length)
    return FitAccuracy(float(error.mean()), float(error.max()), float(angle[:, 3:].mean()),
                       float(angle[:, 3:].max()), tuple(float(x) for x in angle[:, :3].mean(0)),
                       fit_jitter / max(truth_jitter, 1e-12))
