"""Real third-party avatars without a joint map: recognition, side, the solver's frames, lossless export.

The rigs are vendored in assets/hands/real/ (godot-xr-tools hands, CC0; the Mesh2Motion human-female
character, CC0) and assets/hands/webxr/ (MIT). Broken variants are made here from them with pygltflib.
Exports are checked by an independent reader written in this file (pygltflib nodes and animation
samples, and a BVH parser, with their own forward kinematics), not by the project's loaders.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pygltflib
import pytest
import torch
from scipy.spatial.transform import Rotation

from s2h_viewer.annotate.solver import solve_tbs_frames
from s2h_viewer.errors import InputFileError, TooFewBonesError, UnrecognisedRigError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.mirror import reflection
from s2h_viewer.hand.rig_mapping import check_user_mapping
from s2h_viewer.io.files import (RigOptions, load_hand_file, load_motion_file, read_rig_skeleton, save_joint_map,
                                 save_motion_file, suggested_joint_map)
from s2h_viewer.io.gltf import load_gltf_motion, save_gltf_motion
from s2h_viewer.io.rig import MIRROR_NORMAL
from s2h_viewer.motions.synthesis import synthesize
from s2h_viewer.retarget import retarget
from s2h_viewer.samples import ASSETS_DIR

REAL = ASSETS_DIR / "hands" / "real"
WEBXR = ASSETS_DIR / "hands" / "webxr"
#: (file, --side, the side it is, the scheme its names are in)
RIGS = [(REAL / "godot_hand_r.gltf", None, "right", "openxr"), (REAL / "godot_hand_l.gltf", None, "left", "openxr"),
        (REAL / "human-female.glb", "right", "right", "unreal"), (REAL / "human-female.glb", "left", "left", "unreal"),
        (WEBXR / "generic-hand-right.glb", None, "right", "webxr"),
        (WEBXR / "generic-hand-left.glb", None, "left", "webxr")]
RIG_IDS = ["godot_r", "godot_l", "female_right", "female_left", "webxr_r", "webxr_l"]


def run_cli(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "s2h_viewer.cli", *argv], capture_output=True, text=True)


def bend_axis_spread(frames: np.ndarray) -> np.ndarray:
    """(5, 2) degrees between the bend axes of neighbouring joints of each finger."""
    y = frames[:, :, 1].reshape(topo.N_FINGERS, 3, 3)
    cos = np.abs(np.einsum("fki,fki->fk", y[:, :-1], y[:, 1:]))
    return np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))


@pytest.mark.parametrize("path,side,expected_side,scheme", RIGS, ids=RIG_IDS)
def test_real_rigs_load_with_the_right_side_and_consistent_frames(path, side, expected_side, scheme):
    hand = load_hand_file(path, RigOptions(side=side))  # no joint map
    assert hand.meta["rig_scheme"] == scheme and hand.meta["side"] == expected_side
    assert hand.meta["side_from"] == ("geometry (confidence 1.00)" if scheme == "webxr" else "names")
    assert hand.meta["annotation"] == "solver" and 0.12 < hand.hand_length < 0.25
    # mirrored to a right hand: thumb on the +y side of the palm frame
    local = hand.rest_positions @ hand.palm_frame
    assert local[topo.joint_index("thumb_tip"), 1] > 0 > local[topo.joint_index("pinky_mcp"), 1]
    solution = solve_tbs_frames(hand)
    assert bend_axis_spread(solution.frames).max() <= 20.0, np.round(bend_axis_spread(solution.frames))
    assert not solution.fallback.any()
    # the frames agree with the palm: a finger's splay axis leans out of the back of the hand
    assert (np.einsum("ji,i->j", solution.frames[3:, :, 2], hand.palm_frame[:, 2]) > 0.5).all()


def test_palm_bones_keep_their_skin():
    """Every vertex the file skins to the hand's bones (metacarpals and the palm bone included) is kept."""
    gltf = pygltflib.GLTF2().load(str(REAL / "godot_hand_r.gltf"))
    hand = load_hand_file(REAL / "godot_hand_r.gltf")
    assert len(hand.mesh.vertices) == gltf.accessors[gltf.meshes[0].primitives[0].attributes.POSITION].count
    assert hand.mesh.weights[:, 0].max() > 0.99  # the palm's own vertices move with the wrist


