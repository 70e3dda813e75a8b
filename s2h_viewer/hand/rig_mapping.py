"""Joint-name mapping: which bones of a real rig are the wrist and the 20 finger joints (DESIGN.md section 1).

Built-in schemes (compared case-, separator- and namespace-insensitively, with the side read off the
name first: ``_R``/``.L`` suffixes, ``Right``/``Left`` prefixes, ``r_``/``l_`` and Meta's ``b_r_``/``b_l_``
prefixes):

- ``s2h``: the project's own names; ``webxr``: ``index-finger-phalanx-proximal``;
- ``openxr``: ``XR_HAND_JOINT_INDEX_PROXIMAL_EXT`` and Title_Case ``Index_Proximal_R`` (``Little`` = pinky);
- ``mixamo``: ``mixamorig:RightHandIndex1..4``, also without the prefix (Ready Player Me, Unity exports);
- ``unity``: Unity Humanoid ``RightIndexProximal`` (thumb Proximal = CMC), also VRM 0.x bone names;
- ``unreal``: the Unreal mannequin ``hand_r``, ``index_01_r``..``index_03_r``, ``index_04_leaf_r`` tips,
  ``index_metacarpal_r`` palm bones (UE5);
- ``rigify``: Blender Rigify ``f_index.01.R`` with ``DEF-`` (preferred) or ``ORG-`` prefixes;
- ``mano``: MANO's 16 joints ``index1..3`` with optional ``index4`` tips;
- ``meta``: Meta / Oculus hand-tracking hands ``b_r_wrist`` (or ``b_r_hand``), ``b_r_thumb1..3`` (``thumb0``, the
  trapezium, and ``pinky0`` are palm bones), ``b_r_index1..3``, ``b_r_index_null`` (or ``_ignore``) tips.

A user JSON map ``{"wrist": "...", "index_mcp": "...", ...}`` overrides names. Tips may be absent: the
loader extrapolates them. What names cannot settle, `rig_recognition` settles from topology and geometry.
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
_PREFIX_SIDE = re.compile(r"^(?:(?i:(right|left))(?=[A-Z0-9_.\- ]|$)|(?i:(r|l))[_.\- ]|(?i:b_(r|l))_)")
_SUFFIX_SIDE = re.compile(r"(?:[_.\- ](r|l)|[_.\- ]?(right|left))$", re.IGNORECASE)
_RIGIFY_PREFIXES = ("def", "", "org")  # deform bones first: they carry the skin
#: a per-DOF mocap joint's degree-of-freedom suffix (``INDEX_MCP_FE``, ``THUMB_CMC_AA``), normalised
_DOF_SUFFIX = re.compile(r"(?<=[a-z0-9])(fe|aa|flex|abd)$")


def normalise_name(name: str) -> str:
    """Lower case, no namespace (``mixamorig:``, ``Armature|``), no separators: ``f_index.01.R`` -> ``findex01r``."""
    name = re.split(r"[:|]", name)[-1]
    return re.sub(r"[^0-9a-z]", "", name.lower())


def split_side(name: str) -> tuple[str, str | None]:
    """(normalised name without its side marker, "right"/"left"/None): ``Index_Proximal_R`` ->
    (``indexproximal``, "right"), ``mixamorig:LeftHandIndex1`` -> (``handindex1``, "left")."""
    name = re.split(r"[:|]", name)[-1]
    side = None
    match = _SUFFIX_SIDE.search(name)
    if match and len(name) > len(match.group(0)):
        side = "right" if (match.group(1) or match.group(2)).lower().startswith("r") else "left"
        name = name[:match.start()]
    else:
        match = _PREFIX_SIDE.search(name)
        if match and len(name) > len(match.group(0)):
            side = "right" if (match.group(1) or match.group(2) or match.group(3)).lower().startswith("r") else "left"
            name = name[match.end():]
    return normalise_name(name), side


def _levels(scheme_names: dict[str, tuple[str, ...]]) -> dict[str, list[str]]:
    """Canonical joint -> candidate names from per-finger tuples of (level 1, level 2, level 3, tip) names."""
    out = {}
    for f in topo.FINGERS:
        for level, name in zip(topo.FINGER_LEVELS[f], scheme_names[f]):
            out[f"{f}_{level}"] = [normalise_name(n) for n in name.split("|")]
    return out


def _webxr() -> tuple[dict[str, list[str]], list[str]]:
    names = {"thumb": ("thumb-metacarpal", "thumb-phalanx-proximal", "thumb-phalanx-distal", "thumb-tip")}
    for f in topo.FINGERS[1:]:
        names[f] = tuple(f"{f}-finger-{p}" for p in ("phalanx-proximal", "phalanx-intermediate", "phalanx-distal",
                                                     "tip"))
    return {"wrist": ["wrist"], **_levels(names)}, [f"{f}fingermetacarpal" for f in topo.FINGERS[1:]]


_XR = {"thumb": "thumb", "index": "index", "middle": "middle", "ring": "ring", "pinky": "little"}


def _openxr() -> tuple[dict[str, list[str]], list[str]]:
    names = {}
    for f, xr in _XR.items():
        parts = ("metacarpal", "proximal", "distal", "tip") if f == "thumb" else (
            "proximal", "intermediate", "distal", "tip")
        names[f] = tuple(f"XR_HAND_JOINT_{xr}_{p}_EXT|{xr}_{p}|{xr}_{p}_bone" for p in parts)
    palm = [normalise_name(f"{p}{_XR[f]}metacarpal{s}") for f in topo.FINGERS[1:] for p in ("xrhandjoint", "")
            for s in (("ext",) if p else ("", "bone"))]
    return {"wrist": ["xrhandjointwristext", "wrist", "wristbone"], **_levels(names)}, palm + [
        "xrhandjointpalmext", "palm", "palmbone"]


def _mixamo() -> tuple[dict[str, list[str]], list[str]]:
    names = {f: tuple(f"Hand{f.capitalize()}{i}" for i in range(1, 5)) for f in topo.FINGERS}
    return {"wrist": ["hand"], **_levels(names)}, []


def _unity() -> tuple[dict[str, list[str]], list[str]]:
    names = {f: tuple(f"{f.capitalize()}{p}" for p in ("Proximal", "Intermediate", "Distal", "Tip"))
             for f in ("thumb", "index", "middle", "ring")}
    names["pinky"] = tuple(f"Little{p}|Pinky{p}" for p in ("Proximal", "Intermediate", "Distal", "Tip"))
    return {"wrist": ["hand"], **_levels(names)}, []


def _unreal() -> tuple[dict[str, list[str]], list[str]]:
    names = {f: (f"{f}_01", f"{f}_02", f"{f}_03", f"{f}_04_leaf|{f}_04|{f}_tip") for f in topo.FINGERS}
    return {"wrist": ["hand"], **_levels(names)}, [f"{f}metacarpal" for f in topo.FINGERS[1:]]


def _rigify() -> tuple[dict[str, list[str]], list[str]]:
    names = {f: tuple("|".join(f"{p}{'thumb' if f == 'thumb' else 'f_' + f}.0{i}" for p in _RIGIFY_PREFIXES)
                      for i in (1, 2, 3)) for f in topo.FINGERS}
    joints = {"wrist": [f"{p}hand" for p in _RIGIFY_PREFIXES]}
    for f in topo.FINGERS:
        for level, name in zip(topo.FINGER_LEVELS[f], names[f]):
            joints[f"{f}_{level}"] = [normalise_name(n) for n in name.split("|")]
    return joints, [f"{p}palm0{i}" for p in _RIGIFY_PREFIXES for i in range(1, 5)]


def _mano() -> tuple[dict[str, list[str]], list[str]]:
    names = {f: tuple(f"{f}{i}" for i in range(1, 5)) for f in topo.FINGERS}
    return {"wrist": ["wrist"], **_levels(names)}, []


def _meta() -> tuple[dict[str, list[str]], list[str]]:
    names = {f: (f"{f}1", f"{f}2", f"{f}3", f"{f}_null|{f}_ignore|{f}_tip") for f in topo.FINGERS}
    return {"wrist": ["wrist", "hand"], **_levels(names)}, ["thumb0", "pinky0", "forearmstub", "handignore", "grip"]


def _project() -> tuple[dict[str, list[str]], list[str]]:
    return {name: [normalise_name(name)] for name in topo.JOINT_NAMES}, []


#: scheme name -> function() -> (canonical joint -> candidate normalised names, palm bones' normalised names)
SCHEMES = {"s2h": _project, "webxr": _webxr, "openxr": _openxr, "mixamo": _mixamo, "unity": _unity,
           "unreal": _unreal, "rigify": _rigify, "mano": _mano, "meta": _meta}


@dataclass
class RigMapping:
    """Rig bone name of each canonical joint; tips absent from the rig are missing from ``joints``.

    ``side`` is the hand the bones belong to, ``side_from`` how that was decided (names, geometry,
    the user); ``confidence`` in [0, 1] how sure the recognition is (1 for names that all matched)."""

    scheme: str
    joints: dict[str, str]  # canonical joint name -> rig bone name
    palm_bones: list[str] = field(default_factory=list)  # rig bones whose skin weights go to the wrist
    side: str = "right"
    side_from: str = "names"
    confidence: float = 1.0
    notes: list[str] = field(default_factory=list)
    both_hands: bool = False  # the rig has the other hand too (a character), named or in its humanoid map

    @property
    def missing_tips(self) -> list[str]:
        return [topo.JOINT_NAMES[t] for t in topo.TIP_JOINTS if topo.JOINT_NAMES[t] not in self.joints]

    @property
    def missing(self) -> list[str]:
        """Required (non-tip) canonical joints the mapping lacks."""
        return [n for j, n in enumerate(topo.JOINT_NAMES) if j not in topo.TIP_JOINTS and n not in self.joints]


def sides_named(rig_names: list[str]) -> set[str]:
    """The sides the rig's bone names mark (empty when none does)."""
    return {s for s in (split_side(n)[1] for n in rig_names) if s}


