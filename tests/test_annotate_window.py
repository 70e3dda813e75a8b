"""Annotate mode in the real window (Xvfb, pytest-qt, shipped hands): a joint clicked in 3D through the
render window, its ring dragged with the mouse and undone, a second hand opened, a sidecar reopened with
who set each frame, the questions before manual frames or unsaved edits are lost (saving beside the hand,
elsewhere, or failing to), and shortcuts working again once a dialog closes."""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Callable

import numpy as np
import pygltflib
import pytest

pytest.importorskip("pytestqt")
if not os.environ.get("DISPLAY"):
    pytest.skip("the Qt viewport needs an X display: `make test` runs the suite under Xvfb", allow_module_level=True)

from PySide6.QtCore import QPoint, QSettings, Qt, QTimer  # noqa: E402
from PySide6.QtTest import QTest  # noqa: E402
from PySide6.QtWidgets import QApplication, QFileDialog, QLineEdit, QMessageBox, QWidget  # noqa: E402
from vtkmodules.vtkRenderingCore import vtkCoordinate  # noqa: E402

from s2h_viewer.annotate.editing import rotate_about_twist  # noqa: E402
from s2h_viewer.app.main_window import CompareSetup, MainWindow  # noqa: E402
from s2h_viewer.hand import topology as topo  # noqa: E402
from s2h_viewer.io.files import load_hand_file  # noqa: E402
from s2h_viewer.motions.synthesis import synthesize  # noqa: E402
from s2h_viewer.render.scene import to_view  # noqa: E402
from s2h_viewer.samples import ASSETS_DIR  # noqa: E402
from s2h_viewer.widgets.annotation_view import RING_RADIUS  # noqa: E402
from s2h_viewer.widgets.joint_map_dialog import NO_BONE, JointMapDialog  # noqa: E402
from s2h_viewer.widgets.text_dialog import TextDialog  # noqa: E402

WEBXR = ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb"


@pytest.fixture
def window(qtbot, sample_hands, tmp_path):
    """The main window (compare mode idle: annotate mode needs no comparison), settings thrown away."""
    motion = synthesize(["fist"], sample_hands["birch"], seed=1, name="short")
    settings = QSettings(str(tmp_path / "settings.ini"), QSettings.Format.IniFormat)
    win = MainWindow(CompareSetup(motion, sample_hands["birch"], [sample_hands["iris"]], ["tbs_copy"]), settings)
    win.resize(1200, 800)
    qtbot.addWidget(win, before_close_func=lambda w: w.undo_stack.clear())  # closed without a "save?" question
    win.show()
    qtbot.waitExposed(win)
    return win


@pytest.fixture
def hand_file(tmp_path):
    return shutil.copy(WEBXR, tmp_path / "hand.glb")


def widget_point(view, point: np.ndarray) -> QPoint:
    """Where a view-space point is drawn, in the 3D widget's Qt pixels (VTK's own projection)."""
    coordinate = vtkCoordinate()
    coordinate.SetCoordinateSystemToWorld()
    coordinate.SetValue(*point)
    x, y = coordinate.GetComputedDoubleDisplayValue(view.plotter.renderer)
    scale = view.interactor.devicePixelRatioF()
    return QPoint(round(x / scale), round(view.interactor.height() - 1 - y / scale))


def ring_point(view, joint: int, degrees: float) -> np.ndarray:
    """The point of ``joint``'s ring ``degrees`` from its bend axis towards its splay axis, in view space."""
    session = view.session
    frame = to_view(session.hand, session.frames[joint].T).T
    a = np.radians(degrees)
    radius = RING_RADIUS * session.hand.hand_length
    return view.joint_centres()[joint] + radius * (np.cos(a) * frame[:, 1] + np.sin(a) * frame[:, 2])


def answer(*steps: tuple[type[QWidget], Callable[[QWidget], None]], shown: list[str] | None = None) -> list[str]:
    """Answer the modal dialogs that open next, in order, each once it is the active modal widget: a step is the
    dialog's class and what the user does in it. What each showed (a box's text and detail, the file a file
    dialog offers) goes to ``shown``, returned."""
    shown = [] if shown is None else shown
    left = list(steps)

    def look() -> None:
        kind, act = left[0]
        dialog = QApplication.activeModalWidget()
        if isinstance(dialog, kind):
            shown.append(f"{dialog.text()}\n{dialog.informativeText()}" if isinstance(dialog, QMessageBox)
                         else (dialog.selectedFiles() or [""])[0] if isinstance(dialog, QFileDialog)
                         else dialog.windowTitle())
            left.pop(0)
            act(dialog)
        if left:
            QTimer.singleShot(20, look)

    QTimer.singleShot(0, look)
    return shown


