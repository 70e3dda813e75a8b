"""The real desktop window, driven headless (Xvfb) with pytest-qt: compare mode, timeline, exports, errors."""

from __future__ import annotations

import os

import numpy as np
import pytest

pytest.importorskip("pytestqt")
if not os.environ.get("DISPLAY"):
    pytest.skip("the Qt viewport needs an X display: `make test` runs the suite under Xvfb", allow_module_level=True)

from PySide6.QtGui import QAction  # noqa: E402
from PySide6.QtWidgets import QMessageBox  # noqa: E402

from compare_window import open_compare_window, when_shown  # noqa: E402


@pytest.fixture
def window(qtbot, sample_hands, tmp_path):
    return open_compare_window(qtbot, sample_hands, tmp_path)


def test_compare_mode_shows_two_methods_and_their_scores(qtbot, sample_hands, tmp_path):
    window = open_compare_window(qtbot, sample_hands, tmp_path, computed_here=True)  # the window computes them
    assert window.compare.queue.computed == window.compare.state.wanted()
    comparison = window.comparison
    assert [r.method for r in comparison.results] == ["tbs_copy", "asrn"]
    assert window.scores.rowCount() == 2 and window.scores.item(1, 0).text() == "ASRN"
    assert window.heatmap_choice.count() == 2
    assert window.timeline.n_frames == comparison.n_frames


def test_a_retarget_that_makes_no_contact_has_no_precision_in_the_scores(qtbot, sample_hands, tmp_path):
    # TBS Copy onto laurel loses every touch of the clip, ASRN keeps them (onto iris TBS Copy's OK sign touches at
    # the fingertips, and its precision is defined)
    window = open_compare_window(qtbot, sample_hands, tmp_path, targets=("laurel",))
    tbs_copy, asrn = window.comparison.results
    assert np.isnan(tbs_copy.scores.contact_precision) and tbs_copy.scores.contact_recall == 0.0
    precision = window.scores.item(0, 4)  # Contact P
    assert precision.text() == "n/a" and "no pad contact" in precision.toolTip()
    assert window.scores.item(0, 5).text() == "0.000"  # its recall is defined: nothing kept
    assert window.scores.item(1, 4).text() == f"{asrn.scores.contact_precision:.3f}"


def test_timeline_steps_and_keys_move_every_view(window, qtbot):
    before = window.view._hands[1].mesh.points.copy()
    window.timeline.step(5)
    assert window.timeline.frame == 5 and window.timeline.spin.value() == 5
    after = window.view._hands[1].mesh.points
    assert np.abs(after - before).max() > 1e-4  # the retargeted hand moved
    np.testing.assert_allclose(window.heatmap.current, window.comparison.results[0].cell_error[5], equal_nan=True)
    window.timeline.set_frame(window.timeline.n_frames - 1)
    window.timeline.step(1)
    assert window.timeline.frame == window.timeline.n_frames - 1  # clamped at the end
    with qtbot.waitSignal(window.timeline.frame_changed, timeout=5000):
        window.timeline.set_playing(True)
    window.timeline.set_playing(False)


