"""FK, rotation conventions, rig-local conversions, mirroring and skinning."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation

from conftest import random_tbs_motion
from s2h_viewer.errors import InvalidHandError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import (forward_kinematics, identity_motion, joint_positions, rest_motion,
                                        rig_local_to_tbs, tbs_to_rig_local)
from s2h_viewer.hand.mirror import mirror_hand, mirror_motion
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.hand.rotations import (matrix_to_tbs_euler, quat_angle, quat_multiply, quat_to_matrix,
                                       quat_to_tbs_euler, quat_to_tbs_euler_past_lock, random_quats,
                                       tbs_euler_to_quat)
from s2h_viewer.hand.skinning import skin_vertices
from s2h_viewer.semantics.reference import fk_frame

BONE = (0.025, 0.02, 0.015)  # phalanx lengths of the straight test hand


def straight_hand() -> HandModel:
    """Five straight fingers along +x, identity TBS and rig frames: easy to compute by hand."""
    offsets = np.zeros((21, 3))
    for f in range(5):
        offsets[1 + 4 * f] = [0.08, 0.04 - 0.02 * f, 0.0]
        offsets[2 + 4 * f: 5 + 4 * f, 0] = BONE
    return HandModel(name="straight", offsets=offsets, rest_frames=np.tile(np.eye(3), (15, 1, 1)),
                     rig_frames=np.tile(np.eye(3), (16, 1, 1)), radii=np.full(21, 0.008))


def test_fk_matches_a_hand_computed_chain():
    hand = straight_hand()
    q = identity_motion(1, torch.float64)
    index_mcp = 3 * 1  # articulated index of the index finger's MCP
    q[0, index_mcp] = torch.tensor([math.cos(math.pi / 4), 0, math.sin(math.pi / 4), 0])  # bend 90 deg
    q[0, index_mcp + 1] = q[0, index_mcp]  # PIP bends 90 deg too
    pose = forward_kinematics(hand, q)
    mcp = np.array([0.08, 0.02, 0.0])
    pip = mcp + [0, 0, -0.025]  # proximal phalanx now points to the palm side (-z)
    dip = pip + [-0.02, 0, 0]  # middle phalanx points back toward the wrist
    tip = dip + [-0.015, 0, 0]
    got = pose.positions[0, [5, 6, 7, 8]].numpy()
    np.testing.assert_allclose(got, [mcp, pip, dip, tip], atol=1e-12)
    np.testing.assert_allclose(pose.frames[0, 7].numpy(), Rotation.from_euler("y", 180, degrees=True).as_matrix(),
                               atol=1e-12)
    np.testing.assert_allclose(pose.frames[0, 8].numpy(), pose.frames[0, 7].numpy())  # tip takes its parent's


def test_the_rest_tbs_rotations_give_the_rest_pose(sample_hands):
    for hand in sample_hands.values():
        pose = forward_kinematics(hand, rest_motion(hand, 3, torch.float64))
        np.testing.assert_allclose(pose.positions[2].numpy(), hand.rest_positions, atol=1e-12)
        np.testing.assert_allclose(pose.frames[1, topo.ARTICULATED_JOINTS].numpy(), hand.rest_frames, atol=1e-12)


def test_batched_fk_equals_the_per_joint_reference(skeleton_hands, rng):
    q = random_tbs_motion(6, rng)
    for hand in skeleton_hands:
        pose = forward_kinematics(hand, q)
        for t in range(len(q)):
            positions, frames = fk_frame(hand, q[t].numpy())
            np.testing.assert_allclose(pose.positions[t].numpy(), positions, atol=1e-12)
            np.testing.assert_allclose(pose.frames[t].numpy(), frames, atol=1e-12)
        # the positions alone (the contact fit's FK), with their gradients
        np.testing.assert_allclose(joint_positions(hand, q).numpy(), pose.positions.numpy(), atol=1e-12)
        leaf = q.clone().requires_grad_(True)
        grads = [torch.autograd.grad(fk(hand, leaf).square().sum(), leaf)[0].numpy()
                 for fk in (joint_positions, lambda h, x: forward_kinematics(h, x).positions)]
        np.testing.assert_allclose(grads[0], grads[1], atol=1e-12)
        assert np.abs(grads[0]).sum() > 0


def test_tbs_rig_local_round_trip_on_random_rotations(skeleton_hands, rng):
    q = random_quats((200, 15), generator=rng)
    for hand in skeleton_hands:
        back = rig_local_to_tbs(hand, tbs_to_rig_local(hand, q))
        assert quat_angle(back, q).max() < 1e-5
    # and the rig-local rotation really is a different number on a rig whose bones are not TBS-aligned
    assert quat_angle(tbs_to_rig_local(skeleton_hands[1], q), q).mean() > 0.3


def test_rig_local_rotation_moves_the_rig_frame_as_tbs_moves_the_tbs_frame(skeleton_hands, rng):
    """Q = K R K^T must describe the same physical rotation: rotating the rig frame by Q in its parent's
    rig frame lands where the TBS frame lands, up to the rig's fixed offset from TBS."""
    hand = skeleton_hands[2]
    q = random_tbs_motion(1, rng)
    pose = forward_kinematics(hand, q)
    q_local = quat_to_matrix(tbs_to_rig_local(hand, q))[0].numpy()
    offset = hand.rest_frames.transpose(0, 2, 1) @ hand.rig_frames[1:]  # rig frame seen from the TBS frame
    for a in (0, 1, 4):  # thumb CMC (parent wrist), thumb MCP, index PIP
        parent_rot = topo.ARTICULATED_PARENT_ROTATING[a]
        parent_global = hand.rig_frames[0] if parent_rot == 0 else (
            pose.frames[0, topo.ARTICULATED_JOINTS[parent_rot - 1]].numpy() @ offset[parent_rot - 1])
        parent_rest = hand.rig_frames[parent_rot]
        rig_now = parent_global @ q_local[a] @ parent_rest.T @ hand.rig_frames[a + 1]
        np.testing.assert_allclose(rig_now, pose.frames[0, topo.ARTICULATED_JOINTS[a]].numpy() @ offset[a], atol=1e-6)


