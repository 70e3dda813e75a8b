"""The Compare tab's layout from its 1000 x 700 minimum up (issue 25, item 2): every panel whole and apart, the
scores table across the window with its rows in view, the selected retarget framed in the grid, exports at a
chosen size whatever the window's."""

from __future__ import annotations

import os

import numpy as np
import pytest
import pyvista as pv

pytest.importorskip("pytestqt")
if not os.environ.get("DISPLAY"):
    pytest.skip("the Qt viewport needs an X display: `make test` runs the suite under Xvfb", allow_module_level=True)

from PIL import Image  # noqa: E402
from PySide6.QtCore import QRect  # noqa: E402
from PySide6.QtWidgets import QScrollArea  # noqa: E402

from compare_window import open_compare_window  # noqa: E402
from s2h_viewer.app.main_window import FIRST_SIZE, MIN_SIZE, first_size  # noqa: E402
from s2h_viewer.render.caption import BAND, band_within  # noqa: E402
from s2h_viewer.render.compare_scene import SELECTED_COLOUR  # noqa: E402


@pytest.fixture
def window(qtbot, sample_hands, tmp_path):
    return open_compare_window(qtbot, sample_hands, tmp_path, methods=("tbs_copy", "dm"), targets=("iris", "laurel"))


def on_screen(widget) -> QRect:
    return QRect(widget.mapToGlobal(widget.rect().topLeft()), widget.size())


def test_the_window_holds_its_panels_whole_and_apart_at_its_minimum_size(window, qtbot):
    window.resize(700, 450)  # below the minimum: the window stays at it
    qtbot.waitUntil(lambda: (window.width(), window.height()) == MIN_SIZE, timeout=5000)
    compare, table = window.compare, window.scores
    side = compare.heatmap.parentWidget()
    while not isinstance(side, QScrollArea):
        side = side.parentWidget()
    panels = {"grid": window.view, "heatmap": side.viewport(), "table": table, "timeline": compare.timeline,
              "curve": compare.curve}
    rects = {name: on_screen(widget) for name, widget in panels.items()}
    for a in panels:
        for b in panels:
            if a < b:
                assert not rects[a].intersects(rects[b]), (a, b, rects[a], rects[b])
    assert window.view.width() >= 400 and window.view.height() >= 250
    heatmap = compare.heatmap
    assert heatmap.legend.geometry().top() > heatmap.matrix.geometry().bottom()
    assert heatmap.matrix.size() == heatmap.matrix.labels.size()  # never squeezed: it scrolls instead
    assert all(table.rowViewportPosition(r) + table.rowHeight(r) <= table.viewport().height() for r in range(2))
    last = table.columnCount() - 1
    assert table.columnViewportPosition(last) + table.columnWidth(last) <= table.viewport().width()
    assert compare.curve.height() >= compare.curve.minimumHeight()


def test_the_selected_retarget_is_framed_in_the_grid(window):
    view = window.view
    window.scores.selectRow(2)  # TBS Copy -> laurel
    framed = [i for i, hand in enumerate(view._hands[1:]) if hand.border is not None and hand.border.GetVisibility()]
    assert framed == [2] == [view.selected]
    image = view.grab_rgb().astype(int)
    blue = (np.abs(image - np.array(pv.Color(SELECTED_COLOUR).int_rgb)).max(-1) < 10)
    x0, y0, x1, y1 = view._hands[3].renderer.GetViewport()
    height, width = blue.shape
    inside = blue[round((1 - y1) * height):round((1 - y0) * height), round(x0 * width):round(x1 * width)]
    assert inside.sum() > 0.8 * blue.sum() > 200  # the frame is that cell's
    # its label clear of the frame: no dark text pixel within 2 pixels of it (at a pad of 4 the first line touched it)
    cell = image[round((1 - y1) * height):round((1 - y0) * height), round(x0 * width):round(x1 * width)]
    dark = cell.max(-1) < 120
    near_frame = np.zeros_like(inside)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            near_frame |= np.roll(inside, (dy, dx), axis=(0, 1))
    assert dark[:40, :200].sum() > 50  # the label's first line is there
    assert not (dark & near_frame).any(), np.argwhere(dark & near_frame)[:5]
    window.heatmap_choice.setCurrentIndex(0)
    assert [i for i, h in enumerate(view._hands[1:]) if h.border is not None and h.border.GetVisibility()] == [0]


