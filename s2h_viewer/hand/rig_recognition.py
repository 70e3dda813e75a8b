"""Which bones of a rig are a hand, and which hand: a user map, a humanoid map (VRM), names, then topology.

Names settle most rigs (`rig_mapping`). When they cannot, the hand is found from the skeleton's shape:
a bone with five unbranched chains of three or more bones under it (palm bones in between are
allowed), the thumb being the chain that points most unlike the other four (opposition), the others
ordered across the palm from the thumb's side. When names do not say which hand it is, the side comes
from geometry: fingers curl and the thumb sits toward the palm, so the palm normal is known apart from
the finger order, and a right hand's index lies on the thumb side of ``palm normal x finger direction``.
Every refusal says what was found and what to do.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from s2h_viewer.errors import TooFewBonesError, UnrecognisedRigError
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.rig_mapping import (SCHEMES, SIDES, RigMapping, best_name_match, describe_missing, map_user,
                                         normalise_name, sides_named, split_side)
from s2h_viewer.wording import counted

#: a side or thumb call below this confidence is reported as a guess to check
SURE = 0.5
#: normalised name endings of helper nodes (`is_helper`)
HELPER_SUFFIXES = ("marker",)
#: normalised endings an exporter appends to a bone's name for the node at its tail (`is_tail`)
TAIL_SUFFIXES = ("end", "tip", "nub", "leaf")
TEMPLATE_HINT = "write a joint map (`s2h rig FILE` writes an editable template) and pass it with --joint-map"


@dataclass
class Skeleton:
    """What recognition needs of a rig: bone names, parent indices (-1 roots) and rest world positions."""

    names: list[str]
    parents: np.ndarray  # (N,)
    positions: np.ndarray  # (N, 3)

    def children(self) -> list[list[int]]:
        """Each bone's children, helper nodes left out (`is_helper`: they would branch a finger's chain)."""
        out: list[list[int]] = [[] for _ in self.names]
        for i, p in enumerate(self.parents):
            if p >= 0 and not is_helper(self.names[i]):
                out[p].append(i)
        return out

    def is_tail(self, bone: int) -> bool:
        """Whether ``bone`` marks its parent's tail, named as its parent plus a `TAIL_SUFFIXES` ending
        (``LittleFinger3_R_End``): a fingertip, whatever an exporter hung below it (``LittleFinger3_R_End_end``)."""
        parent = self.parents[bone]
        if parent < 0:
            return False
        name, base = normalise_name(self.names[bone]), normalise_name(self.names[parent])
        return name.startswith(base) and name[len(base):] in TAIL_SUFFIXES


def is_helper(name: str) -> bool:
    """A node that marks a point on the hand and is no bone: Meta's ``r_index_finger_pad_marker`` and its kind,
    hung beside a finger's next bone."""
    return normalise_name(name).endswith(HELPER_SUFFIXES)


@dataclass
class FingerChains:
    """The unbranched chains of three or more bones under one bone, and the bones between it and them."""

    wrist: int
    chains: list[list[int]]
    between: list[int]  # branching bones between the wrist and the chains (palm bones)


def finger_chains(skeleton: Skeleton, wrist: int, children: list[list[int]] | None = None) -> FingerChains:
    """Chains of >= 3 bones under ``wrist``: each ends at a leaf or a bone's tail (`Skeleton.is_tail`); a bone
    with several children starts new ones."""
    children = children or skeleton.children()
    chains, between, short = [], [], []
    stack = [(c, []) for c in children[wrist]]
    while stack:
        node, chain = stack.pop()
        chain = chain + [node]
        if skeleton.is_tail(node) or not children[node]:
            (chains if len(chain) >= 3 else short).append(chain)
        elif len(children[node]) == 1:
            stack.append((children[node][0], chain))
        else:  # a palm bone carrying several fingers: its own chain so far are palm bones too
            between.extend(chain)
            stack.extend((c, []) for c in children[node])
    chains.sort(key=lambda c: c[0])
    return FingerChains(wrist, chains, between + [b for c in short for b in c])


