"""Hostile files: a seeded mutator over the shipped samples through every reader and the CLI entry points.

Every outcome must be a load whose values are all finite, or one clean line (`InputFileError`, CLI
exit 2) naming the file: never a traceback, a hang, an allocation a check should have stopped, or
NaN accepted (see tests/fuzzing.py). The default run takes a couple of minutes; ``-m fuzz_long`` runs
ten times as many inputs with other seeds. ``-s`` prints the table of outcomes per reader.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from fuzzing import (Tally, classify, mutate_bvh, mutate_bytes, mutate_gltf, mutate_json, mutate_npz,
                     unreadable_supported)

from s2h_viewer import samples
from s2h_viewer.annotate.solver import solve_tbs_frames
from s2h_viewer.errors import InputFileError
from s2h_viewer.hand.motion import Motion
from s2h_viewer.io.annotation import Annotation, save_annotation, sidecar_path
from s2h_viewer.io.bvh import save_bvh
from s2h_viewer.io.files import RigOptions, load_hand_file, load_motion_file
from s2h_viewer.io.gltf import save_gltf_motion
from s2h_viewer.io.mediapipe_hand import save_mediapipe_hand
from s2h_viewer.io.npz import load_motion, save_motion
from s2h_viewer.io.webxr_hand import save_webxr_hand
from s2h_viewer.tracking.synthetic import synthetic_recording

ASSETS = samples.ASSETS_DIR
WEBXR = ASSETS / "hands" / "webxr" / "generic-hand-right.glb"
FBX = ASSETS / "hands" / "fbx" / "mixamo_right_hand.fbx"
ROOT = Path(__file__).resolve().parent.parent
CLI_TIMEOUT_S = 240


@pytest.fixture(scope="module")
def originals(tmp_path_factory) -> dict[str, Path]:
    """One valid file per reader: shipped samples, and files the project writes from them."""
    folder = tmp_path_factory.mktemp("originals")
    webxr = load_hand_file(WEBXR)
    clip = load_motion(ASSETS / "motions" / "gestures.npz")
    short = Motion(q_tbs=clip.q_tbs[:60], fps=clip.fps, name="short", hand_name=clip.hand_name)
    anim = save_gltf_motion(folder / "animated.glb", short, webxr)
    bvh = save_bvh(folder / "clip.bvh", short, samples.load_sample_hand(clip.hand_name))
    joint_map = folder / "map.json"
    joint_map.write_text(json.dumps(webxr.meta["rig_joints"]))
    annotated = folder / "annotated"
    annotated.mkdir()
    hand_copy = annotated / "hand.glb"
    hand_copy.write_bytes(WEBXR.read_bytes())
    solution = solve_tbs_frames(webxr)
    sidecar = save_annotation(Annotation(solution.frames, ["solver"] * 15, solution.confidence, ["a note"]),
                              hand_copy, "right")
    valid_sidecar = folder / "valid.tbs.json"
    valid_sidecar.write_bytes(sidecar.read_bytes())
    # the gestures clip's first 60 frames, its labels and meta kept: a damaged copy the reader still takes is
    # retargeted by ASRN in the CLI's fuzz, which took most of its minute on the whole clip
    labelled = save_motion(dataclasses.replace(clip, q_tbs=clip.q_tbs[:60], labels=clip.labels[:60]),
                           folder / "gestures_60.npz")
    recording = synthetic_recording(samples.load_sample_hand("iris"), short, noise_mm=2.0, lost=0.1, seed=1)
    recording.positions, recording.orientations = recording.positions[:24], recording.orientations[:24]
    recording.labels = None
    np.save(folder / "keypoints.npy", recording.positions)
    return {"npz hand": ASSETS / "hands" / "iris.npz", "npz motion": labelled,
            "glTF hand": WEBXR, "glTF motion": anim, "BVH": bvh, "FBX": FBX, "sidecar": valid_sidecar,
            "annotated hand": hand_copy, "joint map": joint_map,
            "WebXR recording": save_webxr_hand(folder / "webxr.json", recording),
            "MediaPipe recording": save_mediapipe_hand(folder / "mediapipe.json", recording, "Left"),
            "keypoint array": folder / "keypoints.npy"}


#: reader -> (mutator, loader of the damaged file at a path, suffix of the damaged file)
READERS = {
    "npz hand": (mutate_npz, load_hand_file, ".npz"),
    "npz motion": (mutate_npz, load_motion_file, ".npz"),
    "glTF hand": (mutate_gltf, load_hand_file, ".glb"),
    "glTF motion": (mutate_gltf, load_motion_file, ".glb"),
    "BVH": (mutate_bvh, load_motion_file, ".bvh"),
    "FBX": (mutate_bytes, load_motion_file, ".fbx"),
    "WebXR recording": (mutate_json, load_motion_file, ".json"),
    "MediaPipe recording": (mutate_json, load_motion_file, ".json"),
    "keypoint array": (mutate_bytes, load_motion_file, ".npy"),
}
#: inputs per reader in the default run (``fuzz_long`` runs ten times as many)
#: (the slow readers fewer: a damaged keypoint array is fitted, 1 s each; an FBX 1.4 s; a glTF hand 0.25 s)
COUNTS = {"npz hand": 50, "npz motion": 50, "glTF hand": 30, "glTF motion": 25, "BVH": 50, "FBX": 3,
          "sidecar": 30, "joint map": 15, "WebXR recording": 20, "MediaPipe recording": 20, "keypoint array": 6}


def _fuzz_readers(originals: dict[str, Path], folder: Path, seed: int, scale: int) -> Tally:
    tally = Tally()
    for reader, count in COUNTS.items():
        rng = np.random.default_rng([seed, list(COUNTS).index(reader)])
        source = originals[reader].read_bytes()
        for case in range(count * scale):
            if reader == "sidecar":
                what, data = mutate_json(source, rng)
                hand_file = originals["annotated hand"]
                damaged = sidecar_path(hand_file, "right")
                damaged.write_bytes(data)
                outcome, detail = classify(lambda: load_hand_file(hand_file), damaged)
            elif reader == "joint map":
                what, data = mutate_json(source, rng)
                damaged = folder / f"map_{case}.json"
                damaged.write_bytes(data)
                outcome, detail = classify(lambda: load_hand_file(WEBXR, RigOptions(joint_map=damaged)), damaged)
                if outcome == "unclear" and "\n" not in detail and detail.startswith(str(WEBXR)):
                    outcome = "clean"  # a map that does not fit the rig: the line names the rig file
            else:
                mutate, load, suffix = READERS[reader]
                what, data = mutate(source, rng)
                damaged = folder / f"{reader.replace(' ', '_')}_{case}{suffix}"
                damaged.write_bytes(data)
                outcome, detail = classify(lambda: load(damaged), damaged)
            tally.add(reader, what, outcome, detail)
    return tally


def _path_cases(originals: dict[str, Path], folder: Path) -> Tally:
    """Directories, FIFOs, missing, empty and unreadable paths, and files under the wrong suffix."""
    tally = Tally()
    loaders = {".npz": load_hand_file, ".glb": load_hand_file, ".gltf": load_hand_file, ".bvh": load_motion_file,
               ".fbx": load_hand_file}
    contents = {"npz": originals["npz hand"], "glb": originals["glTF hand"], "bvh": originals["BVH"],
                "json": originals["joint map"]}
    for suffix, load in loaders.items():
        cases = {"directory": folder / f"dir{suffix}", "fifo": folder / f"fifo{suffix}",
                 "missing": folder / f"missing{suffix}", "empty": folder / f"empty{suffix}"}
        cases["directory"].mkdir()
        os.mkfifo(cases["fifo"])
        cases["empty"].write_bytes(b"")
        if unreadable_supported():
            cases["unreadable"] = folder / f"unreadable{suffix}"
            cases["unreadable"].write_bytes(originals["npz hand"].read_bytes())
            cases["unreadable"].chmod(0)
        for kind, src in contents.items():
            if f".{kind}" != suffix:
                cases[f"{kind} as {suffix}"] = folder / f"{kind}_as{suffix}"
                cases[f"{kind} as {suffix}"].write_bytes(src.read_bytes())
        for what, path in cases.items():
            tally.add("paths", what, *classify(lambda: load(path), path))
    return tally


def _run_fuzz(originals, folder: Path, seed: int, scale: int) -> Tally:
    readers = _fuzz_readers(originals, folder, seed, scale)
    (folder / "paths").mkdir()
    paths = _path_cases(originals, folder / "paths")
    readers.counts.update(paths.counts)
    readers.examples += paths.examples
    print("\n" + readers.table())
    return readers


def test_every_reader_gives_a_clean_line_or_a_finite_result(originals, tmp_path):
    tally = _run_fuzz(originals, tmp_path, seed=13, scale=1)
    assert sum(sum(c.values()) for c in tally.counts.values()) >= 300
    assert sum(c["clean"] for c in tally.counts.values()) > 200  # the mutations do damage
    assert tally.bad() == 0, "\n".join(tally.examples[:20])


@pytest.mark.fuzz_long
def test_every_reader_long_run(originals, tmp_path):
    tally = _run_fuzz(originals, tmp_path, seed=1013, scale=10)
    assert tally.bad() == 0, "\n".join(tally.examples[:40])


# ---------------------------------------------------------------- the CLI entry points

def _cli(argv: list[str]) -> tuple[str, str]:
    """(outcome, detail) of one CLI run: ok (exit 0), clean (exit 2, one `s2h: error:` line), else
    traceback / hang / other exit."""
    try:
        done = subprocess.run([sys.executable, "-m", "s2h_viewer.cli", *argv], capture_output=True, text=True,
                              timeout=CLI_TIMEOUT_S, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return "hang", f"over {CLI_TIMEOUT_S} s: {' '.join(argv)}"
    if "Traceback" in done.stderr:
        return "traceback", done.stderr.strip().splitlines()[-1]
    if done.returncode == 0:
        return "ok", ""
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    if done.returncode == 2 and len(lines) == 1 and lines[0].startswith("s2h: error: "):
        return "clean", lines[0]
    return "unclear", f"exit {done.returncode}: {done.stderr.strip()[-300:]}"


def _cli_cases(originals: dict[str, Path], folder: Path, seed: int, per_kind: int) -> list[tuple[str, list[str], Path]]:
    """(entry point, argv, damaged file) for annotate, retarget (motion and target) and evaluate."""
    rng = np.random.default_rng(seed)
    good_motion = originals["npz motion"]
    cases = []
    for n in range(per_kind):
        damaged = {}
        for reader, (mutate, _, suffix) in READERS.items():
            if reader != "FBX":
                path = folder / f"cli_{reader.replace(' ', '_')}_{n}{suffix}"
                path.write_bytes(mutate(originals[reader].read_bytes(), rng)[1])
                damaged[reader] = path
        out = folder / f"out_{n}"
        cases += [
            ("annotate", ["annotate", str(damaged["glTF hand"])], damaged["glTF hand"]),
            ("retarget --motion", ["retarget", "--quiet", "--motion", str(damaged[["npz motion", "BVH", "glTF motion"][n % 3]]),
                                   "--target", "iris", "--method", "asrn", "--out", f"{out}.npz"],
             damaged[["npz motion", "BVH", "glTF motion"][n % 3]]),
            ("retarget --target", ["retarget", "--quiet", "--motion", str(good_motion), "--target",
                                   str(damaged[["glTF hand", "npz hand"][n % 2]]), "--method", "tbs_copy",
                                   "--out", f"{out}_t.npz"], damaged[["glTF hand", "npz hand"][n % 2]]),
            ("evaluate --motion", ["evaluate", "--quiet", "--methods", "tbs_copy", "--motion",
                                   str(damaged["npz motion"]), "--target", "iris", "--out", f"{out}_e"],
             damaged["npz motion"]),
            ("evaluate --target", ["evaluate", "--quiet", "--methods", "tbs_copy", "--motion", str(good_motion),
                                   "--target", str(damaged["npz hand"]), "--out", f"{out}_f"], damaged["npz hand"]),
        ]
    return cases


def _run_cli_fuzz(originals, folder: Path, seed: int, per_kind: int) -> Tally:
    cases = _cli_cases(originals, folder, seed, per_kind)
    tally = Tally()
    with ThreadPoolExecutor(max_workers=2) as pool:
        for (entry, argv, damaged), (outcome, detail) in zip(cases, pool.map(lambda c: _cli(c[1]), cases)):
            if outcome == "clean" and damaged.name not in detail:
                outcome, detail = "unclear", f"does not name {damaged.name}: {detail}"
            if outcome == "ok" and entry.startswith("retarget"):
                written = Path(argv[argv.index("--out") + 1])
                if not np.isfinite(load_motion(written).q_tbs).all():
                    outcome, detail = "nan", f"{written} holds NaN"
            tally.add(f"CLI {entry}", " ".join(argv[:2]), outcome, detail)
    print("\n" + tally.table())
    return tally


def test_cli_entry_points_print_one_line_never_a_traceback(originals, tmp_path):
    tally = _run_cli_fuzz(originals, tmp_path, seed=13, per_kind=1)  # every entry point once (the long run: 8 each)
    assert tally.bad() == 0, "\n".join(tally.examples)
    assert sum(c["clean"] for c in tally.counts.values()) >= 5


@pytest.mark.fuzz_long
def test_cli_entry_points_long_run(originals, tmp_path):
    tally = _run_cli_fuzz(originals, tmp_path, seed=1013, per_kind=8)
    assert tally.bad() == 0, "\n".join(tally.examples)


def test_debug_flag_shows_the_original_error_under_the_line(tmp_path):
    lying = tmp_path / "lying.glb"
    lying.write_bytes(WEBXR.read_bytes()[:200])
    plain = _cli(["annotate", str(lying)])
    assert plain[0] == "clean" and "lying.glb" in plain[1]
    done = subprocess.run([sys.executable, "-m", "s2h_viewer.cli", "annotate", "--debug", str(lying)],
                          capture_output=True, text=True, timeout=CLI_TIMEOUT_S, cwd=ROOT)
    assert done.returncode == 2
    assert done.stderr.splitlines()[0] == plain[1]
    assert "Traceback" in done.stderr  # the library's own error, kept for --debug


def test_unexpected_errors_inside_a_loader_become_one_line_with_the_original_kept(tmp_path):
    from s2h_viewer.errors import reading
    path = tmp_path / "x.npz"
    with pytest.raises(InputFileError, match=r"x\.npz: cannot be read as a thing \(ZeroDivisionError") as info:
        with reading(path, "a thing"):
            1 / 0  # noqa: B018
    assert isinstance(info.value.__cause__, ZeroDivisionError)
