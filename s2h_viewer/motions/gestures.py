"""The gesture library: key poses in TBS angles, each labelled with the contacts that define it.

Angles are degrees per articulated joint (twist, bend, splay) measured from the canonical pose (flat
hand, straight fingers, thumb in the palm plane), so a fist is the same angles on every hand. Twist
stays 0, splay is used only at knuckles, bends stay inside the anatomical limits (DESIGN.md section
5), so every pose has zero anatomical violation. The thumb's authored CMC angles are offsets from
where a relaxed thumb sits (``THUMB_CMC_REST``: below the palm plane and across it), not from the
flattened canonical thumb. The angles are authored for an average hand; `fit_gesture_angles`
adjusts them to a particular hand until the labelled contacts hold (and others stay apart).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from s2h_viewer.hand import topology as topo
from s2h_viewer.semantics.contacts import CONTACT_PAIRS, pair_index

# finger (MCP, PIP, DIP) bends and thumb (CMC, MCP, IP) bends, degrees
EXT = (0, 0, 0)
CURL = (80, 90, 65)  # fingertip into the palm
HALF = (40, 50, 35)
HOOK = (15, 85, 70)
T_OUT = (-30, 0, 0)  # out to its side: a thumbs-up's 40-60 deg out (`semantics.flexion.thumb_out`), as authored
T_SIDE = (12, 8, 5)  # alongside the index
T_OVER = (40, 35, 40)  # over curled fingers
T_ACROSS = (55, 40, 20)  # folded across the palm
#: (bend, splay) of a relaxed thumb's CMC from the canonical (flattened) thumb, degrees: the mean rest
#: pose of the procedural family, added to every authored thumb CMC.
THUMB_CMC_REST = (8.0, 30.0)


@dataclass(frozen=True)
class Gesture:
    """A named key pose with the contacts (pairs of sites: fingertips, "palm") it must show."""

    name: str
    category: str  # "gesture", "count" or "letter"
    angles_deg: np.ndarray  # (15, 3) twist, bend, splay per articulated joint
    contacts: frozenset[tuple[str, str]]
    description: str

    def contact_vector(self) -> np.ndarray:
        """(15,) bool over ``CONTACT_PAIRS``."""
        out = np.zeros(len(CONTACT_PAIRS), dtype=bool)
        for a, b in self.contacts:
            out[pair_index(a, b)] = True
        return out


def _pose(thumb=T_OUT, index=EXT, middle=EXT, ring=EXT, pinky=EXT, splay=(0, 0, 0, 0, 0)) -> np.ndarray:
    angles = np.zeros((topo.N_ARTICULATED, 3))
    for f, bends in enumerate((thumb, index, middle, ring, pinky)):
        angles[3 * f:3 * f + 3, 1] = bends
        angles[3 * f, 2] = splay[f]
    angles[0, 1:] += THUMB_CMC_REST
    return angles


def _palm(*fingers: str) -> set[tuple[str, str]]:
    return {(f, "palm") for f in fingers}


_LIBRARY = [
    # everyday gestures
    ("relaxed", "gesture", _pose((10, 10, 10), (15, 20, 10), (18, 22, 12), (20, 25, 14), (22, 28, 15)), set(),
     "a resting hand, slightly curled"),
    ("flat", "gesture", _pose(T_SIDE, splay=(0, -3, 0, 3, 5)), set(), "flat hand, fingers together"),
    ("spread", "gesture", _pose(T_OUT, splay=(-8, 10, 0, -8, -10)), set(), "fingers spread wide"),
    ("fist", "gesture", _pose(T_OVER, CURL, CURL, CURL, CURL), _palm("index", "middle", "ring", "pinky"),
     "closed fist, thumb over the fingers"),
    ("point", "gesture", _pose(T_SIDE, EXT, CURL, CURL, CURL), _palm("middle", "ring", "pinky"),
     "index pointing, thumb alongside"),
    ("thumbs_up", "gesture", _pose(T_OUT, CURL, CURL, CURL, CURL), _palm("index", "middle", "ring", "pinky"),
     "thumb extended, fingers curled"),
    ("ok", "gesture", _pose((30, 25, 20), (45, 50, 35), EXT, EXT, EXT, splay=(0, 0, 0, -4, -8)),
     {("thumb", "index")}, "thumb and index tips form a ring"),
    ("pinch", "gesture", _pose((25, 20, 15), (35, 40, 25), (30, 40, 30), (35, 45, 30), (40, 45, 30)),
     {("thumb", "index")}, "precision pinch"),
    ("v_sign", "gesture", _pose(T_OVER, EXT, EXT, CURL, CURL, splay=(0, 10, -10, 0, 0)),
     _palm("ring", "pinky"), "victory: index and middle apart, thumb over the ring finger"),
    ("rock", "gesture", _pose(T_OVER, EXT, CURL, CURL, EXT, splay=(0, 6, 0, 0, -8)), _palm("middle", "ring"),
     "horns: index and pinky up"),
    ("claw", "gesture", _pose((20, 30, 30), HOOK, HOOK, HOOK, HOOK, splay=(0, 6, 0, -4, -8)), set(),
     "fingers hooked, tips apart from the palm"),
    ("pinch_middle", "gesture", _pose((30, 25, 20), (20, 25, 15), (45, 50, 35), (25, 30, 20), (25, 30, 20)),
     {("thumb", "middle")}, "thumb and middle tips touch"),
    # counting, American style
    ("count_1", "count", _pose(T_OVER, EXT, CURL, CURL, CURL), _palm("middle", "ring", "pinky"), "one: index up"),
    ("count_2", "count", _pose(T_OVER, EXT, EXT, CURL, CURL, splay=(0, 6, -6, 0, 0)), _palm("ring", "pinky"),
     "two: index and middle up"),
    ("count_3", "count", _pose(T_OUT, EXT, EXT, CURL, CURL, splay=(0, 6, -6, 0, 0)), _palm("ring", "pinky"),
     "three: thumb, index and middle"),
    ("count_4", "count", _pose(T_ACROSS, splay=(0, 6, 0, -5, -8)), _palm("thumb"), "four: thumb folded"),
    ("count_5", "count", _pose(T_OUT, splay=(-5, 8, 0, -6, -9)), set(), "five: all out"),
    # fingerspelling (static ASL letters; J and Z move, E, K, M, N, P, Q, R, T need crossing or occlusion)
    ("letter_a", "letter", _pose(T_SIDE, CURL, CURL, CURL, CURL), _palm("index", "middle", "ring", "pinky"),
     "A: fist, thumb alongside"),
    ("letter_b", "letter", _pose(T_ACROSS, splay=(0, -3, 0, 3, 5)), _palm("thumb"),
     "B: flat fingers together, thumb across the palm"),
    ("letter_c", "letter", _pose((20, 15, 10), HALF, HALF, HALF, HALF), set(), "C: curved hand"),
    ("letter_d", "letter", _pose((35, 25, 25), EXT, (55, 60, 40), (60, 60, 40), (65, 60, 40)),
     {("thumb", "middle")}, "D: index up, thumb meets the middle finger"),
    ("letter_f", "letter", _pose((30, 25, 20), (50, 50, 30), EXT, EXT, EXT, splay=(0, 0, 2, 0, -2)),
     {("thumb", "index")}, "F: thumb and index touch, others up together"),
    ("letter_g", "letter", _pose((20, 5, 0), EXT, CURL, CURL, CURL), _palm("middle", "ring", "pinky"),
     "G: index and thumb parallel"),
    ("letter_i", "letter", _pose(T_OVER, CURL, CURL, CURL, EXT), _palm("index", "middle", "ring"), "I: pinky up"),
    ("letter_l", "letter", _pose(T_OUT, EXT, CURL, CURL, CURL), _palm("middle", "ring", "pinky"),
     "L: thumb and index at a right angle"),
    ("letter_o", "letter", _pose((30, 25, 25), (50, 50, 35), (55, 50, 35), (60, 50, 35), (65, 50, 35)),
     {("thumb", "index"), ("thumb", "middle")}, "O: fingertips round onto the thumb"),
    ("letter_s", "letter", _pose((50, 40, 30), CURL, CURL, CURL, CURL), _palm("index", "middle", "ring", "pinky"),
     "S: fist, thumb across the fingers"),
    ("letter_u", "letter", _pose(T_OVER, EXT, EXT, CURL, CURL, splay=(0, -3, 3, 0, 0)), _palm("ring", "pinky"),
     "U: index and middle together"),
    ("letter_w", "letter", _pose((45, 40, 30), EXT, EXT, EXT, (70, 80, 60), splay=(0, 7, 0, -7, 0)),
     {("thumb", "pinky")}, "W: three fingers spread, thumb holds the pinky"),
    ("letter_x", "letter", _pose(T_OVER, HOOK, CURL, CURL, CURL), _palm("middle", "ring", "pinky"),
     "X: index hooked"),
    ("letter_y", "letter", _pose(T_OUT, CURL, CURL, CURL, EXT, splay=(-6, 0, 0, 0, -8)),
     _palm("index", "middle", "ring"), "Y: thumb and pinky out"),
]

GESTURES: dict[str, Gesture] = {
    name: Gesture(name, category, angles, frozenset(tuple(p) for p in contacts), description)
    for name, category, angles, contacts, description in _LIBRARY
}


def gesture(name: str) -> Gesture:
    """Look a gesture up by name, with an error listing the known ones."""
    try:
        return GESTURES[name]
    except KeyError:
        raise KeyError(f"unknown gesture {name!r}; known: {', '.join(GESTURES)}") from None
