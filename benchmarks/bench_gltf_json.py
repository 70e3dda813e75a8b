"""Benchmark and report: a glTF document's JSON decoded by `io.gltf_json` against pygltflib's own decoding
(dataclasses-json), on the shipped files with the most objects. The ratio is the figure to read: both are timed
in the same run, on the same machine.

    python benchmarks/bench_gltf_json.py      # or: make bench
"""

from __future__ import annotations

import json

import pygltflib

from timing import median_seconds  # benchmarks/timing.py, beside this script

from s2h_viewer.io.gltf_json import decode_gltf_json
from s2h_viewer.samples import ASSETS_DIR

FILES = ["motions/real/godot_hand_poses_r.gltf", "hands/real/RPM_Template_Mesh_XR.glb", "hands/real/human-female.glb"]


def json_chunk(data: bytes) -> bytes:
    """A .gltf's text, or a GLB's JSON chunk."""
    return data[20:20 + int.from_bytes(data[12:16], "little")] if data[:4] == b"glTF" else data


def objects(value) -> int:
    """How many JSON objects the document holds (what both decoders make one Python object of)."""
    if isinstance(value, dict):
        return 1 + sum(objects(v) for v in value.values())
    if isinstance(value, list):
        return sum(objects(v) for v in value)
    return 0


def main() -> None:
    print("| File | JSON objects | pygltflib (s) | s2h (s) | s2h / pygltflib |")
    print("|---|---:|---:|---:|---:|")
    for name in FILES:
        text = json_chunk((ASSETS_DIR / name).read_bytes())
        theirs = median_seconds(lambda: pygltflib.GLTF2.from_json(text, infer_missing=True), 3)
        ours = median_seconds(lambda: decode_gltf_json(text), 3)
        print(f"| {name} | {objects(json.loads(text))} | {theirs:.3f} | {ours:.4f} | {ours / theirs:.3f} |")


if __name__ == "__main__":
    main()
