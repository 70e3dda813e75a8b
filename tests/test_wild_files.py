"""Files from the wild (issue 22, first items): a `.vrm` read as the GLB it is, a joint-map template that is not
loaded until filled in, and a damaged GLB named for what is wrong with it."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from s2h_viewer.errors import InputFileError
from s2h_viewer.io.files import RigOptions, load_hand_file, load_motion_file, recognise_file
from s2h_viewer.samples import ASSETS_DIR

ROBOT = ASSETS_DIR / "hands" / "real" / "debug_robot.vrm"
WEBXR = ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb"
GESTURES = ASSETS_DIR / "motions" / "gestures.npz"
ROOT = Path(__file__).resolve().parent.parent


def run_cli(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "s2h_viewer.cli", *argv], capture_output=True, text=True, cwd=ROOT,
                          timeout=300)


@pytest.mark.parametrize("side", ["right", "left"])
def test_a_vrm_avatar_is_read_by_every_command_as_the_glb_it_is(tmp_path, side):
    mapping = recognise_file(ROBOT, RigOptions(side=side))
    assert mapping.scheme == "vrm" and mapping.side == side
    hand = load_hand_file(ROBOT, RigOptions(side=side))
    assert hand.hand_length > 0.05
    out = tmp_path / f"robot_{side}.glb"
    done = run_cli("retarget", "--motion", str(GESTURES), "--target", str(ROBOT), "--side", side,
                   "--method", "tbs_copy", "--out", str(out), "--quiet")
    assert done.returncode == 0, done.stderr
    motion, rig = load_motion_file(out, options=RigOptions(side=side))
    assert motion.n_frames == 378 and rig.hand_length == pytest.approx(hand.hand_length, rel=1e-3)
    assert run_cli("rig", str(ROBOT)).returncode == 0


def test_the_joint_map_template_is_not_loaded_until_it_is_filled(tmp_path):
    """`s2h rig` on an unrecognised rig writes a template to fill; the next retarget still says what is wrong
    with the rig, not that an empty joint map (the template) leaves joints unnamed."""
    renamed = tmp_path / "anon.glb"
    data = WEBXR.read_bytes()
    for old, new in ((b"index-finger", b"pointer-xxxx"), (b"thumb", b"thumm")):
        data = data.replace(old, new)  # same lengths: the GLB stays valid
    renamed.write_bytes(data)
    done = run_cli("rig", str(renamed))
    assert done.returncode == 2
    template = tmp_path / "anon.joints.template.json"
    assert template.exists() and not (tmp_path / "anon.right.joints.json").exists()
    assert "anon.right.joints.json" in done.stdout and str(template) in done.stdout
    again = run_cli("retarget", "--motion", str(GESTURES), "--target", str(renamed), "--out", str(tmp_path / "o.glb"))
    assert again.returncode == 2 and "joint map leaves" not in again.stderr, again.stderr
    assert "missing thumb_cmc" in again.stderr  # the real problem: these bones are not named as a hand
    filled = json.loads(template.read_text())
    assert filled["wrist"] == "wrist" and filled["index_mcp"] == ""  # names it could guess, blanks to fill


def test_a_glb_mangled_by_a_text_conversion_is_named_for_it(tmp_path):
    data = WEBXR.read_bytes()
    crlf = tmp_path / "crlf.glb"
    crlf.write_bytes(data.replace(b"\n", b"\r\n"))
    with pytest.raises(InputFileError, match=r"header declares 94004 bytes, the file has \d+ .*line-ending"):
        load_hand_file(crlf)
    not_utf8 = tmp_path / "latin.glb"
    broken = bytearray(data)
    broken[30] = 0xFF
    not_utf8.write_bytes(bytes(broken))
    with pytest.raises(InputFileError, match="JSON chunk is not UTF-8 text"):
        load_hand_file(not_utf8)
    short_chunk = tmp_path / "chunk.glb"
    shutil.copy(WEBXR, short_chunk)
    raw = bytearray(short_chunk.read_bytes())
    raw[12:16] = (len(raw) * 2).to_bytes(4, "little")
    short_chunk.write_bytes(bytes(raw))
    with pytest.raises(InputFileError, match="JSON chunk declares .* past the end"):
        load_hand_file(short_chunk)


CRYPTOVOXELS = ASSETS_DIR / "hands" / "real" / "cryptovoxels.vrm"
FEMALE = ASSETS_DIR / "hands" / "real" / "human-female.glb"


def _vrm_with_humanoid_bones(source: Path, out: Path, drop: list[str], **changes: int) -> Path:
    """A copy of a VRM 1.0 file whose humanoid map leaves out ``drop`` and points ``changes`` elsewhere."""
    import pygltflib
    gltf = pygltflib.GLTF2().load_binary(str(source))
    bones = gltf.extensions["VRMC_vrm"]["humanoid"]["humanBones"]
    for name in drop:
        del bones[name]
    for name, node in changes.items():
        bones[name] = {"node": node}
    gltf.save_binary(str(out))
    return out


@pytest.mark.parametrize("side", ["right", "left"])
def test_a_vrm0_humanoid_map_naming_no_thumb_is_completed_from_the_finger_chains(side, tmp_path):
    """cryptovoxels.vrm (VRM 0.0): its map names no thumb and no index distal, though the bones are there
    (``Thumb0_R``, ``IndexFinger3_R``); they are taken from the chains under the mapped wrist, and said so."""
    mark = side[0].upper()
    mapping = recognise_file(CRYPTOVOXELS, RigOptions(side=side))
    assert mapping.scheme == "vrm" and mapping.side == side and mapping.side_from == "humanoid map"
    assert [mapping.joints[j] for j in ("thumb_cmc", "thumb_mcp", "thumb_ip", "index_dip", "pinky_dip")] == [
        f"Thumb0_{mark}", f"Thumb1_{mark}", f"Thumb2_{mark}", f"IndexFinger3_{mark}", f"LittleFinger3_{mark}"]
    assert "humanoid map names no thumb_cmc, thumb_mcp, thumb_ip, index_dip" in mapping.notes[0]
    out = tmp_path / f"cv_{side}.glb"
    done = run_cli("retarget", "--motion", str(GESTURES), "--target", str(CRYPTOVOXELS), "--side", side,
                   "--method", "tbs_copy", "--out", str(out), "--quiet")
    assert done.returncode == 0, done.stderr
    motion, rig = load_motion_file(out, options=RigOptions(side=side))
    assert motion.n_frames == 378 and rig.meta["rig_joints"]["thumb_cmc"] == f"Thumb0_{mark}"


@pytest.mark.parametrize("side", ["right", "left"])
def test_a_fingertip_is_the_distal_bones_tail_not_what_an_exporter_hung_below_it(side):
    """cryptovoxels.vrm ends some fingers in ``LittleFinger3_R_End`` with a ``LittleFinger3_R_End_end`` leaf below
    it, others in ``IndexFinger3_R_end``: the tip is the distal bone's tail either way. Taking the leaf made the
    ring and pinky (the left middle too) a phalanx too long and the two hands 0.107 and 0.135 m."""
    from s2h_viewer.hand import topology as topo
    mark = side[0].upper()
    mapping = recognise_file(CRYPTOVOXELS, RigOptions(side=side))
    assert mapping.joints["pinky_tip"] == f"LittleFinger3_{mark}_End"
    assert mapping.joints["ring_tip"] == f"RingFinger3_{mark}_End"
    assert mapping.joints["index_tip"] == f"IndexFinger3_{mark}_end"
    hand = load_hand_file(CRYPTOVOXELS, RigOptions(side=side))
    bones = np.linalg.norm(hand.offsets, axis=1)
    for finger in ("middle", "ring", "pinky"):  # the last phalanx no longer than the middle one
        tip = topo.joint_index(f"{finger}_tip")
        assert bones[tip] < 1.1 * bones[tip - 1], (finger, bones[tip - 1:tip + 1])


def test_a_named_rig_without_tip_bones_takes_the_tails_an_exporter_wrote(tmp_path):
    """Mixamo names without the ``Index4`` tips, as a Blender export with leaf bones writes them (``Index3_end``):
    the tails are the tips, where they are, not a guess extrapolated from the finger; without them the tips are
    extrapolated as before, and a leaf not named as the distal bone's tail is not taken for one."""
    from s2h_viewer import samples
    from s2h_viewer.hand import topology as topo
    from wild_rigs import write_gltf_skeleton
    truth = samples.load_sample_hand("birch").rest_positions
    names = ["mixamorig:RightHand"] + [f"mixamorig:RightHand{f.capitalize()}{i}" for f in topo.FINGERS
                                       for i in (1, 2, 3, 4)]
    tips = [topo.joint_index(f"{f}_tip") for f in topo.FINGERS]
    for tail, taken in (("{}_end", True), ("{}_gem", False)):
        named = [tail.format(names[j - 1]) if j in tips else n for j, n in enumerate(names)]
        rig = write_gltf_skeleton(tmp_path / f"mixamo{tail[2:]}.gltf", named, list(topo.PARENTS), truth)
        mapping = recognise_file(rig)
        assert mapping.scheme == "mixamo"
        assert (mapping.joints.get("index_tip") == named[topo.joint_index("index_tip")]) == taken
        if taken:  # the last phalanges as long as the file has them
            offsets = np.linalg.norm(load_hand_file(rig).offsets[tips], axis=1)
            np.testing.assert_allclose(offsets, np.linalg.norm(truth[tips] - truth[np.array(tips) - 1], axis=1),
                                       rtol=1e-5)
    no_tips = [n for j, n in enumerate(names) if j not in tips]
    parents = [no_tips.index(names[p]) if p >= 0 else -1 for j, p in enumerate(topo.PARENTS) if j not in tips]
    rig = write_gltf_skeleton(tmp_path / "mixamo_no_tips.gltf", no_tips, parents, np.delete(truth, tips, 0))
    assert "index_tip" not in recognise_file(rig).joints


