"""Compare mode in the real window (Xvfb, pytest-qt, shipped assets): actions that queue or cancel
retargets so the grid and the menus agree, per-method caching, exports in the background with a
caption, clock-driven playback and the QA tools (solo, error curve, overlays, heatmap tooltip)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

pytest.importorskip("pytestqt")
if not os.environ.get("DISPLAY"):
    pytest.skip("the Qt viewport needs an X display: `make test` runs the suite under Xvfb", allow_module_level=True)

import imageio.v2 as imageio  # noqa: E402
from PIL import Image  # noqa: E402
from PySide6.QtCore import QPoint, Qt, QTimer  # noqa: E402
from PySide6.QtGui import QImage  # noqa: E402
from PySide6.QtTest import QTest  # noqa: E402
from PySide6.QtWidgets import QPushButton  # noqa: E402

from compare_window import open_compare_window, when_shown  # noqa: E402
from grid_text import cell_pixels, hand_drawn, inside, intruders, text_actors, text_box  # noqa: E402
from s2h_viewer.hand import topology as topo  # noqa: E402
from s2h_viewer.render.caption import BAND  # noqa: E402
from s2h_viewer.render.compare_scene import (COLOUR_BAR_SHARE, CONTACT_COLOUR, ELLIPSIS, MIN_LABEL_PX,  # noqa: E402
                                             OVERLAY_LEAST, OVERLAY_PX)
from s2h_viewer.retarget.methods import METHODS  # noqa: E402
from s2h_viewer.samples import ASSETS_DIR  # noqa: E402
from s2h_viewer.widgets.asm_heatmap import CELL, LEFT, TOP  # noqa: E402
from s2h_viewer.widgets.error_curve import worst_frames  # noqa: E402


#: clip repeats that make ASM-Opt's work long enough to catch running (20 x 138 frames: 6-9 s here, not 0.1 s)
LONG = 20


@pytest.fixture
def window(qtbot, sample_hands, tmp_path):
    win = open_compare_window(qtbot, sample_hands, tmp_path)
    yield win
    win.close()


@pytest.fixture
def long_window(qtbot, sample_hands, tmp_path):
    """The window on the clip played `LONG` times over, TBS Copy shown: ASM-Opt added to it runs for seconds
    (ASRN, DM: 10 s each on it; the tests' jobs that must end at once are Copy's)."""
    win = open_compare_window(qtbot, sample_hands, tmp_path, methods=("tbs_copy",), repeats=LONG)
    yield win
    win.close()


def ticked(window) -> list[str]:
    return [name for name, action in window.method_actions.items() if action.isChecked()]


def removals(window) -> list:
    """The Targets menu's "Remove <target>" items (after its "Add target hand..." and a separator)."""
    return [a for a in window.targets_menu.actions() if a.text().startswith("Remove ")]


def grid_methods(window) -> list[str]:
    return [r.method for r in window.comparison.results]


def click_cancel(dialog, qtbot) -> None:
    """Press the progress dialog's Cancel button, as a user does, once the dialog shows."""
    qtbot.waitUntil(dialog.isVisible, timeout=30_000)
    qtbot.mouseClick(dialog.findChild(QPushButton), Qt.MouseButton.LeftButton)


def wait_until_running(window, qtbot, method: str) -> None:
    """Until the queue's running job is ``method`` and it has reported progress."""
    qtbot.waitUntil(lambda: window.compare.queue.pending()[:1] and
                    window.compare.queue.pending()[0].method == method, timeout=30_000)
    with qtbot.waitSignal(window.compare.queue.progress, timeout=60_000):
        pass


def test_toggling_a_method_during_a_retarget_queues_it_and_computes_only_it(long_window, qtbot):
    window = long_window
    before = dict(window.setup.results)
    computed = len(window.compare.queue.computed)
    window.method_actions["asm_opt"].trigger()
    wait_until_running(window, qtbot, "asm_opt")
    assert window.compare.queue.busy
    with qtbot.waitSignal(window.comparison_ready, timeout=300_000):
        window.method_actions["copy"].trigger()  # while ASM-Opt runs
    expected = [m for m in METHODS if m in ("copy", "tbs_copy", "asm_opt")]
    assert ticked(window) == window.setup.methods == grid_methods(window) == expected
    assert sorted(k.method for k in window.compare.queue.computed[computed:]) == ["asm_opt", "copy"]
    for key, result in before.items():  # the cached ones are the same objects, not recomputed
        assert window.setup.results[key] is result
    assert len(window.view._hands) == 1 + len(expected)


def test_unticking_the_running_method_cancels_it_and_the_grid_follows(long_window, qtbot):
    window = long_window
    window.method_actions["asm_opt"].trigger()
    wait_until_running(window, qtbot, "asm_opt")
    with qtbot.waitSignal(window.compare.queue.job_cancelled, timeout=60_000) as cancelled:
        window.method_actions["asm_opt"].trigger()  # untick while it runs
    assert cancelled.args[0].method == "asm_opt"
    assert ticked(window) == window.setup.methods == grid_methods(window) == ["tbs_copy"]
    assert not window.compare.queue.busy or not window.compare.queue.pending()


def test_cancel_a_retarget_goes_back_to_the_grid_and_the_menu_follows(long_window, qtbot):
    window = long_window
    shown = window.comparison
    window.method_actions["asm_opt"].trigger()
    wait_until_running(window, qtbot, "asm_opt")
    dialog = window.compare._progress
    assert dialog is not None and not dialog.isModal()  # the menus stay usable while it runs
    with qtbot.waitSignal(window.compare.queue.job_cancelled, timeout=60_000):
        click_cancel(dialog, qtbot)
    assert ticked(window) == window.setup.methods == grid_methods(window) == ["tbs_copy"]
    assert window.comparison is shown and window.compare._progress is None
    assert window.settings.value("compare/methods") == ["tbs_copy"]  # remembered as shown
    stack = window.compare.undo_stack  # the cancelled tick is undone: Redo ticks ASM-Opt again
    assert not stack.canUndo() and stack.canRedo() and stack.redoText() == "tick ASM-Opt"
    stack.redo()
    assert ticked(window) == window.setup.methods == ["tbs_copy", "asm_opt"]
    assert window.compare._progress is not None  # computing it again


def test_every_progress_text_names_the_retarget_it_belongs_to(window, qtbot):
    """A stage of ASRN said only "contact fit (4 of 5)": which method, which target?"""
    texts, strip = [], []

    def read_strip() -> None:
        if window.compare._progress is not None:  # the strip: the retarget on a line, its stage under it, whole
            strip.append(window.compare._progress.labelText())
    window.compare.queue.progress.connect(lambda _, what: (texts.append(what), read_strip()))
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(ASSETS_DIR / "hands" / "laurel.npz"))
    assert any(line.splitlines()[0] == "ASRN -> laurel" and line.splitlines()[1].startswith("contact fit (")
               for line in strip), sorted(set(strip))
    assert all(t.startswith(("TBS Copy -> laurel", "ASRN -> laurel")) for t in texts), sorted(set(texts))
    assert "ASRN -> laurel: contact fit" in texts  # a stage inside the retarget, named with it


def test_redo_at_once_after_a_cancel_computes_the_cancelled_method(long_window, qtbot):
    """Cancel, then Redo before the running job has stopped: the job was cancelled all the same and never
    came back (the grid waited for it for ever); now it is queued again."""
    window = long_window
    window.method_actions["asm_opt"].trigger()
    wait_until_running(window, qtbot, "asm_opt")
    window.compare.cancel()
    assert window.compare.queue.pending()[:1] and window.compare.queue.pending()[0].method == "asm_opt"  # stopping
    with qtbot.waitSignal(window.comparison_ready, timeout=300_000):
        window.compare.undo_stack.redo()
    assert ticked(window) == grid_methods(window) == ["tbs_copy", "asm_opt"]


def test_cancel_the_first_retarget_keeps_the_targets_and_ticking_a_method_computes_it(qtbot, sample_hands,
                                                                                      tmp_path):
    window = open_compare_window(qtbot, sample_hands, tmp_path, methods=("asm_opt",), compute=False,
                                 repeats=LONG)
    window.start_comparison()
    wait_until_running(window, qtbot, "asm_opt")
    with qtbot.waitSignal(window.compare.queue.job_cancelled, timeout=60_000):
        click_cancel(window.compare._progress, qtbot)
    assert ticked(window) == window.setup.methods == [] and window.comparison is None  # menus say what is shown
    assert [t.name for t in window.setup.targets] == ["iris"]  # the targets stay
    assert window.targets_menu.isEnabled() and [a.text() for a in removals(window)] == ["Remove iris"]
    assert window.targets_menu.actions()[0] is window.add_target_action  # adding one is there too, as in File
    assert window.compare._progress is None
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.method_actions["tbs_copy"].trigger()
    assert ticked(window) == window.setup.methods == grid_methods(window) == ["tbs_copy"]
    assert [r.target.name for r in window.comparison.results] == ["iris"] and len(window.view._hands) == 2
    window.close()


def test_cancel_the_first_retarget_shows_the_methods_already_computed(qtbot, sample_hands, tmp_path):
    window = open_compare_window(qtbot, sample_hands, tmp_path, methods=("tbs_copy", "asm_opt"), compute=False,
                                 repeats=LONG)
    window.start_comparison()
    wait_until_running(window, qtbot, "asm_opt")  # TBS Copy is computed by now
    with qtbot.waitSignal(window.comparison_ready, timeout=60_000):
        click_cancel(window.compare._progress, qtbot)
    assert ticked(window) == window.setup.methods == grid_methods(window) == ["tbs_copy"]
    assert [r.target.name for r in window.comparison.results] == ["iris"]
    window.close()


def test_add_and_remove_a_target(window, qtbot):
    computed = len(window.compare.queue.computed)
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(ASSETS_DIR / "hands" / "laurel.npz"))
    assert [r.target.name for r in window.comparison.results] == ["iris", "iris", "laurel", "laurel"]
    assert [k.method for k in window.compare.queue.computed[computed:]] == ["tbs_copy", "asrn"]  # laurel only
    laurel_results = window.comparison.results[2:]
    assert [a.text() for a in removals(window)] == ["Remove iris", "Remove laurel"]
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        removals(window)[0].trigger()
    assert [r.target.name for r in window.comparison.results] == ["laurel", "laurel"]
    assert all(a is b for a, b in zip(window.comparison.results, laurel_results))  # kept, not recomputed
    assert [a.text() for a in removals(window)] == ["Remove laurel"]
    assert not removals(window)[0].isEnabled()  # the last target stays: nothing to compare without
    assert window.scores.rowCount() == 2 and len(window.view._hands) == 3


def test_the_last_ticked_method_cannot_be_unticked(window, qtbot):
    """Unticking the last method opened an error dialog; now its menu entry is greyed, as the last target's."""
    actions = window.method_actions
    assert actions["tbs_copy"].isEnabled() and actions["asrn"].isEnabled()
    with qtbot.waitSignal(window.comparison_ready, timeout=60_000):
        actions["asrn"].trigger()
    assert window.setup.methods == ["tbs_copy"] and not actions["tbs_copy"].isEnabled()
    assert all(actions[m].isEnabled() for m in METHODS if m != "tbs_copy")
    with qtbot.waitSignal(window.comparison_ready, timeout=60_000):
        window.compare.undo_stack.undo()
    assert window.setup.methods == ["tbs_copy", "asrn"] and actions["tbs_copy"].isEnabled()


def test_a_hand_that_is_a_target_already_is_not_added_twice(window, qtbot):
    from PySide6.QtWidgets import QMessageBox
    said = []
    when_shown(QMessageBox, lambda box: (said.append(box.text()), box.accept()))
    window.add_target_file(str(ASSETS_DIR / "hands" / "iris.npz"))  # iris, the window's target, loaded again
    qtbot.waitUntil(lambda: bool(said), timeout=10_000)
    assert said[0].startswith("iris is a target already")
    assert [t.name for t in window.setup.targets] == ["iris"] and not window.compare.queue.pending()
    assert [a.text() for a in removals(window)] == ["Remove iris"]
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(ASSETS_DIR / "hands" / "laurel.npz"))  # another hand is added as before
    assert [t.name for t in window.setup.targets] == ["iris", "laurel"]