def _anonymous_copy(src: Path, dst: Path) -> dict[str, str]:
    """A copy of a glTF whose node names say nothing (``bone17``); returns old name -> new name."""
    gltf = pygltflib.GLTF2().load(str(src))
    renamed = {}
    for i, node in enumerate(gltf.nodes):
        renamed[node.name] = f"bone{i}"
        node.name = f"bone{i}"
    gltf.save(str(dst))
    return renamed


@pytest.mark.parametrize("name,side", [("godot_hand_r.gltf", "right"), ("godot_hand_l.gltf", "left"),
                                       ("human-female.glb", "right")])
def test_hand_found_by_topology_and_side_by_geometry_when_names_say_nothing(tmp_path, name, side):
    renamed = _anonymous_copy(REAL / name, tmp_path / f"anon{Path(name).suffix}")
    hand = load_hand_file(tmp_path / f"anon{Path(name).suffix}")
    named = load_hand_file(REAL / name)
    assert hand.meta["rig_scheme"] == "topology" and hand.meta["side"] == side
    assert hand.meta["side_from"].startswith("geometry")
    assert hand.meta["rig_joints"] == {j: renamed[b] for j, b in named.meta["rig_joints"].items()}
    assert any("found by topology" in note for note in hand.meta["rig_notes"])
    done = run_cli("rig", str(tmp_path / f"anon{Path(name).suffix}"))
    assert done.returncode == 0 and "topology scheme" in done.stdout and f"{side} hand" in done.stdout


def test_side_override_mirrors_a_lone_hand():
    hand = load_hand_file(WEBXR / "generic-hand-right.glb", RigOptions(side="left"))
    assert hand.meta["side"] == "left" and hand.meta["side_from"] == "user"
    assert any("geometry says right" in note for note in hand.meta["rig_notes"])


def _vrm_copy(src: Path, dst: Path, version: int) -> None:
    """The godot right hand with anonymous names and a VRM humanoid map (0.x list or 1.0 dict)."""
    gltf = pygltflib.GLTF2().load(str(src))
    index = {n.name: i for i, n in enumerate(gltf.nodes)}
    vrm_fingers = {"thumb": "Thumb", "index": "Index", "middle": "Middle", "ring": "Ring", "pinky": "Little"}
    bones = {"rightHand": index["Wrist_R"]}
    for f, xr in vrm_fingers.items():
        rig_parts = ("Metacarpal", "Proximal", "Distal") if f == "thumb" else ("Proximal", "Intermediate", "Distal")
        vrm_parts = (("Metacarpal", "Proximal", "Distal") if version == 1 else ("Proximal", "Intermediate", "Distal")
                     ) if f == "thumb" else ("Proximal", "Intermediate", "Distal")
        for rig_part, vrm_part in zip(rig_parts, vrm_parts):
            bones[f"right{xr}{vrm_part}"] = index[f"{'Little' if f == 'pinky' else xr}_{rig_part}_R"]
    for i, node in enumerate(gltf.nodes):
        node.name = f"J{i:02d}"
    if version == 1:
        gltf.extensions = {"VRMC_vrm": {"specVersion": "1.0", "humanoid": {
            "humanBones": {k: {"node": v} for k, v in bones.items()}}}}
    else:
        gltf.extensions = {"VRM": {"humanoid": {"humanBones": [{"bone": k, "node": v} for k, v in bones.items()]}}}
    gltf.save(str(dst))