def _match(scheme: str, rig_names: list[str], side: str | None) -> RigMapping:
    """Bones of ``side`` (or carrying no side) whose names fit ``scheme``; a side-marked bone wins."""
    candidates, palm = SCHEMES[scheme]()
    side_specific: dict[str, str] = {}
    sideless: dict[str, str] = {}
    for name in rig_names:
        base, name_side = split_side(name)
        if name_side == side:
            side_specific.setdefault(base, name)
        elif name_side is None:
            sideless.setdefault(base, name)
    by_base = {**sideless, **side_specific}
    for base, name in list(by_base.items()):  # per-DOF mocap: INDEX_MCP_FE answers to INDEX_MCP too
        by_base.setdefault(_DOF_SUFFIX.sub("", base), name)
    joints = {}
    for joint, options in candidates.items():
        found = next((by_base[o] for o in options if o in by_base), None)
        if found is not None:
            joints[joint] = found
    palm_bones = [by_base[p] for p in palm if p in by_base]
    return RigMapping(scheme, joints, palm_bones, side or "right")


def describe_missing(missing: list[str]) -> str:
    absent_fingers = [f for f in topo.FINGERS if all(f"{f}_{lv}" in missing for lv in topo.FINGER_LEVELS[f][:3])]
    text = f"missing {', '.join(missing)}"
    if absent_fingers:
        text += (f" (no {', '.join(absent_fingers)} finger: s2h needs a hand with 5 fingers and does not guess "
                 f"one)")
    return text


