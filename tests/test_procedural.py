"""The procedural hand family and the shipped sample assets."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import trimesh

from s2h_viewer import samples
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.procedural import generate_hand, sample_params


def test_same_seed_same_hand_and_seeds_differ():
    a, b, c = (generate_hand(s, with_mesh=False) for s in (7, 7, 8))
    np.testing.assert_array_equal(a.offsets, b.offsets)
    assert np.abs(a.offsets - c.offsets).max() > 1e-3
    assert sample_params(7) == sample_params(7)
    with pytest.raises(ValueError, match="unknown hand style 'anime'"):
        sample_params(7, style="anime")


def test_stylised_hands_vary_more_and_fingers_never_fuse():
    realistic = [sample_params(s) for s in range(40)]
    stylised = [sample_params(s, style="stylised") for s in range(40)]
    spread = lambda ps, f: np.ptp([f(p) for p in ps])  # noqa: E731
    assert spread(stylised, lambda p: p.middle_ratio) > 2 * spread(realistic, lambda p: p.middle_ratio)
    assert max(p.thickness for p in stylised) > 1.2 > max(p.thickness for p in realistic)
    for p in stylised:  # knuckle diameter stays under 85% of the knuckle spacing
        assert 2 * 0.0097 * p.thickness / 0.185 <= 0.85 * p.knuckle_spacing + 1e-12


@pytest.mark.parametrize("seed,style", [(21, "realistic"), (209, "stylised")])
def test_generated_mesh_is_a_watertight_hand_with_sound_weights(seed, style):
    hand = generate_hand(seed, style=style)
    mesh = trimesh.Trimesh(hand.mesh.vertices, hand.mesh.faces, process=False)
    assert mesh.is_watertight and mesh.volume > 0
    assert 5_000 <= len(mesh.faces) <= 30_000
    assert len(mesh.split(only_watertight=False)) == 1  # one connected body
    # hand-sized: volume of a real hand (with a short wrist stub) is a few hundred cm^3
    assert 100e-6 < mesh.volume < 800e-6
    w = hand.mesh.weights
    np.testing.assert_allclose(w.sum(1), 1.0, atol=1e-5)
    assert (w >= 0).all() and (w.max(1) > 0.5).mean() > 0.95
    # fingertip vertices belong to their distal bone
    tips = hand.rest_positions[topo.TIP_JOINTS]
    nearest = np.argmin(np.linalg.norm(hand.mesh.vertices[:, None] - tips[None], axis=2), axis=0)
    assert (np.argmax(w[nearest], axis=1) == [3, 6, 9, 12, 15]).all()


def test_fingers_are_thinner_pad_to_back_than_side_to_side():
    """What the TBS annotation solver relies on (DESIGN.md section 3)."""
    hand = generate_hand(22)
    mesh = trimesh.Trimesh(hand.mesh.vertices, hand.mesh.faces, process=False)
    for a in (4, 7, 10):  # index, middle, ring PIP: rays from the middle of the middle phalanx
        joint = topo.ARTICULATED_JOINTS[a]
        origin = (hand.rest_positions[joint] + hand.rest_positions[joint + 1]) / 2
        frame = hand.rest_frames[a]
        dirs = np.array([frame[:, 1], -frame[:, 1], frame[:, 2], -frame[:, 2]])
        hits, ray_ids, _ = mesh.ray.intersects_location(np.repeat(origin[None], 4, 0), dirs, multiple_hits=False)
        dist = np.full(4, np.inf)
        dist[ray_ids] = np.linalg.norm(hits - origin, axis=1)
        assert np.isfinite(dist).all()
        assert dist[2] + dist[3] < 0.95 * (dist[0] + dist[1])


def test_rig_conventions_make_copy_and_tbs_copy_differ():
    a = generate_hand(5, with_mesh=False, rig_convention="tbs")
    b = generate_hand(5, with_mesh=False, rig_convention="y_along_bone")
    np.testing.assert_allclose(a.rest_frames, b.rest_frames)  # same hand, same TBS frames
    k_a = a.rig_frames[topo.ARTICULATED_PARENT_ROTATING].transpose(0, 2, 1) @ a.rest_frames
    k_b = b.rig_frames[topo.ARTICULATED_PARENT_ROTATING].transpose(0, 2, 1) @ b.rest_frames
    assert np.abs(k_a - k_b).max() > 0.5


def test_shipped_assets_have_twelve_disjoint_hands_and_sample_motions(sample_hands):
    index = samples.read_index()
    train, test = samples.hand_names("train"), samples.hand_names("test")
    assert len(train) >= 8 and len(test) >= 4 and not set(train) & set(test)
    seeds = {h["split"]: set() for h in index["hands"]}
    for h in index["hands"]:
        seeds[h["split"]].add(h["seed"])
    assert not seeds["train"] & seeds["test"]
    assert len({h["rig_convention"] for h in index["hands"] if h["split"] == "test"}) >= 3
    for split in ("train", "test"):
        assert {h["style"] for h in index["hands"] if h["split"] == split} == {"realistic", "stylised"}
    for motion in samples.load_sample_motions():
        hand = sample_hands[motion.hand_name]
        assert motion.n_frames > 100 and (motion.labels != "").any()
        pose = forward_kinematics(hand, torch.as_tensor(motion.q_tbs[:5], dtype=torch.float64))
        assert torch.isfinite(pose.positions).all()
    lengths = [h.hand_length for h in sample_hands.values()]
    assert max(lengths) / min(lengths) > 1.2  # the family really varies in size


@pytest.mark.parametrize("seed", [100, 109])
def test_shipped_hand_matches_its_generator(sample_hands, seed):
    """The assets are what scripts/generate_assets.py makes: a generator change needs `make assets`."""
    entry = next(h for h in samples.read_index()["hands"] if h["seed"] == seed)
    fresh = generate_hand(seed, rig_convention=entry["rig_convention"], style=entry["style"])
    shipped = sample_hands[entry["name"]]
    np.testing.assert_allclose(shipped.offsets, fresh.offsets, atol=1e-12)
    np.testing.assert_allclose(shipped.rig_frames, fresh.rig_frames, atol=1e-12)
    np.testing.assert_array_equal(shipped.mesh.faces, fresh.mesh.faces)
    np.testing.assert_allclose(shipped.mesh.vertices, fresh.mesh.vertices, atol=1e-5)
    np.testing.assert_allclose(shipped.mesh.weights, fresh.mesh.weights, atol=1e-4)


@pytest.mark.parametrize("name", ["gestures", "fingerspelling"])
def test_shipped_motion_matches_its_script(sample_hands, name):
    """The sample motions are their script re-synthesised on birch, touches fitted pad to pad as the gesture library
    labels them (`contact_gaps(thumb_tips=False)`): a thumb measured to its tip there moves these two clips' keys by
    0.05-0.13 (quaternion components), and the networks' training data with them."""
    from s2h_viewer.io.npz import load_motion
    from s2h_viewer.motions.synthesis import synthesize
    shipped = load_motion(samples.ASSETS_DIR / "motions" / f"{name}.npz")
    fresh = synthesize(shipped.meta["script"], sample_hands["birch"], seed=shipped.meta["seed"], name=name)
    np.testing.assert_allclose(fresh.q_tbs, shipped.q_tbs, atol=1e-3)
