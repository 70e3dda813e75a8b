"""File > Open batch: a batch's summary as a table (`widgets.batch_table`) in a dock under the grid (drag it
out to float it, close it with its button), and a row double-clicked there
shown in Compare: a row of another clip as a comparison of its own (that clip, its target and its method alone), a
row of the clip shown added to the grid (its target, its method ticked), then that retarget selected at its worst
frame once the grid shows it. The table follows its summary: a batch run again (or more of it) while the
viewer is open is listed as it is written."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QFileSystemWatcher, QObject, Qt, QTimer
from PySide6.QtWidgets import QDockWidget

from s2h_viewer.app.opened_clips import OpenedClips
from s2h_viewer.errors import S2HError
from s2h_viewer.hand.model import HandModel
from s2h_viewer.widgets.batch_table import BatchTable


#: milliseconds after a summary changes on disk that the table reads it again (a batch writes it once per run)
RELOAD_AFTER_MS = 500


class BatchBrowser(QObject):
    def __init__(self, window):
        super().__init__(window)
        self.window = window
        self.table: BatchTable | None = None
        self.dock = QDockWidget("Batch", window)
        self.dock.setObjectName("batch_dock")
        self.dock.setAllowedAreas(Qt.DockWidgetArea.BottomDockWidgetArea | Qt.DockWidgetArea.RightDockWidgetArea)
        window.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, self.dock)
        self.dock.hide()
        self._motion_read: tuple[str, str, str] | None = None  # (file, animation, source rig) of the clip shown
        self._motion = None
        self._pending: tuple[HandModel, str, int] | None = None  # (target, method, frame) to select when shown
        self._rows: dict[tuple[int, int, str], dict] = {}  # (id of clip, id of target, method) -> its row shown
        window.comparison_ready.connect(self._select_pending)
        self._watcher = QFileSystemWatcher(self)  # the summary shown, read again when a batch writes it
        self._watcher.fileChanged.connect(lambda path: self._reload.start())
        self._reload = QTimer(self, singleShot=True, interval=RELOAD_AFTER_MS)
        self._reload.timeout.connect(self._read_again)

    def open(self, path: str) -> BatchTable | None:
        from s2h_viewer.batch.summary import read_summary
        try:
            rows = read_summary(path)
        except S2HError as exc:
            self.window.error(str(exc))
            return None
        self._show(path, rows)
        compare = self.window.compare
        result = compare.selected_result() if compare.comparison is not None else None
        shown = self.row_of(compare.state.motion, result) if result is not None else None
        if shown is not None:  # the retarget the grid shows, opened from this batch: its row, not the first
            self.table.select((shown["motion"], shown["target"], shown["method"]))
        self.dock.show()
        self.dock.raise_()
        self.table.table.setFocus()
        return self.table

    def _show(self, path: str, rows: list[dict]) -> None:
        """``rows`` of the summary ``path`` as the table, the row selected before still selected."""
        chosen = self.table.current_row() if self.table is not None else None
        if self.table is not None:
            self.table.deleteLater()
        self.table = BatchTable(path, rows)
        self.table.row_chosen.connect(self.show_row)
        if chosen is not None:
            self.table.select(chosen)
        self.dock.setWidget(self.table)
        self.dock.setWindowTitle(self.table.windowTitle())
        if self._watcher.files():
            self._watcher.removePaths(self._watcher.files())
        self._watcher.addPath(path)

    def _read_again(self) -> None:
        """The summary shown was written again (a batch run again into its folder): its rows, without taking the
        focus; one being written (or gone) keeps the table as it is until it is whole."""
        from s2h_viewer.batch.summary import read_summary
        path = str(self.table.summary) if self.table is not None else ""
        if not path or not Path(path).is_file():
            return
        try:
            rows = read_summary(path)
        except S2HError:
            return
        self._show(path, rows)

    def show_row(self, row: dict) -> None:
        """Show one summary row's retarget in Compare (a failed row: its error, in a dialog)."""
        what = f"{row['motion']} -> {row['target']} ({row['method']})"
        if row.get("status") == "not run":
            self.window.error(f"{what} was not run: the batch was interrupted first. Run the same s2h batch "
                              f"command again to finish it.")
            return
        if row.get("status") != "ok":
            self.window.error(f"{what} failed in the batch: {row.get('error') or 'no error recorded'}")
            return
        from s2h_viewer.retarget.methods import METHODS
        if row["method"] not in METHODS:
            self.window.error(f"{what}: this viewer has no method {row['method']!r}")
            return
        compare = self.window.compare
        try:
            read = (row["motion_path"], row.get("animation") or "", row.get("source_path") or "")
            shown = compare.state.motion
            if not ((self._motion_read == read and shown is self._motion)
                    or self.window.opened_clips.origin(shown) == OpenedClips.origin_of(*read)):
                motion, source = self._read_motion(*read)
            else:  # the clip shown, whether from this summary or opened (or launched) on the same file
                motion = None
            target = self._target(row["target_path"], compare.state.targets)
        except (S2HError, KeyError) as exc:
            self.window.error(str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc))
            return
        frame = int(row["worst_frame"]) if str(row.get("worst_frame", "")).isdigit() else 0
        if motion is not None:  # another clip: a comparison of its own, this row's target and method alone
            if not self.window.confirm_corrections(f"opening {row['motion']}"):
                return
            self._pending = (target, row["method"], frame)
            self._motion_read, self._motion = read, motion
            # the next Open motion starts where this clip is, as after opening it by hand (it started in the
            # shipped motions: a fresh-eyes user)
            self.window.settings.setValue("files/motion_dir", str(Path(row["motion_path"]).resolve().parent))
            self._rows[(id(motion), id(target), row["method"])] = row
            compare.replace_comparison(motion, source, [target], [row["method"]])
        else:  # the clip shown: the row's retarget joins the grid, to compare with the others of the clip
            if all(t is not target for t in compare.state.targets):
                target = compare.add_target(target) or target  # perhaps a copy, named apart from the others
            self._pending = (target, row["method"], frame)
            self._rows[(id(compare.state.motion), id(target), row["method"])] = row
            if row["method"] not in compare.state.methods:
                compare.set_methods([*compare.state.methods, row["method"]])
        if not compare.state.missing():
            self._select_pending()

    def row_of(self, motion, result) -> dict | None:
        """The batch row a retarget of ``motion`` shown from the batch came from (its export goes beside its
        output), or None."""
        return self._rows.get((id(motion), id(result.target), result.method))

    def _read_motion(self, path: str, animation: str, source: str):
        """The row's clip read as the batch read it: its animation of the file, on the batch's --source rig."""
        from s2h_viewer.io.files import RigOptions, load_hand_file, load_motion_file
        from s2h_viewer.samples import load_sample_hand
        performer = load_hand_file(source) if source else None
        motion, rig = load_motion_file(path, performer, RigOptions(animation=animation or None))  # digits: an index
        return motion, rig or load_sample_hand(motion.hand_name)

    def _target(self, path: str, targets: list[HandModel]) -> HandModel:
        """The target already in the grid that came from ``path`` (or is the sample of that name), else the hand
        read from it."""
        from s2h_viewer.io.files import load_hand_file
        for hand in targets:
            if (Path(path).suffix and hand.source and Path(hand.source).resolve() == Path(path).resolve()) or \
                    (not Path(path).suffix and hand.name == path):
                return hand
        hand = load_hand_file(path)
        return next((t for t in targets if t.same_as(hand)), hand)

    def _select_pending(self) -> None:
        if self._pending is None:
            return
        target, method, frame = self._pending
        compare = self.window.compare
        if all(t is not target for t in compare.state.targets) or method not in compare.state.methods:
            self._pending = None  # the user changed the grid meanwhile (cancelled, removed): nothing to select
            return
        key = compare.state.key(target, method)
        if key not in compare.state.results:
            return  # not computed yet: the next comparison_ready
        self._pending = None
        compare.select(key)
        compare.timeline.set_frame(min(frame, compare.timeline.n_frames - 1))
        self.window.statusBar().showMessage(f"{method} -> {target.name}: frame {frame}, the batch's worst", 8000)
