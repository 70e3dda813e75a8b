"""Whether a skeleton's rest pose is itself a pose: a clip exported without its mesh often keeps a key as the
skeleton's rest (Oculus's r_hand_pinch_anim.fbx rests in its pinch). TBS rotations are measured from the canonical
pose made from the rest (DESIGN.md section 2): it flattens the rest's thumb into the palm, so a thumb resting on a
fingertip makes every thumb rotation wrong on other hands, and it turns each finger bone the shortest way to the
palm's direction, which a bone curled back past 90 deg does not reach cleanly (the Godot pose file re-rested in its
horns: the curled middle fingertip a third of a hand off). The rig the clip was made for fixes both."""

from __future__ import annotations

import numpy as np
import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.semantics.contacts import thumb_pair_gaps
from s2h_viewer.semantics.signature import CURLED_ABOVE, THUMB_TOUCH, finger_curls


def posed_rest_note(hand: HandModel) -> str | None:
    """A line saying why ``hand``'s rest is a pose, for a hand with no mesh whose rest holds its thumb on a
    fingertip (no rig is bound so: the nearest of the 29 rigs and procedural hands here is 18% of a hand away) or
    curls a finger (over `CURLED_ABOVE`: rigs rest at 6-121 deg, the pose file's skeleton at 28-44); None otherwise.
    A skinned hand's rest is its bind pose, whatever it is."""
    if hand.mesh is not None:
        return None
    positions = hand.rest_positions[None]
    gaps = thumb_pair_gaps(hand, torch.as_tensor(positions, dtype=torch.float64))[0].numpy() / hand.hand_length
    curls = finger_curls(positions)[0]
    what = [f"the thumb on the {topo.FINGERS[1 + f]} fingertip" for f in np.flatnonzero(gaps < THUMB_TOUCH)[:1]]
    curled = [f"{topo.FINGERS[1 + f]} {curls[f]:.0f} deg" for f in np.flatnonzero(curls > CURLED_ABOVE)]
    if curled:
        what.append("fingers curled: " + ", ".join(curled))
    if not what:
        return None
    return (f"its skeleton has no mesh and rests in a pose ({'; '.join(what)}), so its rotations are measured from "
            f"that pose and come out wrong on other hands")
