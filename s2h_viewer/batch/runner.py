"""`s2h batch`: plan, skip what an earlier run finished, run the rest on the cluster with a progress bar
(done / failed / running, ETA), then write ``summary.csv`` and ``report.html``: this batch's rows, then those
other batches left in the folder.

Exit status: 0 when every task is ok, 1 when some failed (the summary says which), 2 for a usage error
(raised as `BatchUsageError` before anything runs), 130 after Ctrl+C (the cluster stopped, the finished
tasks kept, the others "not run", no half-written file left: outputs are renamed into place whole, and the
temporary files of interrupted writes are removed).
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from tqdm import tqdm

from s2h_viewer.batch.plan import Task, TaskOptions, plan_batch
from s2h_viewer.batch.report import write_report
from s2h_viewer.batch.summary import read_row_json, write_summary
from s2h_viewer.batch.task import base_row
from s2h_viewer.io.annotation import SIDES, sidecar_path
from s2h_viewer.io.atomic import remove_stale_temps


@dataclass(frozen=True)
class BatchConfig:
    motions: list[str]
    targets: list[str]
    methods: list[str]
    out: str
    options: TaskOptions = TaskOptions()
    scheduler: str | None = None  # a running Dask scheduler's address; None: a LocalCluster here
    workers: int | None = None  # LocalCluster processes (default: one per core)


@dataclass
class BatchResult:
    rows: list[dict]  # one per task, in the plan's order
    skipped: int  # finished by an earlier run
    seconds: float
    summary: Path
    report: Path
    interrupted: bool = False
    failed: list[dict] = field(default_factory=list)  # status failed (tasks an interrupt left are "not run")
    startup_seconds: float = 0.0  # planning, the cluster's start and its workers' imports, before the first task
    earlier: int = 0  # rows of other batches into the same folder, listed in its summary after this batch's
    rigs: list[str] = field(default_factory=list)  # files of the motion folders with no animation, left out
    #: tasks an earlier run finished ok with other inputs or options (another --source, a changed file), done
    #: again over its files: a fresh-eyes user's result made with a --source was replaced and nothing said so
    redone: int = 0

    @property
    def exit_code(self) -> int:
        return 130 if self.interrupted else (1 if self.failed else 0)


def run_batch(config: BatchConfig, show_progress: bool | None = None) -> BatchResult:
    """Run a batch (see the module docstring); ``show_progress`` None: a bar when stderr is a terminal."""
    from s2h_viewer.retarget import METHODS  # registers every method, to check the names before any work

    start = time.perf_counter()
    rigs: list[str] = []
    tasks = plan_batch(config.motions, config.targets, config.methods, config.out, config.options, tuple(METHODS),
                       rigs)
    rows: dict[int, dict] = {}
    for i, task in enumerate(tasks):
        earlier = task.finished_row()
        if earlier is not None:
            rows[i] = earlier
    skipped = len(rows)
    todo = [i for i in range(len(tasks)) if i not in rows]
    redone = sum((read_row_json(tasks[i].row_file) or {}).get("status") == "ok" for i in todo)
    index = {(tasks[i].motion.name, tasks[i].target.name, tasks[i].method): i for i in todo}
    interrupted = False
    # no terminal (a log, a pipe): a line per finished task instead of the bar (a user saw no progress at all)
    lines = show_progress is None and not sys.stderr.isatty()
    with tqdm(total=len(tasks), initial=skipped, desc="batch", unit="task", file=sys.stderr,
              disable=(not sys.stderr.isatty()) if show_progress is None else not show_progress) as bar:
        counts = {"ok": sum(r["status"] == "ok" for r in rows.values()),  # those done before count as the summary
                  "failed": sum(r["status"] == "failed" for r in rows.values()), "running": 0}  # does: both
        workers, started_at = [0], [start]

        def show() -> None:
            counts["running"] = min(workers[0], len(tasks) - len(rows))
            bar.set_postfix_str(f"ok {counts['ok']}, failed {counts['failed']}, running {counts['running']}"
                                + (f", {skipped} done before" if skipped else ""), refresh=False)

        def started(n_workers: int) -> None:
            workers[0] = n_workers
            started_at[0] = time.perf_counter()
            show()
            bar.refresh()

        def finished(row: dict) -> None:
            i = index[(row["motion"], row["target"], row["method"])]
            rows[i] = row
            counts["ok" if row["status"] == "ok" else "failed"] += 1
            show()
            bar.update()
            if lines:
                print(f"batch: {len(rows)}/{len(tasks)} {row['motion']} -> {row['target']} ({row['method']}): "
                      f"{row['status']}", file=sys.stderr, flush=True)

        if todo:
            from s2h_viewer.batch.cluster import batch_client, run_tasks

            where = f"connecting to {config.scheduler}" if config.scheduler else \
                f"starting {config.workers or os.cpu_count() or 1} local workers"
            bar.set_postfix_str(f"{where} (imports take a few seconds)", refresh=True)
            try:
                with batch_client(config.scheduler, config.workers) as client:
                    run_tasks(client, [tasks[i] for i in todo], finished, started)
            except KeyboardInterrupt:
                interrupted = True
    if interrupted:
        for i in todo:
            if i not in rows:  # finished while the cluster stopped (its row written whole), or not run
                _remove_partial_files(tasks[i])
                rows[i] = tasks[i].finished_row() or base_row(tasks[i]) | {
                    "status": "not run", "error": "the batch was interrupted (Ctrl+C) first; run it again to finish"}
    ordered_rows = [rows[i] for i in range(len(tasks))]
    out = Path(config.out)
    earlier = earlier_rows(out, {task.row_file.resolve() for task in tasks})
    summary = write_summary(ordered_rows + earlier, out / "summary.csv")
    report = write_report(ordered_rows + earlier, out / "report.html", title=f"s2h batch: {out.resolve().name}")
    return BatchResult(ordered_rows, skipped, time.perf_counter() - start, summary, report, interrupted,
                       [r for r in ordered_rows if r["status"] == "failed"], started_at[0] - start, len(earlier),
                       rigs, redone)


def earlier_rows(out: Path, planned: set[Path]) -> list[dict]:
    """The rows other batches left in ``out`` (other motions, targets or methods), ok with their output still
    there or failed: a second batch into a folder rewrote its summary with its own rows alone, and the first's
    results, still on disk, were listed nowhere."""
    found = []
    for row_file in sorted(out.glob("*/*/*.row.json")):
        if row_file.resolve() in planned:
            continue
        row = read_row_json(row_file)
        if row is None or not all(isinstance(row.get(k), str) for k in ("motion", "target", "method")):
            continue
        if row.get("status") == "failed" or (row.get("status") == "ok" and Path(str(row.get("output"))).is_file()):
            found.append(row)
    return found


def _remove_partial_files(task: Task) -> None:
    """The temporary files a write killed by Ctrl+C left behind (their process is gone by now)."""
    sidecars = [sidecar_path(task.output, side) for side in SIDES]
    for path in (task.output, task.picture, task.sideways_picture, task.row_file, *sidecars):
        if path.parent.exists():
            remove_stale_temps(path)
