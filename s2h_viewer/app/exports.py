"""Exports of compare mode: a PNG of the grid, an MP4/GIF of the clip or of frames of it, the selected
retarget's motion.
Every image carries a caption (clip, frame, selected method and target). Each export writes what the window
showed when it was asked (`Shown`): its file dialog waits while retargets come in, and the grid may change
meanwhile (a clip opened before it finished). The video is rendered off screen in a worker thread (its own VTK
window), so the window stays live; Cancel stops it between frames and nothing is written."""

from __future__ import annotations

import re
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PySide6.QtCore import QObject, Qt, Signal
from PySide6.QtGui import QFontMetrics
from PySide6.QtWidgets import QWidget

from s2h_viewer.app.compare_mode import CompareMode, label
from s2h_viewer.app.job_progress import JobProgress
from s2h_viewer.errors import S2HError
from s2h_viewer.render.caption import add_caption, band_within, caption_text, clip_at, page_caption
from s2h_viewer.render.compare_scene import Framing, ViewOptions, render_comparison
from s2h_viewer.retarget.comparison import Comparison, MethodResult
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.retarget.progress import Cancelled
from s2h_viewer.wording import counted


def wrote_text(path: Path, what: str, metrics: QFontMetrics, room: int) -> str:
    """"wrote PATH WHAT" in ``room`` pixels: where it does not fit, the file's name with what came with it, then
    its folder elided in the middle (a motion's message named three files, and the window's edge cut off all
    but the first); where even the names do not fit, the sidecars named after the file in ``what`` say "…" for
    its stem (a suggested name 61 characters long cut off the corrections file's name at 1400 pixels)."""
    whole = f"wrote {path}{what}"
    if metrics.horizontalAdvance(whole) <= room:
        return whole
    head = f"wrote {Path(path).name}{what} in "
    if metrics.horizontalAdvance(head + "/...//") > room:
        head = f"wrote {Path(path).name}{what.replace(Path(path).stem, chr(0x2026))} in "
    folder = metrics.elidedText(str(Path(path).parent), Qt.TextElideMode.ElideMiddle,
                                max(room - metrics.horizontalAdvance(head), metrics.horizontalAdvance("/...//")))
    return metrics.elidedText(head + folder, Qt.TextElideMode.ElideRight, room)


@dataclass(frozen=True)
class Shown:
    """What the compare window shows at one moment, for an export asked then: the comparison, its page of
    targets in the grid, the selected retarget, the frame, the view's options, camera and size, and with
    ``grab`` its picture. A PNG written after its file dialog closed had held another clip than its name said:
    the clip opened before had come in meanwhile."""

    comparison: Comparison  # every target's results
    page: Comparison  # the page of targets in the grid
    selected: MethodResult
    frame: int
    options: ViewOptions
    framing: Framing
    view_size: tuple[int, int]
    image: np.ndarray | None = None  # the view grabbed (RGB), for a PNG at the view's size

    @classmethod
    def of(cls, mode: CompareMode, grab: bool = False) -> "Shown":
        view = mode.view
        size = (view.interactor.width(), view.interactor.height()) if view.interactor is not None else (1400, 900)
        image = None
        if grab:
            with mode.fixing.ring_hidden():  # the fixer's ring is no part of the picture
                image = view.grab_rgb()
        return cls(mode.comparison, view.comparison, mode.selected_result(), mode.timeline.frame, view.options,
                   view.framing(), size, image)

    def caption(self, frame: int) -> str:
        """The picture's line: clip (and the pose it holds there), frame and the selected retarget, or, where the
        selection is on another page of targets than the one exported, the page's targets (the caption names what the
        picture shows)."""
        motion, n_frames = self.comparison.motion, self.comparison.n_frames
        clip = clip_at(motion.name, motion.labels, frame)
        if self.page is not None and not any(r is self.selected for r in self.page.results):
            return page_caption(clip, frame, n_frames, motion.fps,
                                list(dict.fromkeys(r.target.name for r in self.page.results)))
        return caption_text(clip, frame, n_frames, motion.fps,
                            METHODS[self.selected.method].label + (" (fixed)" if self.selected.corrections else ""),
                            self.selected.target.name)

    def name(self, suffix: str, frame: int | None = None, result: MethodResult | None = None) -> str:
        """'<clip>_<target>_<method>[_f<frame>]<suffix>' for the selected retarget (or ``result``), safe as a file
        name."""
        result = result or self.selected
        parts = [self.comparison.motion.name, result.target.name, result.method] + ["fixed"] * bool(result.corrections)
        stem = "_".join(re.sub(r"[^\w.-]+", "-", part).strip("-.") or "x" for part in parts)
        return f"{stem}{'' if frame is None else f'_f{frame:04d}'}{suffix}"


#: the export sizes File > Export size offers, pixels; None: the view's own
EXPORT_SIZES: tuple[tuple[int, int] | None, ...] = (None, (1280, 720), (1920, 1080), (2560, 1440), (3840, 2160))


def size_text(size: tuple[int, int] | None) -> str:
    return "as the view" if size is None else f"{size[0]} x {size[1]}"


def sized(size: tuple[int, int] | None, shown: Shown) -> tuple[tuple[int, int], int | None]:
    """The grid's pixels and its caption band's for an export at ``size`` (band included: a 1920 x 1080 export
    was 1108 tall, its caption as small as at 720), or at the view's size with the band under it (None)."""
    if size is None:
        return shown.view_size, None
    band = band_within(size[1])
    return (size[0], size[1] - band), band


