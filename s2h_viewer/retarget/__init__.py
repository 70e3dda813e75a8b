"""Retargeting methods (one interface, a registry) and their evaluation."""

from s2h_viewer.retarget.methods import METHODS, RetargetMethod, register, retarget

__all__ = ["METHODS", "RetargetMethod", "register", "retarget"]
