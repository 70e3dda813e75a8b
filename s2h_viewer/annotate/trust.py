"""How far a hand's TBS frames can be trusted, joint by joint, from where they came from (`io.rig.annotate`
records it in ``hand.meta``): a solver frame scored under `LOW_CONFIDENCE` is unsure, a palm-plane frame
(no ray hit, or no mesh) is a guess. Compare mode warns on a target with either: its retargets may bend a
finger sideways where the frames are wrong, and no score of the motion alone can say why."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from s2h_viewer.annotate.solver import LOW_CONFIDENCE
from s2h_viewer.hand import topology as topo
from s2h_viewer.hand.model import HandModel

#: ``hand.meta`` keys: per articulated joint, what set its frame ("solver", "manual", "palm plane") and the
#: solver's confidence (NaN: not scored)
SET_BY_KEY, CONFIDENCE_KEY = "frame_set_by", "frame_confidence"
GUESS = "palm plane"


def record(hand: HandModel, set_by: list[str], confidence: np.ndarray) -> None:
    """Keep where each of ``hand``'s frames came from in its meta, for `frame_warning`."""
    hand.meta[SET_BY_KEY] = list(set_by)
    hand.meta[CONFIDENCE_KEY] = [float(c) for c in np.asarray(confidence, dtype=float)]


def _joint_names(joints: list[int], levels: bool = True) -> str:
    """"index DIP, pinky MCP/PIP/DIP": the joints grouped by finger ("every joint": all 15); without ``levels``
    the fingers alone ("index, pinky")."""
    if len(joints) == topo.N_ARTICULATED:
        return "every joint"
    by_finger: dict[str, list[str]] = {}
    for j in joints:
        finger, _, level = topo.ARTICULATED_NAMES[j].partition("_")
        by_finger.setdefault(finger, []).append(level.upper())
    return ", ".join(f"{finger} {'/'.join(names)}" if levels else finger for finger, names in by_finger.items())


@dataclass(frozen=True)
class FrameWarning:
    """A hand's frames that are unsure (solver, low confidence) or guessed (palm plane), as joint indices."""

    hand: str
    unsure: tuple[int, ...]
    guessed: tuple[int, ...]
    lowest: float  # the lowest confidence among the unsure (NaN if none is)
    unparted: tuple[str, ...] = ()  # fingers its mesh does not part from their neighbours (a mitten)

    @property
    def banner(self) -> str:
        """One short line for a grid cell: "frames unsure: pinky MCP/PIP/DIP"."""
        return self.banners[0]

    @property
    def banners(self) -> tuple[str, str, str]:
        """The banner, then shorter for narrower cells: the fingers alone ("frames guessed: index"), then what
        is wrong alone ("frames guessed"), so a small cell does not cut it to "frames guessed: i..."."""
        kinds = (("unsure", self.unsure), ("guessed", self.guessed))
        return ("frames " + "; ".join(f"{kind}: {_joint_names(list(joints))}" for kind, joints in kinds if joints),
                "frames " + "; ".join(f"{kind}: {_joint_names(list(joints), False)}" for kind, joints in kinds
                                      if joints),
                "frames " + ", ".join(kind for kind, joints in kinds if joints))

    def describe(self) -> str:
        """The whole warning, for the table's tooltip and the note over the curve."""
        parts = []
        if self.unsure:
            parts.append(f"the TBS solver is unsure of {_joint_names(list(self.unsure))} (confidence "
                         f"{self.lowest:.2f} at lowest)")
        if self.guessed:
            parts.append(f"{_joint_names(list(self.guessed))}: frames from the palm plane (a guess: no rays "
                         f"decided them)")
        mitten = (f"; its mesh does not part {', '.join(self.unparted)} from their neighbours (a mitten): its bones "
                  f"are drawn over the skin" if self.unparted else "")
        return (f"{self.hand}: {' and '.join(parts)}; retargets there may bend a finger sideways: check its frames "
                f"(Annotate > Open hand...){mitten}")


def frame_warning(hand: HandModel) -> FrameWarning | None:
    """``hand``'s unsure and guessed frames, None when all are trusted or nothing was recorded (a procedural
    hand's frames are its ground truth)."""
    set_by, confidence = hand.meta.get(SET_BY_KEY), hand.meta.get(CONFIDENCE_KEY)
    if set_by is None or confidence is None:
        return None
    confidence = np.asarray(confidence, dtype=float)
    unsure = tuple(j for j, by in enumerate(set_by) if by == "solver" and confidence[j] < LOW_CONFIDENCE)
    guessed = tuple(j for j, by in enumerate(set_by) if by == GUESS)
    if not unsure and not guessed:
        return None
    lowest = float(confidence[list(unsure)].min()) if unsure else float("nan")
    return FrameWarning(hand.name, unsure, guessed, lowest, tuple(hand.meta.get("unparted_fingers", ())))
