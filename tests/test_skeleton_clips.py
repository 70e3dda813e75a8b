"""Issue 26's authored Oculus pinch: a skeleton-only clip whose nodes rest in the pinch itself. Its rest is said to
be a pose and the rig it was made for can be given (`--source`); the thumb meeting the index at the tips is a
touch (the pads 60% along the last phalanx stay 6% of the hand apart), which ASRN keeps on every rig."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from wild_rigs import rested_in_pose_gltf
from s2h_viewer.cli import main
from s2h_viewer.hand.kinematics import joint_positions
from s2h_viewer.io.files import RigOptions, load_hand_file, load_motion_file
from s2h_viewer.io.npz import load_motion
from s2h_viewer.retarget.methods import retarget
from s2h_viewer.samples import load_sample_hand
from s2h_viewer.semantics.contacts import CONTACT_TOLERANCE, pad_centres, thumb_pair_gaps
from s2h_viewer.semantics.signature import THUMB_TOUCH, signatures

ROOT = Path(__file__).resolve().parents[1]
PINCH = ROOT / "assets/motions/real/r_hand_pinch_anim.fbx"
META = ROOT / "assets/hands/real/r_hand_skeletal_lowres.fbx"
HUMAN = ROOT / "assets/hands/real/human-female.glb"
GODOT_R = ROOT / "assets/hands/real/godot_hand_r.gltf"
GODOT_POSES = ROOT / "assets/motions/real/godot_hand_poses_r.gltf"
INDEX = 0  # thumb_pair_gaps' columns: index .. pinky


def thumb_index_gap(hand, q_tbs: np.ndarray) -> np.ndarray:
    """(T,) the thumb's fingertip to the index's, in hand lengths."""
    positions = joint_positions(hand, torch.as_tensor(q_tbs, dtype=torch.float64))
    return thumb_pair_gaps(hand, positions)[:, INDEX].numpy() / hand.hand_length


@pytest.fixture(scope="module")
def meta():
    return load_hand_file(META)


@pytest.fixture(scope="module")
def pinch(meta):
    """The pinch on the rig it was made for."""
    return load_motion_file(PINCH, meta)


def test_a_clip_resting_in_its_pose_is_said_and_its_own_rig_gives_back_the_pinch(meta, pinch):
    motion, own = load_motion_file(PINCH)
    assert "no mesh" in own.meta["rest_note"] and "index fingertip" in own.meta["rest_note"]
    assert load_motion_file(GODOT_POSES)[1].meta["rest_note"] is None  # no mesh, an open rest
    assert meta.meta["rest_note"] is None  # the skinned hand
    # on the skeleton it rests in, the thumb's canonical pose is the pinch's thumb flattened: copied onto the very
    # rig it was made for, the thumb misses the index by a third of a hand; read onto that rig, it touches
    missed = thumb_index_gap(meta, retarget(motion, own, meta, "tbs_copy").q_tbs)
    kept = thumb_index_gap(meta, retarget(pinch[0], pinch[1], meta, "tbs_copy").q_tbs)
    assert (missed > 0.15).all() and (kept < CONTACT_TOLERANCE).all()


def test_a_pose_file_re_rested_in_its_horns_is_said_and_reads_as_the_original_on_its_rig(tmp_path):
    """The Godot pose file with its nodes resting in "Metal" (the horns: middle and ring curled), as an exporter
    baking a key leaves it: said ("fingers curled"), and its curled middle fingertip comes out a quarter of a hand
    off on its own skeleton; read onto the rig the poses were made for, it is the original file's pose."""
    rested = rested_in_pose_gltf(GODOT_POSES, tmp_path / "metal_rest.gltf", "Metal")
    options = RigOptions(animation="Metal")
    motion, own = load_motion_file(rested, options=options)
    assert "fingers curled: middle" in own.meta["rest_note"] and "ring" in own.meta["rest_note"]
    original, plain = load_motion_file(GODOT_POSES, options=options)  # its skeleton rests open: the rig it was made on
    target = load_sample_hand("iris")
    tips = [joint_positions(target, torch.as_tensor(retarget(m, h, target, "tbs_copy").q_tbs))[0, 12].numpy()
            for m, h in ((motion, own), (original, plain))]
    assert np.linalg.norm(tips[0] - tips[1]) > 0.15 * target.hand_length
    on_rig = load_motion_file(rested, plain, options)[0].q_tbs
    np.testing.assert_allclose(np.abs((on_rig * original.q_tbs).sum(-1)), 1.0, atol=1e-5)


def test_a_tip_pinch_is_a_touch_though_its_pads_stay_apart(pinch):
    motion, source = pinch
    positions = joint_positions(source, torch.as_tensor(motion.q_tbs, dtype=torch.float64))
    pads = pad_centres(positions)
    pad_apart = ((pads[:, 0] - pads[:, 1]).norm(dim=-1) / source.hand_length).numpy()
    assert (pad_apart > 0.1).all()  # centre to centre: the pads 60% along the last phalanx do not meet
    assert (thumb_index_gap(source, motion.q_tbs) < CONTACT_TOLERANCE).all()
    assert all(s.thumb_contacts.tolist() == [True, False, False, False] for s in signatures(source, motion.q_tbs))