def test_pictures_are_exported_at_the_chosen_size_whatever_the_window(window, tmp_path):
    size = (1280, 720)
    window.export_size_actions[size].trigger()
    assert window.export_size == size and window.settings.value("export/size") == "1280 x 720"
    window.scores.selectRow(1)
    png = window.export_screenshot(str(tmp_path / "sized.png"))
    image = np.asarray(Image.open(png).convert("RGB"))
    assert image.shape[:2] == (size[1], size[0])  # the caption band within: 720 tall, not 748
    blue = (np.abs(image.astype(int) - np.array(pv.Color(SELECTED_COLOUR).int_rgb)).max(-1) < 10).sum()
    assert blue > 200  # the selected retarget framed there too

    def text_rows(picture: np.ndarray) -> int:  # the caption's dark rows, in its band at the bottom
        band = picture[-band_within(picture.shape[0]):]
        return int((band.min(-1) < 100).any(1).sum())
    window.export_size_actions[(1920, 1080)].trigger()
    full_hd = np.asarray(Image.open(window.export_screenshot(str(tmp_path / "full_hd.png"))).convert("RGB"))
    assert full_hd.shape[:2] == (1080, 1920)  # a fresh-eyes user's 1920 x 1080 was 1108 tall
    assert text_rows(full_hd) > text_rows(image) + 2  # and its caption as small as at 720: now larger
    window.export_size_actions[None].trigger()
    png = window.export_screenshot(str(tmp_path / "as_view.png"))
    shown = np.asarray(Image.open(png)).shape[:2]
    assert shown == (window.view.interactor.height() + BAND, window.view.interactor.width())


def test_targets_past_what_fits_page_and_the_selection_turns_the_page(qtbot, sample_hands, tmp_path):
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    four = ("iris", "laurel", "kale", "juniper")
    window = open_compare_window(qtbot, sample_hands, tmp_path, methods=("tbs_copy",), targets=four)
    view = window.view
    assert view.rows == view.rows_fitting() < 4 and view.page_count == -(-4 // view.rows) > 1
    assert view.pager.isVisible() and view.page_label.text().startswith(
        f"targets 1-{view.rows} of 4" if view.rows > 1 else "target 1 of 4")
    assert [r.target.name for r in view.comparison.results] == list(four[:view.rows])
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)
    QTest.keyClick(window, Qt.Key.Key_PageDown, Qt.KeyboardModifier.ControlModifier)
    assert view.page == 1 and view.comparison.results[0].target.name == four[view.rows]
    window.scores.selectRow(3)  # juniper, on the last page
    assert view.page == view.page_count - 1 and view.comparison.results[-1].target.name == "juniper"
    view.set_solo(view.hand_of_result(len(view.comparison.results) - 1))  # alone: no pages to turn, no page bar
    assert not view.pager.isVisible() and window.compare.fixing.bar.isVisible()
    window.heatmap_choice.setCurrentIndex(0)  # iris, on the first page, picked in the drop-down: alone in turn
    assert view.page == 0 and view.solo_hand() is not None and view.solo_hand().hand.name == "iris"
    view.set_solo(-1)  # (it dropped back to the grid: a fresh-eyes user; a table click kept it alone)
    assert view.pager.isVisible()
    window.scores.selectRow(3)
    window.scores.selectRow(0)  # iris, on the first page: the grid turns back to it and frames it
    assert view.page == 0 and view.selected == 0 and view._hands[1].border.GetVisibility()
    hand = view.hand_of_result(3)
    assert view._hands[hand].hand.name == "juniper"
    from s2h_viewer.app.exports import Shown  # a picture of this page names its targets, not iris
    shown = list(dict.fromkeys(r.target.name for r in view.comparison.results))
    assert "iris" not in shown and Shown.of(window.compare).caption(0).endswith(f"targets: {', '.join(shown)}")
    view.set_page(0)
    assert Shown.of(window.compare).caption(0).endswith("selected: TBS Copy -> iris")
    window.resize(1600, 1000)  # room for every row: one page
    qtbot.waitUntil(lambda: view.page_count == 1, timeout=10_000)
    assert not view.pager.isVisible() and len(view._hands) == 5 and view._hands[1].border.GetVisibility()  # iris
    window.close()