def test_export_retargeted_motion_and_a_bad_file_gives_a_dialog(window, tmp_path, monkeypatch):
    out = window.export_motion(str(tmp_path / "on_iris.bvh"))
    assert out.exists() and out.read_text().startswith("HIERARCHY")
    message = window.statusBar().currentMessage()  # the status names both files the export wrote
    assert message == f"wrote {out} and its TBS frames on_iris.bvh.right.tbs.json"
    assert (tmp_path / "on_iris.bvh.right.tbs.json").is_file()
    window.export_motion(str(tmp_path / "on_iris.npz"))
    assert window.statusBar().currentMessage() == f"wrote {tmp_path / 'on_iris.npz'}"
    shown = []
    monkeypatch.setattr(QMessageBox, "critical", lambda parent, title, text: shown.append(text))
    # an FBX with no Blender here: said at once, before the frames are asked (a fresh-eyes user answered which
    # frames, then heard it could not be written)
    monkeypatch.setenv("S2H_BLENDER_PYTHON", str(tmp_path / "no_blender" / "python"))
    monkeypatch.setattr(window, "_ask_to_save", lambda *args: str(tmp_path / "on_iris.fbx"))
    asked = []
    monkeypatch.setattr(window, "_ask_frames", lambda *args: asked.append(args))
    assert window.export_motion() is None
    assert asked == [] and shown == [f"{tmp_path / 'on_iris.fbx'}: writing FBX goes through Blender, which is not "
                                     "installed here: run `make blender` (or set S2H_BLENDER_PYTHON to a Python with "
                                     "bpy), or write .glb, which Blender, Unity and Unreal import"]
    assert not (tmp_path / "on_iris.fbx").exists()
    shown.clear()
    broken = tmp_path / "broken.glb"
    broken.write_bytes(b"glTF not really")
    window.add_target_file(str(broken))
    assert shown and shown[0].startswith(str(broken)) and len(window.setup.targets) == 1



def test_add_target_with_unrecognised_bones_maps_them_in_the_dialog(window, qtbot, tmp_path):
    """A target hand whose bones say nothing (a WebXR hand renamed ``bone0``..): Add target offers the joint map
    dialog (nothing to prefill), and the hand mapped there joins the grid; the map is saved beside it."""
    import json

    import pygltflib

    from s2h_viewer.io.files import load_hand_file
    from s2h_viewer.samples import ASSETS_DIR
    from s2h_viewer.widgets.joint_map_dialog import JointMapDialog
    webxr = ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb"
    gltf = pygltflib.GLTF2().load(str(webxr))
    renamed = {}
    for i, node in enumerate(gltf.nodes):
        renamed[node.name], node.name = f"bone{i}", f"bone{i}"
    gltf.save(str(tmp_path / "anon.glb"))
    joint_map = {j: renamed[b] for j, b in load_hand_file(webxr).meta["rig_joints"].items()}
    prefilled = []

    def map_every_joint(dialog: JointMapDialog) -> None:
        prefilled.append(dialog.mapping())
        for joint, bone in joint_map.items():
            dialog.combos[joint].setCurrentText(bone)
        dialog.buttons.button(dialog.buttons.StandardButton.Ok).click()

    when_shown(QMessageBox, lambda box: next(b for b in box.buttons() if b.text() == "Map the bones...").click())
    when_shown(JointMapDialog, map_every_joint)
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.add_target_file(str(tmp_path / "anon.glb"))
    assert prefilled == [{}]
    assert [t.name for t in window.setup.targets] == ["iris", "anon"]
    assert {r.target.name for r in window.comparison.results} == {"iris", "anon"}
    assert json.loads((tmp_path / "anon.right.joints.json").read_text()) == joint_map