def test_a_complete_vrm0_map_takes_each_tip_from_below_its_distal_bone_alike(tmp_path):
    """The same avatar with a humanoid map naming every bone (nothing completed from the chains): each tip is
    the distal bone's tail found below it, the ``_End`` bone where one is there, as with the partial map."""
    import pygltflib
    gltf = pygltflib.GLTF2().load_binary(str(CRYPTOVOXELS))
    names = [node.name for node in gltf.nodes]
    bones = gltf.extensions["VRM"]["humanoid"]["humanBones"]
    for side, mark in (("right", "R"), ("left", "L")):
        for level, suffix in zip(("Proximal", "Intermediate", "Distal"), ("0", "1", "2")):
            bones.append({"bone": f"{side}Thumb{level}", "node": names.index(f"Thumb{suffix}_{mark}")})
        bones.append({"bone": f"{side}IndexDistal", "node": names.index(f"IndexFinger3_{mark}")})
    complete = tmp_path / "complete_map.vrm"
    gltf.save_binary(str(complete))
    for side in ("right", "left"):
        mapping = recognise_file(complete, RigOptions(side=side))
        partial = recognise_file(CRYPTOVOXELS, RigOptions(side=side))
        assert not mapping.notes and mapping.joints == partial.joints


@pytest.mark.parametrize("side, unparted", [("right", ["middle", "ring", "pinky"]), ("left", ["middle", "ring"])])
def test_a_mitten_mesh_gives_its_fingers_no_frames_or_widths_of_its_own(side, unparted):
    """cryptovoxels.vrm's hand is one low-poly paddle (140 vertices): a finger's section there spans its
    neighbours, read 0.11-0.13 of the hand as fingertip radii (3x a real hand's) and made fingers side by side
    touch: ASRN's contact precision on the authored poses 0.64. The solver says the mesh does not part them,
    trusts none of their rays, and the radii are the procedural hands' proportions (the left pinky's joints lie
    outside the mesh: no ray hits it at all)."""
    from s2h_viewer.annotate.solver import DEFAULT_RADIUS_FRACTIONS, solve_tbs_frames
    from s2h_viewer.hand import topology as topo
    hand = load_hand_file(CRYPTOVOXELS, RigOptions(side=side))
    solution = solve_tbs_frames(hand)
    lines = [line for line in solution.diagnostics if "the mesh does not part it from its neighbours" in line]
    assert [line.split(":")[0] for line in lines] == unparted
    assert "rays" not in solution.basis and (solution.confidence <= 0.6).all()
    np.testing.assert_allclose(hand.radii[topo.TIP_JOINTS], DEFAULT_RADIUS_FRACTIONS[topo.TIP_JOINTS]
                               * hand.hand_length)
    separate = solve_tbs_frames(load_hand_file(FEMALE, RigOptions(side="right")))
    assert not any("does not part" in line for line in separate.diagnostics)