def _chain_joints(chain: list[int]) -> tuple[list[int], list[int]]:
    """(three articulated bones + the tip if there is one, the palm bones before them)."""
    if len(chain) >= 4:
        return chain[-4:], chain[:-4]
    return chain, []


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def order_fingers(skeleton: Skeleton, found: FingerChains) -> tuple[list[list[int]], float, str]:
    """Five chains as thumb, index, middle, ring, pinky; the confidence of the thumb call; a note."""
    pos = skeleton.positions
    joints = [_chain_joints(c)[0] for c in found.chains]
    knuckles = np.array([pos[j[0]] for j in joints])
    direction = _unit(np.array([pos[j[2]] - pos[j[0]] for j in joints]))
    similarity = direction @ direction.T
    opposition = (similarity.sum(1) - 1.0) / 4.0  # mean cosine to the other four
    order = np.argsort(opposition)
    thumb = int(order[0])
    gap = float(opposition[order[1]] - opposition[thumb])
    confidence = float(np.clip(gap / 0.3, 0.0, 1.0))
    others = [i for i in range(5) if i != thumb]
    centre = knuckles[others].mean(0)
    _, _, vt = np.linalg.svd(knuckles[others] - centre)
    across = vt[0] * np.sign((knuckles[thumb] - centre) @ vt[0] or 1.0)
    others.sort(key=lambda i: -(knuckles[i] - centre) @ across)
    names = [skeleton.names[found.chains[i][0]] for i in [thumb] + others]
    note = (f"found by topology: 5 finger chains under {skeleton.names[found.wrist]!r}, thumb "
            f"{names[0]!r} by opposition (confidence {confidence:.2f}), then {', '.join(repr(n) for n in names[1:])} "
            f"across the palm")
    return [joints[i] for i in [thumb] + others], confidence, note


def detect_side(positions: np.ndarray) -> tuple[str, float]:
    """Left or right from 21 canonical joint positions (any axes), and how sure (0-1).

    The palm side is where the fingers curl to (PIP and DIP lie on the back side of the MCP-tip chord)
    and where the thumb sits; ``n = (index - wrist) x (pinky - wrist)`` points to the palm side of a
    right hand and to the back of a left one."""
    wrist = positions[0]
    n = _unit(np.cross(positions[topo.joint_index("index_mcp")] - wrist, positions[topo.joint_index("pinky_mcp")] - wrist))
    palmar = np.zeros(3)
    for f in topo.FINGERS:
        mcp, mid, dip, tip = (positions[topo.joint_index(f"{f}_{lv}")] for lv in topo.FINGER_LEVELS[f])
        palmar += 0.5 * (mcp + tip) - 0.5 * (mid + dip)
    thumb = positions[topo.joint_index("thumb_tip")] - positions[topo.joint_index("index_mcp")]
    palmar += thumb
    length = np.linalg.norm(positions[topo.joint_index("middle_mcp")] - wrist)
    score = float(palmar @ n) / max(length, 1e-12)
    return ("right" if score > 0 else "left"), float(np.clip(abs(score) / 0.3, 0.0, 1.0))


def canonical_positions(skeleton: Skeleton, joints: dict[str, str]) -> np.ndarray:
    """(21, 3) world positions of the mapped joints; a missing tip extrapolated from its finger."""
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    out = np.zeros((topo.N_JOINTS, 3))
    for j, name in enumerate(topo.JOINT_NAMES):
        if name in joints:
            out[j] = skeleton.positions[lookup[joints[name]]]
        else:
            out[j] = out[j - 1] + 0.8 * (out[j - 1] - out[j - 2])
    return out


def _topology_mapping(skeleton: Skeleton, found: FingerChains) -> RigMapping:
    ordered, confidence, note = order_fingers(skeleton, found)
    joints = {"wrist": skeleton.names[found.wrist]}
    palm = [skeleton.names[b] for b in found.between]
    for f, chain in zip(topo.FINGERS, ordered):
        for level, bone in zip(topo.FINGER_LEVELS[f], chain):
            joints[f"{f}_{level}"] = skeleton.names[bone]
    for chain in found.chains:
        palm += [skeleton.names[b] for b in _chain_joints(chain)[1]]
    return RigMapping("topology", joints, palm, confidence=confidence, notes=[note])


def _hand_candidates(skeleton: Skeleton) -> tuple[list[FingerChains], list[FingerChains]]:
    """Bones with five hand-like finger chains under them (lowest first), and partial finds (2-7 chains)."""
    children = skeleton.children()
    five, partial = [], []
    for node in range(len(skeleton.names)):
        if len(children[node]) < 2:
            continue
        found = finger_chains(skeleton, node, children)
        if len(found.chains) == 5 and _hand_like(skeleton, found):
            five.append(found)
        elif 2 <= len(found.chains) < 8 and len(found.chains) != 5 and _hand_like(skeleton, found):
            partial.append(found)
    # a hand found under its own forearm is found again under the forearm: keep the lowest bone
    lowest = [f for f in five if not any(g is not f and _is_ancestor(skeleton, f.wrist, g.wrist) for g in five)]
    return lowest, partial


