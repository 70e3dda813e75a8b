"""Compare mode's retargets off the GUI thread: a queue of (target, method) jobs one worker thread
works through. The GUI replaces what is pending at any time (``submit``); a running job nothing asks
for any more is cancelled between chunks (``retarget.progress``), never thrown away after the fact."""

from __future__ import annotations

import threading

from PySide6.QtCore import QObject, Signal

from s2h_viewer.errors import S2HError
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.retarget.compare_state import ResultKey
from s2h_viewer.retarget.comparison import compute_result, source_semantics
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.retarget.progress import Cancelled, report, reporting, stage

Job = tuple[ResultKey, Motion, HandModel, HandModel]  # key, motion, source, target (the key names the method)


class RetargetQueue(QObject):
    """Signals arrive on the GUI thread (queued): results, progress of the running job, cancels, failures."""

    semantics_ready = Signal(object, object)  # (motion id, source id), (source pose, source ASM)
    result_ready = Signal(object, object)  # ResultKey, MethodResult
    progress = Signal(float, str)  # fraction of the running job, what it is
    job_cancelled = Signal(object)  # ResultKey
    failed = Signal(object, str)  # ResultKey, one-line message
    idle = Signal()

    def __init__(self, parent: QObject | None = None):
        super().__init__(parent)
        self._lock = threading.Lock()
        self._pending: list[Job] = []
        self._current: ResultKey | None = None
        self._cancel = threading.Event()
        self._thread: threading.Thread | None = None
        #: the last clip's source semantics, (motion, source, (pose, ASM)): matched by the objects themselves, so that
        #: a later clip given a freed one's id is never served its semantics
        self._semantics: tuple | None = None
        self.computed: list[ResultKey] = []  # every job that ran to the end, in order (what tests check)

    @property
    def busy(self) -> bool:
        with self._lock:
            return self._thread is not None

    def pending(self) -> list[ResultKey]:
        """The running job's key first, then the queued ones."""
        with self._lock:
            return ([self._current] if self._current is not None else []) + [job[0] for job in self._pending]

    def submit(self, jobs: list[Job]) -> None:
        """Make ``jobs`` the work to do: queue the new ones, drop queued ones not in it, cancel the running
        one if it is not in it. A running job cancelled already (a Cancel, then Redo at once) stops all the
        same, so it is queued again: it would never finish otherwise."""
        keys = {job[0] for job in jobs}
        with self._lock:
            if self._current is not None and self._current not in keys:
                self._cancel.set()
            running_on = None if self._cancel.is_set() else self._current
            self._pending = [job for job in jobs if job[0] != running_on]
            if self._pending and self._thread is None:
                self._thread = threading.Thread(target=self._work, name="retargets", daemon=True)
                self._thread.start()

    def cancel_all(self) -> None:
        self.submit([])

    def wait(self) -> None:
        """Block until the worker stops (closing the window)."""
        thread = self._thread
        if thread is not None:
            thread.join()

    def _work(self) -> None:
        while True:
            with self._lock:
                if not self._pending:
                    self._thread = None
                    break
                key, motion, source, target = self._pending.pop(0)
                self._current = key
                self._cancel.clear()
            what = f"{METHODS[key.method].label if key.method in METHODS else key.method} -> {target.name}"

            def hook(fraction: float, part: str, job: str = what) -> None:
                if self._cancel.is_set():
                    raise Cancelled()
                self.progress.emit(fraction, job if part == job else f"{job}: {part}")  # which retarget, always

            try:
                with reporting(hook), stage(0.0, 1.0, what):
                    report(0.0)
                    held = self._semantics
                    if held is None or held[0] is not motion or held[1] is not source:
                        held = self._semantics = (motion, source, source_semantics(motion, source))
                        self.semantics_ready.emit((key.motion, key.source), held[2])
                    result = compute_result(motion, source, held[2][1], target, key.method)
                    report(1.0)
                self.computed.append(key)
                outcome = (self.result_ready, key, result)
            except Cancelled:
                outcome = (self.job_cancelled, key)
            except (S2HError, KeyError, ValueError, OSError, RuntimeError) as exc:  # RuntimeError: torch's
                outcome = (self.failed, key, str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc))
            with self._lock:  # the job is over before anyone hears how it ended
                self._current = None
            signal, *args = outcome
            signal.emit(*args)
        self.idle.emit()