def click(button_text: str) -> tuple[type[QWidget], Callable[[QWidget], None]]:
    """A step of `answer`: click ``button_text`` in a message box."""
    return QMessageBox, lambda box: QTest.mouseClick(next(b for b in box.buttons() if b.text() == button_text),
                                                     Qt.MouseButton.LeftButton)


def choose_file(path) -> tuple[type[QWidget], Callable[[QWidget], None]]:
    """A step of `answer`: type ``path`` into a file dialog and accept it (None: cancel the dialog)."""
    def act(dialog: QFileDialog) -> None:
        if path is None:
            dialog.reject()
            return
        dialog.findChild(QLineEdit, "fileNameEdit").setText(str(path))
        dialog.accept()
    return QFileDialog, act


def turn_angle(before: np.ndarray, after: np.ndarray) -> float:
    """Signed degrees about ``before``'s twist axis that take ``before`` to ``after``."""
    axis = before[:, 0]
    return float(np.degrees(np.arctan2(np.dot(axis, np.cross(before[:, 1], after[:, 1])),
                                       np.dot(before[:, 1], after[:, 1]))))


def ring_drag_path(view, joint: int, degrees: float) -> list[QPoint]:
    """11 pointer positions along ``joint``'s ring, ``degrees`` round it from a point where that turn moves the
    pointer well apart on screen."""
    start = next(a for a in range(0, 360, 15) if (widget_point(view, ring_point(view, joint, a)) -
                 widget_point(view, ring_point(view, joint, a + degrees))).manhattanLength() > 25)
    return [widget_point(view, ring_point(view, joint, start + t)) for t in np.linspace(0, degrees, 11)]


def keyboard_to(qtbot, widget) -> None:
    """The window active and ``widget`` focused, as after a user's click there: shortcuts reach the window."""
    widget.window().activateWindow()
    qtbot.waitActive(widget.window())
    widget.setFocus()
    qtbot.waitUntil(widget.hasFocus)


def settle() -> None:
    for _ in range(5):
        QApplication.processEvents()


def test_click_a_joint_drag_its_ring_and_undo(window, qtbot, hand_file):
    window.annotate_file(str(hand_file))
    view = window.annotate_view
    settle()
    assert view.selected == 0
    # a click at a joint drawn well apart from the others (and from the selected joint's ring) selects it
    on_screen = np.array([[widget_point(view, p).x(), widget_point(view, p).y()] for p in view.joint_centres()])
    gaps = np.linalg.norm(on_screen[:, None] - on_screen[None], axis=2) + np.eye(len(on_screen)) * 1e9
    ring_px = np.linalg.norm(on_screen[0] - np.array([widget_point(view, ring_point(view, 0, 0)).x(),
                                                      widget_point(view, ring_point(view, 0, 0)).y()]))
    towards_viewer = -np.array(view.plotter.camera.GetDirectionOfProjection())
    frames = to_view(window.annotation.hand, window.annotation.frames.transpose(0, 2, 1)).transpose(0, 2, 1)
    facing = np.abs(frames[:, :, 0] @ towards_viewer)  # rings that face the camera follow the pointer exactly
    candidates = [j for j in np.argsort(-gaps.min(axis=1)) if j != 0 and gaps[j, 0] > 2 * ring_px and facing[j] > 0.5]
    joint = int(candidates[0])
    QTest.mouseClick(view.interactor, Qt.MouseButton.LeftButton, pos=QPoint(*on_screen[joint]))
    assert view.selected == joint and view.joints.currentRow() == joint

    # drag the ring from one of its points to another 50 deg further round: the frame turns by 50 deg
    drag = 50.0
    path = ring_drag_path(view, joint, drag)
    before = window.annotation.frames[joint].copy()
    camera = np.array(view.plotter.camera.position)
    QTest.mousePress(view.interactor, Qt.MouseButton.LeftButton, pos=path[0])
    assert view.ring.dragging  # the ring, not the camera, took the press
    for point in path[1:6]:
        QTest.mouseMove(view.interactor, point)
    halfway = turn_angle(before, window.annotation.frames[joint])
    assert abs(halfway - drag / 2) < 3.0  # live, while the button is held
    for point in path[6:]:
        QTest.mouseMove(view.interactor, point)
    QTest.mouseRelease(view.interactor, Qt.MouseButton.LeftButton, pos=path[-1])
    after = window.annotation.frames[joint].copy()
    assert abs(turn_angle(before, after) - drag) < 3.0
    np.testing.assert_allclose(after[:, 0], before[:, 0], atol=1e-9)  # the twist axis stays on the bone
    np.testing.assert_allclose(after, rotate_about_twist(before, turn_angle(before, after)), atol=1e-9)
    np.testing.assert_allclose(view.plotter.camera.position, camera)  # the camera did not orbit
    assert window.annotation.set_by[joint] == "manual" and window.isWindowModified()
    assert view.joints.item(joint).text() == f"{topo.ARTICULATED_NAMES[joint]}: manual"  # not the solver's 1.00
    tab = window.tabs.indexOf(view)
    assert window.windowTitle() == "s2h-viewer: annotating hand.glb (right hand)[*]"  # '*' shown by Qt
    assert window.tabs.tabText(tab) == "Annotate *"  # unsaved, seen where no window manager draws the title

    keyboard_to(qtbot, view.interactor)
    QTest.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    np.testing.assert_allclose(window.annotation.frames[joint], before, atol=1e-12)
    assert window.annotation.set_by[joint] == "solver" and not window.isWindowModified()
    assert window.tabs.tabText(tab) == "Annotate"
    QTest.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    np.testing.assert_allclose(window.annotation.frames[joint], after, atol=1e-12)


