"""One lock for VTK's process-wide text machinery (the vtkTextRenderer singleton, FreeType's glyph caches),
which is not thread-safe: measuring a label and drawing text for the first time take it. The window's renders
and a video export's setup on its worker thread (building its grid, drawing its first frame) hold it, so
they never lay out or draw text at the same time."""

from __future__ import annotations

import threading

TEXT_LOCK = threading.RLock()