def test_undoing_a_removal_brings_the_target_back_selected(window, qtbot):
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(ASSETS_DIR / "hands" / "laurel.npz"))
    window.scores.selectRow(3)  # ASRN -> laurel
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        window.compare.remove_target(1)
    assert window.compare.selected_result().target.name == "iris"  # its selection went with it
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        window.compare.undo_stack.undo()
    selected = window.compare.selected_result()
    assert (selected.method, selected.target.name) == ("asrn", "laurel")
    assert window.heatmap_choice.currentIndex() == 3 and window.scores.currentRow() == 3
    np.testing.assert_array_equal(window.compare.curve.error, selected.frame_error)


def test_while_another_clip_is_retargeted_the_heatmap_and_curve_stay_on_the_selected_retarget(window, qtbot):
    """A fresh-eyes run: while a newly opened clip computed, a click on the curve filled the heatmap with yellow
    (the first retarget's errors, Copy's, under "ASRN -> laurel" in the drop-down) and a click on a heatmap row
    put "Copy -> iris" over the curve: the retargets on screen were keyed by the clip being computed."""
    window.scores.selectRow(1)  # ASRN -> iris, not the first
    selected = window.compare.selected_result()
    assert selected.method == "asrn"
    shown = window.comparison.motion
    window.load_motion(str(ASSETS_DIR / "motions" / "counting.npz"))  # queued; the grid stays on screen meanwhile
    assert window.compare.queue.pending() and window.comparison.motion is shown
    window.compare.curve.frame_clicked.emit(57)  # a click on the curve
    assert window.timeline.frame == 57
    assert window.compare.selected_result() is selected
    np.testing.assert_array_equal(window.heatmap.current, selected.cell_error[57])
    window.compare.choose_joint(topo.FINGER_JOINT_NAMES.index("ring_pip"))  # a click on a heatmap row
    window.angle_curve.trigger()
    assert window.compare.curve.title == "ASRN -> iris" and window.heatmap_choice.currentIndex() == 1
    window.sideways_curve.trigger()
    assert window.compare.curve.title == "ASRN -> iris"
    assert window.compare.sideways_note.text().startswith("ASRN -&gt; iris")
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        pass
    selected = window.compare.selected_result()  # the new clip keeps the choice of method and target
    assert window.comparison.motion.name == "counting" and (selected.method, selected.target.name) == ("asrn", "iris")


def test_a_clip_opened_again_shows_its_retargets_without_computing_them(window, qtbot, sample_hands, tmp_path):
    """A fresh-eyes run reopened a clip it had seen minutes before and waited for all 15 retargets again. The same
    file, unchanged, gives back the same clip: its results come from the cache; a changed file is read again."""
    from s2h_viewer.io.npz import save_motion
    from s2h_viewer.motions.synthesis import synthesize
    paths = [tmp_path / "first.npz", tmp_path / "second.npz"]
    for path, gestures in zip(paths, (["point", "fist"], ["ok", "thumbs_up"])):
        save_motion(synthesize(gestures, sample_hands["birch"], seed=2, name=path.stem), path)
    shown = {}
    for path in paths:
        with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
            window.load_motion(str(path))
        shown[path.stem] = list(window.comparison.results)
    computed = len(window.compare.queue.computed)
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        window.load_motion(str(paths[0]))  # back to the first clip
    assert window.comparison.motion.name == "first" and len(window.compare.queue.computed) == computed
    assert all(a is b for a, b in zip(window.comparison.results, shown["first"]))  # the very results shown before
    assert not window.compare.queue.pending()
    save_motion(synthesize(["fist", "point"], sample_hands["birch"], seed=3, name="second"), paths[1])  # changed
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.load_motion(str(paths[1]))
    assert len(window.compare.queue.computed) == computed + 2  # read again, retargeted again
    assert not any(a is b for a, b in zip(window.comparison.results, shown["second"]))


def test_the_clip_shown_at_launch_opened_again_is_not_computed_again(qtbot, sample_hands, tmp_path):
    """The same for the clip the window starts on (`s2h view`'s sample or its MOTION argument): a second fresh-eyes
    run opened the sample gestures again and watched its retargets computed again."""
    from compare_window import open_window
    from s2h_viewer.app.main_window import CompareSetup
    from s2h_viewer.io.files import load_motion_file
    from s2h_viewer.io.npz import save_motion
    from s2h_viewer.motions.synthesis import synthesize
    path = save_motion(synthesize(["point", "ok"], sample_hands["birch"], seed=5, name="launch"), tmp_path / "l.npz")
    setup = CompareSetup(load_motion_file(path)[0], sample_hands["birch"], [sample_hands["iris"]], ["tbs_copy"],
                         path=path)
    window = open_window(qtbot, setup, tmp_path)
    shown, computed = list(window.comparison.results), len(window.compare.queue.computed)
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        window.load_motion(str(path))
    assert len(window.compare.queue.computed) == computed and window.comparison.results == shown


def test_a_clip_resting_in_its_pose_asks_for_its_rig_and_opens_on_it(window, qtbot):
    """Oculus's pinch clip has no mesh and rests in the pinch: opening it says so and offers its rig's hand file,
    on which the source touches thumb to index; Cancel keeps the clip on screen, "as it is" opens it on its own
    skeleton."""
    from test_annotate_window import answer, choose_file, click
    from s2h_viewer.hand.kinematics import joint_positions
    from s2h_viewer.semantics.contacts import CONTACT_TOLERANCE, thumb_pair_gaps
    import torch
    pinch = str(ASSETS_DIR / "motions" / "real" / "r_hand_pinch_anim.fbx")
    rig = ASSETS_DIR / "hands" / "real" / "r_hand_skeletal_lowres.fbx"
    before = window.comparison.motion
    shown = answer(click("Cancel"))
    window.load_motion(pinch)
    assert "r_hand_pinch_anim.fbx: its skeleton has no mesh and rests in a pose" in shown[0]
    assert window.comparison.motion is before and not window.compare.queue.pending()
    answer(click("Choose its rig's hand file..."), choose_file(rig))
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.load_motion(pinch)
    source = window.comparison.source
    assert source.name == "r_hand_skeletal_lowres" and source.mesh is not None
    positions = joint_positions(source, torch.as_tensor(window.comparison.motion.q_tbs, dtype=torch.float64))
    assert (thumb_pair_gaps(source, positions)[:, 0] < CONTACT_TOLERANCE * source.hand_length).all()
    answer(click("Open it as it is"))
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.load_motion(pinch)
    assert window.comparison.source.mesh is None and window.comparison.source.meta["rest_note"]
    # opened again it asks again (a fresh-eyes run got the cached rig-less clip with no word), offering the rig
    # chosen for it before, whose results are still cached
    computed = len(window.compare.queue.computed)
    shown = answer(click("Open it on r_hand_skeletal_lowres.fbx"))
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        window.load_motion(pinch)
    assert "was chosen for it before" in shown[0]
    assert window.comparison.source.mesh is not None and len(window.compare.queue.computed) == computed
    # `s2h view --motion` shows the clip first, then makes the same offer; keeping it changes nothing
    from s2h_viewer.app.main_window import CompareSetup
    from s2h_viewer.io.files import load_motion_file
    shown = answer(click("Keep it as it is"))
    window.offer_launch_rig(CompareSetup(*load_motion_file(pinch), [], path=Path(pinch)))
    assert "rests in a pose" in shown[0] and window.comparison.source.mesh is not None
    assert not window.compare.queue.pending()


def test_playback_pauses_for_a_new_retarget_and_plays_on_after_it(window, qtbot):
    window.timeline.set_playing(True)
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(ASSETS_DIR / "hands" / "laurel.npz"))
        assert not window.timeline.playing  # paused while laurel is retargeted
    assert window.timeline.playing
    frame = window.timeline.frame
    qtbot.waitUntil(lambda: window.timeline.frame != frame, timeout=10_000)  # and the frames move on


def test_playback_plays_on_after_a_cancelled_retarget(long_window, qtbot):
    window = long_window
    window.timeline.set_playing(True)
    window.method_actions["asm_opt"].trigger()
    assert not window.timeline.playing
    wait_until_running(window, qtbot, "asm_opt")
    with qtbot.waitSignal(window.compare.queue.job_cancelled, timeout=60_000):
        click_cancel(window.compare._progress, qtbot)
    assert window.timeline.playing and grid_methods(window) == ["tbs_copy"]
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.method_actions["copy"].trigger()
        window.timeline.toggle()  # the user plays, then pauses during the job: paused it stays
        window.timeline.toggle()
    assert not window.timeline.playing


def test_video_export_runs_in_the_background_while_the_timeline_plays(window, qtbot, tmp_path):
    fired, frames = [], []
    timer = QTimer()
    timer.timeout.connect(lambda: (fired.append(time.perf_counter()), window.timeline.step(1),
                                   frames.append(window.timeline.frame)))
    timer.start(20)
    job = window.export_video(str(tmp_path / "compare.mp4"))
    started = time.perf_counter()
    with qtbot.waitSignal(job.written, timeout=300_000):
        pass
    ended = time.perf_counter()
    timer.stop()
    during = [t for t in fired if started < t < ended]
    assert len(during) >= 10 and len(set(frames)) >= 10  # the GUI thread kept running and drawing frames
    reader = imageio.get_reader(tmp_path / "compare.mp4")
    assert reader.count_frames() == window.comparison.n_frames
    first = reader.get_data(0)
    reader.close()
    view_height = window.view.interactor.height()
    assert first.shape[0] >= view_height + BAND  # the caption band under the grid (an odd height padded to even)
    assert window.video_export is None


def test_cancel_a_video_export_writes_nothing(window, qtbot, tmp_path):
    path = tmp_path / "cancelled.mp4"
    job = window.export_video(str(path))
    with qtbot.waitSignal(job.progress, timeout=60_000):
        pass
    with qtbot.waitSignal(job.cancelled, timeout=60_000):
        click_cancel(job.strip, qtbot)
        assert window.statusBar().currentMessage().startswith("cancelling the video export")  # said at once
    job.thread.join()
    assert not path.exists() and not list(tmp_path.glob("*.mp4*"))
    assert window.statusBar().currentMessage() == "video export cancelled: no file written (cancelled.mp4)"


def test_cancelling_a_video_export_in_its_dialog_gives_the_keyboard_back_to_the_window(window, qtbot, tmp_path):
    job = window.export_video(str(tmp_path / "cancelled.mp4"))
    with qtbot.waitSignal(job.progress, timeout=60_000):
        pass
    qtbot.waitUntil(job.strip.isVisible, timeout=30_000)
    job.strip.activateWindow()  # the user clicks into the progress dialog: it holds the keyboard
    qtbot.waitUntil(job.strip.isActiveWindow, timeout=5000)
    with qtbot.waitSignal(job.cancelled, timeout=60_000):
        qtbot.mouseClick(job.strip.findChild(QPushButton), Qt.MouseButton.LeftButton)
    # without a window manager the focus fell to the root window: the app hands it back to the main window
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)


def test_png_export_carries_a_caption_of_the_selected_retarget(window, tmp_path):
    window.scores.selectRow(1)  # ASRN -> iris, picked in the scores table
    assert window.heatmap_choice.currentIndex() == 1
    np.testing.assert_allclose(window.heatmap.current, window.comparison.results[1].cell_error[0], equal_nan=True)
    window.timeline.set_frame(30)
    assert window.timeline.pose_label.text() == "between poses" and window.timeline.pose_label.isVisible()
    window.timeline.set_frame(7)
    assert window.timeline.pose_label.text() == "pose: relaxed"  # which pose of the clip this is
    png = window.export_screenshot(str(tmp_path / "compare.png"))
    image = np.asarray(Image.open(png).convert("RGB"))
    assert image.shape[0] == window.view.interactor.height() + BAND
    band = image[-BAND:]
    assert (band < 80).any() and (band > 250).mean() > 0.8  # dark text on white
    from s2h_viewer.app.exports import Shown
    text = Shown.of(window.compare).caption(7)
    assert "short, pose relaxed" in text and "frame 7/" in text and "ASRN -> iris" in text
    bvh = window.export_motion(str(tmp_path / "selected.bvh"))
    assert bvh.read_text().startswith("HIERARCHY")


