"""Retargeting methods behind one interface, and the registry the app and CLI list them from.

``retarget(motion, source_hand, target_hand, method)`` returns the motion in the target's TBS space.
This module holds the two copy baselines; learned and optimised methods register themselves the same way.
A method says how far it is, and is cancelled, through `retarget.progress` (the caller installs the hook).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from s2h_viewer.hand.chunks import frame_chunks
from s2h_viewer.hand.kinematics import rig_local_to_tbs, tbs_to_rig_local
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.retarget.progress import report

#: fn(motion, source hand, target hand) -> the motion on the target; reports through `retarget.progress`
RetargetFn = Callable[[Motion, HandModel, HandModel], Motion]


@dataclass(frozen=True)
class RetargetMethod:
    name: str
    label: str  # how the UI and tables show it
    description: str
    run: RetargetFn


METHODS: dict[str, RetargetMethod] = {}


def register(name: str, label: str, description: str) -> Callable[[RetargetFn], RetargetFn]:
    """Decorator adding a retargeting function to ``METHODS`` under ``name``."""
    def wrap(fn: RetargetFn) -> RetargetFn:
        METHODS[name] = RetargetMethod(name, label, description, fn)
        return fn
    return wrap


def retarget(motion: Motion, source_hand: HandModel, target_hand: HandModel, method: str = "tbs_copy") -> Motion:
    """Retarget ``motion`` (posed on ``source_hand``) onto ``target_hand`` with a registered method (how far
    it is goes to the hook of `retarget.progress.reporting`, which may cancel it)."""
    try:
        chosen = METHODS[method]
    except KeyError:
        raise KeyError(f"unknown retargeting method {method!r}; available: {', '.join(METHODS)}") from None
    return chosen.run(motion, source_hand, target_hand)


def on_target(motion: Motion, target_hand: HandModel, q_tbs, method: str) -> Motion:
    """The retargeted motion: same timing and labels, the target's rotations, provenance in ``meta``."""
    return dataclasses.replace(motion, q_tbs=q_tbs, hand_name=target_hand.name,
                               meta={**motion.meta, "retargeted_by": method, "source_hand": motion.hand_name})


@register("copy", "Copy", "copy the rig's local joint rotations (what most tools do)")
def retarget_copy(motion: Motion, source_hand: HandModel, target_hand: HandModel) -> Motion:
    q = np.empty_like(motion.q_tbs)
    for first, end in frame_chunks(motion.n_frames):  # the conversions' temporaries stay one chunk's
        q_local = tbs_to_rig_local(source_hand, motion.q_tbs[first:end])
        q[first:end] = rig_local_to_tbs(target_hand, q_local).numpy()
        report(end / motion.n_frames)
    return on_target(motion, target_hand, q, "copy")


@register("tbs_copy", "TBS Copy", "copy twist-bend-splay rotations, so a bend stays a bend on any rig")
def retarget_tbs_copy(motion: Motion, source_hand: HandModel, target_hand: HandModel) -> Motion:
    result = on_target(motion, target_hand, motion.q_tbs.copy(), "tbs_copy")
    report(1.0)
    return result
