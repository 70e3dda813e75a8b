"""File > Open batch in the real window: a batch's summary as a table, worst first; a double-clicked row shown in
Compare (its clip, target and method) at its worst frame; a failed row says why."""

from __future__ import annotations

from pathlib import Path

import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QFileDialog, QLineEdit, QMessageBox

from compare_window import open_compare_window, when_shown
from test_annotate_window import keyboard_to
from s2h_viewer.batch.plan import TaskOptions, plan_batch
from s2h_viewer.batch.summary import write_summary
from s2h_viewer.batch.task import run_task
from s2h_viewer.retarget import METHODS
from s2h_viewer.samples import ASSETS_DIR

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


@pytest.fixture(scope="module")
def summary(tmp_path_factory) -> Path:
    """A real batch's summary (its tasks run in this process): counting onto laurel, two methods, and a
    target that cannot be read."""
    out = tmp_path_factory.mktemp("batch")
    broken = out / "broken.glb"
    broken.write_text("not a glb")
    tasks = plan_batch([str(ASSETS_DIR / "motions" / "counting.npz")], ["laurel", str(broken)],
                       ["tbs_copy", "dm"], out, TaskOptions(format="npz", render=False), tuple(METHODS))
    return write_summary([run_task(t) for t in tasks], out / "summary.csv")


def test_a_double_clicked_row_is_shown_in_compare_at_its_worst_frame(qtbot, sample_hands, tmp_path, summary,
                                                                     monkeypatch):
    win = open_compare_window(qtbot, sample_hands, tmp_path)
    open_action = next(a for a in win.menuBar().actions()[0].menu().actions() if a.text().startswith("Open batch"))
    assert open_action.shortcut().toString() == "Ctrl+B"

    def choose_summary(dialog: QFileDialog) -> None:
        dialog.findChild(QLineEdit, "fileNameEdit").setText(str(summary))
        dialog.accept()

    when_shown(QFileDialog, choose_summary)
    open_action.trigger()  # File > Open batch summary..., the file typed into its dialog
    table = win.batch_browser.table
    qtbot.waitExposed(table)
    rows = table.rows
    assert [r["status"] for r in rows] == ["failed", "failed", "ok", "ok"]  # worst first: failures, then kept
    assert (rows[2]["kept"], rows[2]["s_finger"]) <= (rows[3]["kept"], rows[3]["s_finger"])
    reopen = win.recent_menu.actions()[0]  # the summary is a recent file, named by its batch's folder
    assert win.recent_menu.isEnabled() and reopen.text() == f"{summary.parent.name}/summary.csv (batch)"
    win.batch_browser.dock.close()
    reopen.trigger()
    assert win.batch_browser.dock.isVisible()
    assert [(r["motion"], r["target"], r["method"]) for r in win.batch_browser.table.rows] == [
        (r["motion"], r["target"], r["method"]) for r in rows]
    table = win.batch_browser.table
    rows = table.rows

    shown = []
    monkeypatch.setattr(QMessageBox, "critical", lambda *args: shown.append(args[2]))
    view = table.table
    view.sortItems(0)  # sorted by a heading: a row still opens its own task

    def double_click(row: int) -> None:
        where = view.visualItemRect(view.item(row, 0)).center()
        qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, pos=where)  # a double click's first press
        qtbot.mouseDClick(view.viewport(), Qt.MouseButton.LeftButton, pos=where)

    double_click(next(r for r in range(view.rowCount()) if view.item(r, 3).text() == "failed"))
    assert shown and "failed in the batch" in shown[-1] and "broken.glb" in shown[-1]

    remembered = win.settings.value("compare/methods")
    chosen = next(r for r in range(view.rowCount()) if view.item(r, 2).text() == "dm"
                  and view.item(r, 3).text() == "ok")
    wanted = table.rows[view.item(chosen, 0).data(Qt.ItemDataRole.UserRole)]
    with qtbot.waitSignal(win.comparison_ready, timeout=120_000):
        double_click(chosen)
    qtbot.waitUntil(lambda: win.compare.selected_result().method == "dm", timeout=30_000)
    selected = win.compare.selected_result()
    assert selected.target.name == "laurel" and win.compare.state.motion.name == "counting"
    assert win.timeline.frame == wanted["worst_frame"]
    assert len(shown) == 1
    # another clip than the grid's: a comparison of its own, the row's target and method alone (the grid's iris
    # and its two methods had stayed, computed onto the new clip for nothing)
    assert [t.name for t in win.compare.state.targets] == ["laurel"] and win.compare.state.methods == ["dm"]
    ok = next(r for r in range(view.rowCount()) if view.item(r, 2).text() == "tbs_copy"
              and view.item(r, 3).text() == "ok")
    with qtbot.waitSignal(win.comparison_ready, timeout=120_000):
        double_click(ok)  # the same clip: its retarget joins the grid
    assert win.compare.state.methods == ["tbs_copy", "dm"] and len(win.compare.state.targets) == 1
    qtbot.waitUntil(lambda: win.compare.selected_result().method == "tbs_copy", timeout=30_000)
    win.batch_browser.table.table.selectRow(0)  # a row looked at, not opened
    win.open_batch(str(summary))  # opened again: the row of the retarget shown is the one selected, not the first
    assert win.batch_browser.table.current_row() == ("counting", "laurel", "tbs_copy")
    assert Path(str(win.settings.value("files/motion_dir"))) == Path(wanted["motion_path"]).resolve().parent
    # the rows' methods are not the user's choice: the next session starts with the methods the user chose
    assert win.settings.value("compare/methods") == remembered and remembered != ["tbs_copy", "dm"]