@pytest.mark.parametrize("version", [0, 1])
def test_vrm_humanoid_map_is_read_from_the_file(tmp_path, version):
    _vrm_copy(REAL / "godot_hand_r.gltf", tmp_path / "avatar.gltf", version)
    hand = load_hand_file(tmp_path / "avatar.gltf")
    named = load_hand_file(REAL / "godot_hand_r.gltf")
    assert hand.meta["rig_scheme"] == "vrm" and hand.meta["side"] == "right"
    np.testing.assert_allclose(hand.rest_positions, named.rest_positions, atol=1e-9)


def test_joint_map_beside_a_hand_file_is_picked_up_and_keeps_the_palm(tmp_path):
    renamed = _anonymous_copy(REAL / "godot_hand_l.gltf", tmp_path / "hand.gltf")
    named = load_hand_file(REAL / "godot_hand_l.gltf")
    joint_map = {j: renamed[b] for j, b in named.meta["rig_joints"].items()}
    (tmp_path / "hand.joints.json").write_text(json.dumps(joint_map))
    hand = load_hand_file(tmp_path / "hand.gltf", RigOptions(side="left"))
    assert hand.meta["rig_scheme"] == "user" and hand.meta["side"] == "left"
    # the metacarpals and Palm_L are named nowhere in the map: their vertices stay, weighted to the wrist
    assert len(hand.mesh.vertices) == len(named.mesh.vertices)
    np.testing.assert_allclose(hand.mesh.weights, named.mesh.weights, atol=1e-6)


# --- a joint map the user makes (the app's dialog) for a hand whose bones say nothing ---

@pytest.fixture
def renamed_webxr(tmp_path) -> tuple[Path, dict[str, str]]:
    """A copy of the WebXR hand with meaningless bone names (its bones hang side by side under one root, so
    topology cannot find the hand either), and the joint map that gives it back its named hand."""
    renamed = _anonymous_copy(WEBXR / "generic-hand-right.glb", tmp_path / "hand.glb")
    named = load_hand_file(WEBXR / "generic-hand-right.glb")
    return tmp_path / "hand.glb", {j: renamed[b] for j, b in named.meta["rig_joints"].items()}


def test_a_joint_map_is_checked_against_the_rig_naming_the_joint_and_the_bone(renamed_webxr):
    path, good = renamed_webxr
    with pytest.raises(UnrecognisedRigError) as refused:
        load_hand_file(path)
    assert not isinstance(refused.value, TooFewBonesError)  # a joint map can make it a hand: the app offers one
    bones = read_rig_skeleton(path).names
    assert check_user_mapping(good, bones, path) == good
    tipless = {j: b for j, b in good.items() if j != "index_tip"}
    assert check_user_mapping(tipless, bones, path) == tipless  # a tip left out is extrapolated
    cases = [({**good, "index_pip": "bone99"}, "joint map names bones the rig does not have: bone99 (index_pip)"),
             ({**good, "middle_dip": good["index_dip"]},
              f"one bone to several joints: index_dip and middle_dip both use {good['index_dip']!r}"),
             ({j: b for j, b in good.items() if j != "thumb_mcp"}, "the joint map does not name thumb_mcp"),
             ({**good, "wrist": " "}, "joint map leaves wrist empty"),
             ({**good, "index_knuckle": "bone3"}, "unknown joint names index_knuckle")]
    for mapping, message in cases:
        with pytest.raises(InputFileError, match=rf"hand\.glb: .*{re.escape(message)}"):
            check_user_mapping(mapping, bones, path)


def test_a_joint_map_given_as_a_dict_loads_the_hand_the_names_give(renamed_webxr):
    path, good = renamed_webxr
    hand = load_hand_file(path, RigOptions(joint_map=good))
    named = load_hand_file(WEBXR / "generic-hand-right.glb")
    assert hand.meta["rig_scheme"] == "user" and hand.meta["side"] == named.meta["side"] == "right"
    np.testing.assert_allclose(hand.rest_positions, named.rest_positions, atol=1e-9)
    np.testing.assert_allclose(hand.mesh.vertices, named.mesh.vertices, atol=1e-9)
    np.testing.assert_allclose(hand.mesh.weights, named.mesh.weights, atol=1e-6)  # metacarpals with the wrist


