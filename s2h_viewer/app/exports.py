"""Exports of compare mode: a PNG of the grid, an MP4/GIF of the clip, the selected retarget's motion."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtWidgets import QProgressDialog, QWidget

from s2h_viewer.app.compare_mode import CompareMode


class Cancelled(Exception):
    """The user cancelled an export."""


def export_screenshot(mode: CompareMode, path: str) -> Path:
    """The grid as it is on screen, written atomically."""
    from PIL import Image

    from s2h_viewer.io.atomic import atomic_path
    with atomic_path(path) as tmp:
        Image.fromarray(mode.view.grab_rgb()).save(tmp, format="PNG")
    return Path(path)


def export_video(mode: CompareMode, path: str, parent: QWidget) -> Path:
    """Every frame of the clip into a video; raises ``Cancelled`` when the user cancels."""
    from s2h_viewer.render.video import write_video
    mode.timeline.set_playing(False)
    n = mode.comparison.n_frames
    progress = QProgressDialog("Rendering video...", "Cancel", 0, n, parent)
    progress.setMinimumDuration(300)

    def frames():
        for frame in range(n):
            if progress.wasCanceled():
                raise Cancelled()
            mode.timeline.set_frame(frame)
            mode.show_frame(frame)
            progress.setValue(frame)
            yield mode.view.grab_rgb()

    try:
        write_video(path, frames(), mode.comparison.motion.fps)
    finally:
        progress.close()
    return Path(path)


def export_motion(mode: CompareMode, path: str) -> Path:
    """The selected retarget's motion on its target's rig."""
    from s2h_viewer.io.files import save_motion_file
    result = mode.selected_result()
    save_motion_file(path, result.motion, result.target)
    return Path(path)