def test_a_humanoid_map_naming_few_fingers_is_completed_as_the_full_one_and_refused_in_its_own_words(tmp_path):
    """Made from debug_robot.vrm: a map without its middle finger and thumb distal, and one without the whole
    thumb and index, give the full map's joints; one whose wrist is a finger bone is refused, naming the file's
    humanoid map, never a joint map the user did not pass."""
    full = recognise_file(ROBOT).joints
    for drop in (["rightMiddleProximal", "rightMiddleIntermediate", "rightMiddleDistal", "rightThumbDistal"],
                 ["rightThumbMetacarpal", "rightThumbProximal", "rightThumbDistal", "rightIndexProximal",
                  "rightIndexIntermediate", "rightIndexDistal"]):
        partial = _vrm_with_humanoid_bones(ROBOT, tmp_path / "partial.vrm", drop)
        mapping = recognise_file(partial)
        assert mapping.joints == full and mapping.scheme == "vrm"
    from s2h_viewer.io.gltf import _Document
    doc = _Document(ROBOT)
    broken = _vrm_with_humanoid_bones(ROBOT, tmp_path / "broken.vrm", ["rightThumbMetacarpal"],
                                      rightHand=doc.names.index(full["index_mcp"]))
    with pytest.raises(InputFileError) as refused:
        recognise_file(broken)
    message = str(refused.value)
    assert "the file's humanoid map of the right hand names no" in message and "thumb_cmc" in message
    assert "the joint map" not in message