def test_a_row_of_one_animation_of_a_file_shows_that_animation(qtbot, sample_hands, tmp_path):
    """A batch takes each animation of a file as its own motion: its row opens that animation, not the file's
    first."""
    from s2h_viewer.io.files import load_hand_file
    from s2h_viewer.io.gltf import save_gltf_motion
    from s2h_viewer.motions.synthesis import synthesize
    from s2h_viewer.retarget import retarget

    hand = load_hand_file(ASSETS_DIR / "hands" / "real" / "godot_hand_r.gltf")
    birch = sample_hands["birch"]
    clips = [retarget(synthesize(gestures, birch, seed=1, name=name), birch, hand, "tbs_copy")
             for name, gestures in (("grip", ["fist"]), ("sign", ["v_sign", "ok"]))]
    one = save_gltf_motion(tmp_path / "one.glb", clips[0], hand)
    two = save_gltf_motion(tmp_path / "two.glb", clips[1], load_hand_file(one))  # grip, then sign
    tasks = plan_batch([str(two)], ["laurel"], ["tbs_copy"], tmp_path / "out", TaskOptions(format="npz",
                                                                                          render=False))
    assert [t.motion.name for t in tasks] == ["two.grip", "two.sign"]
    summary = write_summary([run_task(t) for t in tasks], tmp_path / "out" / "summary.csv")
    win = open_compare_window(qtbot, sample_hands, tmp_path)
    table = win.batch_browser.open(str(summary))
    row = next(r for r in table.rows if r["motion"] == "two.sign")
    with qtbot.waitSignal(win.comparison_ready, timeout=120_000):
        win.batch_browser.show_row(row)
    assert win.compare.state.motion.name == "sign" and win.compare.state.motion.n_frames == clips[1].n_frames
    offered = []  # File > Export retargeted motion offers the batch's own folder and name, not the working folder

    def look(dialog: QFileDialog) -> None:
        offered.append(Path(dialog.directory().absolutePath()) / dialog.findChild(QLineEdit, "fileNameEdit").text())
        dialog.reject()
    when_shown(QFileDialog, look)
    assert win.export_motion() is None
    assert offered == [tmp_path / "out" / "two.sign" / "laurel" / "tbs_copy.npz"]


def test_letters_typed_in_the_batch_table_find_a_row_and_fire_no_shortcut(qtbot, sample_hands, tmp_path, summary,
                                                                         monkeypatch):
    """A fresh-eyes user typed a motion's name in the batch table to find its row: O marked a range out, R turned
    the fixing ring's axis. Letters typed there go to the table's search; Ctrl shortcuts still work."""
    from PySide6.QtTest import QTest

    win = open_compare_window(qtbot, sample_hands, tmp_path)
    table = win.batch_browser.open(str(summary))
    qtbot.waitExposed(table)
    view = table.table
    keyboard_to(qtbot, view)
    marked = win.timeline.marked
    view.setCurrentCell(view.rowCount() - 1, 1)  # the target column: "laurel" rows and "broken" rows
    QTest.keyClicks(view, "bro")  # b, r, o: none is a shortcut here
    assert win.timeline.marked == marked
    assert view.item(view.currentRow(), 1).text() == "broken"
    QTest.keyClick(view, Qt.Key.Key_M, Qt.KeyboardModifier.ControlModifier)  # a Ctrl shortcut: still the window's
    assert win.view.solo >= 0
    # Return opens the row in the table, and only there: in the frame box it went back to the row's worst frame
    chosen = []
    table.row_chosen.connect(chosen.append)
    spin = win.timeline.spin
    keyboard_to(qtbot, spin)
    spin.selectAll()
    QTest.keyClicks(spin, "5")
    QTest.keyClick(spin, Qt.Key.Key_Return)
    assert win.timeline.frame == 5 and chosen == []
    monkeypatch.setattr(QMessageBox, "critical", lambda *args: None)  # the broken row: "failed in the batch"
    keyboard_to(qtbot, view)
    QTest.keyClick(view, Qt.Key.Key_Return)
    assert [row["target"] for row in chosen] == ["broken"]


