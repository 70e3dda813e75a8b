"""Issue 26, item 3: ASRN trains on random key poses over the whole pose space as well as on the gesture
scripts; the poses are anatomical, varied finger by finger, and make the contacts they are labelled with."""

from __future__ import annotations

import numpy as np
import torch

from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.rotations import tbs_euler_to_quat
from s2h_viewer.motions.fitting import fit_gesture_angles
from s2h_viewer.motions.pose_space import random_key_pose, random_pose_motion
from s2h_viewer.retarget.asrn.dataset import build_training_set
from s2h_viewer.retarget.asrn.inference import MODELS_DIR
from s2h_viewer.retarget.asrn.training import default_config, load_checkpoint, stored_config
from s2h_viewer.semantics.anatomy import violation_rate
from s2h_viewer.semantics.contacts import CONTACT_TOLERANCE, contact_gaps, pair_index
from s2h_viewer.semantics.signature import finger_curls


def test_random_poses_cover_the_pose_space_finger_by_finger(sample_hands):
    """200 keys fitted to a hand: inside the limits, each finger from straight to curled on its own (the fingers'
    curls far from moving together as in the library's gestures), spreads both ways, and the thumb opposed to
    every fingertip, the labelled touches made on most keys."""
    hand = sample_hands["birch"]
    rng = np.random.default_rng(7)
    poses = [random_key_pose(rng) for _ in range(200)]
    q = tbs_euler_to_quat(torch.as_tensor(fit_gesture_angles(hand, poses)))
    assert violation_rate(q) == 0.0
    positions = forward_kinematics(hand, q).positions.numpy()
    curls = finger_curls(positions)  # (K, 4) summed curl per finger, degrees
    assert (curls.min(0) < 40).all() and (curls.max(0) > 200).all()
    correlation = np.corrcoef(curls.T)[np.triu_indices(4, 1)]
    assert correlation.max() < 0.8, correlation
    splay = np.stack([p.angles_deg[3::3, 2] for p in poses])
    assert (splay.min(0) < -10).all() and (splay.max(0) > 10).all()
    gaps = (contact_gaps(hand, forward_kinematics(hand, q)) / hand.hand_length).numpy()
    for finger in ("index", "middle", "ring", "pinky"):
        pair = pair_index("thumb", finger)
        opposed = [k for k, p in enumerate(poses) if ("thumb", finger) in p.contacts]
        assert len(opposed) >= 8, finger
        assert (gaps[opposed, pair] < CONTACT_TOLERANCE).mean() >= 0.75, finger
        others = [k for k, p in enumerate(poses) if ("thumb", finger) not in p.contacts]
        assert (gaps[others, pair] < CONTACT_TOLERANCE).mean() <= 0.05, finger


def test_a_random_pose_clip_is_seeded_and_moves_between_its_keys(sample_hands):
    hand = sample_hands["cedar"]
    first, again = random_pose_motion(hand, 6, seed=3), random_pose_motion(hand, 6, seed=3)
    np.testing.assert_array_equal(first.q_tbs, again.q_tbs)
    assert not np.array_equal(first.q_tbs, random_pose_motion(hand, 6, seed=4).q_tbs)
    assert len(set(first.labels) - {""}) == 6 and violation_rate(first.q_tbs) == 0.0


def test_the_random_poses_widen_the_training_set_and_leave_the_gesture_clips_as_they_were(sample_hands):
    """DM's training (no random poses) stays what `make train` reproduces: the gesture clips are the same with or
    without the random-pose clips beside them."""
    hands = [sample_hands["birch"], sample_hands["laurel"]]
    plain = build_training_set("asrn", hands, scripts_per_hand=1, gestures_per_script=4, seed=2)
    wide = build_training_set("asrn", hands, scripts_per_hand=1, gestures_per_script=4, seed=2,
                              pose_scripts_per_hand=1)
    assert len(wide.clips) == 2 * len(plain.clips)
    gesture_clips = [c for i, c in enumerate(wide.clips) if i % 2 == 0]
    for a, b in zip(plain.clips, gesture_clips):
        torch.testing.assert_close(a.q, b.q, rtol=0, atol=0)
    assert default_config("asrn").pose_scripts_per_hand > 0 and default_config("dm").pose_scripts_per_hand == 0
    shipped = stored_config(load_checkpoint(MODELS_DIR / "asrn.pt"))
    assert shipped == default_config("asrn", steps=shipped.steps)
    assert stored_config(load_checkpoint(MODELS_DIR / "dm.pt")).pose_scripts_per_hand == 0