def _annotate_and_save(path: Path, side: str) -> Path:
    """What `s2h annotate FILE --side SIDE --save` does, in this process."""
    from s2h_viewer.annotate.solver import solve_tbs_frames
    from s2h_viewer.io.annotation import Annotation, save_annotation
    hand = load_hand_file(path, RigOptions(side=side))
    solution = solve_tbs_frames(hand)
    return save_annotation(Annotation(solution.frames, ["solver"] * 15, solution.confidence), path, side)


def test_each_hand_of_a_character_has_its_own_sidecar_in_either_order(tmp_path):
    """A full body annotated and saved for one hand, then retargeted onto the other (the issue: "twist axis does
    not follow the bone"), in either order; each hand then opens with its own frames."""
    for first, second in (("right", "left"), ("left", "right")):
        folder = tmp_path / first
        folder.mkdir()
        body = folder / "human-female.glb"
        shutil.copy(FEMALE, body)
        done = run_cli("annotate", str(body), "--side", first, "--save")
        assert done.returncode == 0, done.stderr
        assert (folder / f"human-female.{first}.tbs.json").is_file()
        out = folder / f"on_{second}.glb"
        done = run_cli("retarget", "--motion", str(GESTURES), "--target", str(body), "--side", second,
                       "--method", "tbs_copy", "--out", str(out), "--quiet")
        assert done.returncode == 0, done.stderr
        assert load_hand_file(body, RigOptions(side=second)).meta["annotation"] == "solver"
        _annotate_and_save(body, second)
        hands = {side: load_hand_file(body, RigOptions(side=side)) for side in ("right", "left")}
        assert all(h.meta["annotation"] == "sidecar" for h in hands.values())
        saved = json.loads((folder / f"human-female.{second}.tbs.json").read_text())
        assert saved["side"] == second and saved["version"] == 2


