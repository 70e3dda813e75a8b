"""Atomic file writes: write beside the target, then rename, so no reader ever sees half a file.

Temporary files are named ``.<stem>.s2h-<pid>-<random><suffix>``: a write killed before its rename
leaves one behind, and the next write to the same place removes those whose process is gone.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path


def _temp_prefix(path: Path) -> str:
    return f".{path.stem}.s2h-"


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        return True
    return True


def remove_stale_temps(path: str | Path) -> list[Path]:
    """Delete the temporary files that killed writes to ``path`` left behind (their process is gone)."""
    path = Path(path)
    pattern = glob.escape(str(path.parent / _temp_prefix(path))) + "*-*" + glob.escape(path.suffix)
    removed = []
    for name in glob.glob(pattern):
        pid_text = Path(name).name[len(_temp_prefix(path)):].split("-", 1)[0]
        if pid_text.isdigit() and int(pid_text) != os.getpid() and not _process_alive(int(pid_text)):
            Path(name).unlink(missing_ok=True)
            removed.append(Path(name))
    return removed


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path in the target's folder (same suffix); rename it onto ``path`` on success.

    On any error the temporary file is removed and the existing ``path`` is left untouched.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except FileExistsError:  # the folder's name is a file's: say so, not "file exists"
        raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(path.parent)) from None
    remove_stale_temps(path)
    fd, tmp = tempfile.mkstemp(prefix=f"{_temp_prefix(path)}{os.getpid()}-", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; a saved file gets the usual permissions
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.replace(tmp_path, path)
    finally:
        tmp_path.unlink(missing_ok=True)