def _hand_like(skeleton: Skeleton, found: FingerChains) -> bool:
    """The chains but the most opposed one (the thumb) point roughly one way, as fingers do and a body's
    limbs and head do not."""
    pos = skeleton.positions
    direction = _unit(np.array([pos[c[-1]] - pos[c[0]] for c in found.chains]))
    similarity = direction @ direction.T
    thumb = int(np.argmin(similarity.sum(1)))
    fingers = [i for i in range(len(found.chains)) if i != thumb]
    return float(similarity[np.ix_(fingers, fingers)].mean()) > 0.5


def complete_humanoid_map(skeleton: Skeleton, joints: dict[str, str], side: str, source: str | Path
                          ) -> tuple[dict[str, str], list[str]]:
    """A file's humanoid map of one hand with the joints it leaves out (VRM 0.x maps often name no thumb and no
    index distal) taken from the finger chains under its wrist: a chain holding a named bone is that finger, its
    other bones the finger's other levels; the chain no name claims is the finger no name claims. Returns the
    completed map and a note of what was added; an `UnrecognisedRigError` speaking of the file's humanoid map
    where the chains cannot complete it."""
    missing = RigMapping("vrm", joints).missing
    if not missing:
        return dict(joints), []
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    found = finger_chains(skeleton, lookup[joints["wrist"]])
    levels = {f: [f"{f}_{lv}" for lv in topo.FINGER_LEVELS[f]] for f in topo.FINGERS}
    finger_of: dict[int, str] = {}  # chain -> finger, from the bones the map names
    for c, chain in enumerate(found.chains):
        named = {f for f in topo.FINGERS for j in levels[f] if joints.get(j) in {skeleton.names[b] for b in chain}}
        if len(named) == 1:
            finger_of[c] = named.pop()
    unclaimed = [c for c in range(len(found.chains)) if c not in finger_of]
    unnamed = [f for f in topo.FINGERS if f not in finger_of.values()]
    if len(found.chains) == 5 and len(unclaimed) == len(unnamed) == 1:
        finger_of[unclaimed[0]] = unnamed[0]
    elif len(found.chains) == 5 and unclaimed:  # several fingers unnamed: topology orders them, if it agrees
        ordered = order_fingers(skeleton, found)[0]
        by_topology = {c: f for f, joints_of in zip(topo.FINGERS, ordered) for c, chain in enumerate(found.chains)
                       if _chain_joints(chain)[0] == joints_of}
        if all(by_topology.get(c) == f for c, f in finger_of.items()):
            finger_of.update({c: by_topology[c] for c in unclaimed})
    completed = dict(joints)
    for c, finger in finger_of.items():
        bones = [skeleton.names[b] for b in _chain_joints(found.chains[c])[0]]
        anchor = next((k for k, j in enumerate(levels[finger]) if j in joints), None)
        if anchor is None:  # the one unnamed finger: its chain from the top
            placed = dict(zip(levels[finger], bones))
        else:  # the named bone fixes where the chain's levels sit
            named_bone = joints[levels[finger][anchor]]
            start = bones.index(named_bone) - anchor if named_bone in bones else 0
            placed = {j: bones[start + k] for k, j in enumerate(levels[finger]) if 0 <= start + k < len(bones)}
        for joint, bone in placed.items():
            completed.setdefault(joint, bone)
    still = RigMapping("vrm", completed).missing
    if still:
        raise UnrecognisedRigError(source, f"the file's humanoid map of the {side} hand names no "
                                           f"{', '.join(missing)}, and the bones under its wrist "
                                           f"{joints['wrist']!r} do not give {', '.join(still)} "
                                           f"({_describe_chains(skeleton, found)}); {TEMPLATE_HINT}")
    added = ", ".join(f"{j} = {completed[j]!r}" for j in missing)
    return completed, [f"the file's humanoid map names no {', '.join(missing)}: taken from the finger chains under "
                       f"{joints['wrist']!r} ({added})"]


def _add_leaf_tips(skeleton: Skeleton, mapping: RigMapping, tails_only: bool = False) -> None:
    """Tips the mapping lacks (a humanoid map names none, a scheme may not): a distal bone's only child, its tail
    (`Skeleton.is_tail`) or, but with ``tails_only``, any leaf, is its finger's tip."""
    children = skeleton.children()
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    for tip in mapping.missing_tips:
        kids = children[lookup[mapping.joints[topo.JOINT_NAMES[topo.joint_index(tip) - 1]]]]
        if len(kids) == 1 and (skeleton.is_tail(kids[0]) or not (tails_only or children[kids[0]])):
            mapping.joints[tip] = skeleton.names[kids[0]]


