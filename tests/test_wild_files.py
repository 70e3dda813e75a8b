"""Files from the wild (issue 22, first items): a `.vrm` read as the GLB it is, a joint-map template that is not
loaded until filled in, and a damaged GLB named for what is wrong with it."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

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
    assert template.exists() and not (tmp_path / "anon.joints.json").exists()
    assert "anon.joints.json" in done.stdout and str(template) in done.stdout
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
