"""Whether a skeleton's rest pose is itself a pose: a clip exported without its mesh often keeps its first key
as the skeleton's rest (Oculus's r_hand_pinch_anim.fbx rests in its pinch). The canonical pose flattens the
thumb of the rest into the palm (DESIGN.md section 2), so a thumb resting on a fingertip makes every thumb
rotation of that clip wrong on any other hand; the rig the clip was made for (its skinned hand) fixes it."""

from __future__ import annotations

import torch

from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel
from s2h_viewer.semantics.contacts import thumb_pair_gaps
from s2h_viewer.semantics.signature import THUMB_TOUCH

def posed_rest_note(hand: HandModel) -> str | None:
    """A line saying why ``hand``'s rest is a pose, for a hand with no mesh whose rest holds its thumb on a
    fingertip (no rig is bound so: the nearest of the 29 rigs and procedural hands here is 18% of a hand away);
    None otherwise."""
    if hand.mesh is not None:
        return None
    positions = torch.as_tensor(hand.rest_positions[None], dtype=torch.float64)
    gaps = thumb_pair_gaps(hand, positions)[0].numpy() / hand.hand_length
    nearest = int(gaps.argmin())
    if gaps[nearest] >= THUMB_TOUCH:
        return None
    finger = topo.FINGERS[1 + nearest]
    return (f"its skeleton has no mesh and rests in a pose (the thumb on the {finger} fingertip), so its thumb's "
            f"rotations are measured from that pose and come out wrong on other hands")