def test_an_older_sidelesss_sidecar_is_not_applied_to_the_hand_it_was_not_made_for(tmp_path):
    """A version 1 ``<stem>.tbs.json`` (no side) made for the right hand still opens the right hand; the left
    hand, which its frames do not fit, is solved and says why; a renamed sidecar of the other side is refused."""
    body = tmp_path / "human-female.glb"
    shutil.copy(FEMALE, body)
    document = json.loads(_annotate_and_save(body, "right").read_text())
    (tmp_path / "human-female.right.tbs.json").unlink()
    document["version"] = 1
    del document["side"]
    (tmp_path / "human-female.tbs.json").write_text(json.dumps(document))
    assert load_hand_file(body, RigOptions(side="right")).meta["annotation"] == "sidecar"
    left = load_hand_file(body, RigOptions(side="left"))
    assert left.meta["annotation"] == "solver"
    assert "human-female.tbs.json (an older sidecar that does not say its hand) does not fit the left hand" in \
        left.meta["solver_diagnostics"][0]
    (tmp_path / "human-female.tbs.json").unlink()
    shutil.copy(_annotate_and_save(body, "right"), tmp_path / "human-female.left.tbs.json")
    with pytest.raises(InputFileError, match=r"human-female\.left\.tbs\.json: holds the right hand's frames"):
        load_hand_file(body, RigOptions(side="left"))


def test_joint_maps_are_kept_per_hand_and_an_older_one_is_not_applied_to_the_other_hand(tmp_path):
    """A joint map saved for the right hand (per side, or an older side-less one naming right-hand bones) is not
    used for the left hand; the left hand's own map is."""
    from s2h_viewer.io.files import legacy_joint_map_sidecar, save_joint_map
    body = tmp_path / "human-female.glb"
    shutil.copy(FEMALE, body)
    right = recognise_file(body, RigOptions(side="right")).joints
    left = recognise_file(body, RigOptions(side="left")).joints
    legacy_joint_map_sidecar(body).write_text(json.dumps(right))
    assert recognise_file(body).scheme == "user"
    assert recognise_file(body, RigOptions(side="left")).joints == left  # by names, not the right hand's map
    legacy_joint_map_sidecar(body).unlink()
    save_joint_map(body, right, "right")
    save_joint_map(body, left, "left")
    for side, joints in (("right", right), ("left", left)):
        mapping = recognise_file(body, RigOptions(side=side))
        assert mapping.scheme == "user" and mapping.joints == joints and mapping.side == side


OCULUS = ASSETS_DIR / "hands" / "real" / "r_hand_skeletal_lowres.fbx"