def test_second_hand_replaces_the_first_and_a_sidecar_brings_back_who_set_each_frame(window, qtbot, hand_file):
    window.annotate_file(str(hand_file))
    first = window.annotation
    assert first.frames_from == "solver" and np.isfinite(first.confidence).all()  # the solver's, scored
    window.annotate_view.select(6)
    window.annotate_view.turn_selected(25)
    saved_frames = first.frames.copy()
    assert window.save_annotation().name == "hand.right.tbs.json"

    iris = ASSETS_DIR / "hands" / "iris.npz"
    window.annotate_file(str(iris))  # saved: no question; the list is iris's now
    view = window.annotate_view
    assert window.annotation.hand.name == "iris" and view.joints.count() == topo.N_ARTICULATED
    assert view.session is window.annotation and view.selected == 0
    assert all("from the hand file" in view.joints.item(j).text() for j in range(topo.N_ARTICULATED))
    np.testing.assert_allclose(view.joint_centres(), to_view(window.annotation.hand,
                               window.annotation.hand.rest_positions[topo.ARTICULATED_JOINTS]))

    window.annotate_file(str(hand_file))  # reopened: the sidecar's frames, set_by and confidence
    session = window.annotation
    assert session.frames_from == "sidecar"
    assert session.set_by == ["manual" if j == 6 else "solver" for j in range(topo.N_ARTICULATED)]
    np.testing.assert_allclose(session.confidence, first.confidence, atol=1e-4)
    np.testing.assert_allclose(session.frames, saved_frames, atol=1e-7)
    texts = [view.joints.item(j).text() for j in range(topo.N_ARTICULATED)]
    assert texts[6] == f"{topo.ARTICULATED_NAMES[6]}: manual"  # no solver confidence for a frame turned by hand
    assert all(f"{first.confidence[j]:.2f} (solver)" in texts[j]
                                          for j in range(topo.N_ARTICULATED) if j != 6)
    assert len(set(texts)) > 2  # not one "1.00 (solver)" line for every joint


def test_ctrl_r_asks_before_replacing_manual_frames_and_is_undoable(window, qtbot, hand_file):
    window.annotate_file(str(hand_file))
    window.annotate_view.select(3)
    window.annotate_view.turn_selected(40)
    manual = window.annotation.frames[3].copy()
    keyboard_to(qtbot, window.annotate_view.interactor)
    asked: list[str] = []

    answer(click("Cancel"), shown=asked)
    QTest.keyClick(window, Qt.Key.Key_R, Qt.KeyboardModifier.ControlModifier)
    assert asked and topo.ARTICULATED_NAMES[3] in asked[0]
    np.testing.assert_allclose(window.annotation.frames[3], manual)
    assert window.undo_stack.count() == 1

    answer(click("Keep manual frames"), shown=asked)
    with qtbot.waitSignal(window.annotation_ready, timeout=60_000):
        QTest.keyClick(window, Qt.Key.Key_R, Qt.KeyboardModifier.ControlModifier)
    np.testing.assert_allclose(window.annotation.frames[3], manual)
    assert window.annotation.set_by[3] == "manual"
    # the other joints' frames were the solver's already: the run changed nothing, so it is no edit to undo or to
    # save (a fresh-eyes user's rerun marked the tab unsaved, and quitting asked to save edits never made)
    assert window.statusBar().currentMessage().startswith("solver: the frames are as they were")
    assert window.undo_stack.count() == 1  # the turn, still there

    answer(click("Replace all"), shown=asked)
    with qtbot.waitSignal(window.annotation_ready, timeout=60_000):
        QTest.keyClick(window, Qt.Key.Key_R, Qt.KeyboardModifier.ControlModifier)
    assert len(asked) == 3 and window.annotation.set_by == ["solver"] * topo.N_ARTICULATED
    assert np.abs(window.annotation.frames[3] - manual).max() > 1e-3
    QTest.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)  # undo the solver run
    np.testing.assert_allclose(window.annotation.frames[3], manual)
    assert window.annotation.set_by[3] == "manual"


