"""A glTF document's JSON decoded into pygltflib's objects, by each dataclass's field types looked up once per class.

pygltflib decodes through dataclasses-json, which looks every object's type hints up again: 6 s for the 35
authored poses' 13,721 objects, the most of opening that file (0.05 s here). The objects are pygltflib's own, made
as dataclasses-json makes them (tests/test_gltf_json.py compares the two on every glTF shipped): a field's
default where the JSON has none, keys pygltflib does not know left out, numbers and strings converted to the
field's type, a primitive's attributes as pygltflib's `Attributes`. A JSON value of the wrong kind where an object,
a list or a dictionary belongs is a ValueError saying where (pygltflib failed there with whatever Python raised).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import typing
from collections.abc import Callable

import pygltflib

Decoder = Callable[[object, str], object]


def decode_gltf_json(text: str | bytes) -> pygltflib.GLTF2:
    """The document of a glTF JSON text (a .gltf file, a GLB's JSON chunk)."""
    data = json.loads(text)
    if not isinstance(data, dict):
        raise ValueError("the glTF document is not a JSON object")
    gltf = _decoder(pygltflib.GLTF2)(data, "the glTF document")
    for m, mesh in enumerate(gltf.meshes or []):
        for p, primitive in enumerate(getattr(mesh, "primitives", None) or []):
            raw = primitive.attributes
            if isinstance(raw, dict):
                if raw:  # pygltflib leaves an empty one as it is
                    primitive.attributes = pygltflib.Attributes(**raw)
            elif raw or isinstance(raw, pygltflib.Attributes):  # the default: the JSON has none
                raise ValueError(f"mesh {m}, primitive {p}: its attributes are not an object")
    return gltf


class DecodedGLTF2(pygltflib.GLTF2):
    """pygltflib's loaders (a .gltf beside its buffers, a GLB's chunks) with `decode_gltf_json` for the JSON;
    what they return is a plain `pygltflib.GLTF2`."""

    @classmethod
    def from_json(cls, s, *, infer_missing=False, **kw) -> pygltflib.GLTF2:
        return decode_gltf_json(s)


@functools.cache
def _decoder(kind) -> Decoder:
    """How a JSON value becomes a value of type ``kind`` (a pygltflib dataclass, a list, a scalar, Optional of one)."""
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    if origin is typing.Union:
        inner = [a for a in args if a is not type(None)]
        decode = _decoder(inner[0]) if len(inner) == 1 else _as_given
        return lambda value, where: None if value is None else decode(value, where)
    if origin is list:
        return _list_of(_decoder(args[0]) if args else _as_given)
    if origin is dict:
        return _dictionary
    if dataclasses.is_dataclass(kind):
        return _object_of(kind)
    if kind in (int, float, str, bool):
        return lambda value, where: value if isinstance(value, kind) or value is None else kind(value)
    return _as_given  # Any, and pygltflib's Attributes (made afterwards, as pygltflib does)


def _as_given(value, where: str):
    return value


def _dictionary(value, where: str):
    if value is not None and not isinstance(value, dict):
        raise ValueError(f"{where}: not a JSON object")
    return value


def _list_of(item: Decoder) -> Decoder:
    def decode(value, where: str):
        if value is None:
            return None
        if not isinstance(value, list):
            raise ValueError(f"{where}: not a JSON array")
        return [item(v, f"{where}[{i}]") for i, v in enumerate(value)]
    return decode


def _object_of(cls) -> Decoder:
    hints = typing.get_type_hints(cls)
    fields = {f.name: _decoder(hints[f.name]) for f in dataclasses.fields(cls) if f.init}

    def decode(value, where: str):
        if value is None:  # null where an object belongs: kept, as pygltflib keeps it
            return None
        if not isinstance(value, dict):
            raise ValueError(f"{where}: not a JSON object")
        return cls(**{name: fields[name](v, f"{where}.{name}") for name, v in value.items() if name in fields})
    return decode
