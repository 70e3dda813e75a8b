"""Scene building and off-screen rendering, shared by the CLI and the app.

With no display, VTK would first try X and warn before falling back to EGL; ask for EGL directly.
"""

import os

if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
