"""A rig file's length unit: metres, decimetres, centimetres, millimetres or inches, as the user says (``--unit``)
or as the hand's size says.

Formats declare units loosely (glTF: metres; FBX: a scale the reader applies; BVH: none), and files from the wild
break even that (finger mocap in decimetres). A hand's wrist-to-middle-DIP length is 14-18 cm on adults and
3-60 cm on any avatar: the unit that brings it there, nearest a typical 16 cm (by ratio), is the guess; it is
unsure where it is not within 1.5 times of typical or another unit comes within 2 times.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: unit name -> metres per file unit
UNITS = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 0.001, "in": 0.0254}
UNIT_NAMES = {"m": "metres", "dm": "decimetres", "cm": "centimetres", "mm": "millimetres", "in": "inches"}
#: wrist to middle DIP, in metres: the range any hand (stylised, child, giant avatar) falls in, and a typical one
PLAUSIBLE = (0.03, 0.6)
TYPICAL = 0.16
#: a guess is sure when its hand is within this ratio of typical and every other unit's is beyond ``CLEAR``
CLOSE, CLEAR = 1.5, 2.0


@dataclass(frozen=True)
class UnitChoice:
    """The unit a rig is read in: its name, metres per file unit, how it was decided and whether to check it."""

    unit: str
    to_metres: float
    decided_by: str  # "the user" | "the file" | "the hand's size"
    sure: bool = True

    def alternatives(self, length: float) -> list[str]:
        """The other units in which a ``length`` (file units) hand would be plausible too."""
        return [u for u in UNITS if u != self.unit and plausible(length * UNITS[u])]

    def note(self, length: float) -> str | None:
        """A line for the rig's notes where the unit was guessed, None where the user or the file said it."""
        if self.decided_by != "the hand's size":
            return None
        alternatives = ", ".join(self.alternatives(length))
        return (f"length unit guessed from the hand's size: {UNIT_NAMES[self.unit]} (wrist to middle DIP "
                f"{length:.4g} file units = {length * self.to_metres:.3f} m)"
                + (f"; {alternatives} would also give a plausible hand: check it, or pass --unit" if not self.sure
                   else "; pass --unit to say otherwise"))


def plausible(metres: float) -> bool:
    return PLAUSIBLE[0] <= metres <= PLAUSIBLE[1]


def choose_unit(length: float, unit: str | None = None, declared: str | None = "m") -> UnitChoice | None:
    """The unit for a rig whose wrist-to-middle-DIP is ``length`` file units: ``unit`` where the user gives it;
    else the file's ``declared`` unit (None: a format that declares none, as BVH) where the hand is plausible in
    it; else the plausible unit nearest a typical hand (by ratio); None where the user's unit or no unit gives a
    plausible hand."""
    if unit is not None:
        if unit not in UNITS:
            raise ValueError(f"unit must be one of {', '.join(UNITS)}, not {unit!r}")
        return UnitChoice(unit, UNITS[unit], "the user") if plausible(length * UNITS[unit]) else None
    if declared is not None and plausible(length * UNITS[declared]):
        return UnitChoice(declared, UNITS[declared], "the file")
    fits = sorted((abs(math.log(length * f / TYPICAL)), u) for u, f in UNITS.items() if length > 0
                  and plausible(length * f))
    if not fits:
        return None
    best = fits[0][1]
    sure = fits[0][0] <= math.log(CLOSE) and all(d > math.log(CLEAR) for d, _ in fits[1:])
    return UnitChoice(best, UNITS[best], "the hand's size", sure)