def _joint_map_problem(mapping: dict[str, str]) -> str | None:
    """What is wrong with a joint map by itself (not a joint -> bone name object, unknown joints, empty
    names), or None."""
    if not isinstance(mapping, dict) or not all(isinstance(v, str) for v in mapping.values()):
        return 'joint map must be a JSON object {"wrist": "<bone>", "index_mcp": "<bone>", ...}'
    unknown = sorted(set(mapping) - set(topo.JOINT_NAMES))
    if unknown:
        return f"unknown joint names {', '.join(unknown)}; use {', '.join(topo.JOINT_NAMES)}"
    empty = [joint for joint, bone in mapping.items() if not bone.strip()]
    if empty:
        return (f"joint map leaves {', '.join(empty)} empty: write the rig's bone name for each (or remove an "
                f"unknown tip)")
    return None


def load_user_mapping(path: str | Path) -> dict[str, str]:
    """A JSON object canonical joint name -> rig bone name, read and checked by itself (`check_user_mapping`
    checks it against a rig); an `InputFileError` naming the file if malformed."""
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
    problem = _joint_map_problem(document)
    if problem:
        raise InputFileError(path, problem)
    return document


def check_user_mapping(mapping: dict[str, str], bones: list[str], source: str | Path, what: str = "joint map"
                       ) -> dict[str, str]:
    """``mapping`` if it maps every joint but the tips (extrapolated when left out) to its own bone of ``bones``;
    else an `InputFileError` naming ``source``, the joints and the bones at fault, and ``what`` the map is (the
    user's joint map, a file's humanoid map)."""
    problem = _joint_map_problem(mapping)
    if problem:
        raise InputFileError(source, problem)
    present = set(bones)
    absent = [f"{bone} ({joint})" for joint, bone in mapping.items() if bone not in present]
    if absent:
        raise InputFileError(source, f"{what} names bones the rig does not have: {', '.join(absent)}")
    joints_of: dict[str, list[str]] = {}
    for joint, bone in mapping.items():
        joints_of.setdefault(bone, []).append(joint)
    shared = [f"{' and '.join(joints)} both use {bone!r}" for bone, joints in joints_of.items() if len(joints) > 1]
    if shared:
        raise InputFileError(source, f"{what} gives one bone to several joints: {'; '.join(shared)}; each joint "
                                     f"needs its own bone")
    missing = RigMapping("user", mapping).missing
    if missing:
        raise InputFileError(source, f"the {what.removeprefix('the ')} does not name {', '.join(missing)}")
    return mapping


