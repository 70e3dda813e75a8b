"""A tracked recording in the real window (Xvfb, pytest-qt): opened as a motion, the source cell shows the
fitted hand with the recorded keypoints as dots (none on a filled frame), the dots toggle, and the error
curve can show the fit residual."""

from __future__ import annotations

import os

import numpy as np
import pytest

pytest.importorskip("pytestqt")
if not os.environ.get("DISPLAY"):
    pytest.skip("the Qt viewport needs an X display: `make test` runs the suite under Xvfb", allow_module_level=True)

from compare_window import open_window  # noqa: E402
from s2h_viewer.app.main_window import CompareSetup  # noqa: E402
from s2h_viewer.io.files import load_motion_file  # noqa: E402
from s2h_viewer.io.mediapipe_hand import save_mediapipe_hand  # noqa: E402
from s2h_viewer.render.keypoint_dots import KEYPOINT_COLOUR  # noqa: E402
from s2h_viewer.render.scene import to_view  # noqa: E402
from s2h_viewer.samples import ASSETS_DIR, load_sample_motions  # noqa: E402
from s2h_viewer.tracking.synthetic import synthetic_recording  # noqa: E402


@pytest.fixture
def window(qtbot, sample_hands, tmp_path):
    motion, source = load_motion_file(ASSETS_DIR / "recordings" / "webxr_hand_poses_right.json")
    return open_window(qtbot, CompareSetup(motion, source, [sample_hands["iris"]], ["tbs_copy"]), tmp_path)


def _keypoint_pixels(win) -> int:
    """Pixels of the keypoints' colour in the source's cell of the grab."""
    image = win.compare.view.grab_rgb()
    height, width = image.shape[:2]
    x0, y0, x1, y1 = win.compare.view.plotter.renderers[0].GetViewport()
    cell = image[int((1 - y1) * height):int((1 - y0) * height), int(x0 * width):int(x1 * width)].astype(int)
    colour = np.array([int(KEYPOINT_COLOUR[i:i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(cell - colour).sum(-1) < 40).sum())


def test_the_recorded_keypoints_show_on_the_source_and_toggle(window, qtbot):
    source = window.compare.view._hands[0]
    fit = window.compare.comparison.motion.fit
    window.timeline.set_frame(45)  # the pinch
    qtbot.waitUntil(lambda: window.compare.view.frame == 45)
    dots = source.keypoints
    assert dots is not None and dots.actor.visibility
    np.testing.assert_allclose(dots.points.points, to_view(source.hand, fit.keypoints[45]), atol=1e-6)
    assert _keypoint_pixels(window) > 50
    from s2h_viewer.render.compare_scene import cell_pixels
    from s2h_viewer.render.keypoint_dots import CELL_PX, KEYPOINT_PX
    short = min(cell_pixels(window.compare.view.plotter, source.renderer))
    assert short < CELL_PX and dots.actor.prop.point_size == max(4, round(KEYPOINT_PX * short / CELL_PX))  # fitted
    window.keypoint_dots.trigger()  # View > Tracked keypoints off
    assert not dots.actor.visibility and _keypoint_pixels(window) == 0
    window.keypoint_dots.trigger()
    assert dots.actor.visibility and _keypoint_pixels(window) > 50
    assert "fit residual" in window.compare.view._labels[0].text


def test_the_error_curve_shows_the_fit_residual(window):
    curve = window.compare.curve
    asm_error = curve.error.copy()
    window.fit_residual.trigger()
    fit = window.compare.comparison.motion.fit
    assert "residual" in curve.quantity and "mm" in curve.quantity
    np.testing.assert_allclose(curve.error, np.nan_to_num(fit.residual_mm))
    window.fit_residual.trigger()
    np.testing.assert_allclose(curve.error, asm_error)


def test_open_motion_takes_a_mediapipe_recording_with_lost_frames(window, qtbot, sample_hands, tmp_path):
    recording = synthetic_recording(sample_hands["laurel"], load_sample_motions()[1], noise_mm=2.0, lost=0.1,
                                    seed=3)
    path = save_mediapipe_hand(tmp_path / "take.json", recording, handedness="Left")
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.load_motion(str(path))
    comparison = window.compare.comparison
    assert comparison.motion.name == "take" and comparison.motion.fit is not None
    filled = int(np.flatnonzero(comparison.motion.fit.filled)[0])
    window.timeline.set_frame(filled)
    qtbot.waitUntil(lambda: window.compare.view.frame == filled)
    assert not window.compare.view._hands[0].keypoints.actor.visibility  # no dots where the tracker lost it
    kept = int(np.flatnonzero(~comparison.motion.fit.filled)[0])
    window.timeline.set_frame(kept)
    qtbot.waitUntil(lambda: window.compare.view.frame == kept)
    assert window.compare.view._hands[0].keypoints.actor.visibility
    assert "filled" in window.statusBar().currentMessage()  # the fit's report, as the CLI prints it
    window.fit_residual.trigger()
    curve = window.compare.curve
    assert np.array_equal(curve.missing, comparison.motion.fit.filled)  # shaded, not "0 mm"
    filled, measured = int(np.flatnonzero(curve.missing)[0]), int(np.flatnonzero(~curve.missing)[0])
    assert curve.value_at(filled) == f"frame {filled}: not measured"  # the tooltip under the pointer, not "0.000"
    assert curve.value_at(measured) == f"frame {measured}: {comparison.motion.fit.residual_mm[measured]:.3f}"


def test_the_recording_items_are_offered_only_for_a_recording(window, qtbot):
    assert window.keypoint_dots.isEnabled() and window.fit_residual.isEnabled()
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):
        window.load_motion(str(ASSETS_DIR / "motions" / "counting.npz"))
    assert not window.keypoint_dots.isEnabled() and not window.fit_residual.isEnabled()
    assert not window.keypoint_dots.isChecked()  # greyed and unticked: ticked, it read as on but broken
    assert window.compare.view._hands[0].keypoints is None
    with qtbot.waitSignal(window.comparison_ready, timeout=120_000):  # a recording again: ticked again, the choice kept
        window.load_motion(str(ASSETS_DIR / "recordings" / "webxr_hand_poses_right.json"))
    assert window.keypoint_dots.isEnabled() and window.keypoint_dots.isChecked()
