"""Joint-name mapping: which bones of a real rig are the wrist and the 20 finger joints (DESIGN.md section 1).

Built-in schemes: the project's own names, WebXR (``index-finger-phalanx-proximal``), OpenXR
(``XR_HAND_JOINT_INDEX_PROXIMAL_EXT``), Mixamo (``mixamorig:RightHandIndex1..4``), Blender Rigify
(``f_index.01.R``, ``DEF-`` prefixes too) and MANO's 16 joints (``index1..3``, optional ``index4``
tips); a user JSON map ``{"wrist": "...", "index_mcp": "...", ...}`` for anything else. Names
are compared case-, separator- and namespace-insensitively. Tips may be absent (Rigify and MANO
have none): the loader extrapolates them. A rig missing any other joint is refused with the list of
what is missing; a hand without five fingers is never guessed.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from s2h_viewer.errors import InputFileError, require_readable_file
from s2h_viewer.hand import topology as topo

SIDES = ("right", "left")
MAX_JOINT_MAP_BYTES = 1024 ** 2
_MIXAMO_FINGERS = {"thumb": "Thumb", "index": "Index", "middle": "Middle", "ring": "Ring", "pinky": "Pinky"}
_XR_FINGERS = {"thumb": "THUMB", "index": "INDEX", "middle": "MIDDLE", "ring": "RING", "pinky": "LITTLE"}
_WEBXR_LEVELS = {"thumb": ("metacarpal", "phalanx-proximal", "phalanx-distal", "tip"),
                 **{f: ("phalanx-proximal", "phalanx-intermediate", "phalanx-distal", "tip") for f in topo.FINGERS[1:]}}
_XR_LEVELS = {"thumb": ("METACARPAL", "PROXIMAL", "DISTAL", "TIP"),
              **{f: ("PROXIMAL", "INTERMEDIATE", "DISTAL", "TIP") for f in topo.FINGERS[1:]}}


def normalise_name(name: str) -> str:
    """Lower case, no namespace (``mixamorig:``, ``Armature|``), no separators: ``f_index.01.R`` -> ``findex01r``."""
    name = re.split(r"[:|]", name)[-1]
    return re.sub(r"[^0-9a-z]", "", name.lower())


def _webxr(side: str) -> tuple[dict[str, list[str]], list[str]]:
    names = {"wrist": ["wrist"]}
    for f in topo.FINGERS:
        prefix = "thumb" if f == "thumb" else f"{f}-finger"
        for level, part in zip(topo.FINGER_LEVELS[f], _WEBXR_LEVELS[f]):
            names[f"{f}_{level}"] = [f"{prefix}-{part}"]
    return names, [f"{f}-finger-metacarpal" for f in topo.FINGERS[1:]]


def _openxr(side: str) -> tuple[dict[str, list[str]], list[str]]:
    names = {"wrist": ["XR_HAND_JOINT_WRIST_EXT"]}
    for f in topo.FINGERS:
        for level, part in zip(topo.FINGER_LEVELS[f], _XR_LEVELS[f]):
            names[f"{f}_{level}"] = [f"XR_HAND_JOINT_{_XR_FINGERS[f]}_{part}_EXT"]
    return names, [f"XR_HAND_JOINT_{_XR_FINGERS[f]}_METACARPAL_EXT" for f in topo.FINGERS[1:]] + [
        "XR_HAND_JOINT_PALM_EXT"]


def _mixamo(side: str) -> tuple[dict[str, list[str]], list[str]]:
    s = side.capitalize()
    names = {"wrist": [f"{s}Hand"]}
    for f in topo.FINGERS:
        for i, level in enumerate(topo.FINGER_LEVELS[f]):
            names[f"{f}_{level}"] = [f"{s}Hand{_MIXAMO_FINGERS[f]}{i + 1}"]
    return names, []


def _rigify(side: str) -> tuple[dict[str, list[str]], list[str]]:
    s = side[0].upper()
    names = {"wrist": [f"hand.{s}", f"DEF-hand.{s}"]}
    for f in topo.FINGERS:
        bone = "thumb" if f == "thumb" else f"f_{f}"
        for i, level in enumerate(topo.FINGER_LEVELS[f]):
            names[f"{f}_{level}"] = [f"{bone}.0{i + 1}.{s}", f"DEF-{bone}.0{i + 1}.{s}"]
    palm = [f"{p}palm.0{i}.{s}" for p in ("", "DEF-") for i in range(1, 5)]
    return names, palm


def _mano(side: str) -> tuple[dict[str, list[str]], list[str]]:
    names = {"wrist": ["wrist"]}
    for f in topo.FINGERS:
        for i, level in enumerate(topo.FINGER_LEVELS[f]):
            names[f"{f}_{level}"] = [f"{f}{i + 1}"]
    return names, []


def _project(side: str) -> tuple[dict[str, list[str]], list[str]]:
    return {name: [name] for name in topo.JOINT_NAMES}, []


#: scheme name -> function(side) -> (canonical joint -> candidate rig names, palm bones folded into the wrist)
SCHEMES = {"s2h": _project, "webxr": _webxr, "openxr": _openxr, "mixamo": _mixamo, "rigify": _rigify,
           "mano": _mano}


@dataclass
class RigMapping:
    """Rig bone name of each canonical joint; tips absent from the rig are missing from ``joints``."""

    scheme: str
    joints: dict[str, str]  # canonical joint name -> rig bone name
    palm_bones: list[str] = field(default_factory=list)  # rig bones whose skin weights go to the wrist

    @property
    def missing_tips(self) -> list[str]:
        return [topo.JOINT_NAMES[t] for t in topo.TIP_JOINTS if topo.JOINT_NAMES[t] not in self.joints]


def _match(candidates: dict[str, list[str]], palm: list[str], rig_names: list[str], scheme: str) -> RigMapping:
    by_normal = {}
    for name in rig_names:
        by_normal.setdefault(normalise_name(name), name)
    joints = {}
    for joint, options in candidates.items():
        for option in options:
            if normalise_name(option) in by_normal:
                joints[joint] = by_normal[normalise_name(option)]
                break
    palm_bones = [by_normal[normalise_name(p)] for p in palm if normalise_name(p) in by_normal]
    return RigMapping(scheme, joints, palm_bones)


def _missing(mapping: RigMapping) -> list[str]:
    required = [n for j, n in enumerate(topo.JOINT_NAMES) if j not in topo.TIP_JOINTS]
    return [n for n in required if n not in mapping.joints]


def _describe_missing(missing: list[str]) -> str:
    absent_fingers = [f for f in topo.FINGERS if all(f"{f}_{lv}" in missing for lv in topo.FINGER_LEVELS[f][:3])]
    text = f"missing {', '.join(missing)}"
    if absent_fingers:
        text += (f" (no {', '.join(absent_fingers)} finger: s2h needs a hand with 5 fingers and does not guess "
                 f"one)")
    return text


def load_user_mapping(path: str | Path) -> dict[str, str]:
    """A JSON object canonical joint name -> rig bone name; an `InputFileError` naming the file if malformed."""
    path = Path(path)
    if not path.exists():
        raise InputFileError(path, "joint map not found")
    require_readable_file(path, MAX_JOINT_MAP_BYTES)
    try:
        document = json.loads(path.read_text())
    except RecursionError:
        raise InputFileError(path, "joint map is nested too deeply") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputFileError(path, f"joint map is not valid JSON ({exc})") from None
    if not isinstance(document, dict) or not all(isinstance(v, str) for v in document.values()):
        raise InputFileError(path, 'joint map must be a JSON object {"wrist": "<bone>", "index_mcp": "<bone>", ...}')
    unknown = sorted(set(document) - set(topo.JOINT_NAMES))
    if unknown:
        raise InputFileError(path, f"unknown joint names {', '.join(unknown)}; use {', '.join(topo.JOINT_NAMES)}")
    return document


def map_rig(rig_names: list[str], source: str | Path, side: str = "right", scheme: str | None = None,
            user_map: dict[str, str] | None = None) -> RigMapping:
    """Map a rig's bone names onto the 21-joint topology.

    ``scheme`` None tries every built-in scheme and keeps the one matching most joints; ``user_map``
    overrides everything. Raises `InputFileError` naming ``source`` and the missing joints.
    """
    if side not in SIDES:
        raise ValueError(f"side must be one of {SIDES}, not {side!r}")
    if user_map is not None:
        candidates = {joint: [bone] for joint, bone in user_map.items()}
        mapping = _match(candidates, [], rig_names, "user")
        absent = [bone for joint, bone in user_map.items() if joint not in mapping.joints]
        if absent:
            raise InputFileError(source, f"joint map names bones the rig does not have: {', '.join(absent)}")
    else:
        if scheme is not None and scheme not in SCHEMES:
            raise ValueError(f"unknown rig scheme {scheme!r}; choose from {', '.join(SCHEMES)}")
        tried = [_match(*SCHEMES[s](side), rig_names, s) for s in ([scheme] if scheme else SCHEMES)]
        mapping = max(tried, key=lambda m: len(m.joints))
        if not mapping.joints:
            raise InputFileError(source, f"no {side} hand joints found among the rig's {len(rig_names)} bones "
                                         f"(known schemes: {', '.join(SCHEMES)}; pass a JSON joint map for "
                                         f"others)")
    missing = _missing(mapping)
    if missing:
        raise InputFileError(source, f"cannot map the {side} hand ({mapping.scheme} names): "
                                     f"{_describe_missing(missing)}")
    return mapping