def map_user(rig_names: list[str], source: str | Path, user_map: dict[str, str], side: str,
             what: str = "joint map") -> RigMapping:
    """The mapping a user's joint map (or ``what`` else) gives; an `InputFileError` (`check_user_mapping`) if it
    does not fit the rig."""
    check_user_mapping(user_map, rig_names, source, what)
    return RigMapping("user", dict(user_map), [], side, "user")


def map_rig(rig_names: list[str], source: str | Path, side: str | None = "right", scheme: str | None = None,
            user_map: dict[str, str] | None = None) -> RigMapping:
    """Map a rig's bone names onto the 21-joint topology by names alone.

    ``scheme`` None tries every built-in scheme and keeps the one matching most joints; ``user_map``
    overrides everything. ``side`` None takes the side the names mark (right when both are there).
    Raises `InputFileError` naming ``source`` and what is missing.
    """
    if side is not None and side not in SIDES:
        raise ValueError(f"side must be one of {SIDES}, not {side!r}")
    named = sides_named(rig_names)
    chosen = side or ("right" if "right" in named or not named else "left")
    if user_map is not None:
        return map_user(rig_names, source, user_map, chosen)
    mapping = best_name_match(rig_names, chosen, scheme)
    if not mapping.joints:
        raise InputFileError(source, f"no {chosen} hand joints found among the rig's {len(rig_names)} bones "
                                     f"(known schemes: {', '.join(SCHEMES)}; pass a JSON joint map for others)")
    if mapping.missing:
        raise InputFileError(source, f"cannot map the {chosen} hand ({mapping.scheme} names): "
                                     f"{describe_missing(mapping.missing)}")
    mapping.side_from = "names" if chosen in named else ("user" if side else "default")
    return mapping


def best_name_match(rig_names: list[str], side: str, scheme: str | None = None) -> RigMapping:
    """The built-in scheme (or ``scheme``) whose names match most of the rig's bones on ``side``."""
    if scheme is not None and scheme not in SCHEMES:
        raise ValueError(f"unknown rig scheme {scheme!r}; choose from {', '.join(SCHEMES)}")
    tried = [_match(s, rig_names, side) for s in ([scheme] if scheme else SCHEMES)]
    return max(tried, key=lambda m: (len(m.joints) - len(m.missing_tips), len(m.joints)))