def test_pure_bend_of_40_degrees_decomposes_to_bend_only():
    q = tbs_euler_to_quat(torch.tensor([0.0, math.radians(40), 0.0], dtype=torch.float64))
    twist, bend, splay = quat_to_tbs_euler(q).tolist()
    assert math.degrees(bend) == pytest.approx(40.0, abs=1e-9)
    assert abs(twist) < 1e-9 and abs(splay) < 1e-9
    # the rotation is about the bend axis (y) and flexes the finger toward its pad (-z)
    r = quat_to_matrix(q).numpy()
    assert r[2, 0] < 0 and r[1, 1] == pytest.approx(1.0)


def test_tbs_euler_matches_scipy_intrinsic_xyz(rng):
    r = quat_to_matrix(random_quats((500,), generator=rng))
    ours = matrix_to_tbs_euler(r).numpy()
    theirs = Rotation.from_matrix(r.numpy()).as_euler("XYZ")  # intrinsic twist(x), bend(y), splay(z)
    np.testing.assert_allclose(ours, theirs, atol=1e-9)


def test_a_bend_past_90_degrees_reads_as_a_bend_not_a_twist(rng):
    """A knuckle of a fist bent 103 deg: the plain reading keeps the bend within 90 and turns it into a 160 deg
    twist and splay; the past-lock reading gives the angles it was made of, and every reading is the same rotation."""
    made = torch.tensor([math.radians(12.0), math.radians(103.0), math.radians(-8.0)], dtype=torch.float64)
    q = tbs_euler_to_quat(made)
    plain = torch.rad2deg(quat_to_tbs_euler(q))
    assert abs(plain[0]) > 150 and abs(plain[1]) < 90  # the same rotation, read as a twisted finger
    np.testing.assert_allclose(quat_to_tbs_euler_past_lock(q).numpy(), made.numpy(), atol=1e-9)
    many = random_quats((2000,), generator=rng)
    angles = quat_to_tbs_euler_past_lock(many)
    assert (angles[:, 0].abs() <= math.pi / 2 + 1e-9).all()
    assert quat_angle(tbs_euler_to_quat(angles), many).max() < 1e-6


def test_mirroring_twice_is_identity_and_keeps_the_pose(sample_hands, rng):
    hand = sample_hands["iris"]
    left = mirror_hand(hand, normal=(0.3, 1.0, 0.2))
    again = mirror_hand(left, normal=(0.3, 1.0, 0.2))
    np.testing.assert_allclose(again.offsets, hand.offsets, atol=1e-12)
    np.testing.assert_allclose(again.rest_frames, hand.rest_frames, atol=1e-12)
    np.testing.assert_allclose(again.mesh.vertices, hand.mesh.vertices, atol=1e-6)
    # the mirrored motion on the mirrored hand is the mirror image of the original posed hand
    motion = Motion(q_tbs=random_tbs_motion(4, rng).numpy())
    s = np.eye(3) - 2 * np.outer(*(2 * [np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])]))
    original = forward_kinematics(hand, motion.q_tbs.astype(np.float64)).positions.numpy()
    mirrored = forward_kinematics(left, mirror_motion(motion).q_tbs.astype(np.float64)).positions.numpy()
    np.testing.assert_allclose(mirrored, original @ s.T, atol=1e-6)


def test_skinning_the_rest_pose_is_rest_and_a_pure_bend_moves_only_that_finger(sample_hands):
    hand = sample_hands["kale"]
    rest = skin_vertices(hand, forward_kinematics(hand, rest_motion(hand, 1, torch.float64)))
    np.testing.assert_allclose(rest, hand.mesh.vertices, atol=1e-5)
    q = rest_motion(hand, 1, torch.float64)
    bend = tbs_euler_to_quat(torch.tensor([0.0, math.radians(80), 0.0], dtype=torch.float64))
    q[0, 3 * 2 + 1] = quat_multiply(q[0, 3 * 2 + 1], bend)
    moved = np.linalg.norm(skin_vertices(hand, forward_kinematics(hand, q)) - hand.mesh.vertices, axis=1)
    middle_distal = hand.mesh.weights[:, 1 + 3 * 2 + 1:1 + 3 * 2 + 3].sum(1) > 0.99  # middle PIP + DIP bones
    thumb = hand.mesh.weights[:, 1:4].sum(1) > 0.99
    assert moved[middle_distal].min() > 0.002  # the whole distal middle finger swings
    assert moved[thumb].max() < 1e-6  # the thumb does not move (float32 weights: nanometres at most)


@pytest.mark.parametrize("field,value,message", [
    ("offsets", np.full((21, 3), np.nan), "NaN"),
    ("rest_frames", np.zeros((14, 3, 3)), "shape"),
    ("rest_frames", np.tile(np.diag([1.0, 1.0, -1.0]), (15, 1, 1)), "right-handed"),
])
def test_invalid_hands_are_refused_with_a_clear_message(field, value, message):
    hand = straight_hand()
    kwargs = dict(name="bad", offsets=hand.offsets, rest_frames=hand.rest_frames, rig_frames=hand.rig_frames,
                  radii=hand.radii)
    kwargs[field] = value
    with pytest.raises(InvalidHandError, match=message):
        HandModel(**kwargs)