IRIS = str(ASSETS_DIR / "hands" / "iris.npz")


def edit_a_frame(window, joint: int = 5, degrees: int = -20) -> np.ndarray:
    """Turn ``joint``'s frame as a drag of the dial does (press, turn, release); its frame after."""
    window.annotate_view.select(joint)
    window.annotate_view.turn_selected(degrees)
    assert window.isWindowModified()
    return window.annotation.frames[joint].copy()


def test_unsaved_edits_are_asked_about_before_another_hand_or_quitting(window, qtbot, hand_file, tmp_path):
    window.annotate_file(str(hand_file))
    edited = edit_a_frame(window)
    sidecar = tmp_path / "hand.right.tbs.json"
    buttons: list[str] = []
    asked = answer((QMessageBox, lambda box: (buttons.extend(b.text() for b in box.buttons()),
                                              click("Cancel")[1](box))))
    window.annotate_file(IRIS)
    assert len(asked) == 1 and "before opening another hand" in asked[0] and str(sidecar) in asked[0]
    assert sorted(buttons) == sorted(["Save", "Save As...", "Discard", "Cancel"])
    assert window.annotation.hand.name == "hand" and window.isWindowModified()

    answer(click("Cancel"), shown=asked)
    assert not window.close() and window.isVisible()  # quitting cancelled
    assert "before quitting" in asked[1] and str(sidecar) in asked[1]

    answer(click("Save"), shown=asked)
    window.annotate_file(IRIS)
    assert window.annotation.hand.name == "iris" and sidecar.exists()
    saved = sidecar.read_text()

    window.annotate_file(str(hand_file))  # reopened: the saved frames are back, nothing to save
    assert len(asked) == 3 and window.annotation.frames_from == "sidecar" and not window.isWindowModified()
    np.testing.assert_allclose(window.annotation.frames[5], edited, atol=1e-7)
    assert window.annotation.set_by[5] == "manual"

    edit_a_frame(window, 5, 10)
    answer(click("Discard"), shown=asked)
    window.annotate_file(IRIS)
    assert len(asked) == 4 and window.annotation.hand.name == "iris"
    assert sidecar.read_text() == saved  # discarded, not written


def test_save_as_writes_where_the_user_chooses(window, qtbot, hand_file, tmp_path):
    window.annotate_file(str(hand_file))
    edited = edit_a_frame(window)
    menu_entry = next(a for m in window.menuBar().actions() if m.text() == "&Annotate" for a in m.menu().actions()
                      if a.text() == "Save annotation as...")
    offered = answer(choose_file(None))  # Annotate > Save annotation as..., the file dialog cancelled
    menu_entry.trigger()
    assert offered == [str(tmp_path / "hand.right.tbs.json")]  # in the sidecar's folder, the sidecar's name
    assert window.isWindowModified() and sorted(p.name for p in tmp_path.iterdir()) == ["hand.glb", "settings.ini"]

    chosen = tmp_path / "elsewhere" / "mine.tbs.json"
    chosen.parent.mkdir()
    asked = answer(click("Save As..."), choose_file(chosen))
    assert window.close() and not window.isVisible()  # saved, then quit
    assert len(asked) == 2 and asked[1] == str(tmp_path / "hand.right.tbs.json")
    assert not (tmp_path / "hand.right.tbs.json").exists()
    document = json.loads(chosen.read_text())
    assert document["hand_file"] == "hand.glb" and document["joints"][topo.ARTICULATED_NAMES[5]]["set_by"] == "manual"
    np.testing.assert_allclose(document["joints"][topo.ARTICULATED_NAMES[5]]["frame"], edited, atol=1e-7)


