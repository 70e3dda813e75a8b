"""s2h-viewer: transfer hand motion between avatars while keeping what it means.

The core packages (hand, io, semantics, annotate, retarget, motions, render) import no Qt;
only ``app`` and ``widgets`` do. See ``DESIGN.md`` in the shared folder for the method.
"""

import os

__version__ = "0.1.0"

# Large CPU tensors (2 MB and up) on transparent huge pages: PyTorch reads THP_MEM_ALLOC_ENABLE once,
# when torch is first imported, so this must run before (the CLI, the app and the benchmarks import
# s2h_viewer first). A long clip's ASM is tens of MB written once; on 4 kB pages a third of its time
# went to page faults. Where the kernel offers no huge pages this changes nothing.
os.environ.setdefault("THP_MEM_ALLOC_ENABLE", "1")