def _is_ancestor(skeleton: Skeleton, a: int, b: int) -> bool:
    node = skeleton.parents[b]
    while node >= 0:
        if node == a:
            return True
        node = skeleton.parents[node]
    return False


def _describe_chains(skeleton: Skeleton, found: FingerChains) -> str:
    firsts = ", ".join(skeleton.names[c[0]] for c in found.chains)
    return f"found {len(found.chains)} finger chains ({firsts}) under {skeleton.names[found.wrist]!r}"


def _side_of(skeleton: Skeleton, mapping: RigMapping) -> tuple[str, float]:
    return detect_side(canonical_positions(skeleton, mapping.joints))


def recognise_rig(skeleton: Skeleton, source: str | Path, side: str | None = None, scheme: str | None = None,
                  user_map: dict[str, str] | None = None, humanoid: dict[str, dict[str, str]] | None = None
                  ) -> RigMapping:
    """The hand of a rig: ``user_map`` first, then the file's ``humanoid`` map (side -> canonical joint ->
    bone, from VRM), then bone names (``scheme`` or every built-in one), then topology and geometry.

    ``side`` None decides the side from the names, else from geometry; a given side overrides geometry.
    Raises `UnrecognisedRigError` (an `InputFileError`) naming ``source``, what was found and what to do.
    """
    if side is not None and side not in SIDES:
        raise ValueError(f"side must be one of {SIDES}, not {side!r}")
    names = skeleton.names
    named = sides_named(names)
    if user_map is not None:
        mapped_sides = sides_named(list(user_map.values()))
        mapping = map_user(names, source, user_map, side or next(iter(mapped_sides), "right"))
        mapping.palm_bones = bones_beside_the_wrist(skeleton, mapping)
        return _settle_side(skeleton, mapping, side, mapped_sides)
    if humanoid:
        chosen = side or ("right" if "right" in humanoid else next(iter(humanoid)))
        if chosen not in humanoid:
            raise UnrecognisedRigError(source, f"the file's humanoid map has no {chosen} hand; use --side "
                                               f"{next(iter(humanoid))}")
        joints, notes = complete_humanoid_map(skeleton, humanoid[chosen], chosen, source)
        mapping = map_user(names, source, joints, chosen, "the file's humanoid map")
        mapping.scheme, mapping.side_from, mapping.notes = "vrm", "humanoid map", notes
        mapping.both_hands = {"right", "left"} <= set(humanoid)
        _add_leaf_tips(skeleton, mapping)
        return mapping
    chosen = side or ("right" if "right" in named or not named else "left")
    by_name = best_name_match(names, chosen, scheme)
    if by_name.joints and not by_name.missing:
        hand_sides = sides_named([by_name.joints[n] for n in by_name.joints])
        by_name.both_hands = len(named) == 2
        if by_name.both_hands and side is None:
            by_name.notes.append("the rig has both hands; the right one is taken (--side left for the other)")
        _add_leaf_tips(skeleton, by_name, tails_only=True)  # a Blender export's ``Index3_end``, Rigify's kind
        return _settle_side(skeleton, by_name, side, hand_sides)
    if scheme is not None:
        raise UnrecognisedRigError(source, f"cannot map the {chosen} hand ({scheme} names): "
                                     f"{describe_missing(by_name.missing)}")
    hands, partial = _hand_candidates(skeleton)
    if side is not None and named:  # a character: keep the hand whose wrist name says the side asked for
        marked = [h for h in hands if split_side(names[h.wrist])[1] in (side, None)]
        if not marked and hands:
            found = ", ".join(f"{names[h.wrist]!r} ({split_side(names[h.wrist])[1]})" for h in hands)
            raise UnrecognisedRigError(source, f"no {side} hand: found {found}; use --side "
                                         f"{split_side(names[hands[0].wrist])[1]}")
        hands = marked
    if not hands:
        wrist = by_name.joints.get("wrist")
        partial.sort(key=lambda p: (names[p.wrist] != wrist, split_side(names[p.wrist])[1] not in (chosen, None),
                                    -len(p.chains)))
        found = partial[0] if partial else None
        free = free_bones(skeleton, by_name, found)
        if len(free) < len(by_name.missing):
            raise TooFewBonesError(source, f"{counted(len(free), 'bone')} left for "
                                           f"{len(by_name.missing)} joints ({', '.join(by_name.missing)}): a hand "
                                           f"needs 5 fingers of 3 bones each; "
                                           f"{_refusal(skeleton, by_name, found, chosen, hint=False)}")
        raise UnrecognisedRigError(source, _refusal(skeleton, by_name, found, chosen))
    candidates = [_topology_mapping(skeleton, h) for h in hands]
    if len(candidates) > 1:
        sides = [_side_of(skeleton, m)[0] for m in candidates]
        wanted = side or "right"
        matching = [m for m, s in zip(candidates, sides) if s == wanted] or candidates
        mapping = matching[0]
        mapping.notes.append(f"{len(candidates)} hands found ({', '.join(names[h.wrist] for h in hands)}); "
                             f"took {mapping.joints['wrist']!r}")
    else:
        mapping = candidates[0]
    return _settle_side(skeleton, mapping, side, sides_named([mapping.joints["wrist"]]))