def test_a_row_of_the_clip_launched_joins_its_grid(qtbot, sample_hands, tmp_path):
    """A fresh-eyes user launched the viewer on gestures.npz, ran a batch of that file and double-clicked a row:
    the whole grid gave way to that one retarget (only a clip opened from the summary counted as the one shown).
    A row of the file the grid shows, read the same way, joins it: its target added, its method ticked."""
    from compare_window import open_window, short_clip
    from s2h_viewer.app.main_window import CompareSetup
    from s2h_viewer.io.files import load_motion_file
    from s2h_viewer.io.npz import save_motion
    clip = save_motion(short_clip(sample_hands["birch"]), tmp_path / "short.npz")
    tasks = plan_batch([str(clip)], ["laurel"], ["copy"], tmp_path / "out", TaskOptions(format="npz", render=False))
    summary = write_summary([run_task(t) for t in tasks], tmp_path / "out" / "summary.csv")
    motion = load_motion_file(clip)[0]
    setup = CompareSetup(motion, sample_hands["birch"], [sample_hands["iris"]], ["tbs_copy"], path=clip)
    win = open_window(qtbot, setup, tmp_path)
    (row,) = win.batch_browser.open(str(summary)).rows
    with qtbot.waitSignal(win.comparison_ready, timeout=120_000):
        win.batch_browser.show_row(row)
    assert win.compare.state.motion is motion
    assert [t.name for t in win.compare.state.targets] == ["iris", "laurel"]
    assert set(win.compare.state.methods) == {"tbs_copy", "copy"}
    qtbot.waitUntil(lambda: win.compare.selected_result().method == "copy", timeout=30_000)
    assert win.compare.selected_result().target.name == "laurel"


def test_a_finger_bent_sideways_is_red_in_the_batch_table_as_in_the_scores_table(qtbot, tmp_path):
    """TBS Copy of the authored poses onto the VRM robot bends the pinky PIP 59 deg sideways (the source: 38): red,
    with the scores table's words, in the table of a batch, which showed a bare 59.0; the thumb's figure beside it."""
    from PySide6.QtGui import QColor

    from s2h_viewer.batch.summary import read_summary
    from s2h_viewer.widgets.batch_table import COLUMNS, BatchTable
    from s2h_viewer.widgets.scores_table import SIDEWAYS_RED

    real = ASSETS_DIR / "motions" / "real"
    tasks = plan_batch([str(real / "godot_hand_poses_r.gltf"), str(ASSETS_DIR / "motions" / "counting.npz")],
                       [str(ASSETS_DIR / "hands" / "real" / "debug_robot.vrm")], ["tbs_copy"], tmp_path,
                       TaskOptions(format="npz", render=False, side="right", animation="all",
                                   source=str(real / "godot_hand_r_posed_rig.gltf")), tuple(METHODS))
    tasks += plan_batch([str(ASSETS_DIR / "motions" / "gestures.npz")],  # its claw's thumb brought across the palm
                        [str(ASSETS_DIR / "hands" / "real" / "debug_robot.vrm")], ["asrn"], tmp_path,
                        TaskOptions(format="npz", render=False, side="right"), tuple(METHODS))
    summary = write_summary([run_task(t) for t in tasks], tmp_path / "summary.csv")
    table = BatchTable(summary, read_summary(summary))
    qtbot.addWidget(table)
    sideways, thumb = (next(c for c, (_, key, _) in enumerate(COLUMNS) if key == name)
                       for name in ("sideways_deg", "thumb_follow"))
    cells = {table.table.item(r, 0).text(): table.table.item(r, sideways) for r in range(table.table.rowCount())}
    bent, counting = cells["godot_hand_poses_r"], cells["counting"]
    assert float(bent.text()) > 45 and bent.foreground().color() == QColor(SIDEWAYS_RED)
    assert "the source bends 38 there" in bent.toolTip() and "(Sign 3)" in bent.toolTip()
    assert counting.foreground().color() != QColor(SIDEWAYS_RED)  # counting's fingers bend no further than its own
    thumbs = {table.table.item(r, 0).text(): table.table.item(r, thumb) for r in range(table.table.rowCount())}
    assert all(0.0 < float(item.text()) <= 1.0 for item in thumbs.values())
    red = {name for name, item in thumbs.items() if item.foreground().color() == QColor(SIDEWAYS_RED)}
    assert red == {name for name, item in thumbs.items() if float(item.text()) < 0.9} == {"gestures"}
    assert "under 0.9" in thumbs["gestures"].toolTip()
    invented = next(c for c, (_, key, _) in enumerate(COLUMNS) if key == "invented")
    poses = next(r for r in range(table.table.rowCount()) if table.table.item(r, 0).text() == "godot_hand_poses_r")
    assert int(table.table.item(poses, invented).text()) > 0  # fingertips on the palm the source's are not
    assert "with a contact the source does not make: " in table.table.item(poses, invented).toolTip()
    # a heading of one line keeps its text whole beside the sort arrow a click draws ("Sideways" read "ideway")
    header = table.table.horizontalHeader()
    for column, (heading, _, _) in enumerate(COLUMNS[:-1]):
        table.table.sortItems(column)
        if "\n" not in heading:
            assert table.table.columnWidth(column) >= header.sectionSizeHint(column), heading


