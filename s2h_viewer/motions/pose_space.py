"""Random key poses over the whole anatomical pose space, for training (issue 26): the gesture library
alone is 31 poses, so a network trained on it meets real hands' poses it never saw.

Each key draws every finger's flexion on its own (or around a shared rest, from flat to curled), hooks
(straight knuckle, bent PIP/DIP), hyperextended knuckles, spreads within the splay limits, and a thumb
either free over its range or opposed to one fingertip. Opposition and curled-into-the-palm keys carry
those contacts as labels, so `fit_gesture_angles` makes them hold on each hand (and keeps every other
pad pair apart), exactly as for the library's gestures.
"""

from __future__ import annotations

import numpy as np

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.motions.fitting import fit_gesture_angles
from s2h_viewer.motions.gestures import THUMB_CMC_REST, Gesture
from s2h_viewer.motions.synthesis import perform

P_INDEPENDENT = 0.5  # each finger's flexion drawn on its own; else around one rest level for the hand
P_HOOK = 0.15  # a finger hooked: knuckle straight, PIP and DIP bent
P_OPPOSE = 0.4  # the thumb's tip on one fingertip
PALM_CURL = 0.85  # a finger curled at least this far (of a full curl) is labelled as touching the palm
#: thumb (CMC, MCP, IP) bends and the opposed finger's (MCP, PIP, DIP) bends that start each opposition,
#: degrees (from the library's OK, letter D and W); the fit then closes the gap on each hand
OPPOSITION = {"index": ((30, 25, 20), (45, 50, 35)), "middle": ((35, 25, 25), (45, 50, 35)),
              "ring": ((40, 35, 25), (55, 55, 40)), "pinky": ((45, 40, 30), (70, 80, 60))}
FINGERS = topo.FINGERS[1:]
FULL_CURL = np.array([80.0, 88.0, 65.0])  # MCP, PIP, DIP at a flexion of 1 (the library's CURL, PIP inside 89)


def random_key_pose(rng: np.random.Generator, name: str = "") -> Gesture:
    """One key pose drawn over the anatomical ranges, with the contacts it is meant to make."""
    angles = np.zeros((15, 3))
    rest = rng.uniform(0.0, 1.0)
    if rng.random() < P_INDEPENDENT:
        flexion = rng.uniform(0.0, 1.0, 4)
    else:
        flexion = np.clip(rest + rng.normal(0.0, 0.12, 4), 0.0, 1.0)
    contacts: set[tuple[str, str]] = set()
    opposed = FINGERS[int(rng.integers(4))] if rng.random() < P_OPPOSE else None
    for i, finger in enumerate(FINGERS):
        row = slice(3 + 3 * i, 6 + 3 * i)
        if finger == opposed:
            bends = np.asarray(OPPOSITION[finger][1], float) + rng.normal(0.0, 6.0, 3)
        elif rng.random() < P_HOOK:
            bends = np.array([rng.uniform(-10, 20), rng.uniform(55, 89), rng.uniform(40, 80)])
        else:
            bends = flexion[i] * FULL_CURL * rng.uniform(0.85, 1.1, 3)
            if flexion[i] < 0.1 and rng.random() < 0.5:
                bends[0] = rng.uniform(-10.0, 0.0)  # hyperextended knuckle
            if flexion[i] >= PALM_CURL:
                contacts.add((finger, "palm"))
        angles[row, 1] = bends
        angles[3 + 3 * i, 2] = rng.uniform(-1.0, 1.0) * rng.uniform(0.0, 25.0) * (1.0 - 0.6 * flexion[i])
    if opposed:
        angles[0:3, 1] = np.asarray(OPPOSITION[opposed][0], float) + rng.normal(0.0, 5.0, 3)
        contacts.add(("thumb", opposed))
    else:
        angles[0:3, 1] = [rng.uniform(-20, 60), rng.uniform(0, 60), rng.uniform(0, 80)]
        angles[0, 2] = rng.uniform(-25.0, 25.0)
    angles[0, 1:] += THUMB_CMC_REST
    return Gesture(name, "random", angles, frozenset(contacts), "a random key pose")


def random_pose_motion(hand: HandModel, keys: int, seed: int, fps: float = 30.0) -> Motion:
    """A clip through ``keys`` random key poses fitted to ``hand`` (contacts made), shorter holds than the
    gesture scripts' so that a window of training frames sees more moves."""
    rng = np.random.default_rng(seed)
    poses = [random_key_pose(rng, f"random_{k}") for k in range(keys)]
    fitted = fit_gesture_angles(hand, poses)
    return perform(fitted, [p.name for p in poses], rng, fps, hold=(0.2, 0.5), transition=(0.3, 0.6),
                   name=f"random poses {seed}", hand_name=hand.name, meta={"random_poses": keys, "seed": seed})