def _settle_side(skeleton: Skeleton, mapping: RigMapping, side: str | None, names_say: set[str]) -> RigMapping:
    """Side from the user, else the mapped bones' names, else geometry; geometry's guess is noted."""
    geometric, sure = _side_of(skeleton, mapping)
    if side is not None and names_say == {side}:
        mapping.side, mapping.side_from = side, "names"
    elif side is not None:
        mapping.side, mapping.side_from = side, "user"
        if not names_say and geometric != side and sure >= SURE:
            mapping.notes.append(f"geometry says {geometric} (confidence {sure:.2f}); --side {side} overrides")
    elif len(names_say) == 1:
        mapping.side, mapping.side_from = next(iter(names_say)), "names"
    else:
        mapping.side, mapping.side_from = geometric, f"geometry (confidence {sure:.2f})"
        mapping.confidence = min(mapping.confidence, sure)
        if sure < SURE:
            mapping.notes.append(f"the side is a guess ({geometric}, confidence {sure:.2f}): check it, or pass "
                                 f"--side")
    return mapping


def bones_beside_the_wrist(skeleton: Skeleton, mapping: RigMapping) -> list[str]:
    """Where a rig hangs its finger bones beside the wrist, not under it (WebXR), the unmapped bones beside the
    wrist: its palm bones (metacarpals), whose skin moves with the wrist; none in a rig with a hierarchy (there
    a bone moves with its nearest mapped ancestor)."""
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    wrist = lookup[mapping.joints["wrist"]]
    parent = skeleton.parents[wrist]
    mapped = {lookup[bone] for bone in mapping.joints.values()}
    if parent < 0 or not any(skeleton.parents[b] == parent for b in mapped - {wrist}):
        return []
    return [n for b, n in enumerate(skeleton.names) if skeleton.parents[b] == parent and b not in mapped]


def free_bones(skeleton: Skeleton, by_name: RigMapping, partial: FingerChains | None) -> list[str]:
    """Bones a joint map could still give the joints names leave unmapped: those under the hand's wrist (by name,
    else the bone the finger chains hang from) when the rig hangs its fingers from it, else every bone; neither
    mapped nor palm bones."""
    lookup = {n: i for i, n in enumerate(skeleton.names)}
    wrist = lookup[by_name.joints["wrist"]] if "wrist" in by_name.joints else (partial.wrist if partial else None)
    pool = range(len(skeleton.names))
    if wrist is not None:
        below = [b for b in pool if _is_ancestor(skeleton, wrist, b)]
        fingers = {lookup[bone] for joint, bone in by_name.joints.items() if joint != "wrist"}
        if fingers & set(below) or (partial is not None and partial.wrist == wrist):
            pool = below
    used = set(by_name.joints.values()) | set(by_name.palm_bones)
    if partial is not None:
        used |= {skeleton.names[b] for b in partial.between}
    return [skeleton.names[b] for b in pool if b != wrist and skeleton.names[b] not in used]


def _refusal(skeleton: Skeleton, by_name: RigMapping, partial: FingerChains | None, side: str,
             hint: bool = True) -> str:
    """One line: what names matched, what the topology found, and (``hint``) what to do."""
    parts = []
    if set(by_name.joints) == {"wrist"}:
        parts.append(f"only the wrist has a known name ({by_name.joints['wrist']!r}): no finger bone is named as one")
    elif by_name.joints:
        parts.append(f"{by_name.scheme} names give the {side} hand but {describe_missing(by_name.missing)}")
    else:
        parts.append(f"no bone of the {len(skeleton.names)} is named as a {side} hand joint in a known scheme "
                     f"({', '.join(SCHEMES)})")
    if partial is not None:
        parts.append(f"{_describe_chains(skeleton, partial)}, not 5" + (
            "" if by_name.joints else ": s2h needs a hand with 5 fingers and does not guess one"))
    else:
        parts.append("no bone has finger chains (3 or more bones) under it: no hand in this skeleton")
    return "; ".join(parts + ([TEMPLATE_HINT] if hint else []))