def test_a_row_of_a_shorter_clip_opens_from_a_frame_past_its_end(qtbot, sample_hands, tmp_path, summary):
    """A fresh-eyes user at frame 480 of the 692 poses, the second of two retargets selected, opened a row of the
    378-frame gestures clip: the scores table's row moved to the new grid's one retarget and drew it at frame 480
    (an IndexError in the log) before the timeline took the new clip's length."""
    win = open_compare_window(qtbot, sample_hands, tmp_path, methods=("tbs_copy",), targets=("iris", "laurel"),
                              repeats=2)
    table = win.batch_browser.open(str(summary))  # counting: 237 frames
    qtbot.waitExposed(table)
    frames = win.compare.comparison.n_frames
    assert frames > 237
    win.compare.select(win.compare.shown_keys()[1])
    win.timeline.set_frame(frames - 1)
    chosen = next(r for r in table.rows if r["method"] == "dm" and r["status"] == "ok")
    with qtbot.waitSignal(win.comparison_ready, timeout=120_000):
        table.row_chosen.emit(chosen)
    assert win.compare.comparison.n_frames == 237 and win.timeline.frame == chosen["worst_frame"]


def test_the_batch_table_follows_its_summary_as_a_batch_writes_it_again(qtbot, sample_hands, tmp_path, summary):
    """A fresh-eyes user ran the batch again with one more method while the viewer showed it: the table still said
    20 tasks until they opened it once more. It reads the summary again when it is written, keeping the row
    selected and leaving the keyboard where it was."""
    import shutil

    from s2h_viewer.batch.summary import read_summary

    copy = Path(shutil.copy(summary, tmp_path / "summary.csv"))
    win = open_compare_window(qtbot, sample_hands, tmp_path)
    table = win.batch_browser.open(str(copy))
    qtbot.waitExposed(table)
    rows = read_summary(copy)
    ok = next(r for r in range(table.table.rowCount()) if table.table.item(r, 3).text() == "ok")
    table.table.selectRow(ok)
    selected = table.current_row()
    keyboard_to(qtbot, win.timeline.spin)
    more = plan_batch([str(ASSETS_DIR / "motions" / "counting.npz")], ["laurel"], ["copy"], tmp_path,
                      TaskOptions(format="npz", render=False), tuple(METHODS))
    write_summary(rows + [run_task(t) for t in more], copy)  # as a batch writes it: a new file renamed over it
    qtbot.waitUntil(lambda: win.batch_browser.table.table.rowCount() == len(rows) + 1, timeout=10_000)
    again = win.batch_browser.table
    assert "copy" in [r["method"] for r in again.rows] and f"({len(rows) + 1} tasks" in win.batch_browser.dock.windowTitle()
    assert again.current_row() == selected and win.timeline.spin.hasFocus()
    write_summary(rows, copy)  # and again: the watch holds after a file renamed over the one it watched
    qtbot.waitUntil(lambda: win.batch_browser.table.table.rowCount() == len(rows), timeout=10_000)