def test_a_save_that_fails_says_where_and_why_and_loses_nothing(window, qtbot, hand_file, tmp_path):
    window.annotate_file(str(hand_file))
    edited = edit_a_frame(window)
    not_a_folder = tmp_path / "notes.txt"
    not_a_folder.write_text("a file, not a folder")
    inside = not_a_folder / "hand.right.tbs.json"
    asked = answer(click("Save As..."), choose_file(inside), click("OK"))
    assert not window.close() and window.isVisible()
    assert len(asked) == 3 and asked[2].startswith(f"{inside}: could not save the annotation")
    assert f"Not a directory: {not_a_folder}" in asked[2]

    (tmp_path / "hand.right.tbs.json").mkdir()  # where Save writes is a folder
    answer(click("Save"), click("OK"), shown=asked)
    window.annotate_file(IRIS)
    assert len(asked) == 5 and asked[4].startswith(f"{tmp_path / 'hand.right.tbs.json'}: could not save the annotation")
    assert "Is a directory" in asked[4]
    # nothing lost: the hand, its edit and the undo history are there, no file (or half a file) was written
    assert window.annotation.hand.name == "hand" and window.isWindowModified() and window.undo_stack.count() == 1
    np.testing.assert_allclose(window.annotation.frames[5], edited)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hand.glb", "hand.right.tbs.json", "notes.txt",
                                                          "settings.ini"]
    assert not any((tmp_path / "hand.right.tbs.json").iterdir()) and not_a_folder.read_text() == "a file, not a folder"


