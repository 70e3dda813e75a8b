"""Annotating a hand: TBS frames found by rays cast at its mesh, then corrected by a person."""
