"""Errors the user sees: each names what was wrong and where, in one line."""

from __future__ import annotations

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
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")


class UnrecognisedRigError(InputFileError):
    """A rig file whose hand cannot be found; the message says what was found and what to do."""