def test_annotation_mode_solve_turn_undo_save(window, qtbot, tmp_path):
    import shutil

    from s2h_viewer.io.annotation import load_annotation
    from s2h_viewer.samples import ASSETS_DIR
    glb = shutil.copy(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb", tmp_path / "hand.glb")
    window.annotate_file(str(glb))
    assert window.tabs.currentWidget() is window.annotate_view
    assert [a.text() for a in window.recent_menu.actions()] == ["hand.glb (annotate)"]
    with qtbot.waitSignal(window.annotation_ready, timeout=60_000):
        window.run_solver()  # on the frames the solver gave at opening: the same frames, no edit
    assert window.undo_stack.count() == 0 and window.undo_stack.isClean()
    session = window.annotation
    view = window.annotate_view
    view.select(4)  # index_pip
    solved = session.frames[4].copy()
    arrows_before = view._arrow_meshes[2].points.copy()
    view.turn_selected(30)
    assert session.set_by[4] == "manual" and window.undo_stack.count() == 1  # the turn
    angle = np.degrees(np.arccos(np.clip((np.trace(solved.T @ session.frames[4]) - 1) / 2, -1, 1)))
    assert abs(angle - 30) < 1e-6
    np.testing.assert_allclose(session.frames[4][:, 0], solved[:, 0], atol=1e-12)  # twist unchanged
    assert np.abs(view._arrow_meshes[2].points - arrows_before).max() > 1e-4  # the splay arrow moved
    window.undo_stack.undo()
    np.testing.assert_allclose(session.frames[4], solved, atol=1e-12)
    assert session.set_by[4] == "solver"
    window.undo_stack.redo()
    path = window.save_annotation()
    saved = load_annotation(glb, "right")
    assert path.name == "hand.right.tbs.json" and saved.set_by[4] == "manual"
    np.testing.assert_allclose(saved.frames[4], session.frames[4], atol=1e-7)


def test_timeline_readout_counts_frames_as_the_clip_does(window):
    timeline, n = window.timeline, window.comparison.n_frames
    fps = window.comparison.motion.fps
    assert timeline.readout.text() == f"0/{n - 1} ({n} frames)  0.00 s / {n / fps:.2f} s"
    timeline.set_frame(n - 1)  # the last frame: its index, and its start time within the clip's length
    assert timeline.readout.text() == f"{n - 1}/{n - 1} ({n} frames)  {(n - 1) / fps:.2f} s / {n / fps:.2f} s"
    assert timeline.spin.value() == n - 1  # the frame box shows the same index


def test_shortcut_help_lists_every_shortcut_the_menus_define(window, qtbot):
    from PySide6.QtGui import QKeySequence, QUndoCommand
    window.compare.undo_stack.push(QUndoCommand("remove iris"))  # Edit > Undo now reads "Undo remove iris"
    from s2h_viewer.widgets.text_dialog import TextDialog
    shown = []

    def read(dialog) -> None:  # it fits the screen (a message box ran 1052 pixels tall on a 1000-pixel one)
        screen = dialog.screen().availableGeometry()
        shown.append((dialog.text.toPlainText(), dialog.height() <= screen.height(), dialog.width() <= screen.width()))
        dialog.reject()
    when_shown(TextDialog, read)
    help_action = next(a for m in window.menuBar().actions() for a in m.menu().actions() if a.text() ==
                       "Keyboard shortcuts")
    help_action.trigger()
    qtbot.waitUntil(lambda: bool(shown), timeout=10_000)
    text, fits_height, fits_width = shown[0]
    assert fits_height and fits_width
    lines = text.splitlines()

    def in_menus(menu) -> list[QAction]:
        return [b for a in menu.actions() for b in (in_menus(a.menu()) if a.menu() else [a])]

    keyed = [a for top in window.menuBar().actions() for a in in_menus(top.menu()) if a.shortcuts()]
    assert len(keyed) >= 20
    for action in keyed:
        key = action.shortcut().toString(QKeySequence.SequenceFormat.NativeText)
        name = action.property("help_name") or action.text()
        assert any(line.startswith(key) and name in line for line in lines), (key, name)
    assert [line for line in lines if line.startswith("Ctrl+T: ")] == ["Ctrl+T: File > Add target hand..."]  # once
    edit = [line for line in lines if "Edit > " in line]
    assert edit == ["Ctrl+Z: Edit > Undo", "Ctrl+Shift+Z: Edit > Redo"]  # not "Undo remove iris"
    assert any(line.startswith("Ctrl+H: View > Semi-transparent skin") for line in lines)
    mouse = lines[lines.index("Mouse, in the 3D views of both tabs"):]  # the mouse after the keys
    for entry in ("left drag: rotate the camera", "Shift+left drag or middle drag: pan", "right drag or wheel: zoom",
                  "double-click a hand: show it alone", "click a retarget in the grid: select it",
                  "click the error curve (or drag along it): jump to that frame (scrub)",
                  "click a heatmap row (a cell or its name): that joint's bend on the error curve",
                  "click a joint (in 3D or the list): select it", "drag the ring"):
        assert any(line.startswith(entry) for line in mouse), entry
    assert "Mouse, in Compare" in mouse and "Mouse, in Annotate" in mouse


def test_add_target_offers_only_hand_files_and_each_kind_loads_as_a_hand(window, qtbot, tmp_path):
    from PySide6.QtWidgets import QFileDialog

    from s2h_viewer.io.files import load_hand_file
    from s2h_viewer.samples import ASSETS_DIR
    filters = []
    when_shown(QFileDialog, lambda dialog: (filters.extend(dialog.nameFilters()), dialog.reject()))
    window.add_target()
    assert len(filters) == 1 and "bvh" not in filters[0]
    patterns = filters[0].split("(")[1].rstrip(")").split()
    examples = {"*.glb": "webxr/generic-hand-right.glb", "*.gltf": "real/godot_hand_r.gltf",
                "*.fbx": "fbx/mixamo_right_hand.fbx", "*.npz": "iris.npz", "*.vrm": str(tmp_path / "skinned.vrm")}
    # the shipped VRM (debug_robot.vrm) is rigid, unskinned: a VRM's skin is a GLB's, read by the same reader
    (tmp_path / "skinned.vrm").write_bytes((ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb").read_bytes())
    assert sorted(patterns) == sorted(examples)
    for pattern in patterns:  # every kind offered is a hand with a skin to colour
        hand = load_hand_file(ASSETS_DIR / "hands" / examples[pattern])
        assert hand.mesh is not None and len(hand.mesh.faces) > 100, pattern


def test_playback_speed_and_looping_are_kept_for_the_next_launch(qtbot, sample_hands, tmp_path):
    first = open_compare_window(qtbot, sample_hands, tmp_path, compute=False)
    first.timeline.speed.setCurrentIndex(first.timeline.speed.findText("2x"))
    first.timeline.loop.setChecked(False)
    first.undo_stack.clear()
    first.close()
    again = open_compare_window(qtbot, sample_hands, tmp_path, compute=False)  # the same settings file
    assert again.timeline.speed.currentText() == "2x" and not again.timeline.loop.isChecked()


def test_methods_named_on_the_command_line_win_over_the_ones_last_ticked(qtbot, sample_hands, tmp_path, capsys):
    """`s2h view --methods tbs_copy,asrn` opened TBS Copy alone when the window had last closed with it alone: the
    remembered methods won over the ones named. Named, they are the ones ticked and computed (and remembered);
    not named, the last ticked; a name that is no method is one error line before any window."""
    from PySide6.QtCore import QSettings

    from s2h_viewer.app.compare_mode import CompareSetup
    from s2h_viewer.app.main_window import MainWindow
    from s2h_viewer.cli import main
    from s2h_viewer.motions.synthesis import synthesize
    settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
    settings.setValue("compare/methods", ["tbs_copy"])  # the last window closed with TBS Copy alone
    motion = synthesize(["fist"], sample_hands["birch"], seed=4, name="short")
    windows = {}
    for named in (True, False):
        setup = CompareSetup(motion, sample_hands["birch"], [sample_hands["iris"]], ["tbs_copy", "dm"],
                             methods_named=named)
        windows[named] = win = MainWindow(setup, settings)
        qtbot.addWidget(win)
    ticked = {named: [m for m, action in win.method_actions.items() if action.isChecked()]
              for named, win in windows.items()}
    assert windows[True].compare.state.methods == ticked[True] == ["tbs_copy", "dm"]
    assert windows[False].compare.state.methods == ticked[False] == ["tbs_copy"]
    assert main(["view", "--methods", "tbs_copy,asrnx"]) == 2
    err = capsys.readouterr().err
    assert "'asrnx' is not a retargeting method; available: copy, tbs_copy, dm, asrn" in err and err.count("\n") == 1


def test_bracket_keys_jump_between_the_worst_frames_of_the_error_curve(window, qtbot):
    """Issue 25: next/previous worst frame keys (']' and '['), wrapping round the clip, listed in Help."""
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    curve = window.compare.curve
    worst = list(curve.worst)
    assert len(worst) >= 2 and all(curve.error[f] >= np.median(curve.error) for f in worst)
    window.activateWindow()
    qtbot.waitUntil(lambda: window.isActiveWindow(), timeout=5000)
    window.timeline.set_frame(0)
    visited = []
    for _ in range(len(worst) + 1):
        QTest.keyClick(window, Qt.Key.Key_BracketRight)
        visited.append(window.timeline.frame)
    after_zero = [f for f in worst if f > 0]  # marked in frame order
    assert visited[:len(after_zero)] == after_zero and visited[len(after_zero)] == worst[0]  # then round again
    window.timeline.set_frame(worst[0])
    QTest.keyClick(window, Qt.Key.Key_BracketLeft)
    assert window.timeline.frame == worst[-1]  # wrapped to the last marked frame, and said so
    assert window.statusBar().currentMessage() == f"Wrapped round to the last worst frame: frame {worst[-1]}"
    QTest.keyClick(window, Qt.Key.Key_BracketLeft)
    assert window.timeline.frame == worst[-2]
    window.timeline.spin.setFocus()  # with the frame box focused the keys still jump (not typed into it)
    qtbot.waitUntil(lambda: window.timeline.spin.hasFocus(), timeout=5000)
    qtbot.keyClick(window.timeline.spin.lineEdit(), Qt.Key.Key_BracketRight)
    assert window.timeline.frame == worst[-1]
    from s2h_viewer.widgets.error_curve import next_worst
    assert next_worst(np.zeros(0, dtype=int), 5, 1) is None  # nothing marked: the keys leave the frame alone
    # with a range marked (Playback > Mark in / out) the keys stay in it, as playback does: a fresh-eyes run
    # marked 100-300, pressed ] at 300 and landed on 29, outside it
    inside = range(worst[1], worst[-1] + 1)
    window.timeline.set_frame(inside.start)
    QTest.keyClick(window, Qt.Key.Key_I)  # Playback > Mark in
    window.timeline.set_frame(inside[-1])
    QTest.keyClick(window, Qt.Key.Key_O)  # Mark out
    assert window.timeline.marked == inside
    QTest.keyClick(window, Qt.Key.Key_BracketRight)
    assert window.timeline.frame == worst[1] and "between the marks" in window.statusBar().currentMessage()
    QTest.keyClick(window, Qt.Key.Key_BracketRight)  # no wrap: the wrap's message goes (it stayed up, misleading)
    assert window.timeline.frame == worst[2] and window.statusBar().currentMessage() == ""
    assert next_worst(np.array(worst), worst[1], -1, inside) == (worst[-1], True)
    assert next_worst(np.array(worst), 0, 1, range(worst[0] + 1, worst[1])) is None  # none between the marks
    lines = window.shortcut_lines()
    assert "]: Playback > Next worst frame (error curve)" in lines
    assert "[: Playback > Previous worst frame (error curve)" in lines


def test_numpys_blas_runs_one_thread_in_the_app():
    """A video export while the timeline played froze the window for good: its thread and the GUI's both in OpenBLAS's
    threaded matrix product (one spinning in exec_blas, the other blocked on its lock). The app runs it on one."""
    from threadpoolctl import threadpool_info

    import s2h_viewer.app  # noqa: F401
    blas = [lib for lib in threadpool_info() if lib["user_api"] == "blas"]
    assert blas and all(lib["num_threads"] == 1 for lib in blas), blas