def start_recorded_playback(window) -> tuple[list[tuple[float, int]], float, int]:
    """Play from frame 0, recording (time, frame) of every frame shown; also the clock's anchor."""
    shown = []
    window.timeline.frame_changed.connect(lambda f: shown.append((time.perf_counter(), f)))
    window.timeline.set_frame(0)
    shown.clear()
    window.timeline.set_playing(True)
    started, first = window.timeline._anchor
    return shown, started, first


def test_playback_follows_the_clock(window, qtbot):
    shown, started, first = start_recorded_playback(window)
    qtbot.wait(1500)
    window.timeline.set_playing(False)
    fps = window.timeline.clip_fps
    assert len(shown) >= 3
    for when, frame in shown:  # each frame shown is the one real time had reached (frames dropped if late)
        assert frame <= first + (when - started) * fps + 1e-6
        assert frame >= first + (when - started) * fps - fps * 0.25 - 1  # at most a tick and a draw behind


def test_the_fps_label_reads_the_clip_rate_at_1x_and_play_at_the_end_without_loop_starts_again(window, qtbot):
    timeline = window.timeline
    timeline.set_frame(0)
    timeline.set_playing(True)
    qtbot.wait(2500)
    shown = int(timeline.fps_label.text().split()[0])
    timeline.set_playing(False)
    assert timeline.clip_fps - 3 <= shown <= timeline.clip_fps, shown  # at 1x never more frames/s than the clip's
    timeline.loop.setChecked(False)
    timeline.set_frame(timeline.n_frames - 1)
    timeline.set_playing(True)  # at the end, not looping: Play plays the clip from its start
    assert timeline.playing and timeline.frame < 5
    qtbot.waitUntil(lambda: timeline.frame >= 3, timeout=10_000)
    timeline.set_playing(False)


def test_a_slow_view_drops_frames_to_keep_real_time(window, qtbot):
    slow = 0.3  # seconds each draw takes here: at 30 frames/s about 9 clip frames pass during one
    window.view.drawn.connect(lambda: time.sleep(slow) if window.timeline.playing else None)
    shown, started, first = start_recorded_playback(window)
    qtbot.waitUntil(lambda: len(shown) >= 4, timeout=20_000)
    window.timeline.set_playing(False)
    fps = window.timeline.clip_fps
    frames = [frame for _, frame in shown[:4]]
    assert all(b - a >= slow * fps * 0.5 for a, b in zip(frames, frames[1:])), frames  # frames were dropped
    for when, frame in shown[:4]:
        assert frame <= first + (when - started) * fps + 1e-6  # never ahead of the clock


def test_skins_are_lighter_while_the_grid_plays_and_full_when_paused_or_alone(window, qtbot):
    from s2h_viewer.hand.skinning import skin_vertices
    from s2h_viewer.render.scene import to_view
    hand = window.view._hands[1]
    full, light = hand.levels  # the display mesh and the lighter one
    assert light.mesh.n_cells < full.mesh.n_cells / 2
    window.timeline.set_frame(2)
    window.timeline.set_playing(True)
    qtbot.waitUntil(lambda: window.timeline.frame > 6, timeout=20_000)
    assert light.actor.visibility and not full.actor.visibility
    assert hand.frame == window.view.frame and window.view.playing
    window.view.set_solo(1)  # shown alone: full detail even while playing
    assert full.actor.visibility and not light.actor.visibility
    window.view.set_solo(-1)
    assert light.actor.visibility and not full.actor.visibility
    window.timeline.set_playing(False)
    frame = window.timeline.frame
    assert full.actor.visibility and not light.actor.visibility and not window.view.playing
    np.testing.assert_allclose(full.mesh.points, to_view(full.hand, skin_vertices(full.hand, hand.pose, frame)))


def test_frames_posed_ahead_are_the_frames_shown(window, qtbot):
    from s2h_viewer.hand.skinning import skin_vertices
    from s2h_viewer.render.scene import to_view
    view = window.view
    drawn_before = view.prefetched
    window.timeline.set_frame(0)
    window.timeline.set_playing(True)
    checked = []

    def check(frame: int) -> None:  # every skin shown equals the skin posed here for that frame
        checked.append(all(np.allclose(h.mesh.points, to_view(h.skin.hand, skin_vertices(h.skin.hand, h.pose, frame)))
                           and (h.skin.error is None or np.allclose(h.skin.error, h.posed_skin(frame).error))
                           for h in view._hands))
    window.timeline.frame_changed.connect(check)
    qtbot.waitUntil(lambda: len(checked) >= 20, timeout=30_000)
    window.timeline.set_playing(False)
    window.timeline.frame_changed.disconnect(check)
    assert all(checked)
    assert view.prefetched - drawn_before >= 10  # at 1x the frame expected next is the frame asked for
    view.prefetch(5)  # posed ahead for one frame (from the render's start), another one asked: posed when shown
    view.interactor.render()
    assert view._ahead is not None and view._ahead[0] == 5
    view.show_frame(9)
    hand = view._hands[2]
    np.testing.assert_allclose(hand.mesh.points, to_view(hand.skin.hand, skin_vertices(hand.skin.hand, hand.pose, 9)))


def test_the_slider_and_readouts_follow_playback_at_their_rate_and_exactly_when_paused(qtbot):
    from s2h_viewer.widgets.timeline import SPEEDS, WIDGET_RATE, Timeline
    timeline = Timeline()  # the real widget, with a view that draws each frame at once (120 frames/s at 4x)
    qtbot.addWidget(timeline)
    timeline.show()
    timeline.set_clip(2000, 30.0)
    assert timeline.pose_label.isHidden()  # a clip of no poses names none
    timeline.speed.setCurrentIndex(SPEEDS.index(4.0))
    shown, slider = [], []
    timeline.frame_changed.connect(lambda f: (shown.append(f), slider.append(timeline.slider.value()),
                                              QTimer.singleShot(0, timeline.note_drawn)))
    started = time.perf_counter()
    timeline.set_playing(True)
    qtbot.wait(1500)
    timeline.set_playing(False)
    elapsed = time.perf_counter() - started
    moves = sum(a != b for a, b in zip(slider, slider[1:]))
    assert len(shown) > 2 * moves  # the view got every frame, the slider a fraction of them
    assert moves <= WIDGET_RATE * elapsed + 2
    frame = timeline.frame  # paused: every widget shows the frame the view was given last
    assert frame == shown[-1] and timeline.slider.value() == timeline.spin.value() == frame
    assert timeline.readout.text().startswith(f"{frame}/") and timeline.fps_label.text() == "-- fps"
    timeline.set_frame(frame + 1)  # stepping while paused moves them at once
    assert timeline.slider.value() == timeline.spin.value() == frame + 1 == shown[-1]


def test_playback_keys_reach_the_shortcuts_with_the_frame_box_focused(window, qtbot):
    window.activateWindow()
    qtbot.waitUntil(lambda: window.isActiveWindow(), timeout=5000)
    window.timeline.set_frame(3)
    window.timeline.spin.setFocus()
    qtbot.waitUntil(lambda: window.timeline.spin.hasFocus(), timeout=5000)
    qtbot.keyClick(window.timeline.spin.lineEdit(), Qt.Key.Key_Right)
    assert window.timeline.frame == 4
    qtbot.keyClick(window.timeline.spin.lineEdit(), Qt.Key.Key_Left)
    assert window.timeline.frame == 3
    qtbot.keyClick(window.timeline.spin.lineEdit(), Qt.Key.Key_Space)
    assert window.timeline.playing
    qtbot.keyClick(window.timeline.spin.lineEdit(), Qt.Key.Key_Space)
    assert not window.timeline.playing
    assert window.timeline.readout.text().startswith(f"{window.timeline.frame}/{window.timeline.n_frames - 1}")


def test_ctrl_shortcuts_reach_the_window_with_the_frame_box_focused(window, qtbot, tmp_path):
    from PySide6.QtWidgets import QFileDialog
    window.settings.setValue("files/export_dir", str(tmp_path))
    window.activateWindow()
    qtbot.waitUntil(lambda: window.isActiveWindow(), timeout=5000)
    window.timeline.spin.setFocus()
    qtbot.waitUntil(lambda: window.timeline.spin.hasFocus(), timeout=5000)
    box = window.timeline.spin.lineEdit()
    qtbot.keyClick(box, Qt.Key.Key_K, Qt.KeyboardModifier.ControlModifier)
    assert window.skeleton_overlay.isChecked()  # Ctrl+K: the skeleton overlay
    qtbot.keyClick(box, Qt.Key.Key_M, Qt.KeyboardModifier.ControlModifier)
    assert window.view.solo > 0  # Ctrl+M: solo
    qtbot.keyClick(box, Qt.Key.Key_M, Qt.KeyboardModifier.ControlModifier)
    assert window.view.solo < 0
    asked = []

    def answer_dialog() -> None:  # the export's file dialog opened: note its title, then close it
        dialog = next((w for w in window.findChildren(QFileDialog) if w.isVisible()), None)
        if dialog is None:
            QTimer.singleShot(50, answer_dialog)
            return
        asked.append(dialog.windowTitle())
        dialog.reject()

    for key, title in ((Qt.Key.Key_E, "Export video"), (Qt.Key.Key_S, "Export screenshot")):
        window.timeline.spin.setFocus()
        qtbot.waitUntil(lambda: window.timeline.spin.hasFocus(), timeout=5000)
        QTimer.singleShot(0, answer_dialog)
        qtbot.keyClick(box, key, Qt.KeyboardModifier.ControlModifier)
        qtbot.waitUntil(lambda: len(asked) == [Qt.Key.Key_E, Qt.Key.Key_S].index(key) + 1, timeout=10_000)
        assert asked[-1] == title
    assert window.video_export is None and not list(tmp_path.glob("*.mp4"))
    window.timeline.spin.setFocus()
    qtbot.waitUntil(lambda: window.timeline.spin.hasFocus(), timeout=5000)
    box.selectAll()
    qtbot.keyClicks(box, "5")  # the box still takes its own keys
    qtbot.keyClick(box, Qt.Key.Key_Return)
    assert window.timeline.frame == 5


def test_double_click_solos_a_viewport_and_back(window, qtbot):
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(ASSETS_DIR / "hands" / "laurel.npz"))  # two rows: cells != renderers
    view = window.view
    viewports = view.hand_viewports()
    hand = 4  # ASRN -> laurel, in the second row
    x0, y0, x1, y1 = viewports[hand]
    w, h = view.interactor.width(), view.interactor.height()
    centre = QPoint(int((x0 + x1) / 2 * w), int((1 - (y0 + y1) / 2) * h))
    assert view.hand_at(centre.x(), centre.y()) == hand
    qtbot.mouseClick(view.interactor, Qt.MouseButton.LeftButton, pos=centre)  # a click selects it (a fresh-eyes user)
    assert window.compare.selected_result() is window.comparison.results[view.result_of_hand(hand)]
    assert window.scores.currentRow() == view.result_of_hand(hand) and view.selected == view.result_of_hand(hand)
    first = view.hand_of_result(0)
    x0, y0, x1, y1 = viewports[first]
    start = QPoint(int((x0 + x1) / 2 * w), int((1 - (y0 + y1) / 2) * h))
    qtbot.mousePress(view.interactor, Qt.MouseButton.LeftButton, pos=start)  # a drag turns the camera, selects nothing
    qtbot.mouseMove(view.interactor, start + QPoint(40, 10))
    qtbot.mouseRelease(view.interactor, Qt.MouseButton.LeftButton, pos=start + QPoint(40, 10))
    assert view.selected == view.result_of_hand(hand)
    qtbot.mouseDClick(view.interactor, Qt.MouseButton.LeftButton, pos=centre)
    assert view.solo == hand
    drawn = [r for r in view.plotter.renderers if r.GetDraw()]
    bar = view.plotter.renderers[view.plotter.renderers.loc_to_index((0, view.plotter.shape[1] - 1))]
    assert len(drawn) == 2 and view._hands[hand].renderer in drawn and bar in drawn  # the hand and its colour bar
    assert tuple(view._hands[hand].renderer.GetViewport()) == (0.0, 0.0, 1.0 - COLOUR_BAR_SHARE, 1.0)
    grid_camera = np.array([view.plotter.camera.position, view.plotter.camera.focal_point])
    from PySide6.QtGui import QAction
    next(a for a in window.findChildren(QAction) if a.text().startswith("Frame the hand shown alone")).trigger()
    # framed (F): the hand fills the view, the camera nearer
    framed = np.array([view.plotter.camera.position, view.plotter.camera.focal_point])
    assert np.linalg.norm(framed[0] - framed[1]) < 0.8 * np.linalg.norm(grid_camera[0] - grid_camera[1])
    qtbot.mouseDClick(view.interactor, Qt.MouseButton.LeftButton, pos=centre)
    assert view.solo == -1 and all(r.GetDraw() for r in view.plotter.renderers)
    # the grid's camera again: framed, the hands overflowed their cells over the labels (a fresh-eyes user)
    np.testing.assert_allclose([view.plotter.camera.position, view.plotter.camera.focal_point], grid_camera)