def test_meta_hand_skeletons_with_marker_nodes_are_read_by_their_names_and_their_chains(tmp_path):
    """Meta hand-tracking hands hang ``*_marker`` nodes beside each finger's bones and end fingers in ``*_null``
    tips (made here from the Oculus custom hand's skeleton): the names give the hand and its side (a ``b_r_``
    rig mirrored is still the right hand: names win over geometry), and with the names gone the markers do not
    hide the five chains from topology."""
    from wild_rigs import meta_hand_skeleton, mirrored, write_gltf_skeleton
    real = recognise_file(OCULUS)
    assert (real.scheme, real.side, real.side_from, real.confidence) == ("meta", "right", "names", 1.0)
    for mark, side in (("r", "right"), ("l", "left")):
        names, parents, positions = meta_hand_skeleton(OCULUS, mark)
        rig = write_gltf_skeleton(tmp_path / f"meta_{mark}.gltf", names, parents,
                                  positions if mark == "r" else mirrored(positions))
        mapping = recognise_file(rig)
        assert (mapping.scheme, mapping.side, mapping.side_from) == ("meta", side, "names")
        assert mapping.joints["thumb_cmc"] == f"b_{mark}_thumb1"
        assert mapping.joints["pinky_tip"] == f"b_{mark}_pinky_null"
        assert f"b_{mark}_pinky0" in mapping.palm_bones
    names, parents, positions = meta_hand_skeleton(OCULUS, "r")
    flipped = recognise_file(write_gltf_skeleton(tmp_path / "meta_r_mirrored.gltf", names, parents,
                                                 mirrored(positions)))
    assert (flipped.side, flipped.side_from) == ("right", "names")
    anonymous = [n if n.endswith("_marker") else f"Bone{i:03d}" for i, n in enumerate(names)]
    by_shape = recognise_file(write_gltf_skeleton(tmp_path / "anon.gltf", anonymous, parents, positions))
    assert by_shape.scheme == "topology" and by_shape.side == "right"
    assert [anonymous.index(by_shape.joints[f"{f}_mcp" if f != "thumb" else "thumb_cmc"]) for f in
            ("thumb", "index", "middle", "ring", "pinky")] == [names.index(f"b_r_{f}1") for f in
                                                              ("thumb", "index", "middle", "ring", "pinky")]
    # the tips named as their distal bone's tail, each with an exporter's leaf below it (cryptovoxels' kind)
    tails = [f"{anonymous[parents[i]]}_End" if n.endswith("_null") else n for i, n in enumerate(names)]
    tails = [t if t.endswith(("_marker", "_End")) else a for t, a in zip(tails, anonymous)]
    leaves = [i for i, n in enumerate(tails) if n.endswith("_End")]
    extended = tails + [f"{tails[i]}_end" for i in leaves]
    beyond = positions[leaves] + (positions[leaves] - positions[[parents[i] for i in leaves]])
    by_tails = recognise_file(write_gltf_skeleton(tmp_path / "tails.gltf", extended, parents + leaves,
                                                  np.vstack([positions, beyond])))
    assert by_tails.scheme == "topology"
    assert [by_tails.joints[f"{f}_tip"] for f in ("thumb", "index", "middle", "ring", "pinky")] == [
        tails[names.index(f"b_r_{f}_null")] for f in ("thumb", "index", "middle", "ring", "pinky")]
    out = tmp_path / "on_meta.glb"
    done = run_cli("retarget", "--motion", str(GESTURES), "--target", str(tmp_path / "meta_l.gltf"),
                   "--method", "tbs_copy", "--out", str(out), "--quiet")
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("extension", ["EXT_meshopt_compression", "KHR_draco_mesh_compression"])
def test_a_compressed_gltf_is_refused_naming_its_compression_never_misread(extension, tmp_path):
    """A VRoid avatar written with meshopt compression read as plain buffers gave "skins vertices to joint 255 of
    a 244-joint skin": a file that requires a compression extension s2h does not decode is refused, naming it."""
    import pygltflib
    gltf = pygltflib.GLTF2().load_binary(str(ROBOT))
    gltf.extensionsUsed = [*(gltf.extensionsUsed or []), extension]
    gltf.extensionsRequired = [*(gltf.extensionsRequired or []), extension]
    compressed = tmp_path / "compressed.vrm"
    gltf.save_binary(str(compressed))
    kind = "meshopt" if "meshopt" in extension else "Draco"
    for read in (load_hand_file, recognise_file):
        with pytest.raises(InputFileError, match=rf"compressed\.vrm: its meshes are {kind} \({extension}\) "
                                                 rf"compressed, which s2h does not decode"):
            read(compressed)
    done = run_cli("rig", str(compressed))
    assert done.returncode == 2 and f"{kind} ({extension})" in done.stderr and "Traceback" not in done.stderr


