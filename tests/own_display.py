"""An Xvfb display of this test process's own, for the window's tests: each pytest-xdist worker gets one (two
workers' windows on one display took each other's keyboard focus), and so does a lone pytest with no display.

The display ends with the process that started it: the kernel stops Xvfb when its parent exits
(``PR_SET_PDEATHSIG``), after Qt and VTK have let go of it, crashed or not. Stopping it from an atexit handler
came before Qt's own teardown, which then died on the broken connection ("The X11 connection broke")."""

from __future__ import annotations

import ctypes
import os
import shutil
import signal
import subprocess

#: the size of the screen the windows open on (the window's tests ask up to 1400 x 1000)
SCREEN = "1600x1000x24"
_PR_SET_PDEATHSIG = 1
#: this process's Xvfb, held for as long as the process lives
_xvfb: subprocess.Popen | None = None


def _stop_with_parent() -> None:
    ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)


def start_own_display() -> str | None:
    """Start Xvfb on the first free display number and point ``DISPLAY`` at it (under xdist always, alone only
    where there is no display); the display, or None where nothing was started (no Xvfb: those tests skip)."""
    global _xvfb
    use_given_display = os.environ.get("DISPLAY") and not os.environ.get("PYTEST_XDIST_WORKER")
    if use_given_display or shutil.which("Xvfb") is None:
        return None
    read, write = os.pipe()
    _xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", SCREEN, "-nolisten", "tcp"],
                             pass_fds=(write,), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL, preexec_fn=_stop_with_parent)
    os.close(write)
    with os.fdopen(read) as said:  # Xvfb writes its display number once it accepts connections
        number = said.readline().strip()
    if not number.isdigit():
        return None
    os.environ["DISPLAY"] = f":{number}"
    return os.environ["DISPLAY"]