def export_screenshot(shown: Shown, path: str, size: tuple[int, int] | None = None) -> Path:
    """The grid as it was ``shown`` with its caption, written atomically: its grabbed picture, or a ``size``
    picture rendered off screen with its page of targets, camera, overlays, solo and selection."""
    from PIL import Image

    from s2h_viewer.io.atomic import atomic_path
    if size is not None or shown.image is None:
        grid, band = sized(size, shown)
        return render_comparison(shown.page, path, frame=shown.frame, size=grid, band=band, caption=shown.caption,
                                 options=shown.options, framing=shown.framing)
    image = add_caption(shown.image, shown.caption(shown.frame))
    with atomic_path(path) as tmp:
        Image.fromarray(image).save(tmp, format="PNG")
    return Path(path)


def frames_text(frames: range, n_frames: int) -> str:
    """'138 frames' for a whole clip of 138, else '81 frames: 40 to 120' (the clip's indices), '1 frame: 1'."""
    count = counted(len(frames), "frame")
    if len(frames) == n_frames:
        return count
    return f"{count}: {frames.start}" + (f" to {frames[-1]}" if len(frames) > 1 else "")


class VideoExport(QObject):
    """One video export of ``frames`` of the clip (default: all) in a worker thread: ``written(path)``,
    ``cancelled()`` or ``failed(message)`` arrive on the GUI thread; ``progress(done, total)`` after each
    frame, counting the frames asked."""

    progress = Signal(int, int)
    written = Signal(object)
    cancelled = Signal()
    failed = Signal(str)

    def __init__(self, shown: Shown, path: str, parent: QWidget, frames: range | None = None,
                 size: tuple[int, int] | None = None):
        super().__init__(parent)
        n_frames = shown.comparison.n_frames
        self.path, self.frames = path, range(n_frames) if frames is None else frames
        self._cancel = threading.Event()
        captions = {f: shown.caption(f) for f in self.frames}
        self._job = (shown.page, captions, *sized(size, shown), shown.options, shown.framing)
        label = f"Rendering {Path(path).name}\n({frames_text(self.frames, n_frames)})..."  # the range whole
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
        comparison, captions, size, band, options, framing = self._job
        try:
            path = render_comparison(comparison, self.path, size=size, band=band, progress=self._frame_done,
                                     caption=captions.__getitem__, options=options, frames=self.frames,
                                     framing=framing)
        except Cancelled:
            self.cancelled.emit()
        except (OSError, ValueError) as exc:
            self.failed.emit(f"{self.path}: could not write the video ({exc})")
        else:
            self.written.emit(path)


def export_motion(shown: Shown, path: str, frames: range | None = None) -> Path:
    """The selected retarget's motion on its target's rig: ``frames`` of it (default: the whole clip)."""
    import dataclasses

    from s2h_viewer.io.files import save_motion_file
    result = shown.selected
    motion = result.motion
    if frames is not None and len(frames) < motion.n_frames:
        part = slice(frames.start, frames.stop)
        motion = dataclasses.replace(motion, q_tbs=motion.q_tbs[part], labels=motion.labels[part], fit=None,
                                     meta={**motion.meta, "frames": [frames.start, frames[-1]]})
    save_motion_file(path, motion, result.target)
    return Path(path)


def corrections_to_remove(mode: CompareMode, shown: Shown, motion_path: str | Path) -> str | None:
    """What an export of the selected retarget to ``motion_path`` would take away with the sidecar beside it: the
    corrections it holds, said for a question, where the retarget has none of its own and the sidecar's keys are
    held nowhere in this session (an earlier session's export: the file is their only record). None: nothing lost."""
    from s2h_viewer.io.corrections import is_corrections_file, load_corrections, sidecar_path
    sidecar = sidecar_path(motion_path)
    if shown.selected.corrections or not is_corrections_file(sidecar) or mode.fixing.holds(sidecar):
        return None
    try:
        held = load_corrections(sidecar)
    except S2HError:  # a damaged sidecar holds nothing that could be loaded back
        return None
    if not held.corrections:
        return None
    return (f"{sidecar.name} beside it holds {counted(held.corrections.n_keys, 'correction key')} "
            f"({held.corrections.describe()}) made on "
            f"{METHODS[held.method].label if held.method in METHODS else held.method} -> {held.target}; "
            f"this export has none, so it would be removed")


def export_corrections(mode: CompareMode, shown: Shown, motion_path: str | Path, frames: range | None = None
                       ) -> tuple[Path | None, str]:
    """Beside a motion just exported from the selected retarget (``frames`` of the clip): the sidecar of its
    corrections (`io.corrections`; a part says which frames it is of), or, without corrections, none (an
    earlier export's sidecar there is removed: it would tell of corrections the motion no longer has). Returns the
    sidecar written (or None) and a note for the status line (a removed sidecar, and whose corrections it held)."""
    from s2h_viewer.io.corrections import is_corrections_file, sidecar_path
    result = shown.selected
    sidecar = sidecar_path(motion_path)
    part = frames if frames is not None and len(frames) < shown.comparison.n_frames else None
    if result.corrections:
        return mode.fixing.save(sidecar, result, part), ""
    if not is_corrections_file(sidecar):
        return None, ""
    sidecar.unlink(missing_ok=True)
    held = mode.fixing.removed(sidecar)
    return None, f"; removed {sidecar.name}, an earlier export's" + (
        f" (it held the corrections of {held}: not saved now)" if held else "")
