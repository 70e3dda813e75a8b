"""A rig made by Blender's own tools, as a Blender user brings one: Rigify's human generated into its control rig,
a skinned mesh on both hands, written by Blender's glTF and FBX exporters with deform bones only
(scripts/rigify_hands.py). Rigify's names (``DEF-f_index.01.R``) were tested only as lists of names before.

Also renamed as the Unreal 5 mannequin's and Mixamo's bones, over the same Blender-made hierarchy.

Runs where `.venv-blender` exists (CI builds it: `make test` with CI=true); skipped elsewhere, saying how to make it.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pygltflib
import pytest

from rigify_character import BLENDER_PYTHON
from s2h_viewer import samples
from s2h_viewer.io.files import RigOptions, load_hand_file, load_motion_file, read_rig_skeleton
from s2h_viewer.retarget.methods import retarget
from s2h_viewer.semantics.metrics import score_retarget
from s2h_viewer.semantics.signature import pose_differences

ROOT = Path(__file__).resolve().parents[1]
POSES = ROOT / "assets/motions/real/godot_hand_poses_r.gltf"
POSED_RIG = ROOT / "assets/motions/real/godot_hand_r_posed_rig.gltf"

pytestmark = [pytest.mark.blender,
              pytest.mark.skipif(not BLENDER_PYTHON.exists(), reason="no Blender venv: `make blender` makes it")]


@pytest.fixture(scope="module")
def hands(rigify_files) -> dict[tuple[str, str], object]:
    return {(suffix, side): load_hand_file(path, RigOptions(side=side))
            for suffix, path in rigify_files.items() for side in ("right", "left")}


def test_blenders_glb_and_fbx_of_a_rigify_character_read_as_the_same_two_hands(rigify_files, hands):
    """Both exports: the Rigify scheme, the deform bones (``DEF-``) mapped, not the ``ORG-`` copies the FBX keeps
    beside them; the same hand from either file, and the left hand the right one's mirror (Rigify's human is
    symmetric): positions within 0.1% of the hand's length, the bend axes the same from either file and within a
    few degrees from either hand (the mesh's facets are not mirrored about the bones)."""
    for suffix, path in rigify_files.items():
        skeleton = read_rig_skeleton(path)
        assert any(name.startswith("DEF-f_index.01") for name in skeleton.names), suffix
    for hand in hands.values():
        assert hand.meta["rig_scheme"] == "rigify" and hand.mesh is not None
        assert 0.15 < hand.hand_length < 0.25  # metres: Rigify's human is 1.8 m tall
    def in_palm_axes(hand):  # hand space is the wrist bone's frame, which a mirrored wrist turns about
        return hand.rest_positions @ hand.palm_frame / hand.hand_length, hand.palm_frame.T @ hand.rest_frames

    positions, frames = in_palm_axes(hands[("glb", "right")])
    for key, hand in hands.items():
        other_positions, other_frames = in_palm_axes(hand)
        np.testing.assert_allclose(other_positions, positions, atol=1e-3, err_msg=str(key))
        bend = (other_frames[:, :, 1] * frames[:, :, 1]).sum(-1)
        off = np.degrees(np.arccos(np.clip(np.abs(bend), 0.0, 1.0)))
        # the other file: the same; the other hand: its tubes' facets lie otherwise about the bones (3 deg here)
        assert off.max() < (0.1 if key[1] == "right" else 4.0), (key, off.round(1))


def test_asrn_keeps_every_authored_pose_on_a_rigify_character_left_and_right_alike(hands):
    """The 35 authored poses onto the Rigify character's two hands: ASRN keeps all 35 with no invented contact
    and no added violation; on the gestures clip no finger curls more than 25 deg sideways, the left hand within
    2 deg of the right."""
    motion, source = load_motion_file(POSES, load_hand_file(POSED_RIG), RigOptions(animation="all"))
    gestures = next(m for m in samples.load_sample_motions() if m.name.startswith("gestures"))
    gestures_source = samples.load_sample_hand(gestures.hand_name)
    sideways = {}
    for side in ("right", "left"):
        hand = hands[("glb" if side == "right" else "fbx", side)]
        moved = retarget(motion, source, hand, "asrn").q_tbs
        lost = [name for name, gone in pose_differences(source, motion.q_tbs, hand, moved, motion.labels).items()
                if gone]
        assert lost == [], (side, lost)
        scores = score_retarget(source, motion.q_tbs, hand, moved)
        assert scores.contact_precision >= 0.95 and scores.added_violation_rate <= 0.01, (side, scores)
        on_gestures = score_retarget(gestures_source, gestures.q_tbs, hand,
                                     retarget(gestures, gestures_source, hand, "asrn").q_tbs)
        sideways[side] = on_gestures.sideways_deg
    assert max(sideways.values()) <= 25.0 and abs(sideways["right"] - sideways["left"]) <= 2.0, sideways


def _unreal_name(name: str) -> str:
    """A Rigify deform bone's name as the Unreal 5 mannequin's (``DEF-f_index.01.R`` -> ``index_01_r``, the palm
    bones its metacarpals)."""
    finger = re.fullmatch(r"DEF-(?:f_)?(thumb|index|middle|ring|pinky)\.0(\d)\.([LR])", name)
    if finger:
        return f"{finger[1]}_0{finger[2]}_{finger[3].lower()}"
    palm = re.fullmatch(r"DEF-palm\.0(\d)\.([LR])", name)
    if palm:
        return f"{('index', 'middle', 'ring', 'pinky')[int(palm[1]) - 1]}_metacarpal_{palm[2].lower()}"
    wrist = re.fullmatch(r"DEF-hand\.([LR])", name)
    return f"hand_{wrist[1].lower()}" if wrist else name


def _mixamo_name(name: str) -> str:
    """As Mixamo's (``mixamorig:RightHandIndex1``); the palm bones, which Mixamo has not, keep Rigify's names."""
    side = {"L": "Left", "R": "Right"}
    finger = re.fullmatch(r"DEF-(?:f_)?(thumb|index|middle|ring|pinky)\.0(\d)\.([LR])", name)
    if finger:
        return f"mixamorig:{side[finger[3]]}Hand{finger[1].capitalize()}{finger[2]}"
    wrist = re.fullmatch(r"DEF-hand\.([LR])", name)
    return f"mixamorig:{side[wrist[1]]}Hand" if wrist else name


@pytest.mark.parametrize("scheme, rename", [("unreal", _unreal_name), ("mixamo", _mixamo_name)])
def test_the_rigify_character_renamed_as_unreals_or_mixamos_reads_as_the_same_hands(rigify_files, hands, scheme,
                                                                                   rename, tmp_path):
    """Blender's hierarchy with another scheme's names (the same character sent through a renaming step, as users
    do to retarget in Unreal or to match Mixamo clips): recognised as that scheme, both hands the same as under
    Rigify's names, the metacarpals (Unreal) or the unnamed palm bones (Mixamo) moving with the wrist."""
    gltf = pygltflib.GLTF2().load_binary(str(rigify_files["glb"]))
    for node in gltf.nodes:
        node.name = rename(node.name or "")
    renamed = tmp_path / f"{scheme}.glb"
    gltf.save_binary(str(renamed))
    for side in ("right", "left"):
        hand = load_hand_file(renamed, RigOptions(side=side))
        rigify = hands[("glb", side)]
        assert hand.meta["rig_scheme"] == scheme
        assert hand.meta["rig_joints"]["index_mcp"] == rename(f"DEF-f_index.01.{side[0].upper()}")
        np.testing.assert_allclose(hand.rest_positions, rigify.rest_positions, atol=1e-6)
        np.testing.assert_allclose(hand.rest_frames, rigify.rest_frames, atol=1e-4)
        np.testing.assert_allclose(hand.mesh.vertices, rigify.mesh.vertices, atol=1e-6)
