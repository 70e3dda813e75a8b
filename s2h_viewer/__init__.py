"""s2h-viewer: transfer hand motion between avatars while keeping what it means.

The core packages (hand, io, semantics, annotate, retarget, motions, render) import no Qt;
only ``app`` and ``widgets`` do. See ``DESIGN.md`` in the shared folder for the method.
"""

__version__ = "0.1.0"