GODOT = ASSETS_DIR / "hands" / "real" / "godot_hand_r.gltf"


@pytest.fixture(scope="module")
def gestures_bvh(tmp_path_factory) -> Path:
    """The gestures clip on its own sample hand as a BVH (centimetres, as our writer writes a hand of its own)."""
    from s2h_viewer.io.files import save_motion_file
    from s2h_viewer.io.npz import load_motion
    from s2h_viewer.samples import load_sample_hand
    motion = load_motion(GESTURES)
    return save_motion_file(tmp_path_factory.mktemp("bvh") / "gestures.bvh", motion,
                            load_sample_hand(motion.hand_name))


@pytest.mark.parametrize("unit,factor", [("cm", 1.0), ("m", 0.01), ("dm", 0.1), ("mm", 10.0), ("in", 1 / 2.54)])
def test_a_mocap_bvh_in_any_unit_reads_as_the_same_hand_and_says_its_guess(unit, factor, gestures_bvh, tmp_path):
    """A finger-mocap BVH in decimetres was refused as implausible with no way to say its unit: m, dm, cm, mm and
    inches are told from the hand's size (and said), --unit says it, a wrong --unit is refused naming it."""
    from wild_rigs import rescaled_bvh
    reference, reference_rig = load_motion_file(shutil.copy(gestures_bvh, tmp_path / "copy.bvh"))  # no sidecar
    path = rescaled_bvh(gestures_bvh, tmp_path / f"gestures_{unit}.bvh", factor)
    motion, rig = load_motion_file(path)
    assert rig.meta["unit"] == unit and "guessed from the hand's size: " in rig.meta["unit_note"]
    assert rig.hand_length == pytest.approx(reference_rig.hand_length, rel=1e-6)
    np.testing.assert_allclose(motion.q_tbs, reference.q_tbs, atol=1e-5)
    told, _ = load_motion_file(path, options=RigOptions(unit=unit))
    np.testing.assert_allclose(told.q_tbs, reference.q_tbs, atol=1e-5)
    wrong = "mm" if unit in ("cm", "m", "dm") else "m"
    with pytest.raises(InputFileError, match=rf"gestures_{unit}\.bvh: wrist to middle DIP is .*\(--unit {wrong}\) a "
                                             rf"hand of .* not a plausible one"):
        load_hand_file(path, RigOptions(unit=wrong))
    done = run_cli("retarget", "--motion", str(path), "--target", "iris", "--method", "tbs_copy", "--unit", unit,
                   "--out", str(tmp_path / "out.npz"), "--quiet")
    assert done.returncode == 0, done.stderr


def test_a_hand_scaled_to_nothing_is_refused_and_scaled_roots_read_in_world_units(tmp_path):
    """A node scale of 0 on the hand (or one finger) collapses it to a point: refused naming the bone, never
    retargeted. A skeleton under root nodes scaled 0.1 and 0.01 (a Blender re-export) reads in world units."""
    import pygltflib
    from wild_rigs import meta_hand_skeleton, write_gltf_skeleton
    names = [n.name for n in pygltflib.GLTF2().load(str(GODOT)).nodes]
    for bone in ("Index_Proximal_R", "Wrist_R"):
        gltf = pygltflib.GLTF2().load(str(GODOT))
        gltf.nodes[names.index(bone)].scale = [0.0, 0.0, 0.0]
        gltf.save(str(tmp_path / "collapsed.gltf"))
        with pytest.raises(InputFileError, match=rf"collapsed\.gltf: bone '{bone}' is scaled to 0 .* collapses"):
            load_hand_file(tmp_path / "collapsed.gltf")
    bones, parents, positions = meta_hand_skeleton(OCULUS)
    plain = load_hand_file(write_gltf_skeleton(tmp_path / "plain.gltf", bones, parents, positions))
    nested = write_gltf_skeleton(tmp_path / "nested.gltf", bones, parents, positions * 1000.0, scale=0.01)
    gltf = pygltflib.GLTF2().load(str(nested))
    gltf.nodes.append(pygltflib.Node(name="Scene root", scale=[0.1] * 3, children=[len(gltf.nodes) - 1]))
    gltf.scenes[0].nodes = [len(gltf.nodes) - 1]
    gltf.save(str(nested))
    scaled = load_hand_file(nested)
    assert scaled.meta["unit"] == "m" and scaled.hand_length == pytest.approx(plain.hand_length, rel=1e-9)


