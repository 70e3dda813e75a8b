"""Recordings made from a motion on a known hand, where the truth is known: the hand placed and turned
smoothly in a room, its 21 joints taken as keypoints, with tracking noise, lost frames and spikes as asked.
For tests, benchmarks and trying the tracking path (never from real recordings)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.mirror import reflection
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.tracking.recording import KeypointRecording


def placed_joints(hand: HandModel, motion: Motion, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(T, 21, 3) the motion's joints in a room (metres) and (T, 21, 3, 3) their TBS frames there: the hand
    turning up to ~25 deg and drifting ~10 cm, smoothly, around a random pose at chest height."""
    rng = np.random.default_rng(seed)
    pose = forward_kinematics(hand, motion.q_tbs)
    t = np.arange(motion.n_frames)[:, None] / motion.fps
    turn = Rotation.from_rotvec(rng.normal(0, 1, 3) + 0.4 * np.sin(2 * np.pi * 0.3 * t + rng.uniform(0, 6, 3)))
    place = np.array([0.1, 1.2, -0.3]) + 0.1 * np.sin(2 * np.pi * 0.25 * t + rng.uniform(0, 6, 3))
    rotation = turn.as_matrix()
    joints = np.einsum("tab,tjb->tja", rotation, pose.positions.numpy().astype(np.float64)) + place[:, None]
    frames = np.einsum("tab,tjbc->tjac", rotation, pose.frames.numpy().astype(np.float64))
    return joints, frames


def synthetic_recording(hand: HandModel, motion: Motion, noise_mm: float = 0.0, lost: float = 0.0,
                        spikes: float = 0.0, side: str = "right", seed: int = 0) -> KeypointRecording:
    """A recording of ``motion`` on ``hand``: ``noise_mm`` RMS 3D error per keypoint (isotropic Gaussian),
    a fraction ``lost`` of frames lost (in runs of 1-8), a fraction ``spikes`` with one keypoint thrown
    3-6 cm; ``side="left"`` records the mirror image (a left hand)."""
    rng = np.random.default_rng(seed + 1)
    joints, frames = placed_joints(hand, motion, seed)
    n = len(joints)
    joints = joints + rng.normal(0.0, noise_mm / 1000.0 / np.sqrt(3.0), joints.shape)
    for frame in rng.choice(n, int(spikes * n), replace=False):
        direction = rng.normal(size=3)
        joints[frame, rng.integers(1, 21)] += direction / np.linalg.norm(direction) * rng.uniform(0.03, 0.06)
    missing = np.zeros(n, dtype=bool)
    while missing.mean() < lost:
        first = rng.integers(0, n)
        missing[first:first + rng.integers(1, 9)] = True
    joints[missing] = np.nan
    orientations = frames
    if side == "left":
        s = reflection((1.0, 0.0, 0.0))
        joints, orientations = joints @ s.T, s @ frames @ np.diag([1.0, -1.0, 1.0])
    orientations = orientations.copy()
    orientations[missing] = np.nan
    return KeypointRecording(positions=joints, fps=motion.fps, side=side, name=f"{motion.name}-on-{hand.name}",
                             format="synthetic", orientations=orientations, labels=motion.labels)
