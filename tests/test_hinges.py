"""Issue 26, item 2: each joint's hinge taken from animations on the rig's own skeleton, the solver checked
against it; a pose file made on another skeleton refused."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from s2h_viewer.annotate.hinges import (AGREE_DEGREES, HINGE_JOINTS, LABEL, animation_hinges, hinge_disagreement,
                                        overrule_with_hinges)
from s2h_viewer.annotate.solver import TbsSolution
from s2h_viewer.cli import main
from s2h_viewer.errors import InputFileError
from s2h_viewer.hand import topology as topo
from s2h_viewer.io.files import RigOptions, load_hand_file
from s2h_viewer.motions.synthesis import synthesize

ROOT = Path(__file__).resolve().parents[1]
POSES = ROOT / "assets/motions/real/godot_hand_poses_r.gltf"
POSES_L = ROOT / "assets/motions/real/godot_hand_poses_l.gltf"
POSED_RIG = ROOT / "assets/motions/real/godot_hand_r_posed_rig.gltf"
GODOT_R = ROOT / "assets/hands/real/godot_hand_r.gltf"


def _rolled(frames: np.ndarray, joints: list[int], degrees: float) -> np.ndarray:
    """``frames`` with the bend and splay axes of ``joints`` turned ``degrees`` about their twist axis."""
    out = frames.copy()
    for j in joints:
        turn = Rotation.from_rotvec(np.radians(degrees) * frames[j][:, 0]).as_matrix()
        out[j] = turn @ frames[j]
    return out


def test_a_clips_hinges_are_the_frames_it_was_made_with(sample_hands):
    """A gesture clip bends each PIP/DIP about its frame's bend axis only: the hinges found are those axes."""
    hand = sample_hands["kale"]
    clip = synthesize(["fist", "ok", "point", "letter_c", "claw"], hand, seed=1)
    hinges = animation_hinges(clip.q_tbs, hand.rest_frames, "clip")
    off = hinge_disagreement(hand.rest_frames, hinges)
    pips_dips = [j for j, name in enumerate(topo.ARTICULATED_NAMES) if name.endswith(("_pip", "_dip"))]
    assert off[pips_dips].max() < 0.5 and (hinges.share[pips_dips] > 0.99).all()
    assert hinges.usable()[pips_dips].all() and not hinges.usable()[~HINGE_JOINTS].any()


def test_frames_rolled_off_their_hinges_are_put_back(sample_hands):
    """Frames of three joints rolled 35 deg about their bones (as a solver misled by round sections would):
    checked against the clip's hinges they come back within a degree; the others are left exactly."""
    hand = sample_hands["kale"]
    clip = synthesize(["fist", "ok", "point", "letter_c", "claw", "pinch"], hand, seed=2)
    hinges = animation_hinges(clip.q_tbs, hand.rest_frames, "clip")
    wrong = [topo.ARTICULATED_NAMES.index(n) for n in ("index_pip", "ring_dip", "thumb_ip")]
    n = topo.N_ARTICULATED
    solution = TbsSolution(_rolled(hand.rest_frames, wrong, 35.0), np.ones(n), np.ones(n), np.zeros(n), np.zeros(n),
                           np.zeros(n, dtype=bool))
    assert hinge_disagreement(solution.frames, hinges)[wrong].min() > 30
    fixed = overrule_with_hinges(solution, hinges, hand.rest_positions)
    assert hinge_disagreement(fixed.frames, hinges)[wrong].max() < 1.0
    # the splay axis still leans out of the back of the hand: the frame is the true one, not its mirror
    for j in wrong:
        assert fixed.frames[j][:, 2] @ hand.rest_frames[j][:, 2] > 0.999
    others = [j for j in range(n) if j not in wrong]
    np.testing.assert_array_equal(fixed.frames[others], solution.frames[others])
    assert [fixed.basis[j] for j in wrong] == [LABEL] * 3 and fixed.basis[others[0]] == "rays"
    assert any(line.startswith("index: ") and "index PIP 35" in line for line in fixed.diagnostics)
    assert AGREE_DEGREES < 30