def test_every_hand_has_a_viewport_of_the_same_size_and_the_colour_bar_its_own(window):
    viewports = np.array(window.view._viewports)
    hands = np.array(window.view.hand_viewports())
    sizes = np.column_stack([hands[:, 2] - hands[:, 0], hands[:, 3] - hands[:, 1]])
    assert np.abs(sizes - sizes[0]).max() < 1e-6
    bar = viewports[-1]  # the colour bar's column: right of every hand
    assert bar[0] >= hands[:, 2].max() - 1e-6


def test_error_curve_marks_the_worst_frames_and_a_click_jumps(window, qtbot):
    curve = window.compare.curve
    result = window.compare.selected_result()
    np.testing.assert_allclose(curve.error, result.frame_error)
    assert int(np.argmax(result.frame_error)) in curve.worst
    assert worst_frames(np.array([0, 5, 1, 0, 9, 0.0]), count=2, spacing=1).tolist() == [1, 4]
    target = curve.worst[0]
    qtbot.mouseClick(curve, Qt.MouseButton.LeftButton, pos=QPoint(int(round(curve._x(target))), curve.height() // 2))
    assert window.timeline.frame == target and curve.frame == target
    # a drag along it scrubs (a fresh-eyes run dragged and got only the frame it pressed on)
    from PySide6.QtCore import QEvent, QPointF
    from PySide6.QtGui import QMouseEvent
    from PySide6.QtWidgets import QApplication
    last = len(curve.error) - 1
    for frame, buttons in ((last // 4, Qt.MouseButton.LeftButton), (last // 2, Qt.MouseButton.LeftButton),
                           (3 * last // 4, Qt.MouseButton.NoButton)):
        point = QPointF(curve._x(frame), curve.height() / 2)
        QApplication.sendEvent(curve, QMouseEvent(QEvent.Type.MouseMove, point, curve.mapToGlobal(point),
                                                  Qt.MouseButton.NoButton, buttons, Qt.KeyboardModifier.NoModifier))
    assert window.timeline.frame == last // 2  # followed while the button was held, not after


def test_the_error_curve_keeps_clear_of_its_caption_and_its_edges(window):
    """The curve ran through its caption, and a worst frame's ring at the end was cut by the edge."""
    curve = window.compare.curve
    caption_top = curve.height() - 4 - curve.fontMetrics().ascent()  # the caption's baseline is 4 px up
    assert curve._y(0.0) <= caption_top and curve._y(float(curve.error.max())) >= 0
    ring = 3
    assert curve._x(0) - ring >= 0 and curve._x(len(curve.error) - 1) + ring <= curve.width() - 1


def test_the_error_curve_has_a_numbered_frame_axis_and_the_playhead_stops_above_its_numbers(window):
    """Issue 25: the curve had no axis or frame ticks and the playhead ran through its caption."""
    curve = window.compare.curve
    metrics = curve.fontMetrics()
    ticks = curve.ticks()
    step = ticks[1] - ticks[0]
    assert ticks[0] == 0 and len(ticks) >= 3 and ticks[-1] <= len(curve.error) - 1 < ticks[-1] + step
    assert str(step)[0] in "125" and set(str(step)[1:]) <= {"0"} and np.all(np.diff(ticks) == step)
    widest = max(metrics.horizontalAdvance(str(t)) for t in ticks)
    assert curve._x(ticks[1]) - curve._x(ticks[0]) >= widest + 4  # numbers that do not run into each other
    caption_top = curve.height() - 4 - metrics.ascent()
    assert curve.axis_y() + 3 + metrics.height() <= caption_top + 2  # the numbers' row sits over the caption
    assert curve._y(0.0) == curve.axis_y()  # the curve's zero is on the axis; the playhead ends there too
    assert curve.frame_at(curve._x(ticks[1])) == ticks[1]  # clicks still land on the frame drawn there
    from s2h_viewer.widgets.error_curve import frame_ticks
    assert frame_ticks(300, 600) == list(range(0, 300, 50)) and frame_ticks(8, 600) == list(range(8))


def test_a_jump_while_playing_plays_on_from_the_frame_jumped_to(window, qtbot):
    """Home, a click on the error curve, the frame box: while playing the clock went on from the frame shown
    before the jump, so playback sprang back there at the next tick (a user test found every jump ignored)."""
    timeline, curve = window.timeline, window.compare.curve
    window.activateWindow()
    qtbot.waitUntil(lambda: window.isActiveWindow(), timeout=5000)

    n = timeline.n_frames

    def jumps_to(jump, frame: int) -> None:
        qtbot.waitUntil(lambda: abs(timeline.frame - frame) > n // 5, timeout=20_000)  # played far from it
        jump()
        started = time.perf_counter()
        qtbot.wait(400)
        elapsed = time.perf_counter() - started
        assert frame <= timeline.frame <= frame + elapsed * timeline.clip_fps + 2, (frame, timeline.frame)

    timeline.set_frame(n // 2)
    timeline.set_playing(True)
    jumps_to(lambda: qtbot.keyClick(window, Qt.Key.Key_Home), 0)
    x = int(round(curve._x(n // 2)))
    jumps_to(lambda: qtbot.mouseClick(curve, Qt.MouseButton.LeftButton, pos=QPoint(x, curve.height() // 2)),
             curve.frame_at(x))
    jumps_to(lambda: timeline.spin.setValue(n // 5), n // 5)
    assert timeline.playing
    timeline.set_playing(False)


def test_contact_overlay_links_touching_pads_and_marks_lost_contacts(window):
    window.contact_overlay.trigger()
    source, target = window.view._hands[0].overlay, window.view._hands[1].overlay
    np.testing.assert_array_equal(target.lost, source.contacts & ~target.contacts)
    touching = np.flatnonzero(source.contacts.any(1))
    assert len(touching), "the clip has an OK sign: thumb and index touch on the source"
    frame = int(touching[0])
    window.timeline.set_frame(frame)
    assert source.links.n_lines == source.contacts[frame].sum() > 0
    assert target.lost_links.n_lines == target.lost[frame].sum()
    window.view.set_solo(0)  # the source alone, opaque: its pads' centres lie inside the fingers
    image = window.view.grab_rgb().astype(int)
    green = np.array(pv.Color(CONTACT_COLOUR).int_rgb)
    assert (np.abs(image - green).max(-1) < 10).sum() > 50, "the contact drawn over the skin"
    window.view.set_solo(-1)
    window.contact_overlay.trigger()
    assert not source.actors[1].visibility


@pytest.mark.parametrize("driver_flips", [True, False])
def test_the_view_shows_the_frame_upright_whoever_flips_it(window, driver_flips, monkeypatch):
    """The widget shows exactly what VTK drew (its screenshot path), top row first: read so by the driver
    (Mesa's pack invert, here under Xvfb) or flipped in numpy where a driver cannot."""
    from s2h_viewer.widgets import vtk_widget
    if driver_flips:
        assert vtk_widget.TOP_ROW_FIRST.begin(), "llvmpipe reads top row first"
        vtk_widget.TOP_ROW_FIRST.end()
    else:
        monkeypatch.setattr(vtk_widget.TOP_ROW_FIRST, "supported", False)
    view = window.view
    view.set_solo(1)  # one hand at the top of a white view: upside down it would be at the bottom
    view.interactor.render()
    shown = view.interactor.grab().toImage().convertToFormat(QImage.Format.Format_RGB888)
    pixels = np.frombuffer(shown.constBits(), np.uint8).reshape(shown.height(), shown.bytesPerLine())
    pixels = pixels[:, :3 * shown.width()].reshape(shown.height(), shown.width(), 3)
    np.testing.assert_array_equal(pixels, view.grab_rgb())


def test_the_heatmap_legend_stays_under_the_matrix_in_a_small_window(window, qtbot):
    """At 1000 x 700 the wrapped legend got less height than its lines and was drawn over the bottom rows."""
    window.resize(1000, 700)
    heatmap = window.heatmap
    qtbot.waitUntil(lambda: window.width() == 1000, timeout=5000)
    qtbot.waitUntil(lambda: heatmap.legend.geometry().top() > heatmap.matrix.geometry().bottom(), timeout=5000)
    assert heatmap.legend.height() >= heatmap.legend.heightForWidth(heatmap.legend.width())


def test_heatmap_tooltip_names_the_joint_pair(window):
    heatmap = window.heatmap
    row, column = topo.FINGER_JOINT_NAMES.index("index_tip"), topo.N_FINGER_JOINTS + 2
    text = heatmap.cell_text(LEFT + column * CELL + CELL // 2, TOP + row * CELL + CELL // 2)
    value = heatmap.current[row, column]
    assert text.startswith("index tip to palm anchor 3") and (f"{value:.3f}" in text or "masked" in text)
    assert heatmap.cell_text(2, 2) == ""


def test_heatmap_draws_each_cell_in_its_colour_beside_its_labels(window):
    from s2h_viewer.widgets.asm_heatmap import MASKED_GREY, colour_indices, colour_table
    heatmap = window.heatmap
    cell_error = np.linspace(0.0, 0.5, topo.N_FINGER_JOINTS * topo.N_ASM_COLUMNS).reshape(topo.N_FINGER_JOINTS, -1)
    cell_error[3, 7] = np.nan
    heatmap.show_matrix(cell_error, 12)
    image = heatmap.matrix.grab().toImage().convertToFormat(QImage.Format.Format_RGB888)
    assert (image.width(), image.height()) == (heatmap.matrix.width(), heatmap.matrix.height())
    pixels = np.frombuffer(image.constBits(), np.uint8).reshape(image.height(), image.bytesPerLine())
    pixels = pixels[:, :3 * image.width()].reshape(image.height(), image.width(), 3)
    expected = colour_table()[colour_indices(cell_error)]
    for row, column in ((0, 0), (3, 7), (19, 28), (10, 21)):
        centre = pixels[TOP + row * CELL + CELL // 2, LEFT + column * CELL + CELL // 2]
        np.testing.assert_array_equal(centre, expected[row, column])  # the colour map's colour, not swapped
    assert (pixels[TOP + 3 * CELL + 1, LEFT + 7 * CELL + 1] == MASKED_GREY).all()
    labels = pixels[TOP:, :LEFT - 4]  # the row names: dark text on white
    assert (labels.min(-1) < 100).any() and (labels.min(-1) == 255).mean() > 0.5


def test_camera_presets_turn_the_one_shared_camera(window):
    from s2h_viewer.render.compare_scene import CAMERA_PRESETS
    view_menu = next(a.menu() for a in window.menuBar().actions() if a.text() == "&View")
    presets = {a.text(): a for a in view_menu.actions() if a.text().startswith("Camera: ")}
    assert sorted(presets) == ["Camera: back", "Camera: palm", "Camera: reset", "Camera: side"]
    for text, preset in (("Camera: palm", "palm"), ("Camera: side", "side"), ("Camera: reset", "default")):
        presets[text].trigger()
        camera = window.view.plotter.camera
        direction = np.subtract(camera.position, camera.focal_point)
        expected = np.asarray(CAMERA_PRESETS[preset][0])
        np.testing.assert_allclose(direction / np.linalg.norm(direction), expected / np.linalg.norm(expected),
                                   atol=1e-9)
        cameras = {id(h.renderer.GetActiveCamera()) for h in window.view._hands}
        assert len(cameras) == 1  # every hand seen through the same camera: one scale


def test_heatmap_shows_the_frame_the_view_draws_at_4x(window, qtbot):
    from s2h_viewer.widgets.timeline import SPEEDS
    results = window.comparison.results
    window.scores.selectRow(1)  # ASRN -> iris: the heatmap follows the selection
    seen = []  # at every draw: the view's frame, and whether the heatmap holds that frame's matrix
    window.view.drawn.connect(lambda: seen.append((window.view.frame, np.array_equal(
        window.heatmap.current, results[1].cell_error[window.view.frame], equal_nan=True))))
    window.timeline.speed.setCurrentIndex(SPEEDS.index(4.0))
    window.timeline.set_playing(True)
    qtbot.waitUntil(lambda: len({f for f, _ in seen}) >= 8, timeout=30_000)
    window.timeline.set_playing(False)
    assert all(same for _, same in seen), seen
    assert window.heatmap.frame == window.view.frame == window.timeline.frame


def save_clip(sample_hands, path, gestures: tuple[str, ...] = ("thumbs_up", "fist")):
    """A short clip on birch written as a motion file, for loading through the window."""
    from s2h_viewer.io.npz import save_motion
    from s2h_viewer.motions.synthesis import synthesize
    save_motion(synthesize(list(gestures), sample_hands["birch"], seed=5, name=path.stem), path)
    return path


def recent(window) -> list[str]:
    return [a.text() for a in window.recent_menu.actions()]


def test_a_loaded_motion_keeps_the_selection_and_only_a_shown_load_is_recent(window, qtbot, sample_hands, tmp_path):
    window.scores.selectRow(1)  # ASRN -> iris
    clip = save_clip(sample_hands, tmp_path / "other.npz")
    shown = window.comparison
    window.load_motion(str(clip))
    with qtbot.waitSignal(window.comparison_ready, timeout=60_000):
        window.compare.cancel()  # what the progress dialog's Cancel does
    assert window.comparison is shown and "other.npz (motion)" not in recent(window)
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.load_motion(str(clip))
    assert window.comparison.motion.name == "other" and recent(window)[0] == "other.npz (motion)"
    selected = window.compare.selected_result()
    assert (selected.method, selected.target.name) == ("asrn", "iris")
    assert window.heatmap_choice.currentIndex() == 1 and window.scores.currentRow() == 1
    np.testing.assert_array_equal(window.compare.curve.error, selected.frame_error)


def test_a_cancelled_target_is_not_recent(window, qtbot):
    laurel = str(ASSETS_DIR / "hands" / "laurel.npz")
    window.add_target_file(laurel)
    with qtbot.waitSignal(window.comparison_ready, timeout=60_000):
        window.compare.cancel()
    assert "laurel.npz (target)" not in recent(window) and len(window.comparison.results) == 2
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.compare.undo_stack.redo()  # Cancel left the addition redoable: Redo shows laurel, so it is recent
    assert [r.target.name for r in window.comparison.results][2:] == ["laurel", "laurel"]
    assert recent(window) == ["laurel.npz (target)"]


def test_a_recent_file_that_is_gone_leaves_the_menu_with_a_dialog(window, qtbot, tmp_path):
    import shutil
    from PySide6.QtWidgets import QMessageBox

    laurel = shutil.copy(ASSETS_DIR / "hands" / "laurel.npz", tmp_path / "laurel.npz")
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(laurel))
    assert recent(window) == ["laurel.npz (target)"]
    laurel.unlink()  # moved or deleted since
    said = []
    when_shown(QMessageBox, lambda box: (said.append(box.text()), box.accept()))
    window.recent_menu.actions()[0].trigger()
    qtbot.waitUntil(lambda: bool(said), timeout=10_000)
    assert str(laurel) in said[0] and "removed from the recent files" in said[0]
    assert recent(window) == [] and not window.recent_menu.isEnabled()


def test_double_click_solo_selects_that_retarget(window, qtbot):
    view = window.view
    hand = 2  # ASRN -> iris
    x0, y0, x1, y1 = view.hand_viewports()[hand]
    w, h = view.interactor.width(), view.interactor.height()
    assert window.compare.selected_result() is window.comparison.results[0]
    qtbot.mouseDClick(view.interactor, Qt.MouseButton.LeftButton,
                      pos=QPoint(int((x0 + x1) / 2 * w), int((1 - (y0 + y1) / 2) * h)))
    assert view.solo == hand
    assert window.compare.selected_result() is window.comparison.results[1]
    assert window.heatmap_choice.currentIndex() == 1 and window.scores.currentRow() == 1
    np.testing.assert_array_equal(window.heatmap.current, window.comparison.results[1].cell_error[window.timeline.frame])


def test_export_dialogs_start_in_the_export_folder_with_a_suggested_name(window, qtbot, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QFileDialog

    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)  # no export yet: the working directory
    window.settings.setValue("files/last_dir", str(ASSETS_DIR / "hands"))  # the last hand's folder: not for exports
    offered = []

    def ask(export) -> str:
        when_shown(QFileDialog, lambda dialog: (offered.append(dialog.selectedFiles()[0]), dialog.reject()))
        assert export() is None  # the user cancels
        return offered.pop()

    window.timeline.set_frame(7)
    assert ask(window.export_screenshot) == str(work / "short_iris_tbs_copy_f0007.png")
    window.scores.selectRow(1)
    assert ask(window.export_motion) == str(work / "short_iris_asrn.glb")
    exported = tmp_path / "exports"
    exported.mkdir()
    window.export_screenshot(str(exported / "first.png"))  # an export: its folder is where the next ones start
    assert ask(window.export_video) == str(exported / "short_iris_asrn.mp4")
    assert not list(work.iterdir())


def test_an_export_writes_what_was_shown_when_asked_though_the_grid_changes_under_its_dialog(window, qtbot,
                                                                                          tmp_path):
    """A fresh-eyes user pressed Ctrl+S while another clip computed: the dialog offered the shown clip's name, the
    other clip came in while it waited, and the PNG held that one. Here the frame and the selection change while
    the dialog is up: the PNG is the grid as it was asked, under the caption and name of then; the motion is the
    retarget selected then."""
    from PIL import Image
    from PySide6.QtWidgets import QFileDialog

    from s2h_viewer.app.exports import Shown
    from s2h_viewer.render.caption import add_caption
    window.timeline.set_frame(7)
    window.scores.selectRow(0)
    asked = add_caption(window.view.grab_rgb(), Shown.of(window.compare).caption(7))
    offered = []

    def meanwhile(dialog, name: str) -> None:
        offered.append(Path(dialog.selectedFiles()[0]).name)
        window.timeline.set_frame(12)  # the grid moves on while the dialog waits
        window.scores.selectRow(1)
        dialog.selectFile(str(tmp_path / name))
        dialog.accept()
    when_shown(QFileDialog, lambda dialog: meanwhile(dialog, "asked.png"))
    png = window.export_screenshot()
    assert offered == ["short_iris_tbs_copy_f0007.png"] and png == tmp_path / "asked.png"
    written = np.asarray(Image.open(png).convert("RGB")).astype(int)
    assert written.shape == asked.shape and np.abs(written - asked).mean() < 1.0  # frame 7, TBS Copy framed
    now = add_caption(window.view.grab_rgb(), Shown.of(window.compare).caption(12)).astype(int)
    assert np.abs(now - asked).mean() > 1.0  # what the grid shows after the dialog is not what was asked
    window.timeline.set_frame(7)
    window.scores.selectRow(0)
    tbs_copy = window.compare.selected_result()
    when_shown(QFileDialog, lambda dialog: meanwhile(dialog, "asked.npz"))
    window._ask_frames = lambda path, what, shown: range(shown.comparison.n_frames)  # the frames dialog: all
    motion_file = window.export_motion()
    assert offered[-1] == "short_iris_tbs_copy.glb" and window.compare.selected_result() is not tbs_copy
    np.testing.assert_allclose(np.load(motion_file)["q_tbs"], tbs_copy.motion.q_tbs, atol=1e-6)


def test_two_jobs_show_their_progress_side_by_side_in_the_status_bar_covering_no_control(long_window, qtbot,
                                                                                         tmp_path):
    """Issue 25: the progress dialogs sat over Loop, the speed, the fps readout and the error curve."""
    from PySide6.QtCore import QRect
    from PySide6.QtWidgets import QAbstractButton, QAbstractSlider, QAbstractSpinBox, QComboBox

    from s2h_viewer.app.job_progress import WIDTH
    window = long_window
    job = window.export_video(str(tmp_path / "stacked.mp4"))
    qtbot.waitUntil(job.strip.isVisible, timeout=60_000)
    window.method_actions["asm_opt"].trigger()  # a retarget while the export runs: its own strip
    wait_until_running(window, qtbot, "asm_opt")
    retargets = window.compare._progress
    qtbot.waitUntil(retargets.isVisible, timeout=30_000)

    def on_screen(widget) -> QRect:
        return QRect(widget.mapToGlobal(widget.rect().topLeft()), widget.size())

    strips = [on_screen(job.strip), on_screen(retargets)]
    assert not strips[0].intersects(strips[1])
    bar = on_screen(window.statusBar())
    assert all(bar.contains(strip) for strip in strips)  # in the status bar, not floating over the window
    controls = [w for kind in (QAbstractButton, QAbstractSlider, QAbstractSpinBox, QComboBox)
                for w in window.compare.findChildren(kind) if w.isVisible()]
    controls += [window.compare.curve, window.compare.timeline, window.view, window.scores]
    assert len(controls) > 6
    for control in controls:
        assert not any(on_screen(control).intersects(strip) for strip in strips), control
    assert job.strip.width() == retargets.width() == WIDTH
    window.compare.cancel()
    with qtbot.waitSignal(job.cancelled, timeout=60_000):
        job.cancel()


def test_quitting_during_a_video_export_asks_and_never_leaves_a_partial_file(window, qtbot, tmp_path):
    from PySide6.QtWidgets import QMessageBox

    asked = []

    def answer(button: str):
        def click(box) -> None:
            asked.append(box.text())
            next(b for b in box.buttons() if b.text() == button).click()
        when_shown(QMessageBox, click)

    job = window.export_video(str(tmp_path / "kept.mp4"))
    with qtbot.waitSignal(job.progress, timeout=60_000):
        pass
    answer("Keep exporting")
    assert not window.close() and window.isVisible() and window.video_export is job
    assert "kept.mp4" in asked[0] and "writes no file" in asked[0]
    with qtbot.waitSignal(job.written, timeout=300_000):
        pass
    assert (tmp_path / "kept.mp4").stat().st_size > 0
    job = window.export_video(str(tmp_path / "dropped.mp4"))
    with qtbot.waitSignal(job.progress, timeout=60_000):
        pass
    counts = []  # the question's frame count, read twice a second apart while it is up

    def read_then_quit(box) -> None:
        counts.append(box.text())
        QTimer.singleShot(1000, lambda: (counts.append(box.text()),
                                         next(b for b in box.buttons() if b.text() == "Cancel export and quit").click()))
    when_shown(QMessageBox, read_then_quit)
    assert window.close() and not window.isVisible() and len(counts) == 2
    assert counts[0] != counts[1] and "dropped.mp4" in counts[1]  # the frames rendered meanwhile are counted
    assert not job.thread.is_alive()  # stopped before the window went
    assert sorted(p.name for p in tmp_path.iterdir() if p.suffix != ".ini") == ["kept.mp4"]  # no partial file


def test_quitting_while_a_video_export_ends_quits_once_it_is_written(window, qtbot, tmp_path):
    from PySide6.QtWidgets import QMessageBox

    job = window.export_video(str(tmp_path / "short.gif"))
    with qtbot.waitSignal(job.progress, timeout=60_000):
        pass
    asked = []

    def leave_it_up(box) -> None:  # the user leaves the question up until the export is written
        asked.append(box.text())
        keep = next(b for b in box.buttons() if b.text() == "Keep exporting")
        QTimer.singleShot(120_000, box, keep.click)  # else: a question that never goes (gone with the box)
    when_shown(QMessageBox, leave_it_up)
    assert window.close() and not window.isVisible()  # the question went away with the export: quit
    assert len(asked) == 1 and (tmp_path / "short.gif").stat().st_size > 0


def viewport_pixels(window, renderer) -> np.ndarray:
    """The part of the view's image that ``renderer`` draws (rows from the top)."""
    image = window.view.grab_rgb()
    h, w = image.shape[:2]
    x0, y0, x1, y1 = renderer.GetViewport()
    return image[int(round((1 - y1) * h)):int(round((1 - y0) * h)), int(round(x0 * w)):int(round(x1 * w))]


def test_skeleton_overlay_shows_through_an_opaque_skin(window, qtbot):
    window.timeline.set_frame(40)
    assert window.view.opacity == 1.0  # the skin opaque, as it starts
    hand = window.view._hands[2]
    off = viewport_pixels(window, hand.renderer).astype(int)
    window.skeleton_overlay.trigger()
    assert all(h.mesh_actor.prop.opacity < 1.0 for h in window.view._hands)
    on = viewport_pixels(window, hand.renderer).astype(int)
    changed = np.abs(on - off).max(-1) > 40
    assert changed.mean() > 0.02  # the bones (and the skin made see-through for them) are seen
    window.skeleton_overlay.trigger()
    assert all(h.mesh_actor.prop.opacity == 1.0 for h in window.view._hands)


def test_one_target_every_hand_fits_its_viewport(window):
    view = window.view
    view.set_selected(-1)  # no cell framed: the selection's frame lies on the edges this test looks at
    w, h = view.interactor.width(), view.interactor.height()
    x0, y0, x1, y1 = view.hand_viewports()[0]
    assert (x1 - x0) * w / ((y1 - y0) * h) < 0.6  # one target: tall, narrow cells
    for frame in (0, window.timeline.n_frames // 2):
        window.timeline.set_frame(frame)
        for hand in view._hands:
            pixels = viewport_pixels(window, hand.renderer)
            below_title = pixels[pixels.shape[0] // 6:]
            drawn = (below_title < 235).any(-1)  # skin, not the white background
            assert drawn.mean() > 0.02
            assert not drawn[:, :3].any() and not drawn[:, -3:].any(), "the hand is cut off at a side"


def test_colour_bar_title_clear_of_its_top_label(window):
    bar_renderer = window.view.plotter.renderers[-1]
    pixels = viewport_pixels(window, bar_renderer).astype(int)
    saturated = (pixels.max(-1) - pixels.min(-1)) > 120  # the colour bar itself (plasma is saturated)
    bar_top = int(np.flatnonzero(saturated.any(1))[0])
    dark = (pixels.max(-1) < 110).any(1)  # rows holding black text
    rows = np.flatnonzero(dark[:bar_top + 8])  # the title and the top label ("0.10") beside the bar's top
    runs = np.split(rows, np.flatnonzero(np.diff(rows) > 3) + 1)  # blank rows between the two
    assert len(runs) == 2, f"title and top label overlap: text rows {rows.tolist()}"


def test_a_long_target_name_is_elided_and_every_score_column_stays_in_view(window, qtbot, sample_hands):
    import dataclasses

    from s2h_viewer.widgets.scores_table import NAME_WIDTH
    long_name = "laurel_exported_from_a_vendor_rig_with_a_very_long_file_name_v2"
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.compare.add_target(dataclasses.replace(sample_hands["laurel"], name=long_name))
    table = window.scores
    assert table.columnWidth(1) <= NAME_WIDTH and long_name in table.item(2, 1).toolTip()
    last = table.columnCount() - 1
    assert table.columnViewportPosition(last) + table.columnWidth(last) <= table.viewport().width()


def test_a_png_asked_for_while_playing_is_the_frame_named(window, qtbot, tmp_path):
    from PySide6.QtWidgets import QFileDialog

    window.settings.setValue("files/export_dir", str(tmp_path))
    window.timeline.set_playing(True)
    qtbot.waitUntil(lambda: window.timeline.frame > 3, timeout=20_000)
    seen = []

    def save_after_a_while(dialog) -> None:  # the user takes half a second over the name, then saves
        seen.append((dialog.selectedFiles()[0], window.timeline.frame, window.timeline.playing))
        QTimer.singleShot(500, lambda: (seen.append(window.timeline.frame), dialog.accept()))

    when_shown(QFileDialog, save_after_a_while)
    written = window.export_screenshot()
    (offered, frame, playing), frame_when_saved = seen
    assert not playing and frame_when_saved == frame and offered.endswith(f"_f{frame:04d}.png")
    assert written == tmp_path / Path(offered).name and written.exists()
    assert window.timeline.playing  # and it plays on


def edit_menu_action(window, text: str):
    edit_menu = next(a.menu() for a in window.menuBar().actions() if a.text() == "&Edit")
    return next(a for a in edit_menu.actions() if a.text().startswith(text))


def test_undo_in_compare_never_undoes_the_hidden_annotate_tab(window, qtbot):
    window.activateWindow()
    qtbot.waitActive(window)  # the keys below go to the window's shortcuts
    window.annotate_file(str(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb"))
    view = window.annotate_view
    view.select(7)
    view.turn_selected(30)  # a turn in the Annotate tab
    turned = window.annotation.frames[7].copy()
    assert edit_menu_action(window, "Undo").text().startswith("Undo turn")
    window.tabs.setCurrentWidget(window.compare)
    qtbot.wait(200)
    undo = edit_menu_action(window, "Undo")
    assert not undo.isEnabled() and undo.text() == "Undo"  # Compare has nothing to undo
    QTest.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    np.testing.assert_array_equal(window.annotation.frames[7], turned)
    assert window.undo_stack.index() == 1
    window.tabs.setCurrentWidget(window.annotate.view)
    qtbot.wait(200)  # the tab's widgets settle before the key
    QTest.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)  # in Annotate it undoes the turn
    assert window.undo_stack.index() == 0


def test_removing_a_target_is_undone_with_its_results_not_recomputed(window, qtbot):
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(ASSETS_DIR / "hands" / "laurel.npz"))
    iris_results = window.comparison.results[:2]
    computed = len(window.compare.queue.computed)
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        removals(window)[0].trigger()  # Remove iris
    assert edit_menu_action(window, "Undo").text() == "Undo remove iris"
    window.activateWindow()
    qtbot.waitActive(window)  # Ctrl+Z goes to the window's shortcuts
    qtbot.wait(200)
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        QTest.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert window.statusBar().currentMessage() == "Undone: remove iris"  # the key says what it took back
    assert [r.target.name for r in window.comparison.results] == ["iris", "iris", "laurel", "laurel"]
    assert all(a is b for a, b in zip(window.comparison.results, iris_results))  # the same results: not recomputed
    assert len(window.compare.queue.computed) == computed
    assert [a.text() for a in removals(window)] == ["Remove iris", "Remove laurel"]
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        QTest.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert window.statusBar().currentMessage() == "Redone: remove iris"
    assert [a.text() for a in removals(window)] == ["Remove laurel"]


def test_reticking_a_method_takes_its_results_from_the_cache(window, qtbot):
    asrn = window.comparison.results[1]
    computed = len(window.compare.queue.computed)
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        window.method_actions["asrn"].trigger()  # untick
    assert grid_methods(window) == ["tbs_copy"]
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        window.method_actions["asrn"].trigger()  # tick again
    assert grid_methods(window) == ["tbs_copy", "asrn"] and window.comparison.results[1] is asrn
    assert len(window.compare.queue.computed) == computed


def test_the_users_camera_stays_when_the_grid_changes(window, qtbot):
    view = window.view
    preset = np.array(view.plotter.camera.position)
    QTest.mouseMove(view.interactor, QPoint(100, 100))  # drag in the source's viewport: turn the camera
    drag_from, drag_to = QPoint(80, 120), QPoint(200, 60)
    QTest.mousePress(view.interactor, Qt.MouseButton.LeftButton, pos=drag_from)
    for step in range(1, 9):
        QTest.mouseMove(view.interactor, drag_from + (drag_to - drag_from) * step / 8)
    QTest.mouseRelease(view.interactor, Qt.MouseButton.LeftButton, pos=drag_to)
    camera = view.plotter.camera
    dragged = (camera.position, camera.focal_point, camera.up)
    assert np.linalg.norm(np.subtract(dragged[0], preset)) > 1e-3 * np.linalg.norm(preset)  # the drag turned it
    with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
        window.method_actions["asrn"].trigger()  # a new grid
    camera = view.plotter.camera
    np.testing.assert_allclose(camera.position, dragged[0])
    np.testing.assert_allclose(camera.up, dragged[2])
    assert len({id(h.renderer.GetActiveCamera()) for h in view._hands}) == 1  # one camera: one scale
    window.skeleton_overlay.trigger()  # an overlay leaves the camera alone too
    np.testing.assert_allclose(view.plotter.camera.position, dragged[0])


def test_a_click_on_the_timeline_groove_jumps_to_that_frame(window, qtbot):
    from PySide6.QtWidgets import QStyle, QStyleOptionSlider
    slider = window.timeline.slider
    window.timeline.set_frame(0)
    option = QStyleOptionSlider()
    slider.initStyleOption(option)
    groove = slider.style().subControlRect(QStyle.ComplexControl.CC_Slider, option,
                                           QStyle.SubControl.SC_SliderGroove, slider)
    handle = slider.style().subControlRect(QStyle.ComplexControl.CC_Slider, option,
                                           QStyle.SubControl.SC_SliderHandle, slider)
    span = groove.width() - handle.width()
    x = groove.left() + handle.width() // 2 + int(0.75 * span)
    QTest.mouseClick(slider, Qt.MouseButton.LeftButton, pos=QPoint(x, slider.height() // 2))
    expected = QStyle.sliderValueFromPosition(0, slider.maximum(), x - groove.left() - handle.width() // 2, span)
    assert abs(window.timeline.frame - expected) <= 1 and window.timeline.frame > 0.7 * slider.maximum()


def test_the_selected_retarget_is_a_highlighted_row_of_the_scores_table(window, qtbot):
    from PySide6.QtGui import QPalette
    table = window.scores
    window.resize(1200, 1000)  # room under the two rows
    qtbot.waitUntil(lambda: table.viewport().height() > table.visualItemRect(table.item(1, 3)).bottom() + 20)
    cell = table.visualItemRect(table.item(1, 3)).center()
    QTest.mouseClick(table.viewport(), Qt.MouseButton.LeftButton, pos=cell)
    assert window.heatmap_choice.currentIndex() == 1
    assert [i.row() for i in table.selectionModel().selectedRows()] == [1]  # the whole row, not one cell
    below = QPoint(cell.x(), table.viewport().height() - 3)  # empty space under the rows
    assert table.indexAt(below).row() == -1
    QTest.mouseClick(table.viewport(), Qt.MouseButton.LeftButton, pos=below)
    assert [i.row() for i in table.selectionModel().selectedRows()] == [1]  # still shows the selection
    window.view.set_solo(1)  # solo the first retarget: it is selected
    assert [i.row() for i in table.selectionModel().selectedRows()] == [0]
    palette = table.palette()  # the highlight as visible with the focus elsewhere (the 3D view)
    assert palette.color(QPalette.ColorGroup.Inactive, QPalette.ColorRole.Highlight) == palette.color(
        QPalette.ColorGroup.Active, QPalette.ColorRole.Highlight)


def folder_offered(open_dialog) -> Path:
    """The folder the file dialog that ``open_dialog()`` shows starts in (the dialog then cancelled)."""
    from PySide6.QtWidgets import QFileDialog

    offered = []
    when_shown(QFileDialog, lambda dialog: (offered.append(dialog.directory().absolutePath()), dialog.reject()))
    open_dialog()
    return Path(offered.pop())


def test_add_target_hand_opens_in_the_last_hand_folder_else_the_shipped_hands(window, qtbot, tmp_path):
    import shutil

    assert folder_offered(window.add_target) == (ASSETS_DIR / "hands").resolve()  # no hand opened yet: the shipped ones
    folder = tmp_path / "avatars"
    folder.mkdir()
    hand = shutil.copy(ASSETS_DIR / "hands" / "laurel.npz", folder / "laurel.npz")
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(hand))
    window.export_screenshot(str(tmp_path / "shot.png"))  # an export elsewhere does not move the hand folder
    assert folder_offered(window.add_target) == folder.resolve()


def test_a_hand_file_named_at_launch_is_where_the_next_hand_is_looked_for(qtbot, sample_hands, tmp_path):
    """`s2h view --target avatars/x.vrm`: Annotate > Open hand and Add target start beside it (a fresh-eyes user's
    Open hand started in the shipped hands, far from the avatar it was told to check in Annotate)."""
    import shutil

    from compare_window import open_window
    from s2h_viewer.app.compare_mode import CompareSetup
    from s2h_viewer.io.files import load_hand_file
    avatars = tmp_path / "avatars"
    avatars.mkdir()
    hand = load_hand_file(shutil.copy(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb", avatars / "x.glb"))
    from s2h_viewer.samples import load_sample_motions
    gestures = next(m for m in load_sample_motions() if m.name.startswith("gestures"))
    win = open_window(qtbot, CompareSetup(gestures, sample_hands["birch"], [hand], ["tbs_copy"]), tmp_path,
                      compute=False)
    assert folder_offered(win.open_hand_to_annotate) == avatars.resolve()
    assert folder_offered(win.add_target) == avatars.resolve()
    win.settings.sync()
    # the next launch on a shipped hand keeps it: the shipped hands' folder is no folder of the user's
    shipped = load_hand_file(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb")
    again = open_window(qtbot, CompareSetup(gestures, sample_hands["birch"], [shipped], ["tbs_copy"]), tmp_path,
                        compute=False)
    assert folder_offered(again.add_target) == avatars.resolve()


def test_a_shipped_real_rig_named_at_launch_is_where_the_next_hand_is_looked_for_if_no_folder_is_remembered(
        qtbot, sample_hands, tmp_path):
    """A fresh-eyes user launched on --target assets/hands/real/cryptovoxels.vrm; Add target hand then opened in the
    sample hands' folder. It starts beside the shipped rig now, but only where no folder of the user's is remembered
    (the test above), and it is not remembered; a sample hand named by its file leaves the sample hands' folder."""
    from compare_window import open_window, short_clip
    from s2h_viewer.app.compare_mode import CompareSetup
    from s2h_viewer.io.files import load_hand_file

    real = ASSETS_DIR / "hands" / "real" / "godot_hand_r.gltf"
    birch = sample_hands["birch"]
    fresh = tmp_path / "fresh"
    fresh.mkdir()
    win = open_window(qtbot, CompareSetup(short_clip(birch), birch, [sample_hands["iris"], load_hand_file(real)],
                                          ["tbs_copy"]), fresh, compute=False)
    assert folder_offered(win.add_target) == real.parent.resolve()
    assert folder_offered(win.open_hand_to_annotate) == real.parent.resolve()
    assert win.settings.value("files/hand_dir", "") == ""
    samples_only = tmp_path / "samples_only"
    samples_only.mkdir()
    sample = load_hand_file(ASSETS_DIR / "hands" / "iris.npz")
    win = open_window(qtbot, CompareSetup(short_clip(birch), birch, [sample], ["tbs_copy"]), samples_only,
                      compute=False)
    assert folder_offered(win.add_target) == (ASSETS_DIR / "hands").resolve()


def test_open_motion_opens_in_the_last_motion_folder_not_the_last_hand_folder(window, qtbot, tmp_path):
    import shutil

    assert folder_offered(window.open_motion) == (ASSETS_DIR / "motions").resolve()  # none opened: the shipped ones
    clips, avatars = tmp_path / "clips", tmp_path / "avatars"
    clips.mkdir()
    avatars.mkdir()
    motion = shutil.copy(ASSETS_DIR / "motions" / "gestures.npz", clips / "gestures.npz")
    with qtbot.waitSignal(window.comparison_ready, timeout=300_000):
        window.load_motion(str(motion))
    hand = shutil.copy(ASSETS_DIR / "hands" / "laurel.npz", avatars / "laurel.npz")
    with qtbot.waitSignal(window.comparison_ready, timeout=300_000):
        window.add_target_file(str(hand))  # a target from elsewhere does not move the motion folder
    assert folder_offered(window.open_motion) == clips.resolve()


def test_a_gif_is_written_while_its_frames_render_and_cancel_leaves_no_file(window, qtbot, tmp_path):
    """The GIF grows as the progress moves (Pillow once wrote it all after the last frame, the dialog at 100%
    meanwhile); a cancel halfway leaves neither the file nor a temporary one."""
    n = window.comparison.n_frames
    written_at_half = []

    def look(done: int, total: int) -> None:
        if done >= total // 2 and not written_at_half:
            written_at_half.append(sum(p.stat().st_size for p in tmp_path.glob(".clip.s2h-*.gif")))
    job = window.export_video(str(tmp_path / "clip.gif"))
    job.progress.connect(look)
    with qtbot.waitSignal(job.written, timeout=300_000):
        pass
    assert written_at_half[0] > 0  # half the frames rendered: (about) half the file on disk already
    frames = imageio.mimread(tmp_path / "clip.gif", memtest=False)
    assert len(frames) == n and frames[0].shape[0] == window.view.interactor.height() + BAND

    job = window.export_video(str(tmp_path / "late.gif"))
    job.progress.connect(lambda done, total: done >= total // 2 and job.strip.findChild(QPushButton).click())
    with qtbot.waitSignal(job.cancelled, timeout=300_000):
        pass
    job.thread.join()
    assert sorted(p.name for p in tmp_path.iterdir() if p.suffix != ".ini") == ["clip.gif"]


def test_a_gif_lasts_as_long_as_its_clip(window, qtbot, tmp_path):
    """GIF delays count centiseconds: at 30 fps the frames wait 3, 3 and 4 cs in turn, not 3 cs each (which
    played the clip 11% fast)."""
    n, fps = window.comparison.n_frames, window.comparison.motion.fps
    job = window.export_video(str(tmp_path / "clip.gif"))
    with qtbot.waitSignal(job.written, timeout=300_000):
        pass
    with Image.open(tmp_path / "clip.gif") as gif:
        delays = []
        for index in range(gif.n_frames):
            gif.seek(index)
            delays.append(gif.info["duration"])
    assert abs(sum(delays) - 1000.0 * n / fps) <= 10.0
    assert set(delays) <= {30, 40} and 40 in delays


def test_a_take_name_with_a_bar_is_drawn_as_written(window, qtbot, sample_hands):
    """An FBX take "Armature|counting": VTK's default text backend read the '|' as a column break (drawn as
    "Armature   counting", a larger box in another font); the grid's legend draws it as plain text, as wide
    as the same line with '!' (a glyph about as narrow) in its place."""
    from vtkmodules.vtkRenderingCore import vtkTextRenderer
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.compare.add_target(sample_hands["laurel"])
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.load_motion(str(ASSETS_DIR / "hands" / "fbx" / "mixamo_right_hand.fbx"))
    assert window.comparison.motion.name == "Armature|counting"
    actor = next(a for r in window.view.plotter.renderers for a in r.GetViewProps()
                 if hasattr(a, "GetInput") and "Armature" in (a.GetInput() or ""))  # the legend under the source
    text = actor.GetInput()
    boxes = []
    for line in (text, text.replace("|", "!")):
        box = [0, 0, 0, 0]
        assert vtkTextRenderer.GetInstance().GetBoundingBox(actor.GetTextProperty(), line, box, 72)
        boxes.append(box)
    assert boxes[0][3] == boxes[1][3] and abs(boxes[0][1] - boxes[1][1]) <= 8, boxes


def test_a_retarget_shown_alone_keeps_the_colour_bar(window, qtbot):
    """Solo (Ctrl+M or a double-click) showed the hand over the whole view without the colour bar its skin's
    colours are read against; the bar keeps its column, right of the hand, and the grid comes back whole."""
    def bar_pixels() -> int:
        image = window.view.grab_rgb().astype(int)
        strip = image[:, int(image.shape[1] * (1 - COLOUR_BAR_SHARE)):]
        return int(((strip.max(-1) - strip.min(-1)) > 120).sum())  # plasma is saturated, the skin not there

    in_grid = bar_pixels()
    assert in_grid > 2 * window.view.interactor.height()  # the bar: 80% of the view's height, some pixels wide
    window.timeline.set_frame(40)
    window.scores.selectRow(1)  # ASRN -> iris
    window.activateWindow()
    qtbot.waitUntil(lambda: window.isActiveWindow(), timeout=5000)
    qtbot.keyClick(window.timeline.spin.lineEdit(), Qt.Key.Key_M, Qt.KeyboardModifier.ControlModifier)
    assert window.view.solo == 2  # ASRN -> iris, the selected retarget
    assert bar_pixels() > 0.5 * in_grid
    solo = window.view._hands[2].renderer
    assert solo.GetViewport()[2] <= 1 - COLOUR_BAR_SHARE + 1e-9  # the hand clear of the bar
    qtbot.keyClick(window.timeline.spin.lineEdit(), Qt.Key.Key_M, Qt.KeyboardModifier.ControlModifier)
    assert window.view.solo == -1 and all(r.GetDraw() for r in window.view.plotter.renderers)
    assert tuple(window.view.plotter.renderers[-1].GetViewport()) == window.view._viewports[-1]


def test_labels_stay_legible_with_five_methods(qtbot, sample_hands, tmp_path):
    """Five methods on a 1000 x 700 window: the labels (method -> target, the scores) were drawn by corner
    annotations that shrink with their cell, to glyphs 5 pixels high. Their font shrinks with a cell narrower
    than a score line at LABEL_PX (some 70 pixels here), to MIN_LABEL_PX at least: glyphs 6 pixels high and
    more, each line whole in its cell."""
    window = open_compare_window(qtbot, sample_hands, tmp_path, methods=tuple(METHODS))
    try:
        image = window.view.grab_rgb()
        for hand in window.view._hands[:2]:  # the source, the first retarget
            cell = cell_pixels(image, hand.renderer)
            dark = np.flatnonzero((cell[: cell.shape[0] // 3].max(-1) < 110).any(1))  # rows with black text
            lines = np.split(dark, np.flatnonzero(np.diff(dark) > 1) + 1)
            assert len(lines) >= 1 and len(lines[0]) >= 6, [len(line) for line in lines]
            (actor,) = text_actors(hand.renderer)
            assert actor.GetTextProperty().GetFontSize() >= MIN_LABEL_PX
            assert inside(text_box(actor, hand.renderer), cell)
    finally:
        window.close()


def test_a_crowded_grid_keeps_each_label_whole_or_elided_in_a_band_clear_of_the_hands(qtbot, sample_hands, tmp_path):
    """Four targets x five methods on a 1000 x 700 window (pages of the rows that fit, cells some 70 pixels wide):
    the titles and scores were cut mid-letter at the cells' edges and drawn over the hands, their skeletons and contact dots. Now
    each line is whole or a start of it with an ellipsis, inside its cell, in a font no smaller than
    MIN_LABEL_PX, and nothing but the text is drawn from a cell's top down to the text's bottom."""
    import dataclasses
    long_name = "elm_exported_from_a_vendor_rig"
    hands = {**sample_hands, long_name: dataclasses.replace(sample_hands["elm"], name=long_name)}
    four = ("iris", "laurel", "kale", long_name)
    window = open_compare_window(qtbot, hands, tmp_path, methods=tuple(METHODS), targets=four)
    try:
        view = window.view
        every = [f"{METHODS[r.method].label} -> {r.target.name}" for r in window.comparison.results]
        assert view.page_count == -(-len(four) // view.rows) > 1  # four rows do not fit 1000 x 700: they page
        seen, elided = [], []
        for page in range(view.page_count):
            view.set_page(page)
            view.set_selected(-1)  # no cell framed: the selection's frame runs through the label rows looked at
            titles = [f"source: {window.comparison.source.name}"] + [
                f"{METHODS[r.method].label} -> {r.target.name}" for r in view.comparison.results]
            assert len(view._hands) == len(titles) == 1 + view.rows * len(METHODS) or page == view.page_count - 1
            seen += titles[1:]
            for hand, title in zip(view._hands, titles):
                (actor,) = text_actors(hand.renderer)
                line = actor.GetInput().split("\n")[0]
                assert line == title or (line.endswith(ELLIPSIS) and title.startswith(line[:-1])), (line, title)
                assert actor.GetTextProperty().GetFontSize() >= MIN_LABEL_PX
                elided += [title] if line != title else []
            for frame, overlays in ((0, False), (window.timeline.n_frames // 2, False), (40, True)):
                window.timeline.set_frame(frame)
                view.set_options(skeleton=overlays, contacts=overlays)
                image = view.grab_rgb()
                for renderer in view.plotter.renderers:
                    for actor in text_actors(renderer):
                        cell, box = cell_pixels(image, renderer), text_box(actor, renderer)
                        assert inside(box, cell), (actor.GetInput(), box, cell.shape)
                for hand in view._hands:
                    label = text_actors(hand.renderer)[0]
                    cell, box = cell_pixels(image, hand.renderer), text_box(label, hand.renderer)
                    assert intruders(cell, box) == 0, (frame, overlays, label.GetInput())
                    assert hand_drawn(cell) > 0.05 * cell.shape[0] * cell.shape[1]  # the hand still drawn below
                    if overlays:  # dots sized for the cell: the default scene's 16 pixels hid a small cell's hand
                        size = hand.overlay.actors[1].prop.point_size
                        assert OVERLAY_LEAST[2] <= size <= max(OVERLAY_LEAST[2],
                                                               OVERLAY_PX[2] * min(cell.shape[:2]) / 250)
        assert sorted(seen) == sorted(every)  # every retarget on one page
        assert {t for t in every if long_name in t} <= set(elided), elided  # a long name ends in an ellipsis
    finally:
        window.close()


def test_ticking_a_method_and_adding_a_target_are_undone_and_redone_from_the_cache(window, qtbot):
    """Ctrl+Z undid only a removed target; ticking a method and adding a target are undone and redone too,
    the menus, the settings and the grid agreeing each time, and nothing computed twice."""
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.method_actions["dm"].trigger()
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(ASSETS_DIR / "hands" / "laurel.npz"))
    results = list(window.comparison.results)
    computed = len(window.compare.queue.computed)
    window.activateWindow()
    qtbot.waitActive(window)  # the keys go to the window's shortcuts
    qtbot.wait(200)

    def key(modifiers) -> None:
        with qtbot.waitSignal(window.comparison_ready, timeout=10_000):
            QTest.keyClick(window, Qt.Key.Key_Z, modifiers)

    def agree(methods: list[str], targets: list[str]) -> None:
        assert ticked(window) == methods == list(window.settings.value("compare/methods"))
        assert grid_methods(window) == methods * len(targets)
        assert list(dict.fromkeys(r.target.name for r in window.comparison.results)) == targets
        assert [a.text() for a in removals(window)] == [f"Remove {t}" for t in targets]
        assert all(any(r is s for s in results) for r in window.comparison.results)  # the results computed once

    assert edit_menu_action(window, "Undo").text() == "Undo add laurel"
    key(Qt.KeyboardModifier.ControlModifier)
    agree(["tbs_copy", "dm", "asrn"], ["iris"])
    assert edit_menu_action(window, "Undo").text() == "Undo tick DM"
    key(Qt.KeyboardModifier.ControlModifier)
    agree(["tbs_copy", "asrn"], ["iris"])
    key(Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)  # redo
    agree(["tbs_copy", "dm", "asrn"], ["iris"])
    key(Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    agree(["tbs_copy", "dm", "asrn"], ["iris", "laurel"])
    assert len(window.compare.queue.computed) == computed


def answer_video_export(qtbot, choose_frames) -> None:
    """File > Export video as a user answers it: the file dialog's suggested name saved, then the frames dialog
    answered by ``choose_frames(dialog)``."""
    from PySide6.QtWidgets import QFileDialog

    from s2h_viewer.widgets.frame_range_dialog import FrameRangeDialog
    when_shown(QFileDialog, lambda dialog: dialog.accept())
    when_shown(FrameRangeDialog, choose_frames)


def test_a_video_export_writes_the_frames_chosen_with_their_own_frame_numbers(window, qtbot, tmp_path):
    """The frames dialog after the file: the whole clip at first, "From the current frame" and an edited To give
    frames 40 to 47; the file holds those eight, the first one frame 40 as the window shows it, captioned 40."""
    from PySide6.QtWidgets import QDialogButtonBox

    from s2h_viewer.app.exports import Shown
    from s2h_viewer.render.caption import add_caption
    n = window.comparison.n_frames
    window.settings.setValue("files/export_dir", str(tmp_path))
    shots = {}
    for frame in (0, 40):
        window.timeline.set_frame(frame)
        shots[frame] = window.export_screenshot(str(tmp_path / f"f{frame}.png"))
    offered = []

    def from_40_to_47(dialog) -> None:
        offered.append((dialog.start.value(), dialog.end.value()))
        qtbot.mouseClick(dialog.from_current, Qt.MouseButton.LeftButton)
        offered.append((dialog.start.value(), dialog.end.value()))
        dialog.end.setValue(47)
        offered.append(dialog.summary.text())
        qtbot.mouseClick(dialog.buttons.button(QDialogButtonBox.StandardButton.Ok), Qt.MouseButton.LeftButton)

    answer_video_export(qtbot, from_40_to_47)
    job = window.export_video()
    assert offered == [(0, n - 1), (40, n - 1), f"8 frames, {8 / window.comparison.motion.fps:.2f} s"]
    assert job.strip.maximum() == 8 and "(8 frames: 40 to 47)" in job.strip.toolTip()  # progress counts the range
    assert job.strip.labelText().splitlines()[-1] == "(8 frames: 40 to 47)..."  # whole, however long the name
    with qtbot.waitSignal(job.written, timeout=300_000):
        pass
    path = tmp_path / "short_iris_tbs_copy.mp4"
    assert window.statusBar().currentMessage() == f"wrote {path} (8 frames: 40 to 47)"
    reader = imageio.get_reader(path)
    assert reader.count_frames() == 8
    first = reader.get_data(0).astype(int)
    reader.close()
    height, width = window.view.interactor.height(), window.view.interactor.width()
    grid = {frame: imageio.imread(shot)[:height, :, :3].astype(int) for frame, shot in shots.items()}
    off = {frame: np.abs(first[:height, :width] - image).mean() for frame, image in grid.items()}
    assert off[40] < 0.5 * off[0]  # the hands of frame 40, not of the clip's first frame
    band = first[height:height + BAND, :width]
    captions = {frame: add_caption(np.zeros((0, width, 3), np.uint8), Shown.of(window.compare).caption(frame)).astype(int)
                for frame in (0, 40, 41)}
    error = {frame: ((band - caption) ** 2).sum() for frame, caption in captions.items()}
    assert error[40] < min(error[0], error[41])  # "frame 40/...": the clip's own frame number


def test_a_backwards_range_cannot_be_exported_and_cancel_writes_nothing(window, qtbot, tmp_path):
    """From after To: Export disabled, Return does nothing, the dialog says why; Cancel writes no file, says so,
    and the keyboard goes back to the window. Playback pauses while the user chooses (From the current frame is
    the frame shown) and plays on after."""
    from PySide6.QtWidgets import QDialogButtonBox
    window.settings.setValue("files/export_dir", str(tmp_path))
    window.activateWindow()
    qtbot.waitActive(window)
    window.timeline.set_playing(True)
    qtbot.waitUntil(lambda: window.timeline.frame > 3, timeout=20_000)
    seen = []

    def backwards_then_cancel(dialog) -> None:
        export = dialog.buttons.button(QDialogButtonBox.StandardButton.Ok)
        seen.append((window.timeline.playing, window.timeline.frame, dialog.from_current.text()))
        dialog.choose_from_current()
        dialog.end.setValue(dialog.start.value() + 2)
        qtbot.mouseClick(dialog.whole_clip, Qt.MouseButton.LeftButton)
        seen.append((dialog.start.value(), dialog.end.value()))
        dialog.choose_from_current()
        dialog.end.setValue(dialog.start.value() - 1)
        seen.append((export.isEnabled(), dialog.summary.text()))
        qtbot.keyClick(dialog.end, Qt.Key.Key_Return)
        seen.append(dialog.isVisible())
        qtbot.mouseClick(dialog.buttons.button(QDialogButtonBox.StandardButton.Cancel), Qt.MouseButton.LeftButton)

    answer_video_export(qtbot, backwards_then_cancel)
    assert window.export_video() is None
    (playing, frame, quick), whole, (enabled, summary), still_up = seen
    assert not playing and quick == f"From the current frame ({frame})" and whole == (0, window.comparison.n_frames - 1)
    assert not enabled and summary == f"From ({frame}) is after To ({frame - 1}): nothing to export" and still_up
    assert window.video_export is None and not [p for p in tmp_path.iterdir() if p.suffix != ".ini"]
    assert window.statusBar().currentMessage() == "video export cancelled: no file written (short_iris_tbs_copy.mp4)"
    assert window.timeline.playing
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)


def test_both_hands_of_a_character_are_told_apart_in_the_grid_table_and_export_names(qtbot, sample_hands, tmp_path):
    """`s2h view --target human-female.glb --side right` and its left hand added: both read "human-female" (the
    file's stem) in every cell, row and export name. The left one is "human-female (left)" now, and adding it again
    is refused as the same hand."""
    from compare_window import open_window, short_clip
    from s2h_viewer.app.compare_mode import CompareSetup
    from s2h_viewer.io.files import RigOptions, load_hand_file

    female = ASSETS_DIR / "hands" / "real" / "human-female.glb"
    right, left = (load_hand_file(female, RigOptions(side=side)) for side in ("right", "left"))
    birch = sample_hands["birch"]
    win = open_window(qtbot, CompareSetup(short_clip(birch), birch, [right], ["tbs_copy"]), tmp_path)
    with qtbot.waitSignal(win.comparison_ready, timeout=120_000):
        added = win.compare.add_target(left)
    assert added is not left and added.name == "human-female (left)" and left.name == "human-female"
    table = win.scores
    rows = [table.item(row, 1).text().removeprefix("! ") for row in range(table.rowCount())]  # "!": a warning
    assert rows == ["human-female", "human-female (left)"]
    assert [hand.label.text.split("\n")[0] for hand in win.view._hands[1:]] == [
        "TBS Copy -> human-female", "TBS Copy -> human-female (left)"]
    table.selectRow(1)
    from s2h_viewer.app.exports import Shown
    assert Shown.of(win.compare).name(".glb") == "short_human-female-left_tbs_copy.glb"
    from PySide6.QtWidgets import QMessageBox
    shown = []
    when_shown(QMessageBox, lambda box: (shown.append(box.text()), box.accept()))
    assert win.compare.add_target(load_hand_file(female, RigOptions(side="left"))) is None
    assert "is a target already" in shown[0] and len(win.compare.state.targets) == 2


def test_add_target_asks_which_hand_of_a_character_and_both_adds_each_named_by_its_side(qtbot, sample_hands,
                                                                                       tmp_path):
    """File > Add target hand on a character's file (both hands) took its right hand, and the left only came from
    launching with --side left: it asks which, and "Both hands" adds the two, the left one named so; the right one
    alone adds it alone, and Cancel adds nothing. Added together, each is named by its side."""
    from PySide6.QtWidgets import QMessageBox

    from compare_window import open_window, short_clip
    from s2h_viewer.app.compare_mode import CompareSetup

    birch = sample_hands["birch"]
    win = open_window(qtbot, CompareSetup(short_clip(birch), birch, [sample_hands["iris"]], ["tbs_copy"]), tmp_path,
                      compute=False)
    asked = []

    def answer(label: str):
        def click(box: QMessageBox) -> None:
            asked.append((box.text(), [button.text() for button in box.buttons()]))
            next(button for button in box.buttons() if button.text() == label).click()
        when_shown(QMessageBox, click)

    character = ASSETS_DIR / "hands" / "real" / "human-female.glb"
    answer("Cancel")
    win.add_target_file(str(character))
    assert len(win.compare.state.targets) == 1
    answer("Both hands")
    win.add_target_file(str(character))
    assert asked[-1][0] == "human-female.glb has both hands."
    assert set(asked[-1][1]) == {"Right hand", "Left hand", "Both hands", "Cancel"}
    targets = win.compare.state.targets
    assert [(t.name, t.meta.get("side")) for t in targets] == [
        ("iris", None), ("human-female (right)", "right"), ("human-female (left)", "left")]
    assert not targets[1].same_as(targets[2])
    answer("Right hand")  # the right one again: the same hand, refused
    said = []
    win.error = said.append
    win.compare.error = said.append
    win.add_target_file(str(character))
    assert len(win.compare.state.targets) == 3 and "is a target already" in said[0]
    win.add_target_file(str(ASSETS_DIR / "hands" / "real" / "godot_hand_l.gltf"))  # a lone hand: no question
    assert len(asked) == 3 and win.compare.state.targets[-1].name == "godot_hand_l"
    from dataclasses import replace
    win.open_options = replace(win.open_options, side="left")  # `s2h view --side left`: its hand, asking nothing
    win.add_target_file(str(ASSETS_DIR / "hands" / "real" / "RPM_Template_Mesh_XR.glb"))
    assert len(asked) == 3 and win.compare.state.targets[-1].meta["side"] == "left"
