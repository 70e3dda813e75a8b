"""Exports of compare mode: a PNG of the grid, an MP4/GIF of the clip or of frames of it, the selected
retarget's motion.
Every image carries a caption (clip, frame, selected method and target). The video is rendered off
screen in a worker thread (its own VTK window), so the window stays live; Cancel stops it between
frames and nothing is written."""

from __future__ import annotations

import re
import threading
from pathlib import Path

from PySide6.QtCore import QObject, Signal
from PySide6.QtWidgets import QWidget

from s2h_viewer.app.compare_mode import CompareMode, label
from s2h_viewer.app.job_progress import JobProgress
from s2h_viewer.render.caption import add_caption, caption_text, page_caption
from s2h_viewer.render.compare_scene import render_comparison
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.retarget.progress import Cancelled


def caption_for(mode: CompareMode, frame: int) -> str:
    """The picture's line: clip, frame and the selected retarget, or, where the selection is on another page of
    targets than the one exported, the page's targets (the caption names what the picture shows)."""
    comparison, result = mode.comparison, mode.selected_result()
    shown = mode.view.comparison
    if shown is not None and not any(r is result for r in shown.results):
        return page_caption(comparison.motion.name, frame, comparison.n_frames, comparison.motion.fps,
                            list(dict.fromkeys(r.target.name for r in shown.results)))
    return caption_text(comparison.motion.name, frame, comparison.n_frames, comparison.motion.fps,
                        METHODS[result.method].label + (" (fixed)" if result.corrections else ""),
                        result.target.name)


def suggested_name(mode: CompareMode, suffix: str, frame: int | None = None, result=None) -> str:
    """'<clip>_<target>_<method>[_f<frame>]<suffix>' for the selected retarget (or ``result``), safe as a file
    name."""
    result = result or mode.selected_result()
    parts = [mode.comparison.motion.name, result.target.name, result.method] + ["fixed"] * bool(result.corrections)
    stem = "_".join(re.sub(r"[^\w.-]+", "-", part).strip("-.") or "x" for part in parts)
    return f"{stem}{'' if frame is None else f'_f{frame:04d}'}{suffix}"


#: the export sizes File > Export size offers, pixels; None: the view's own
EXPORT_SIZES: tuple[tuple[int, int] | None, ...] = (None, (1280, 720), (1920, 1080), (2560, 1440), (3840, 2160))


def size_text(size: tuple[int, int] | None) -> str:
    return "as the view" if size is None else f"{size[0]} x {size[1]}"


def export_screenshot(mode: CompareMode, path: str, size: tuple[int, int] | None = None) -> Path:
    """The grid as it is on screen with its caption, written atomically: grabbed from the view, or at ``size``
    pixels rendered off screen with the view's page of targets, camera, overlays, solo and selection."""
    from PIL import Image

    from s2h_viewer.io.atomic import atomic_path
    frame = mode.timeline.frame
    if size is not None:
        return render_comparison(mode.view.comparison, path, frame=frame, size=size,
                                 caption=lambda f: caption_for(mode, f), options=mode.view.options,
                                 framing=mode.view.framing())
    image = add_caption(mode.view.grab_rgb(), caption_for(mode, frame))
    with atomic_path(path) as tmp:
        Image.fromarray(image).save(tmp, format="PNG")
    return Path(path)


def frames_text(frames: range, n_frames: int) -> str:
    """'138 frames' for a whole clip of 138, else '81 frames: 40 to 120' (the clip's indices)."""
    return f"{len(frames)} frames" + ("" if len(frames) == n_frames else f": {frames.start} to {frames[-1]}")


class VideoExport(QObject):
    """One video export of ``frames`` of the clip (default: all) in a worker thread: ``written(path)``,
    ``cancelled()`` or ``failed(message)`` arrive on the GUI thread; ``progress(done, total)`` after each
    frame, counting the frames asked."""

    progress = Signal(int, int)
    written = Signal(object)
    cancelled = Signal()
    failed = Signal(str)

    def __init__(self, mode: CompareMode, path: str, parent: QWidget, frames: range | None = None,
                 size: tuple[int, int] | None = None):
        super().__init__(parent)
        comparison, view = mode.comparison, mode.view
        self.path, self.frames = path, range(comparison.n_frames) if frames is None else frames
        self._cancel = threading.Event()
        captions = {f: caption_for(mode, f) for f in self.frames}  # the selection now, not later
        if size is None:  # the view's size
            size = (view.interactor.width(), view.interactor.height()) if view.interactor is not None else (1400, 900)
        self._job = (view.comparison, captions, size, view.options, view.framing())  # the page shown
        label = f"Rendering {Path(path).name}\n({frames_text(self.frames, comparison.n_frames)})..."  # the range whole
        self.strip = JobProgress(label, "Cancel", len(self.frames), parent,
                                        "s2h-viewer: video export")  # non-modal: the timeline stays usable
        self.strip.canceled.connect(self.cancel)
        self.progress.connect(lambda done, _: self.strip.setValue(done))
        for signal in (self.written, self.cancelled, self.failed):
            signal.connect(self.strip.close)
        self.thread = threading.Thread(target=self._run, name="video export", daemon=True)

    def start(self) -> "VideoExport":
        self.strip.setValue(0)
        self.thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    def _frame_done(self, done: int, total: int) -> None:
        if self._cancel.is_set():
            raise Cancelled()
        self.progress.emit(done, total)

    def _run(self) -> None:
        comparison, captions, size, options, framing = self._job
        try:
            path = render_comparison(comparison, self.path, size=size, progress=self._frame_done,
                                     caption=captions.__getitem__, options=options, frames=self.frames,
                                     framing=framing)
        except Cancelled:
            self.cancelled.emit()
        except (OSError, ValueError) as exc:
            self.failed.emit(f"{self.path}: could not write the video ({exc})")
        else:
            self.written.emit(path)


def export_motion(mode: CompareMode, path: str, frames: range | None = None) -> Path:
    """The selected retarget's motion on its target's rig: ``frames`` of it (default: the whole clip)."""
    import dataclasses

    from s2h_viewer.io.files import save_motion_file
    result = mode.selected_result()
    motion = result.motion
    if frames is not None and len(frames) < motion.n_frames:
        part = slice(frames.start, frames.stop)
        motion = dataclasses.replace(motion, q_tbs=motion.q_tbs[part], labels=motion.labels[part], fit=None,
                                     meta={**motion.meta, "frames": [frames.start, frames[-1]]})
    save_motion_file(path, motion, result.target)
    return Path(path)


def export_corrections(mode: CompareMode, motion_path: str | Path, frames: range | None = None) -> tuple[Path | None, str]:
    """Beside a motion just exported from the selected retarget (``frames`` of the clip): the sidecar of its
    corrections (`io.corrections`; a part says which frames it is of), or, without corrections, none (an
    earlier export's sidecar there is removed: it would tell of corrections the motion no longer has). Returns the
    sidecar written (or None) and a note for the status line (a removed sidecar, and whose corrections it held)."""
    from s2h_viewer.io.corrections import is_corrections_file, sidecar_path
    result = mode.selected_result()
    sidecar = sidecar_path(motion_path)
    part = frames if frames is not None and len(frames) < mode.comparison.n_frames else None
    if result.corrections:
        return mode.fixing.save(sidecar, result, part), ""
    if not is_corrections_file(sidecar):
        return None, ""
    sidecar.unlink(missing_ok=True)
    held = mode.fixing.removed(sidecar)
    return None, f"; removed {sidecar.name}, an earlier export's" + (
        f" (it held the corrections of {held}: not saved now)" if held else "")