def test_in_and_out_points_mark_a_range_that_playback_loops_and_exports_write(window, qtbot, tmp_path):
    """Issue 25 item 5: range markers on the timeline, and the motion export's frame range."""
    from PySide6.QtCore import Qt
    from PySide6.QtWidgets import QDialog, QFileDialog

    from compare_window import when_shown
    from s2h_viewer.io.files import load_motion_file
    from s2h_viewer.widgets.frame_range_dialog import FrameRangeDialog
    timeline, curve = window.timeline, window.compare.curve
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)
    timeline.spin.setFocus()  # the keys work with the frame box focused too
    timeline.set_frame(5)
    qtbot.keyClick(timeline.spin.lineEdit(), Qt.Key.Key_I)
    timeline.set_frame(12)
    qtbot.keyClick(timeline.spin.lineEdit(), Qt.Key.Key_O)
    assert timeline.marked == range(5, 13) and curve.marked == range(5, 13)
    seen = []
    timeline.frame_changed.connect(seen.append)
    timeline.set_frame(2)  # outside the range: Play starts at its first frame
    timeline.set_playing(True)

    def looped() -> bool:  # a frame after a later one: playback wrapped (a slow view drops frames, not order)
        return any(b < a for a, b in zip(seen[1:], seen[2:]))
    qtbot.waitUntil(looped, timeout=60_000)
    timeline.set_playing(False)
    assert seen[1] == 5 and set(seen[1:]) <= set(range(5, 13))  # from the range's start, never out of it
    offered = []

    def take_the_marked_range(dialog: QDialog) -> None:
        offered.append((dialog.windowTitle(), dialog.frames()))
        dialog.accept()
    when_shown(FrameRangeDialog, take_the_marked_range)
    path = tmp_path / "part.npz"
    when_shown(QFileDialog, lambda dialog: (dialog.selectFile(str(path)), dialog.accept()))
    written = window.export_motion()
    assert offered == [("Export motion: frames", range(5, 13))] and written == path
    motion, _ = load_motion_file(path)
    np.testing.assert_array_equal(motion.q_tbs, window.compare.selected_result().motion.q_tbs[5:13])
    window.activateWindow()  # the dialogs gone (no window manager here): the window takes the keys again
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)
    qtbot.keyClick(window, Qt.Key.Key_I, Qt.KeyboardModifier.AltModifier)
    assert timeline.marked is None and curve.marked is None


