"""Generate the shipped sample hands and motions under assets/ (deterministic: fixed seeds).

    python scripts/generate_assets.py        # or: make assets

Hands: 12 procedural right hands, 8 for training and 4 held out for testing (disjoint seeds),
realistic and stylised proportions and the rig conventions spread over both splits. Motions: gesture scripts performed by the first
training hand ``PERFORMER``, contacts fitted to it. assets/index.json lists everything.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
import torch

from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.procedural import RIG_CONVENTIONS, generate_hand
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.io.npz import save_hand, save_motion
from s2h_viewer.motions.gestures import GESTURES
from s2h_viewer.motions.synthesis import gesture_contacts, synthesize
from s2h_viewer.samples import ASSETS_DIR, INDEX_PATH
from s2h_viewer.semantics.contacts import detect_contacts

#: name -> style; the first 8 train, the last 4 are held out
HANDS = {"aster": "realistic", "birch": "realistic", "cedar": "stylised", "dahlia": "realistic", "elm": "stylised",
         "fern": "realistic", "gorse": "stylised", "hazel": "realistic",
         "iris": "realistic", "juniper": "stylised", "kale": "realistic", "laurel": "stylised"}
TRAIN = list(HANDS)[:8]
FIRST_SEED = 100
PERFORMER = "birch"  # holds every labelled contact of the library (see the issue note for the others)
SCRIPTS = {
    "gestures": ["fist", "point", "thumbs_up", "ok", "pinch", "v_sign", "spread", "rock", "claw", "flat"],
    "counting": ["count_1", "count_2", "count_3", "count_4", "count_5", "fist"],
    "fingerspelling": ["letter_a", "letter_b", "letter_c", "letter_d", "letter_f", "letter_g", "letter_i",
                       "letter_l", "letter_o", "letter_s", "letter_u", "letter_w", "letter_x", "letter_y"],
}


def main() -> int:
    conventions = sorted(RIG_CONVENTIONS)
    entries, hands = [], {}
    for i, (name, style) in enumerate(HANDS.items()):
        t0 = time.perf_counter()
        convention = conventions[i % len(conventions)]
        hand = generate_hand(FIRST_SEED + i, name=name, rig_convention=convention, style=style)
        hands[name] = hand
        path = save_hand(hand, ASSETS_DIR / "hands" / f"{name}.npz")
        split = "train" if name in TRAIN else "test"
        entries.append({"name": name, "file": f"hands/{name}.npz", "split": split, "seed": FIRST_SEED + i,
                        "style": style, "rig_convention": convention, "faces": int(len(hand.mesh.faces))})
        print(f"{name:8s} {split:5s} {style:9s} {convention:16s} length {hand.hand_length * 100:.1f} cm, "
              f"{len(hand.mesh.faces)} faces, {time.perf_counter() - t0:.1f} s -> {path}")

    motions = []
    performer = hands[PERFORMER]
    for i, (name, script) in enumerate(SCRIPTS.items()):
        motion = synthesize(script, performer, seed=i, name=name)
        path = save_motion(motion, ASSETS_DIR / "motions" / f"{name}.npz")
        held = motion.labels != ""
        pose = forward_kinematics(performer, torch.as_tensor(motion.q_tbs[held], dtype=torch.float64))
        want = gesture_contacts(motion.labels[held])
        got = detect_contacts(performer, pose)
        recall = (got & want).sum() / max(want.sum(), 1)
        motions.append({"name": name, "file": f"motions/{name}.npz", "hand": performer.name,
                        "frames": motion.n_frames, "fps": motion.fps, "script": script})
        print(f"motion {name}: {motion.n_frames} frames ({motion.duration:.1f} s), labelled contacts held "
              f"{recall:.1%} -> {path}")

    index = {"hands": entries, "motions": motions, "gestures": len(GESTURES)}
    with atomic_path(INDEX_PATH) as tmp:
        tmp.write_text(json.dumps(index, indent=2) + "\n")
    print(f"wrote {INDEX_PATH}")
    return 0


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    sys.exit(main())
