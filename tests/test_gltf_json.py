"""`io.gltf_json` makes the objects pygltflib's own decoding makes (its time: `make bench`): on every glTF, GLB and
VRM shipped, on an animation written by s2h, and on JSON a hostile or careless writer produces."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pygltflib
import pytest

from s2h_viewer.io.gltf import read_document
from s2h_viewer.io.gltf_json import decode_gltf_json

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = sorted(p for p in (ROOT / "assets").rglob("*") if p.suffix in (".gltf", ".glb", ".vrm"))


def json_text(path: Path, most: int = 50) -> str:
    """The file's JSON (a GLB's first chunk), each of its lists of objects cut to its first ``most`` (pygltflib
    takes 6 s for the 35 poses' 13,721 objects: the same kinds of objects, fewer of them)."""
    data = path.read_bytes()
    if data[:4] == b"glTF":
        data = data[20:20 + int.from_bytes(data[12:16], "little")]
    document = json.loads(data)
    cut = {key: value[:most] if isinstance(value, list) else value for key, value in document.items()}
    cut["animations"] = cut.get("animations", [])[:3]  # each holds lists of its own
    return json.dumps(cut)


def same(ours, theirs, where: str = "document") -> None:
    """The same types and values all the way down (pygltflib's dataclasses compare only their values)."""
    assert type(ours) is type(theirs), (where, type(ours), type(theirs))
    if dataclasses.is_dataclass(ours) or isinstance(ours, pygltflib.Attributes):
        assert vars(ours).keys() == vars(theirs).keys(), where
        for key in vars(ours):
            same(getattr(ours, key), getattr(theirs, key), f"{where}.{key}")
    elif isinstance(ours, (list, tuple)):
        assert len(ours) == len(theirs), where
        for i, (a, b) in enumerate(zip(ours, theirs)):
            same(a, b, f"{where}[{i}]")
    elif isinstance(ours, dict):
        assert ours.keys() == theirs.keys(), where
        for key in ours:
            same(ours[key], theirs[key], f"{where}[{key!r}]")
    else:
        assert ours == theirs, (where, ours, theirs)


def pygltflibs(text: str) -> pygltflib.GLTF2:
    return pygltflib.GLTF2.from_json(text, infer_missing=True)


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_gltf_decodes_as_pygltflib_decodes_it(path):
    text = json_text(path)
    same(decode_gltf_json(text), pygltflibs(text))


def test_an_animation_s2h_wrote_decodes_as_pygltflib_decodes_it(tmp_path):
    from s2h_viewer import samples
    from s2h_viewer.io.files import load_hand_file, save_motion_file
    from s2h_viewer.retarget.methods import retarget
    hand = load_hand_file(ROOT / "assets/hands/webxr/generic-hand-right.glb")
    motion = samples.load_sample_motions()[0]
    motion = dataclasses.replace(motion, q_tbs=motion.q_tbs[:20], labels=motion.labels[:20])
    moved = retarget(motion, samples.load_sample_hand(motion.hand_name), hand, "tbs_copy")
    text = json_text(save_motion_file(tmp_path / "moved.glb", moved, hand), most=10_000)
    same(decode_gltf_json(text), pygltflibs(text))


def test_careless_json_decodes_as_pygltflib_decodes_it():
    """Unknown keys dropped, numbers written as strings or floats converted to the field's type, nulls kept,
    an empty attributes object left as it is, extensions and extras kept as written."""
    document = {
        "asset": {"version": 2.0, "generator": 7}, "scene": "0", "unknownTopLevel": [1, 2],
        "nodes": [{"name": 5, "children": ["1"], "rotation": [0, 0, 0, 1], "vendorKey": {"a": 1}},
                  {"name": None, "translation": None, "extras": {"nested": {"deep": [1, "x"]}}}],
        "accessors": [{"bufferView": 0.0, "componentType": 5126, "count": "3", "type": "VEC3",
                       "normalized": 1, "max": [1, 2, 3]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "_CUSTOM": 1}, "targets": [{"POSITION": 0}]},
                                   {"attributes": {}}]}],
        "animations": [{"channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}],
                        "samplers": [{"input": 0, "output": 0}]}],
        "extensionsUsed": ["VRMC_vrm"], "extensions": {"VRMC_vrm": {"humanoid": {}}},
    }
    text = json.dumps(document)
    ours = decode_gltf_json(text)
    same(ours, pygltflibs(text))
    assert ours.scene == 0 and ours.accessors[0].count == 3 and ours.nodes[0].children == [1]
    assert ours.meshes[0].primitives[0].attributes._CUSTOM == 1 and ours.meshes[0].primitives[1].attributes == {}


@pytest.mark.parametrize("document, where", [
    ({"nodes": {"0": {}}}, "the glTF document.nodes: not a JSON array"),
    ({"nodes": [3]}, r"the glTF document.nodes\[0\]: not a JSON object"),
    ({"accessors": [{"sparse": [1]}]}, r"the glTF document.accessors\[0\].sparse: not a JSON object"),
    ({"nodes": [{"extras": 4}]}, r"the glTF document.nodes\[0\].extras: not a JSON object"),
    ({"meshes": [{"primitives": [{"attributes": [0]}]}]}, "mesh 0, primitive 0: its attributes are not an object"),
    ({"meshes": [{"primitives": [{"indices": 0}]}]}, "mesh 0, primitive 0: its attributes are not an object"),
    ([1, 2], "the glTF document is not a JSON object"),
])
def test_json_of_the_wrong_kind_is_a_value_error_saying_where(document, where):
    with pytest.raises(ValueError, match=where):
        decode_gltf_json(json.dumps(document))


def test_a_wrong_kind_in_a_file_is_one_line_naming_the_file(tmp_path):
    from s2h_viewer.errors import InputFileError
    path = tmp_path / "bad.gltf"
    path.write_text(json.dumps({"asset": {"version": "2.0"}, "nodes": [{"children": 3}]}))
    with pytest.raises(InputFileError, match=r"bad\.gltf: not a readable glTF/GLB file \(ValueError: the glTF "
                                             r"document\.nodes\[0\]\.children: not a JSON array\)"):
        read_document(path)

