"""The batch's tasks on Dask distributed, the only module of the project that imports Dask.

Default: a `LocalCluster` on this machine (one worker process per core, one thread each, no dashboard,
listening on 127.0.0.1); or a running cluster's scheduler address (its workers must have s2h-viewer
installed). A task whose worker dies (killed, out of memory) is rerun on another by the scheduler, at most
`ALLOWED_FAILURES` times, then reported failed. Each task is submitted as paths, never arrays: the workers
read (and cache) the files themselves.
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import dask
from distributed import Client, LocalCluster, as_completed
from distributed.comm import parse_address
from distributed.comm.addressing import parse_host_port
from distributed.scheduler import KilledWorker

from s2h_viewer.batch.plan import BatchUsageError, Task
from s2h_viewer.batch.task import base_row, run_task

#: worker deaths a task survives before it is reported (so at most 3 attempts)
ALLOWED_FAILURES = 2
#: seconds a scheduler address has to accept and say its handshake (`_check_scheduler_address`); a handshake's
#: first frame is a few hundred bytes, never this many
SCHEDULER_ANSWER_S, MAX_HANDSHAKE_BYTES = 5.0, 1 << 20

#: the nanny sets MALLOC_TRIM_THRESHOLD_=65536 in its workers, which nearly doubled numpy's CPU on this
#: kind of work (issue 23): left unset, glibc's own threshold applies. Off-screen pictures render in one
#: thread per worker (Mesa's llvmpipe takes every core otherwise): a worker per core, each on one thread
_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
           "distributed.nanny.pre-spawn-environ.LP_NUM_THREADS": 1,
           "distributed.scheduler.allowed-failures": ALLOWED_FAILURES,
           # the workers' sampling profiler (a stack every 10 ms, for a dashboard we do not run) competes with
           # each task for the GIL
           "distributed.worker.profile.enabled": False,
           # each worker holds its next task while it runs one, so no task waits on a round trip to the scheduler
           "distributed.scheduler.worker-saturation": 2.0,
           "distributed.worker.daemon": False}


@contextmanager
def batch_client(scheduler: str | None = None, workers: int | None = None) -> Iterator[Client]:
    """A client on ``scheduler``, else on a `LocalCluster` of ``workers`` processes (default: one per core),
    closed (cluster and workers stopped) on leaving, Ctrl+C included."""
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.CRITICAL)  # its chatter as a cluster stops after a Ctrl+C: the bar says enough
    try:
        with dask.config.set(_CONFIG):
            if scheduler:
                try:
                    _check_scheduler_address(scheduler)
                    client = Client(scheduler, timeout="20s")
                except (OSError, TimeoutError, ValueError, MemoryError) as exc:
                    what = f"no Dask scheduler there: {exc}" if isinstance(exc, NotASchedulerError) else \
                        f"cannot reach a Dask scheduler there ({type(exc).__name__}: {exc})"
                    raise BatchUsageError(f"--scheduler {scheduler}: {' '.join(what.split())}") from None
                with client:
                    yield client
                return
            with local_cluster(workers) as cluster, Client(cluster) as client:
                yield client
    finally:
        logger.setLevel(level)


class NotASchedulerError(OSError):
    """A scheduler address that cannot be one (`_check_scheduler_address`), said in the words of its message."""


def _check_scheduler_address(scheduler: str) -> None:
    """Raise at once where a TCP scheduler address cannot be a scheduler's: nothing listens there, no such host, no
    port number, or what listens says nothing a scheduler would (a web page: the dashboard's port) or garbage.
    Dask's client retries a refused connection for its whole timeout (a mistyped port kept the user waiting 20 s),
    waits for ever on a server that does not speak first, and a proxy's bytes read as a frame length made it ask
    for 3 EiB. A scheduler speaks first: its handshake, an 8-byte frame length then the frames."""
    protocol, location = parse_address(scheduler)
    if protocol not in ("tcp", "tls"):
        return
    try:
        host, port = parse_host_port(location)
    except ValueError:
        raise NotASchedulerError(f"{location!r} is not host:port" + (
            "" if ":" in location else f" (a scheduler listens on 8786 by default: tcp://{location}:8786)")) from None
    try:
        connection = socket.create_connection((host, port), timeout=SCHEDULER_ANSWER_S)
    except ConnectionRefusedError:
        raise NotASchedulerError(f"nothing listens at {host}:{port}") from None
    except socket.gaierror:
        raise NotASchedulerError(f"no host named {host}") from None
    except OSError:  # unreachable or slow to answer: the client's own wait says so
        return
    with connection:
        if protocol == "tls":  # its first bytes are the TLS handshake's, not Dask's
            return
        try:
            head = connection.recv(8, socket.MSG_WAITALL)
        except OSError:  # timed out: it waits to be spoken to
            head = b""
    if len(head) < 8:
        raise NotASchedulerError(f"what listens at {host}:{port} says nothing a scheduler would (its dashboard, a "
                                 "web page?); a scheduler's address is the one it prints as 'Scheduler at', "
                                 "tcp://HOST:8786 by default")
    if not 0 < int.from_bytes(head, "little") < MAX_HANDSHAKE_BYTES:
        raise NotASchedulerError(f"what listens at {host}:{port} answers, but not as a scheduler does (its first "
                                 f"bytes: {head!r})")


@contextmanager
def local_cluster(workers: int | None = None, preload: tuple[str, ...] = ()) -> Iterator[LocalCluster]:
    """This machine's cluster as a batch wants it: ``workers`` processes (default one per core) of one thread,
    on 127.0.0.1, no dashboard, worker deaths bounded (`ALLOWED_FAILURES`), glibc's own malloc trimming, deaf
    to Ctrl+C (`worker_setup`); ``preload``: more modules or files each worker runs as it starts. A Ctrl+C
    while the workers start is held until they are up, then stops them."""
    with dask.config.set(_CONFIG):
        with _sigint_held() as caught:
            cluster = LocalCluster(
                n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                dashboard_address=None, host="127.0.0.1", scheduler_port=0, silence_logs=logging.CRITICAL,
                scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},  # its health routes: any free port
                preload=["s2h_viewer.batch.worker_setup", *preload])
        with cluster:
            if caught:
                raise KeyboardInterrupt
            yield cluster


@contextmanager
def _sigint_held() -> Iterator[list]:
    """Ctrl+C in the block is noted (the list it yields gets an entry), not raised: a cluster interrupted half
    built would leave its workers running. Only where Python can set handlers (the main thread)."""
    caught: list = []
    if threading.current_thread() is not threading.main_thread():
        yield caught
        return
    previous = signal.signal(signal.SIGINT, lambda *_: caught.append(True))
    try:
        yield caught
    finally:
        signal.signal(signal.SIGINT, previous)


def warm_up() -> None:
    """What every worker's first task would pay: the imports (torch, the methods, the readers and writers),
    the off-screen render context (a second of its own the first time) and the networks."""
    import pyvista as pv

    import s2h_viewer.io.files  # noqa: F401
    import s2h_viewer.render.offscreen  # noqa: F401
    import s2h_viewer.semantics.flexion  # noqa: F401
    from s2h_viewer.retarget.asrn.inference import MODELS_DIR, load_network

    for name in ("asrn", "dm"):
        load_network(str(MODELS_DIR / f"{name}.pt"))
    plotter = pv.Plotter(off_screen=True, window_size=(64, 64))
    plotter.add_mesh(pv.Sphere())
    plotter.screenshot(None)
    plotter.close()


def worker_count(client: Client) -> int:
    return max(1, sum(client.nthreads().values()))


def run_tasks(client: Client, tasks: list[Task], on_row: Callable[[dict], None],
              on_start: Callable[[int], None] | None = None) -> None:
    """Run ``tasks`` on ``client``'s cluster; ``on_row`` gets each task's row as it finishes (any order).
    Pure functions of their paths: each task is submitted once under its own key (``pure=False``)."""
    if not tasks:
        return
    client.run(warm_up)  # every worker at once: the first task's seconds then measure the task alone
    futures = {client.submit(run_task, task, pure=False, key=f"s2h-{task.key}-{i}"): task
               for i, task in enumerate(tasks)}
    if on_start:
        on_start(worker_count(client))
    try:
        for future in as_completed(futures):
            task = futures[future]
            try:
                row = future.result()
            except KilledWorker:
                row = base_row(task) | {"status": "failed", "error": f"the worker running it died "
                                                                     f"{ALLOWED_FAILURES + 1} times (a crash or "
                                                                     f"out of memory)"}
            except Exception as exc:  # the task itself never raises (run_task): this is the cluster's
                row = base_row(task) | {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
            on_row(row)
    finally:
        client.cancel(list(futures), force=True)
