"""Errors the user sees: each names what was wrong and where, in one line."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path


class S2HError(Exception):
    """Base of every error s2h-viewer reports to a user (CLI prints it, the app shows a dialog)."""


class InvalidHandError(S2HError):
    """A hand model that breaks the topology or conventions (wrong shapes, NaN, bad frames)."""


class InvalidMotionError(S2HError):
    """A motion whose rotations are malformed (wrong shape, NaN, zero quaternions)."""


class InputFileError(S2HError):
    """A file that cannot be read as what it should be; the message names the file and the problem."""

    def __init__(self, path: str | Path, problem: str):
        self.path = Path(path)
        self.problem = " ".join(str(problem).split())  # always one line
        super().__init__(f"{self.path}: {self.problem}")


#: the largest input file any reader opens (a hand, a clip, a sidecar); larger is refused, not read
MAX_INPUT_BYTES = 2 * 1024 ** 3


def require_readable_file(path: str | Path, max_bytes: int = MAX_INPUT_BYTES) -> Path:
    """``path`` if it is a regular, readable file of at most ``max_bytes``; else one `InputFileError`."""
    path = Path(path)
    try:
        if not path.exists():
            raise InputFileError(path, "file not found")
        if path.is_dir():
            raise InputFileError(path, "is a directory, not a file")
        if not path.is_file():
            raise InputFileError(path, "is not a regular file")
        if not os.access(path, os.R_OK):
            raise InputFileError(path, "cannot be read (permission denied)")
        size = path.stat().st_size
    except OSError as exc:
        raise InputFileError(path, f"cannot be opened ({exc.strerror or exc})") from None
    if size == 0:
        raise InputFileError(path, "is empty")
    if size > max_bytes:
        raise InputFileError(path, f"is {size / 1024 ** 2:.0f} MiB, over the {max_bytes / 1024 ** 2:.0f} MiB "
                                   f"limit on input files")
    return path


@contextlib.contextmanager
def reading(path: str | Path, what: str) -> Iterator[None]:
    """Turn any unexpected exception while reading ``path`` as ``what`` into an `InputFileError` naming
    the file; the original stays attached (``__cause__``) for ``s2h --debug``. S2H errors pass through."""
    try:
        yield
    except S2HError:
        raise
    except RecursionError as exc:
        raise InputFileError(path, f"cannot be read as {what}: nested too deeply") from exc
    except MemoryError as exc:
        raise InputFileError(path, f"cannot be read as {what}: it needs more memory than there is") from exc
    except Exception as exc:  # a reader's bug or a library's surprise on damaged data: still one line
        raise InputFileError(path, f"cannot be read as {what} ({type(exc).__name__}: {exc})") from exc


class UnrecognisedRigError(InputFileError):
    """A rig file whose hand cannot be found; the message says what was found and what to do."""


class TooFewBonesError(UnrecognisedRigError):
    """A rig with fewer free bones than the joints its names leave unmapped (a four-finger hand): no joint map
    can make it a hand, so none is asked for."""


class FrameRangeError(S2HError):
    """Frames asked of a clip that it does not have, or a range whose first frame comes after its last."""