@pytest.mark.parametrize("side", ["right", "left"])
def test_a_per_dof_mocap_bvh_is_read_by_its_names_with_its_joints_folded_and_its_side_from_its_poses(
        side, gestures_bvh, tmp_path):
    """Optical finger mocap writes a joint per degree of freedom (``INDEX_MCP_FE`` then ``INDEX_MCP_AA`` at the
    same point), zero-length End Sites and a zero pose that is no hand pose (every finger straight along the
    palm): the zero-length runs fold into one rotation, the finger names win over geometry, the side comes from
    the clip's poses, and every joint moves where the original clip's does."""
    import copy

    import torch

    from s2h_viewer.hand import topology as topo
    from s2h_viewer.hand.kinematics import forward_kinematics
    from s2h_viewer.io.files import save_motion_file
    from s2h_viewer.io.npz import load_motion
    from s2h_viewer.samples import load_sample_hand
    from wild_rigs import per_dof_bvh
    source = gestures_bvh
    if side == "left":  # the same clip on the mirror image of its hand, written as a left hand
        motion = load_motion(GESTURES)
        left = copy.deepcopy(load_sample_hand(motion.hand_name))
        left.meta["side"] = "left"
        source = save_motion_file(tmp_path / "gestures_left.bvh", motion, left)
    mocap = per_dof_bvh(source, tmp_path / "mocap.bvh")
    mapping = recognise_file(mocap)
    assert mapping.scheme == "s2h" and mapping.side == side and "clip's poses" in mapping.side_from
    assert [mapping.joints[f"{f}_{lv}"] for f in topo.FINGERS for lv in topo.FINGER_LEVELS[f][:3]] == [
        f"{f.upper()}_{lv.upper()}_FE" for f in topo.FINGERS for lv in topo.FINGER_LEVELS[f][:3]]
    reference, reference_rig = load_motion_file(shutil.copy(source, tmp_path / "copy.bvh"))
    motion, rig = load_motion_file(mocap)
    assert rig.meta["side"] == side
    joints = [j for j in range(topo.N_JOINTS) if j not in topo.TIP_JOINTS]  # mocap tips are zero-length

    def positions(hand, clip):
        with torch.no_grad():
            return forward_kinematics(hand, torch.as_tensor(clip.q_tbs, dtype=torch.float64)).positions.numpy()
    error = np.abs(positions(rig, motion)[:, joints] - positions(reference_rig, reference)[:, joints]).max()
    assert error < 1e-6


def test_fbx_out_without_blender_is_one_line_saying_how_to_get_it_and_writes_nothing(tmp_path):
    """FBX is written through Blender (`make blender`); where there is none, `--out x.fbx` says so in one line."""
    import os
    out = tmp_path / "out.fbx"
    done = subprocess.run([sys.executable, "-m", "s2h_viewer.cli", "retarget", "--motion", str(GESTURES), "--target",
                           "iris", "--method", "tbs_copy", "--out", str(out), "--quiet"], capture_output=True,
                          text=True, cwd=ROOT, timeout=300,
                          env={**os.environ, "S2H_BLENDER_PYTHON": str(tmp_path / "no-blender" / "python")})
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.strip() == (f"s2h: error: {out}: writing FBX goes through Blender, which is not installed "
                                   f"here: run `make blender` (or set S2H_BLENDER_PYTHON to a Python with bpy), or "
                                   f"write .glb, which Blender, Unity and Unreal import")
    assert list(tmp_path.iterdir()) == []
