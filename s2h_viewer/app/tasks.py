"""Long work off the GUI thread: one job at a time in a QThread behind a progress strip, which hears
the job's reports (`retarget.progress`)."""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import QObject, QThread, Signal
from PySide6.QtWidgets import QWidget

from s2h_viewer.app.job_progress import JobProgress
from s2h_viewer.errors import S2HError
from s2h_viewer.retarget.progress import reporting

#: steps of the progress strip's bar
DIALOG_STEPS = 1000


class Task(QObject):
    """Runs ``fn()`` in a QThread; signals its reports (fraction, what), the result, or the error's one-line
    message."""

    progress = Signal(float, str)
    finished = Signal(object)
    failed = Signal(str)

    def __init__(self, fn: Callable[[], object]):
        super().__init__()
        self.fn = fn

    def run(self) -> None:
        try:
            with reporting(self.progress.emit):
                result = self.fn()
            self.finished.emit(result)
        except (S2HError, KeyError, ValueError) as exc:
            self.failed.emit(str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc))


class TaskRunner(QObject):
    """Starts a job with ``start``; its result goes to ``on_done`` on the GUI thread, its error to ``on_error``."""

    def __init__(self, parent: QWidget, on_error: Callable[[str], None], on_status: Callable[[str], None]):
        super().__init__(parent)
        self._parent, self._on_error, self._on_status = parent, on_error, on_status
        self._thread: QThread | None = None
        self._progress: JobProgress | None = None
        self._task: Task | None = None
        self._on_done: Callable[[object], None] | None = None

    @property
    def busy(self) -> bool:
        return self._thread is not None

    def start(self, fn: Callable[[], object], label: str, on_done: Callable[[object], None]) -> None:
        """Run ``fn()`` off the GUI thread behind a progress strip that follows its reports; errors become an
        error dialog."""
        if self._thread is not None:
            return
        self._thread = QThread(self)
        task = Task(fn)
        task.moveToThread(self._thread)
        self._thread.started.connect(task.run)
        self._progress = JobProgress(label, None, DIALOG_STEPS, self._parent, "s2h-viewer")
        task.progress.connect(self._on_progress)
        self._on_done = on_done
        task.finished.connect(self._on_task_done)  # a bound slot of a GUI-thread object: runs on the GUI thread
        task.failed.connect(self._on_failure)
        self._task = task  # held: Qt would otherwise lose the Python object while it runs
        self._thread.start()

    def finish(self) -> None:
        """Close the progress strip and wait for the thread (on completion, failure or window close)."""
        if self._progress is not None:
            self._progress.close()
            self._progress.deleteLater()
            self._progress = None
        if self._thread is not None:
            self._thread.quit()
            self._thread.wait()
            self._thread = None

    def _on_task_done(self, result: object) -> None:
        self.finish()
        self._on_done(result)

    def _on_progress(self, fraction: float, what: str) -> None:
        if self._progress is not None:
            self._progress.setValue(round(fraction * DIALOG_STEPS))
            self._progress.setLabelText(what)
        self._on_status(f"{fraction:.0%}: {what}")

    def _on_failure(self, message: str) -> None:
        self.finish()
        self._on_error(message)
