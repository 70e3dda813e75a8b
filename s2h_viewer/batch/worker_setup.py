"""Preloaded into each local worker process (`cluster.local_cluster`): Ctrl+C in a terminal reaches the whole
process group, and a worker would die of it printing a traceback; the client stops its workers instead."""

from __future__ import annotations

import signal


def dask_setup(worker) -> None:
    """Dask calls this in the worker process's main thread as the worker starts (and restarts)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