def test_a_saved_joint_map_is_the_sidecar_used_when_the_hand_is_opened_again(renamed_webxr):
    path, good = renamed_webxr
    stale = {**good, "index_mcp": "gone"}
    assert save_joint_map(path, stale, "right") == path.with_name("hand.right.joints.json")
    suggested = suggested_joint_map(path)  # what the app's dialog starts from: the sidecar where it fits the rig
    assert suggested["index_mcp"] == "" and {j: b for j, b in suggested.items() if j != "index_mcp"} == {
        j: b for j, b in good.items() if j != "index_mcp"}
    # replaced whole, nothing left beside
    assert save_joint_map(path, good, "right") == path.with_name("hand.right.joints.json")
    assert json.loads(path.with_name("hand.right.joints.json").read_text()) == good
    assert sorted(p.name for p in path.parent.iterdir()) == ["hand.glb", "hand.right.joints.json"]
    reopened = load_hand_file(path)
    assert reopened.meta["rig_scheme"] == "user"
    np.testing.assert_allclose(reopened.rest_positions, load_hand_file(WEBXR / "generic-hand-right.glb").rest_positions,
                               atol=1e-9)
    assert suggested_joint_map(path) == good


# --- export onto a full-body character, checked by an independent reader ---

def _gltf_rest(gltf: pygltflib.GLTF2) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Names, parents and local rest matrices (4x4) of every node, straight from pygltflib."""
    parents = np.full(len(gltf.nodes), -1)
    for i, node in enumerate(gltf.nodes):
        for c in node.children or []:
            parents[c] = i
    local = np.tile(np.eye(4), (len(gltf.nodes), 1, 1))
    for i, node in enumerate(gltf.nodes):
        if node.matrix:
            local[i] = np.array(node.matrix).reshape(4, 4).T
            continue
        if node.rotation:
            local[i, :3, :3] = Rotation.from_quat(node.rotation).as_matrix()
        if node.scale:
            local[i, :3, :3] *= node.scale
        if node.translation:
            local[i, :3, 3] = node.translation
    return [n.name for n in gltf.nodes], parents, local


def _chain_world(parents: np.ndarray, local: np.ndarray) -> np.ndarray:
    """(..., N, 4, 4) world matrices by walking each node's parents (no project code)."""
    world = np.empty_like(local)
    for i in range(local.shape[-3]):
        m, node = local[..., i, :, :], parents[i]
        while node >= 0:
            m = local[..., node, :, :] @ m
            node = parents[node]
        world[..., i, :, :] = m
    return world


def _independent_glb_rotations(path: Path, animation: int) -> tuple[list[str], np.ndarray, np.ndarray, set[str]]:
    """Names, rest world rotations (N, 3, 3), per-keyframe world rotations (T, N, 3, 3) and the animated
    nodes of a GLB."""
    gltf = pygltflib.GLTF2().load(str(path))
    blob = gltf.binary_blob()
    names, parents, local = _gltf_rest(gltf)

    def read(accessor_index: int, width: int) -> np.ndarray:
        acc = gltf.accessors[accessor_index]
        view = gltf.bufferViews[acc.bufferView]
        start = (view.byteOffset or 0) + (acc.byteOffset or 0)
        return np.frombuffer(blob, np.float32, acc.count * width, start).reshape(acc.count, width)

    anim = gltf.animations[animation]
    n_frames = gltf.accessors[anim.samplers[0].input].count
    posed = np.broadcast_to(local, (n_frames, *local.shape)).copy()
    animated = set()
    for channel in anim.channels:
        assert channel.target.path == "rotation"
        quats = read(anim.samplers[channel.sampler].output, 4)
        posed[:, channel.target.node, :3, :3] = Rotation.from_quat(quats).as_matrix()
        animated.add(names[channel.target.node])
    rest_world = _chain_world(parents, local)[:, :3, :3]
    return names, rest_world, _chain_world(parents, posed)[..., :3, :3], animated