def test_a_click_on_a_heatmap_row_puts_that_joints_bend_on_the_curve_beside_the_sources(window, qtbot):
    """Issue 25 item 5: per-joint angle curves, source beside retarget, for the joint chosen."""
    from PySide6.QtCore import QPoint, Qt

    from s2h_viewer.app.compare_mode import ASM_CURVE
    from s2h_viewer.hand import topology as topo
    from s2h_viewer.semantics.flexion import bend_angles
    from s2h_viewer.widgets.asm_heatmap import CELL, LEFT, TOP
    heatmap, curve = window.heatmap, window.compare.curve
    window.angle_curve.trigger()  # its joint (index PIP at first) framed in the heatmap: where the curve comes from
    assert heatmap.row == topo.FINGER_JOINT_NAMES.index("index_pip") and "index pip bend" in curve.quantity
    window.angle_curve.trigger()  # back to the ASM error: no row framed, and a click on a row shows its bend
    assert heatmap.row is None and curve.reference is None
    row = topo.FINGER_JOINT_NAMES.index("ring_pip")
    qtbot.mouseClick(heatmap.matrix, Qt.MouseButton.LeftButton, pos=QPoint(LEFT + 3 * CELL + 2, TOP + row * CELL + 2))
    assert window.angle_curve.isChecked() and not window.sideways_curve.isChecked()
    assert heatmap.row == row and "ring pip bend" in curve.quantity
    # the frame number stays readable over the chosen row (drawn in the outline's white, it vanished)
    corner = np.asarray(Image.fromqimage(heatmap.matrix.grab().toImage()).convert("L"))[TOP - 20:TOP, :LEFT]
    assert (corner < 128).sum() > 20
    result, joint = window.compare.selected_result(), topo.JOINT_NAMES.index("ring_pip")
    np.testing.assert_allclose(curve.error, bend_angles(result.pose.positions.numpy(), joint))
    np.testing.assert_allclose(curve.reference, bend_angles(window.comparison.source_pose.positions.numpy(), joint))
    assert curve.reference.max() > 30  # the clip curls the ring finger: the source's curve is no flat line
    assert curve.top == max(curve.error.max(), curve.reference.max())
    from s2h_viewer.widgets.error_curve import worst_frames
    # the source's curve shows where the two agree (TBS Copy's bends are the source's: the blue line covered
    # it) and the caption says how far they part
    from s2h_viewer.widgets.error_curve import REFERENCE_COLOUR
    assert window.compare.selected_result().method == "tbs_copy"
    pixels = np.asarray(Image.fromqimage(curve.grab().toImage()).convert("RGB")).astype(int)
    grey = (np.abs(pixels - np.array(REFERENCE_COLOUR.getRgb()[:3])).max(-1) < 8).sum()
    assert grey > curve.width()  # the band shows on both sides of the line along the whole clip
    assert np.abs(curve.error - curve.reference).max() < 0.05
    assert curve.apart() == ", the same as the source's throughout" and "max 89.0," in curve.caption()
    assert len(curve.worst) == 0 and "worst frames (red): none" in curve.toolTip()  # nothing parts: no red marks
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)
    frame = window.timeline.frame
    qtbot.keyClick(window, Qt.Key.Key_BracketRight)  # ] with nothing marked: said, not silent
    assert window.timeline.frame == frame and "No worst frames" in window.statusBar().currentMessage()
    dm = next(key for key in window.compare.shown_keys() if key.method == "dm")
    window.compare.select(dm)
    gap = np.abs(curve.error - curve.reference)
    assert gap.max() > 0.05 and curve.apart() == f", apart by at most {gap.max():.1f} (frame {int(gap.argmax())})"
    np.testing.assert_array_equal(curve.worst, worst_frames(gap))  # the red marks: where they part most
    tip = topo.FINGER_JOINT_NAMES.index("index_tip")  # a tip has no bend of its own: the joint that moves it
    qtbot.mouseClick(heatmap.matrix, Qt.MouseButton.LeftButton, pos=QPoint(LEFT + 3 * CELL + 2, TOP + tip * CELL + 2))
    assert curve.quantity.startswith("index dip bend (it moves the index tip)")
    # the pointer's frame and value, the source's beside it: a 1-3 deg gap hides under the band on a 90 deg axis
    frame = int(curve.gap.argmax())
    assert curve.value_at(curve.frame_at(curve._x(frame))) == (f"frame {frame}: {curve.error[frame]:.1f}, the source's "
                                                               f"{curve.reference[frame]:.1f} (apart by "
                                                               f"{curve.gap[frame]:.1f})")
    # the worst sideways bend over a joint's bend read as the curve's: it is left out there
    note = window.compare.sideways_note
    height = note.height()
    assert note.text() == "" and height >= note.fontMetrics().lineSpacing()
    window.sideways_curve.trigger()  # the choices exclude each other: radio items in the menu
    assert not window.angle_curve.isChecked() and curve.reference is None and heatmap.row is None
    # over the sideways curve, the line names the retarget and gives its worst bend; nothing above it moved
    assert note.text().startswith("DM -&gt; iris: worst sideways flexion:") and note.height() == height
    assert note.textFormat() == Qt.TextFormat.RichText  # the name's arrow shows as one, not as "-&gt;"
    assert window.sideways_curve.actionGroup().isExclusive()
    window.sideways_curve.trigger()  # its key again: the ASM error, with an item of its own (there was none)
    assert window.compare.curve_shows == ASM_CURVE and window.asm_curve.isChecked()
    assert [a.isChecked() for a in window.asm_curve.actionGroup().actions()] == [True, False, False, False]
    window.sideways_curve.trigger()
    window.asm_curve.trigger()
    assert window.compare.curve_shows == ASM_CURVE and not window.sideways_curve.isChecked()


def test_a_last_page_keeps_the_row_height_and_a_new_result_keeps_the_page(qtbot, sample_hands, tmp_path):
    """A fresh-eyes run: page 2 of fewer targets stretched its rows (hands twice as big), and ticking a method
    on page 2 sent the grid back to page 1 (where the selection was)."""
    three = ("iris", "laurel", "kale")
    window = open_compare_window(qtbot, sample_hands, tmp_path, methods=("tbs_copy",), targets=three)
    view = window.view
    assert view.rows == 2 and view.page_count == 2
    first = tuple(view.hand_viewports()[1])
    view.set_page(1)
    assert [r.target.name for r in view.comparison.results] == ["kale"]
    last = tuple(view.hand_viewports()[1])
    assert np.isclose(last[3] - last[1], first[3] - first[1])  # the same cell height: the same scale
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.method_actions["dm"].trigger()
    assert view.page == 1 and [r.target.name for r in view.comparison.results] == ["kale", "kale"]
    window.close()


def test_the_first_launch_fits_the_window_to_the_screen():
    """1400 x 900 on a 1280 x 1024 screen cut the heatmap and the speed box off at the window's right edge: the
    first size stays within the screen's free area less its frame, and never under the smallest that holds."""
    assert first_size((2560, 1400)) == FIRST_SIZE
    width, height = first_size((1280, 1024))
    assert width <= 1280 - 16 and height == FIRST_SIZE[1]
    assert first_size((1366, 728)) == (1366 - 16, MIN_SIZE[1])  # a laptop's free area: the smallest that holds
    assert first_size((800, 600)) == MIN_SIZE
