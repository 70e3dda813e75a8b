"""The compare view draws in a render thread while the GUI thread skins the next frame ahead (real window,
Xvfb, shipped sample hands): every frame shown is that frame's pose, never a frame skinned ahead for
another; the picture shown is the scene as it is; the scene changes and the window closes safely while a
frame is being drawn."""

from __future__ import annotations

import os
import threading

import numpy as np
import pytest

pytest.importorskip("pytestqt")
if not os.environ.get("DISPLAY"):
    pytest.skip("the Qt viewport needs an X display: `make test` runs the suite under Xvfb", allow_module_level=True)

from PySide6.QtWidgets import QApplication  # noqa: E402

from compare_window import open_compare_window  # noqa: E402
from s2h_viewer.hand.skinning import skin_vertices  # noqa: E402
from s2h_viewer.render.compare_scene import PosedHand  # noqa: E402
from s2h_viewer.render.scene import to_view  # noqa: E402
from s2h_viewer.widgets.timeline import SPEEDS  # noqa: E402


@pytest.fixture
def window(qtbot, sample_hands, tmp_path):
    win = open_compare_window(qtbot, sample_hands, tmp_path, methods=("tbs_copy", "asrn", "dm"))
    yield win
    win.close()


def test_each_frame_shown_while_playing_is_that_frames_pose(window, qtbot, monkeypatch):
    ahead_used, wrong = [], []
    show = PosedHand.show

    def checked_show(hand, frame, posed=None):
        show(hand, frame, posed)
        ahead_used.append(posed is not None and posed.frame == frame and posed.skin is hand.skin)
        if hand.levels:
            expected = to_view(hand.skin.hand, skin_vertices(hand.skin.hand, hand.pose, frame))
            if not np.allclose(hand.mesh.points, expected):
                wrong.append(frame)

    monkeypatch.setattr(PosedHand, "show", checked_show)
    window.timeline.speed.setCurrentIndex(SPEEDS.index(4.0))  # drawing flat out: frames skinned ahead
    window.timeline.set_playing(True)
    qtbot.wait(2500)
    window.timeline.set_playing(False)
    assert not wrong
    assert sum(ahead_used) >= len(ahead_used) // 4, (sum(ahead_used), len(ahead_used))  # the ahead path ran


def test_frames_are_drawn_off_the_gui_thread_and_the_picture_is_the_scene(window, qtbot, monkeypatch):
    view = window.view
    widget = view.interactor
    threads = set()
    render = type(widget)._render

    def recorded(self, size):
        threads.add(threading.get_ident())
        return render(self, size)

    monkeypatch.setattr(type(widget), "_render", recorded)
    window.timeline.set_playing(True)
    qtbot.waitUntil(lambda: window.timeline.frame > 10, timeout=20_000)
    window.timeline.set_playing(False)
    qtbot.waitUntil(lambda: widget._job is None and not widget._stale, timeout=5_000)
    qtbot.wait(100)
    assert threads and threading.get_ident() not in threads
    shown = widget._rows.copy()  # the picture painted now, against the scene drawn afresh
    np.testing.assert_array_equal(widget.grab_frame(), shown)


def frame_in_flight(view):
    """The render thread's job drawing the frame asked for (started by the event loop if not at once), or None."""
    if view.interactor._job is None:
        QApplication.processEvents()
    return view.interactor._job


def test_scene_changes_and_closing_while_a_frame_is_drawn(window, qtbot):
    view = window.view
    waited = []
    for index in (2, -1, 1, -1):  # each change right after a frame started: it waits for that frame first
        for change in (lambda: view.show_frame(index % 5 + 3), lambda: view.set_solo(index),
                       lambda: view.set_options(contacts=index > 0)):
            job = frame_in_flight(view)
            change()
            if job is not None:
                waited.append(job.done())
    assert len(waited) >= 3 and all(waited), waited  # some changes came while a frame was drawn
    np.testing.assert_array_equal(view.interactor.grab_frame()[..., :3], view.grab_rgb())
    view.show_frame(5)  # starts drawing at once
    assert view.interactor._job is not None
    view.close_grid()  # closing mid-frame frees the render window once that frame is done
    assert view.interactor is None