def _expected_bone_turns(hand, motion) -> np.ndarray:
    """(T, 15, 3, 3) each articulated bone's rotation from rest in the rig's wrist frame, from the
    project's FK of the motion (TBS frames are fixed to their bones), un-mirrored for a left hand."""
    q = torch.as_tensor(motion.q_tbs, dtype=torch.float64)
    fk = forward_kinematics(hand, q).frames.numpy()[:, topo.ARTICULATED_JOINTS]
    turns = fk @ hand.rest_frames.transpose(0, 2, 1)[None]
    if hand.meta["side"] == "left":
        s = reflection(MIRROR_NORMAL)
        turns = s @ turns @ s
    return turns


def _angle_degrees(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    cos = (np.trace(a.swapaxes(-1, -2) @ b, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _parse_bvh(path: Path) -> tuple[list[str], np.ndarray]:
    """An independent minimal BVH reader: joint names and per-frame world rotations from rest (T, N, 3, 3)."""
    tokens = path.read_text().split()
    names, parents, channels, stack = [], [], [], []
    i = 0
    while tokens[i] != "MOTION":
        if tokens[i] in ("ROOT", "JOINT"):
            names.append(tokens[i + 1])
            parents.append(stack[-1] if stack else -1)
            channels.append([])
            i += 2
        elif tokens[i] == "End":
            names.append(None)
            parents.append(stack[-1])
            channels.append([])
            i += 2
        elif tokens[i] == "{":
            stack.append(len(names) - 1)
            i += 1
        elif tokens[i] == "}":
            stack.pop()
            i += 1
        elif tokens[i] == "CHANNELS":
            n = int(tokens[i + 1])
            channels[-1] = tokens[i + 2:i + 2 + n]
            i += 2 + n
        else:
            i += 1
    n_frames = int(tokens[i + 2])
    values = np.array(tokens[i + 6:], dtype=float).reshape(n_frames, -1)
    world = np.tile(np.eye(3), (n_frames, len(names), 1, 1))
    column = 0
    for j, chans in enumerate(channels):
        rot = [c[0] for c in chans if c.endswith("rotation")]
        cols = [column + k for k, c in enumerate(chans) if c.endswith("rotation")]
        local = Rotation.from_euler("".join(rot), values[:, cols], degrees=True).as_matrix() if rot else np.eye(3)
        world[:, j] = (world[:, parents[j]] @ local) if parents[j] >= 0 else local
        column += len(chans)
    return names, world


@pytest.fixture(scope="module")
def character_exports(tmp_path_factory, sample_hands):
    """The character's right and left hands retargeted (TBS Copy from birch) and exported to GLB and BVH."""
    out = tmp_path_factory.mktemp("exports")
    source = synthesize(["fist", "ok", "pinch", "spread"], sample_hands["birch"], seed=3)
    exports = {}
    for side in ("right", "left"):
        hand = load_hand_file(REAL / "human-female.glb", RigOptions(side=side))
        motion = retarget(source, sample_hands["birch"], hand, "tbs_copy")
        exports[side] = (hand, motion, save_motion_file(out / f"{side}.glb", motion, hand),
                         save_motion_file(out / f"{side}.bvh", motion, hand))
    return exports


@pytest.mark.parametrize("side", ["right", "left"])
def test_character_glb_export_is_read_back_by_an_independent_reader(character_exports, side):
    hand, motion, glb, _ = character_exports[side]
    names, rest_world, world, animated = _independent_glb_rotations(glb, animation=0)
    bones = [hand.meta["rig_joints"][topo.JOINT_NAMES[j]] for j in topo.ARTICULATED_JOINTS]
    # only the hand's 15 articulated bones are animated; the rest of the body stays as it was
    assert animated == set(bones)
    index = [names.index(b) for b in bones]
    wrist = rest_world[names.index(hand.meta["rig_joints"]["wrist"])]
    read = wrist.T @ world[:, index] @ rest_world[index].transpose(0, 2, 1) @ wrist  # turns in the wrist frame
    errors = _angle_degrees(read, _expected_bone_turns(hand, motion))
    assert errors.max() < 0.5, errors.max()
    assert _angle_degrees(_expected_bone_turns(hand, motion), np.eye(3)).max() > 30.0  # a motion that moves


@pytest.mark.parametrize("side", ["right", "left"])
def test_character_bvh_export_has_the_rig_names_and_is_read_back_independently(character_exports, side):
    hand, motion, _, bvh = character_exports[side]
    names, world = _parse_bvh(bvh)
    suffix = "_r" if side == "right" else "_l"
    assert names[0] == f"hand{suffix}" and f"index_04_leaf{suffix}" in names and "index_mcp" not in names
    # rest offsets are the rig's own: index_01 sits where the character has it, relative to the hand
    gltf_names, parents, local = _gltf_rest(pygltflib.GLTF2().load(str(REAL / "human-female.glb")))
    rest_world = _chain_world(parents, local)
    text = bvh.read_text()
    offset = np.array(text.split(f"JOINT index_01{suffix}")[1].split("OFFSET")[1].split()[:3], dtype=float)
    expected = rest_world[gltf_names.index(f"index_01{suffix}"), :3, 3] - rest_world[gltf_names.index(f"hand{suffix}"),
                                                                                          :3, 3]
    np.testing.assert_allclose(offset, expected, atol=1e-5)
    bones = [hand.meta["rig_joints"][topo.JOINT_NAMES[j]] for j in topo.ARTICULATED_JOINTS]
    wrist = rest_world[gltf_names.index(f"hand{suffix}"), :3, :3]
    wrist = wrist / np.linalg.norm(wrist, axis=0)
    read = wrist.T @ world[:, [names.index(b) for b in bones]] @ wrist  # BVH rotations are from rest already
    errors = _angle_degrees(read, _expected_bone_turns(hand, motion))
    assert errors.max() < 0.5, errors.max()


@pytest.mark.parametrize("side", ["right", "left"])
def test_character_exports_reimport_onto_the_avatar(character_exports, side):
    hand, motion, glb, bvh = character_exports[side]
    expected = forward_kinematics(hand, motion.q_tbs).positions.numpy() @ hand.palm_frame
    for path in (glb, bvh):
        again, rig = load_motion_file(path, options=RigOptions(side=side))
        assert rig.meta["side"] == side and rig.meta["rig_scheme"] == "unreal"
        got = forward_kinematics(rig, again.q_tbs).positions.numpy() @ rig.palm_frame
        np.testing.assert_allclose(got, expected, atol=1e-5)


def test_animations_by_name_or_index_and_listed(tmp_path, sample_hands):
    hand = load_hand_file(REAL / "godot_hand_r.gltf")
    birch = sample_hands["birch"]
    first = retarget(synthesize(["fist"], birch, seed=1, name="grip"), birch, hand, "tbs_copy")
    second = retarget(synthesize(["v_sign", "ok"], birch, seed=2, name="sign"), birch, hand, "tbs_copy")
    one = save_gltf_motion(tmp_path / "one.glb", first, hand)
    on_one = load_hand_file(one)
    two = save_gltf_motion(tmp_path / "two.glb", second, on_one)  # the file keeps its first animation
    for wanted in ("sign", "1", 1):
        got = load_gltf_motion(two, on_one, wanted)
        assert got.name == "sign" and got.n_frames == second.n_frames
    assert load_gltf_motion(two, on_one).name == "grip"
    with pytest.raises(InputFileError, match=r"two\.glb: has no animation named 'wave'; it has 'grip', 'sign'"):
        load_gltf_motion(two, on_one, "wave")
    done = run_cli("rig", str(two))
    assert done.returncode == 0 and "[0] grip" in done.stdout and "[1] sign" in done.stdout
    done = run_cli("retarget", "--motion", str(two), "--animation", "sign", "--target", "iris", "--method",
                   "tbs_copy", "--out", str(tmp_path / "on_iris.npz"))
    assert done.returncode == 0, done.stderr
    assert f"sign: {second.n_frames} frames" in done.stdout


def test_cli_retarget_with_a_joint_map_on_a_rig_motion(tmp_path, sample_hands):
    """Was: "unknown rig scheme 'user'" traceback."""
    renamed = _anonymous_copy(REAL / "godot_hand_r.gltf", tmp_path / "rig.gltf")
    named = load_hand_file(REAL / "godot_hand_r.gltf")
    joint_map = tmp_path / "map.json"
    joint_map.write_text(json.dumps({j: renamed[b] for j, b in named.meta["rig_joints"].items()}))
    hand = load_hand_file(tmp_path / "rig.gltf", RigOptions(joint_map=joint_map))
    birch = sample_hands["birch"]
    motion = retarget(synthesize(["fist"], birch, seed=1), birch, hand, "tbs_copy")
    animated = save_gltf_motion(tmp_path / "rig_anim.glb", motion, hand)
    done = run_cli("retarget", "--motion", str(animated), "--joint-map", str(joint_map), "--target", "iris",
                   "--method", "tbs_copy", "--out", str(tmp_path / "out.npz"))
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out.npz").exists()


# --- bad rigs: one clear line each ---

def _edit_glb(src: Path, dst: Path, edit) -> Path:
    gltf = pygltflib.GLTF2().load(str(src))
    edit(gltf, {n.name: i for i, n in enumerate(gltf.nodes)})
    gltf.save(str(dst))
    return dst


def _cut_off(names: set[str]):
    """An edit that detaches these bones (and what hangs from them) from the skeleton and renames them
    ``prop<i>``: left in the file, they are no longer a hand's bones by place or by name."""
    def edit(gltf, index):
        gone = [index[n] for n in names]
        for node in gltf.nodes:
            node.children = [c for c in node.children or [] if c not in gone]
        stack = list(gone)
        while stack:
            node = stack.pop()
            gltf.nodes[node].name = f"prop{node}"
            stack.extend(gltf.nodes[node].children or [])
    return edit


def _one_line_error(path: Path, *extra: str) -> str:
    done = run_cli("annotate", str(path), *extra)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"s2h: error: {path}: "), done.stderr
    return lines[0]


def test_four_finger_character_is_refused_naming_the_chains_found(tmp_path):
    four = _edit_glb(REAL / "human-female.glb", tmp_path / "four.glb", _cut_off({"pinky_01_r", "pinky_01_l"}))
    line = _one_line_error(four)
    assert "0 bones left for 3 joints (pinky_mcp, pinky_pip, pinky_dip): a hand needs 5 fingers" in line
    assert "missing pinky_mcp, pinky_pip, pinky_dip (no pinky finger" in line
    assert "found 4 finger chains (index_01_r, middle_01_r, ring_01_r, thumb_01_r) under 'hand_r'" in line
    assert "joint map" not in line  # refused early: no joint map can make it a hand
    done = run_cli("rig", str(four), "--template", str(tmp_path / "four.joints.json"))
    assert done.returncode == 2 and "a hand needs 5 fingers" in done.stderr and "wrote" not in done.stdout
    assert not (tmp_path / "four.joints.json").exists()


def test_bones_forming_a_cycle_are_refused(tmp_path):
    def cycle(gltf, index):
        gltf.nodes[index["Armature"]].children.remove(index["Wrist_R"])
        gltf.nodes[index["Index_Tip_R"]].children = [index["Wrist_R"]]
    looped = _edit_glb(REAL / "godot_hand_r.gltf", tmp_path / "looped.gltf", cycle)
    line = _one_line_error(looped)
    assert "bones form a cycle (" in line and "Wrist_R" in line and "Index_Tip_R" in line


def test_skeleton_without_a_hand_is_refused(tmp_path):
    fingers = {f"{f}_01_{s}" for f in ("thumb", "index", "middle", "ring", "pinky") for s in "rl"}
    handless = _edit_glb(REAL / "human-female.glb", tmp_path / "handless.glb", _cut_off(fingers))
    line = _one_line_error(handless)
    assert "no bone has finger chains (3 or more bones) under it: no hand in this skeleton" in line


def test_a_lone_left_hand_asked_for_as_right_is_refused_clearly(tmp_path):
    line = _one_line_error(REAL / "godot_hand_l.gltf", "--side", "right")
    assert "right" in line and "--side" in line


def test_real_rigs_ship_with_their_licences():
    readme = (REAL / "README.md").read_text()
    for name in ("godot_hand_r.gltf", "godot_hand_l.gltf", "human-female.glb", "r_hand_skeletal_lowres.fbx",
                 "RPM_Template_Mesh_XR.glb"):
        assert (REAL / name).exists() and name in readme
    assert "Ready Player Me" in (REAL / "rpm-unity-sdk-core-LICENSE.md").read_text()
    assert (REAL / "godot-xr-tools-hands-License.md").exists() and (REAL / "mesh2motion-LICENSE-CC0.MD").exists()
    assert "Facebook Technologies" in (REAL / "Oculus-SampleFramework-license.txt").read_text()
    assert not (REAL / "human-female.glb").is_symlink()  # a copy in the project, not a link to /work/shared


def test_targets_named_alike_are_told_apart_by_side_then_format_then_number(tmp_path):
    """Both hands of a character, or one avatar as GLB and as FBX, are named alike (the file's stem): hands given
    together that are each of its own side are named by it, else each later one apart from those before it, by what
    differs; the hand given is left as it is."""
    from s2h_viewer.retarget.comparison import with_distinct_names

    right, left = (load_hand_file(REAL / "human-female.glb", RigOptions(side=side)) for side in ("right", "left"))
    glb = load_hand_file(WEBXR / "generic-hand-right.glb")
    (tmp_path / "webxr").mkdir()
    as_gltf = tmp_path / "webxr" / "generic-hand-right.gltf"  # the same hand, another format
    document = pygltflib.GLTF2().load_binary(str(WEBXR / "generic-hand-right.glb"))
    document.convert_buffers(pygltflib.BufferFormat.DATAURI)
    document.save_json(str(as_gltf))
    gltf = load_hand_file(as_gltf)
    again = load_hand_file(WEBXR / "generic-hand-right.glb")
    named = with_distinct_names([right, left, glb, gltf, again])
    assert [hand.name for hand in named] == ["human-female (right)", "human-female (left)", "generic-hand-right",
                                             "generic-hand-right (gltf)", "generic-hand-right #2"]
    assert left.name == "human-female" and named[1] is not left and named[1].mesh is left.mesh
    assert named[2] is glb and named[1].same_as(left)
    assert with_distinct_names([left], [right])[0].name == "human-female (left)"  # a target added later
    assert [h.name for h in with_distinct_names([right, left, right])] == [  # not each of its own side: in turn
        "human-female", "human-female (left)", "human-female #2"]


def test_a_characters_file_says_it_has_both_hands_and_a_lone_hand_does_not():
    """What Add target asks from: the other hand named (a glTF character) or in the humanoid map (VRM), whichever
    side was taken; a lone hand's file has one."""
    assert load_hand_file(REAL / "human-female.glb").meta["both_hands"]
    assert load_hand_file(REAL / "human-female.glb", RigOptions(side="left")).meta["both_hands"]
    assert load_hand_file(REAL / "cryptovoxels.vrm").meta["both_hands"]
    assert not load_hand_file(REAL / "godot_hand_r.gltf").meta["both_hands"]
    assert not load_hand_file(WEBXR / "generic-hand-left.glb").meta["both_hands"]
