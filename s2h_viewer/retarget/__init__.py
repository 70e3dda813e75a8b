"""Retargeting methods (one interface, a registry) and their evaluation.

Importing this package registers every method: copy, tbs_copy, dm, asrn, asm_opt (in table order).
"""

from s2h_viewer.retarget.asrn import inference  # noqa: F401  (registers dm, asrn)
from s2h_viewer.retarget import asm_opt  # noqa: F401  (registers asm_opt)
from s2h_viewer.retarget.methods import METHODS, RetargetMethod, register, retarget

__all__ = ["METHODS", "RetargetMethod", "register", "retarget"]
