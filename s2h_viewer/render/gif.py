"""GIF written frame by frame as frames come (Pillow's frame-level GIF functions), so the work of
writing is spread over the frames: a caller reporting progress per frame reports the writing too, and can
stop between any two frames. GIF delays count centiseconds; each frame's delay is the rounded clip time of
the next frame minus its own, so the file lasts the clip's length (a 30 fps clip: 3, 3, 4, 3, 3, 4 cs)."""

from __future__ import annotations

from typing import BinaryIO

import numpy as np
from PIL import GifImagePlugin, Image

#: the shortest delay players honour: browsers play a delay of 0 or 1 cs as 10 cs, so a frame due sooner
#: than this after the last one written is skipped (a 60 fps clip keeps two frames in three, in real time)
MIN_DELAY_CS = 2


def frame_delays(n_frames: int, fps: float) -> dict[int, int]:
    """{frame index: delay in cs} for the frames a GIF of the clip holds; the delays add up to the clip's
    length rounded to a centisecond."""
    ticks = [round(100.0 * i / fps) for i in range(n_frames + 1)]  # each frame's start, the clip's end last
    kept = [0]
    for i in range(1, n_frames):
        if ticks[i] - ticks[kept[-1]] >= MIN_DELAY_CS and ticks[n_frames] - ticks[i] >= MIN_DELAY_CS:
            kept.append(i)
    return {i: ticks[j] - ticks[i] for i, j in zip(kept, [*kept[1:], n_frames])}


class GifWriter:
    """Appends RGB frames to an open binary file: each one quantised to its own 256-colour palette and
    cropped to what changed since the last frame written (the rest stays on screen)."""

    def __init__(self, file: BinaryIO, n_frames: int, fps: float):
        self.file = file
        self.delays = frame_delays(n_frames, fps)
        self.index = 0
        self._last: np.ndarray | None = None

    def append(self, frame: np.ndarray) -> None:
        """Frame ``index`` of the clip, (H, W, 3) uint8; frames the GIF skips (``frame_delays``) are dropped."""
        index, self.index = self.index, self.index + 1
        if index not in self.delays:
            return
        frame = np.ascontiguousarray(np.asarray(frame)[..., :3])
        box = changed_box(self._last, frame)
        image = quantise(frame[box[1]:box[3], box[0]:box[2]])
        if self._last is None:
            header, _ = GifImagePlugin.getheader(image, info={"loop": 0, "duration": 10 * self.delays[index]})
            self.file.write(b"".join(header))
        data = GifImagePlugin.getdata(image, offset=box[:2], duration=10 * self.delays[index],
                                      include_color_table=True)
        self.file.write(b"".join(data))
        self._last = frame

    def close(self) -> None:
        self.file.write(b";")  # the GIF trailer


def quantise(rgb: np.ndarray) -> Image.Image:
    """256 colours of the image's own (octree: a tenth of median cut's time, the same look on shaded skin)."""
    return Image.fromarray(rgb).quantize(256, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)


def changed_box(last: np.ndarray | None, frame: np.ndarray) -> tuple[int, int, int, int]:
    """(left, top, right, bottom) around the pixels that differ from ``last`` (all of them without one; one
    pixel when none does: a GIF frame cannot be empty)."""
    if last is None or last.shape != frame.shape:
        return 0, 0, frame.shape[1], frame.shape[0]
    changed = (last != frame).any(-1)
    rows, columns = np.flatnonzero(changed.any(1)), np.flatnonzero(changed.any(0))
    if not len(rows):
        return 0, 0, 1, 1
    return int(columns[0]), int(rows[0]), int(columns[-1]) + 1, int(rows[-1]) + 1