@pytest.mark.parametrize("target", [META, HUMAN, GODOT_R], ids=lambda p: p.stem)
def test_asrn_keeps_the_authored_pinch_on_every_rig(pinch, target):
    motion, source = pinch
    hand = load_hand_file(target, RigOptions(side="right"))
    assert (thumb_index_gap(hand, retarget(motion, source, hand, "asrn").q_tbs) < THUMB_TOUCH).all()


def test_the_commands_say_a_posed_rest_and_take_the_rig_it_was_made_for(tmp_path, capsys):
    out = tmp_path / "own.npz"
    assert main(["retarget", "--motion", str(PINCH), "--target", str(META), "--method", "tbs_copy", "--out", str(out),
                 "--quiet"]) == 0
    said = capsys.readouterr().err
    assert "r_hand_pinch_anim.fbx: its skeleton has no mesh and rests in a pose" in said and "--source FILE" in said
    out = tmp_path / "rig.npz"
    assert main(["retarget", "--motion", str(PINCH), "--source", str(META), "--target", str(META), "--method",
                 "tbs_copy", "--out", str(out), "--quiet"]) == 0
    assert "rests in a pose" not in capsys.readouterr().err
    assert (thumb_index_gap(load_hand_file(META), load_motion(out).q_tbs) < CONTACT_TOLERANCE).all()
    # a rig with other bones is refused naming them; a BVH has a skeleton of its own
    assert main(["retarget", "--motion", str(GODOT_POSES), "--source", str(META), "--target", "iris", "--out",
                 str(tmp_path / "x.npz"), "--quiet"]) == 2
    assert "has no bones hands:b_r_hand" in capsys.readouterr().err
    bvh = tmp_path / "clip.bvh"
    assert main(["retarget", "--motion", str(out), "--source", str(META), "--target", "iris", "--method", "tbs_copy",
                 "--out", str(bvh), "--quiet"]) == 0
    assert main(["retarget", "--motion", str(bvh), "--source", "iris", "--target", "iris", "--out",
                 str(tmp_path / "y.npz"), "--quiet"]) == 2
    assert "a BVH clip carries its own skeleton" in capsys.readouterr().err
    assert not (tmp_path / "x.npz").exists() and not (tmp_path / "y.npz").exists()


def test_a_batch_row_says_a_posed_rest_and_its_source_rig_fixes_it(tmp_path):
    from s2h_viewer.batch.plan import Input, Task, TaskOptions
    from s2h_viewer.batch.task import run_task

    def row(source):
        out = tmp_path / (Path(source).stem if source else "own")
        return run_task(Task(Input(str(PINCH), "pinch"), Input(str(META), "meta"), "tbs_copy", str(out),
                             TaskOptions(format="npz", render=False, source=source)))
    own, on_rig = row(None), row(str(META))
    assert own["status"] == on_rig["status"] == "ok"
    assert "source: its skeleton has no mesh and rests in a pose" in own["warning"] and on_rig["warning"] == ""
    assert on_rig["contact_r"] == 1.0 and own["s_finger"] < on_rig["s_finger"]
    wrong = row(str(GODOT_R))  # a --source that does not fit (other bones): read as it would be without, and said
    assert wrong["status"] == "ok" and wrong["s_finger"] == own["s_finger"] and wrong["source_path"] == ""
    assert wrong["warning"].startswith("--source godot_hand_r.gltf does not fit it (other bones): read on its own "
                                       "skeleton; source: its skeleton has no mesh and rests in a pose")


def test_a_take_the_exporter_named_is_called_by_its_file(pinch, capsys):
    """The pinch's only take is "Take 001": captions, export names, batch rows and `s2h check` call it by the
    file, and `s2h rig` says so beside the take's name."""
    from s2h_viewer.cli import main
    from s2h_viewer.io.gltf import clip_name
    assert pinch[0].name == "r_hand_pinch_anim"
    assert main(["check", str(PINCH)]) == 0
    assert capsys.readouterr().out.startswith("r_hand_pinch_anim: 2 frames; index PIP bends ")
    assert main(["rig", str(PINCH)]) == 0  # the take's own name, for --animation, and the clip's
    assert "animations: [0] Take 001 (read as r_hand_pinch_anim)\n" in capsys.readouterr().out
    assert load_motion_file(GODOT_POSES, None, RigOptions(animation="Pinch Up"))[0].name == "Pinch Up"
    for default in ("Take 001", "mixamo.com", "Armature|mixamo.com|Layer0", "Armature|Action.001", "Animation_0", ""):
        assert clip_name(default, PINCH) == "r_hand_pinch_anim" and clip_name(default, PINCH, 2) == "r_hand_pinch_anim_2"
    assert clip_name("Armature|counting", PINCH) == "Armature|counting"