def test_the_rig_the_poses_were_made_on_takes_their_hinges():
    """The Godot poses' own rig: its solver frames checked against the 35 poses; the thumb IP (42 deg off the
    hinge it is animated about) and the index PIP (12) take the hinge, and the hand says so."""
    plain = load_hand_file(POSED_RIG)
    hinged = load_hand_file(POSED_RIG, RigOptions(hinges_from=POSES))
    set_by = hinged.meta["frame_set_by"]
    assert set_by[topo.ARTICULATED_NAMES.index("thumb_ip")] == LABEL
    assert set_by[topo.ARTICULATED_NAMES.index("index_pip")] == LABEL
    assert LABEL not in plain.meta["frame_set_by"]
    lines = [line for line in hinged.meta["solver_diagnostics"] if "hinges its animations turn about" in line]
    assert any(line.startswith("thumb: ") and "godot_hand_poses_r.gltf" in line for line in lines)
    changed = [j for j, by in enumerate(set_by) if by == LABEL]
    unchanged = [j for j in range(topo.N_ARTICULATED) if j not in changed]
    np.testing.assert_array_equal(hinged.rest_frames[unchanged], plain.rest_frames[unchanged])
    assert (np.abs(hinged.rest_frames[changed] - plain.rest_frames[changed]).max(axis=(1, 2)) > 0.1).all()


def test_a_skeleton_with_animations_takes_its_own_hinges():
    """The left-hand pose file alone (no mesh): palm-plane frames, and the joints its poses bend about other
    axes take those axes."""
    hand = load_hand_file(POSES_L)
    assert hand.meta["annotation"] == "palm plane (no mesh), animation hinges"
    assert LABEL in hand.meta["frame_set_by"] and "palm plane" in hand.meta["frame_set_by"]
    assert hand.meta["frame_set_by"] == load_hand_file(POSES_L).meta["frame_set_by"]  # read the same every time


def test_poses_made_on_another_skeleton_are_refused(capsys, tmp_path):
    """godot_hand_r.gltf is another export of the Godot hand whose finger bones are rolled ~150 deg from the
    poses' skeleton: its keys would turn them about other axes (hinges 25-48 deg off), so no hinges are taken
    and the hand says why; a hinge file that cannot be read is an error naming it."""
    plain = load_hand_file(GODOT_R)
    hand = load_hand_file(GODOT_R, RigOptions(hinges_from=POSES))
    np.testing.assert_array_equal(hand.rest_frames, plain.rest_frames)
    assert LABEL not in hand.meta["frame_set_by"]
    line = hand.meta["solver_diagnostics"][-1]
    assert re.match(r"hinges from godot_hand_poses_r.gltf not taken: its bones are rolled otherwise, so its keys "
                    r"turn them about other axes \(\w+_Proximal_R rolled 1\d\d deg", line), line
    other = load_hand_file(GODOT_R, RigOptions(hinges_from=ROOT / "assets/hands/real/human-female.glb"))
    assert "not taken: its skeleton is not this hand's (no bone Index_Proximal_R" in other.meta["solver_diagnostics"][-1]
    assert main(["annotate", str(GODOT_R), "--hinges-from", str(POSES)]) == 0
    assert "hinges from godot_hand_poses_r.gltf not taken" in capsys.readouterr().out
    broken = tmp_path / "poses.gltf"
    broken.write_text('{"asset": {"version": "2.0"}, "nodes": [')
    assert main(["annotate", str(POSED_RIG), "--hinges-from", str(broken)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(broken) in err[0], err
    with pytest.raises(InputFileError, match="poses.gltf"):
        load_hand_file(POSED_RIG, RigOptions(hinges_from=broken))