def test_shortcuts_work_again_once_a_dialog_closes(window, qtbot, hand_file):
    window.annotate_file(str(hand_file))
    before = window.annotation.frames[5].copy()
    edit_a_frame(window)
    keyboard_to(qtbot, window.annotate_view.interactor)
    had_the_keyboard: list[bool] = []

    listed: list[str] = []

    def escape_once_it_has_the_keyboard(dialog: TextDialog, tries: int = 250) -> None:
        """Escape once the dialog holds the keyboard, as a user sees it and presses the key (5 s at most)."""
        if dialog.isActiveWindow() or not tries:
            had_the_keyboard.append(dialog.isActiveWindow())
            listed.append(dialog.text.toPlainText())
            QTest.keyClick(dialog, Qt.Key.Key_Escape)
        else:
            QTimer.singleShot(20, lambda: escape_once_it_has_the_keyboard(dialog, tries - 1))

    shown = answer((TextDialog, escape_once_it_has_the_keyboard))
    QTest.keyClick(window, Qt.Key.Key_F1)  # Help > Keyboard shortcuts, closed with Escape
    assert shown == ["Keyboard shortcuts and mouse"] and "Ctrl+Z" in listed[0] and had_the_keyboard == [True]
    # without a window manager the focus fell to the root window: the app hands it back to the main window
    qtbot.waitUntil(window.isActiveWindow, timeout=5000)
    QTest.keyClick(window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    np.testing.assert_allclose(window.annotation.frames[5], before, atol=1e-12)


def test_an_edge_on_ring_rolls_under_the_pointer(window, qtbot, hand_file):
    window.annotate_file(str(hand_file))
    view = window.annotate_view
    joint = 7  # middle_pip
    view.select(joint)
    frame = to_view(window.annotation.hand, window.annotation.frames[joint].T).T
    centre = view.joint_centres()[joint]
    camera = view.plotter.camera  # looking across the bone: the ring is seen edge-on
    distance = camera.distance
    camera.focal_point = centre
    camera.position = centre + distance * frame[:, 2]
    camera.up = frame[:, 0]
    view.interactor.render()
    settle()
    towards_viewer = -np.array(camera.GetDirectionOfProjection())
    assert abs(np.dot(frame[:, 0], towards_viewer)) < 0.05
    radius = RING_RADIUS * window.annotation.hand.hand_length
    front = centre + radius * frame[:, 2]  # the ring's point nearest the camera
    before = window.annotation.frames[joint].copy()
    press = widget_point(view, front)
    side = widget_point(view, centre + radius * frame[:, 1]) - widget_point(view, centre)
    step = np.array([side.x(), side.y()], float)
    step = 12 * step / np.linalg.norm(step)  # 12 pixels along the ring's line on screen
    target = QPoint(round(press.x() + step[0]), round(press.y() + step[1]))
    QTest.mousePress(view.interactor, Qt.MouseButton.LeftButton, pos=press)
    assert view.ring.dragging
    QTest.mouseMove(view.interactor, target)
    QTest.mouseRelease(view.interactor, Qt.MouseButton.LeftButton, pos=target)
    angle = np.radians(turn_angle(before, window.annotation.frames[joint]))
    assert abs(angle) > np.radians(5)
    # the grabbed point, turned with the frame, is under the pointer again (within 2 pixels)
    turned = centre + radius * (np.cos(angle) * frame[:, 2] - np.sin(angle) * frame[:, 1])
    moved = widget_point(view, turned)
    assert (moved - target).manhattanLength() <= 3


def screen_turn(view, path: list[QPoint], centre: np.ndarray) -> float:
    """The signed turn of a pointer path about ``centre`` on screen, clockwise positive (Qt's y runs down)."""
    middle = widget_point(view, centre)
    first, last = (np.array([p.x() - middle.x(), p.y() - middle.y()], float) for p in (path[0], path[-1]))
    return float(np.degrees(np.arctan2(first[0] * last[1] - first[1] * last[0], first @ last)))


@pytest.mark.parametrize("camera_side", [1.0, -1.0], ids=["axis-toward-camera", "axis-away"])
def test_the_dial_turns_the_way_the_ring_does_on_screen_and_follows_undo(window, qtbot, hand_file, camera_side):
    """Issue 25: a clockwise drag of the ring put the dial anticlockwise. Now the dial shows the turn as seen
    on screen, whichever side of the joint the camera is on, and a dial drag turns the ring the same way."""
    window.annotate_file(str(hand_file))
    view = window.annotate_view
    joint = 7  # middle_pip: turned face-on to the camera, so the drag follows the pointer exactly
    view.select(joint)
    frame = to_view(window.annotation.hand, window.annotation.frames[joint].T).T
    centre = view.joint_centres()[joint]
    camera = view.plotter.camera
    camera.focal_point = centre
    camera.position = centre + camera_side * camera.distance * frame[:, 0]
    view.interactor.render()
    settle()
    assert view.dial.value() == 0 and "turned 0 deg" in view.angle_label.text()
    path = ring_drag_path(view, joint, 40.0)
    on_screen = screen_turn(view, path, centre)
    assert 30 < abs(on_screen) < 50
    QTest.mousePress(view.interactor, Qt.MouseButton.LeftButton, pos=path[0])
    for point in path[1:]:
        QTest.mouseMove(view.interactor, point)
    turned = round(view.turn_from_opened())
    assert abs(turned - 40) <= 3
    dial = view.dial.value()  # QDial's value grows clockwise
    assert np.sign(dial) == np.sign(on_screen) and abs(dial) == turned  # live, the ring's way on screen
    QTest.mouseRelease(view.interactor, Qt.MouseButton.LeftButton, pos=path[-1])
    way = "clockwise" if on_screen > 0 else "anticlockwise"
    assert view.dial.value() == dial and f"turned {turned} deg {way}" in view.angle_label.text()  # not back to 0

    ring_before = widget_point(view, ring_point(view, joint, 0.0))
    view.turn_selected(15)  # the dial, 15 deg clockwise, from where the ring left the frame
    assert view.dial.value() == dial + 15
    ring_after = widget_point(view, ring_point(view, joint, 0.0))  # the ring's mark, carried by the frame
    assert screen_turn(view, [ring_before, ring_after], centre) == pytest.approx(15, abs=4)  # clockwise too
    window.undo_stack.undo()
    assert view.dial.value() == dial and f"{turned} deg {way}" in view.angle_label.text()
    window.undo_stack.undo()
    assert view.dial.value() == 0 and "turned 0 deg" in view.angle_label.text()
    window.undo_stack.redo()
    assert view.dial.value() == dial
    view.select(3)  # another joint: its own turn
    assert view.dial.value() == 0 and view.angle_label.text().startswith(topo.ARTICULATED_NAMES[3])


def menu_named(window, title: str):
    return next(a.menu() for a in window.menuBar().actions() if a.text().replace("&", "") == title)


def action_named(window, menu: str, text: str):
    return next(a for a in menu_named(window, menu).actions() if a.text() == text)


def test_the_empty_annotate_tab_says_how_to_open_a_hand_and_each_tab_disables_the_others_menus(window, qtbot,
                                                                                                hand_file):
    view = window.annotate_view
    compare_menus = [menu_named(window, m) for m in ("Methods", "Targets", "View", "Playback")]
    compare_actions = [action_named(window, "File", t) for t in ("Open motion...", "Add target hand...",
                                                                 "Export screenshot (PNG)...",
                                                                 "Export video (MP4, GIF)...",
                                                                 "Export retargeted motion...")]
    annotate_actions = [action_named(window, "Annotate", t) for t in ("Run TBS solver", "Save annotation",
                                                                      "Save annotation as...")]
    assert all(m.isEnabled() for m in compare_menus) and all(a.isEnabled() for a in compare_actions)
    assert not any(a.isEnabled() for a in annotate_actions)  # Compare shows: nothing to solve or save there
    assert action_named(window, "Annotate", "Open hand...").isEnabled()  # it opens the Annotate tab

    window.tabs.setCurrentWidget(view)
    qtbot.waitUntil(view.hint.isVisible)
    assert not view.interactor.isVisible()  # a hint, not a blank 3D view
    assert view.hint.text() == ("Open a hand to annotate: Annotate > Open hand (Ctrl+Shift+O), or drop a GLB, glTF, "
                                "VRM or FBX file here.")
    assert not any(m.isEnabled() for m in compare_menus) and not any(a.isEnabled() for a in compare_actions)
    assert not any(a.isEnabled() for a in annotate_actions)  # no hand yet
    keyboard_to(qtbot, window.tabs)
    QTest.keyClick(window, Qt.Key.Key_H, Qt.KeyboardModifier.ControlModifier)  # View > Semi-transparent skin
    assert not window.see_through.isChecked()  # its shortcut is off with its menu

    window.settings.setValue("files/recent", [f"motion:{ASSETS_DIR / 'motions' / 'counting.npz'}"])
    window.annotate_file(str(hand_file))
    qtbot.waitUntil(view.interactor.isVisible)
    assert not view.hint.isVisible() and view.session is not None
    assert all(a.isEnabled() for a in annotate_actions)
    assert not any(m.isEnabled() for m in compare_menus)
    recent = {a.text(): a for a in window.recent_menu.actions()}
    assert recent["hand.glb (annotate)"].isEnabled() and not recent["counting.npz (motion)"].isEnabled()

    window.tabs.setCurrentWidget(window.compare)
    assert all(m.isEnabled() for m in compare_menus) and all(a.isEnabled() for a in compare_actions)
    assert not any(a.isEnabled() for a in annotate_actions)
    assert all(a.isEnabled() for a in recent.values())  # a hand to annotate opens the Annotate tab from here
    keyboard_to(qtbot, window.tabs)
    QTest.keyClick(window, Qt.Key.Key_H, Qt.KeyboardModifier.ControlModifier)
    assert window.see_through.isChecked()  # back on Compare its shortcut works again


# --- a hand whose bones s2h does not recognise: the user maps them in the joint map dialog ---

@pytest.fixture
def renamed_hand(tmp_path):
    """A copy of the WebXR hand whose index finger's bones no scheme names (its bones hang side by side, so the
    topology cannot find them either): the file and the joint map that makes it the WebXR hand again."""
    gltf = pygltflib.GLTF2().load(str(WEBXR))
    for node in gltf.nodes:
        node.name = node.name.replace("index-finger-", "pointer-")
    gltf.save(str(tmp_path / "renamed.glb"))
    named = load_hand_file(WEBXR).meta["rig_joints"]
    return tmp_path / "renamed.glb", {j: b.replace("index-finger-", "pointer-") for j, b in named.items()}


def map_the_index(joint_map: dict[str, str], seen: dict) -> tuple[type[QWidget], Callable[[QWidget], None]]:
    """A step of `answer`: in the joint map dialog, note what it offers (into ``seen``), choose the index finger's
    bones of ``joint_map`` and press OK."""
    def act(dialog: JointMapDialog) -> None:
        ok = dialog.buttons.button(dialog.buttons.StandardButton.Ok)
        seen.update(prefilled=dialog.mapping(), ok_at_first=ok.isEnabled(), problem=dialog.problem.text(),
                    offered=[dialog.combos["index_mcp"].itemText(i) for i in range(dialog.combos["index_mcp"].count())])
        for joint in ("index_mcp", "index_pip", "index_dip", "index_tip"):
            dialog.combos[joint].setCurrentText(joint_map[joint])
        seen.update(ok_when_mapped=ok.isEnabled(), problem_when_mapped=dialog.problem.text())
        QTest.mouseClick(ok, Qt.MouseButton.LeftButton)
    return JointMapDialog, act


def test_an_unrecognised_hand_is_mapped_in_the_dialog_opened_and_its_map_saved(window, qtbot, renamed_hand):
    path, joint_map = renamed_hand
    seen: dict = {}
    asked = answer(click("Map the bones..."), map_the_index(joint_map, seen))
    window.annotate_file(str(path))
    assert "renamed.glb: s2h does not recognise its hand" in asked[0] and "renamed.right.joints.json" in asked[0]
    assert "--joint-map" not in asked[0] and asked[1] == "Map the bones of renamed.glb"
    # prefilled with what the names give: all but the index finger; OK only once the index is mapped
    assert seen["prefilled"] == {j: b for j, b in joint_map.items() if not j.startswith("index")}
    assert not seen["ok_at_first"] and seen["problem"] == "the joint map does not name index_mcp, index_pip, index_dip"
    assert seen["offered"][0] == NO_BONE and "pointer-phalanx-proximal" in seen["offered"]
    assert seen["ok_when_mapped"] and seen["problem_when_mapped"] == ""
    hand = window.annotation.hand
    assert hand.name == "renamed" and hand.meta["rig_scheme"] == "user"
    np.testing.assert_allclose(hand.rest_positions, load_hand_file(WEBXR).rest_positions, atol=1e-9)
    assert json.loads(path.with_name("renamed.right.joints.json").read_text()) == joint_map
    window.annotate_file(str(path))  # opened again: the saved map, no question (one would block here)
    assert len(asked) == 2 and window.annotation.hand.meta["rig_scheme"] == "user"


def test_cancelling_the_joint_map_leaves_the_window_as_it_was(window, qtbot, renamed_hand, tmp_path):
    path, _ = renamed_hand
    window.annotate_file(IRIS)
    asked = answer(click("Cancel"))
    window.annotate_file(str(path))  # "Map the bones..." not taken
    answer(click("Map the bones..."), (JointMapDialog, lambda dialog: dialog.reject()), shown=asked)
    window.annotate_file(str(path))  # the dialog cancelled
    assert len(asked) == 3 and window.annotation.hand.name == "iris"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["renamed.glb", "settings.ini"]  # no map written


def test_a_four_finger_hand_is_refused_without_offering_a_joint_map(window, qtbot):
    window.annotate_file(IRIS)
    asked = answer(click("OK"))
    window.annotate_file(str(ASSETS_DIR / "hands" / "fbx" / "four_finger_hand.fbx"))
    assert len(asked) == 1 and "0 bones left for 3 joints (pinky_mcp, pinky_pip, pinky_dip): a hand needs 5 " \
                               "fingers" in asked[0]
    assert window.annotation.hand.name == "iris"


def test_open_hand_with_joint_map_edits_the_saved_map(window, qtbot, renamed_hand):
    path, joint_map = renamed_hand
    swapped = {**joint_map, "index_pip": "pointer-phalanx-distal", "index_dip": "pointer-phalanx-intermediate"}
    path.with_name("renamed.right.joints.json").write_text(json.dumps(swapped))
    entry = next(a for m in window.menuBar().actions() if m.text() == "&Annotate" for a in m.menu().actions()
                 if a.text() == "Open hand with joint map...")
    filters: list[str] = []
    answer((QFileDialog, lambda dialog: (filters.extend(dialog.nameFilters()), dialog.reject())))
    entry.trigger()  # Annotate > Open hand with joint map...: a rig file to choose (the dialog cancelled)
    assert filters == ["Rigs (*.glb *.gltf *.vrm *.fbx)"] and window.annotation is None
    seen: dict = {}
    answer(map_the_index(joint_map, seen))
    window.annotate_file(str(path), map_joints=True)  # the file chosen
    assert seen["prefilled"]["index_pip"] == "pointer-phalanx-distal" and seen["ok_at_first"]  # the saved map
    assert json.loads(path.with_name("renamed.right.joints.json").read_text()) == joint_map
    np.testing.assert_allclose(window.annotation.hand.rest_positions, load_hand_file(WEBXR).rest_positions, atol=1e-9)


def test_a_hand_whose_unit_the_size_leaves_open_asks_which_and_opens_in_the_one_chosen(window, sample_hands, tmp_path):
    """A BVH hand of 12 file units from wrist to middle DIP is a small hand in centimetres or a large one in inches:
    the window asks (the guess first), opens it in the unit clicked and says a sure guess in the status bar;
    Cancel opens nothing."""
    from s2h_viewer.io.files import save_motion_file
    from wild_rigs import rescaled_bvh
    clip = synthesize(["fist"], sample_hands["birch"], seed=1, name="short")
    written = save_motion_file(tmp_path / "hand.bvh", clip, sample_hands["birch"])  # centimetres, 18 units
    small = rescaled_bvh(written, tmp_path / "small.bvh", 12.0 / 18.15)
    shown = answer(click("inches"))
    window.annotate_file(str(small))
    assert "small.bvh: in which unit are its lengths?" in shown[0] and "centimetres (wrist to middle DIP" in shown[0]
    hand = window.annotate.session.hand
    assert hand.meta["unit"] == "in" and hand.hand_length == pytest.approx(
        sample_hands["birch"].hand_length * 12.0 / 18.15 * 2.54, rel=1e-2)
    answer(click("Cancel"))
    window.annotate_file(str(small))
    assert window.annotate.session.hand is hand and "not opened (its unit not chosen)" in \
        window.statusBar().currentMessage()
    window.annotate_file(str(written))  # 18 units: centimetres, sure; said, not asked
    assert window.annotate.session.hand.meta["unit"] == "cm"
    assert "length unit guessed from the hand's size: centimetres" in window.statusBar().currentMessage()
