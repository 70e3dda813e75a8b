"""Video files from rendered frames (MP4 through imageio-ffmpeg, GIF through `render.gif`), written
atomically and as the frames come: the frames are never all held, and a stop between two frames (an
exception from the frames' iterator) leaves no file."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import imageio.v2 as imageio
import numpy as np

from s2h_viewer.errors import FrameRangeError
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.render.gif import GifWriter

VIDEO_SUFFIXES = (".mp4", ".gif")


def write_video(path: str | Path, frames: Iterable[np.ndarray], fps: float, n_frames: int) -> Path:
    """Write ``n_frames`` RGB frames (H, W, 3) uint8 as MP4 (H.264) or GIF by suffix; returns the path."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        raise ValueError(f"{path}: video must be {' or '.join(VIDEO_SUFFIXES)}")
    with atomic_path(path) as tmp:
        if suffix == ".mp4":
            with imageio.get_writer(tmp, fps=fps, codec="libx264", quality=8, macro_block_size=2,
                                    ffmpeg_log_level="error") as writer:
                for frame in frames:
                    writer.append_data(_even(np.asarray(frame)[..., :3]))
        else:
            with open(tmp, "wb") as file:
                gif = GifWriter(file, n_frames, fps)
                for frame in frames:
                    gif.append(frame)
                gif.close()
    return path


def frame_range(n_frames: int, start: int | None = None, end: int | None = None, clip: str = "the clip") -> range:
    """Frames ``start`` to ``end`` of a clip of ``n_frames``, both included (indices from 0, as the timeline
    counts; missing ends: the clip's); a `FrameRangeError` naming the clip's frame count for any other."""
    first, last = 0 if start is None else start, n_frames - 1 if end is None else end
    if not (0 <= first < n_frames and 0 <= last < n_frames):
        asked = f"frame {first} is not" if first == last else f"frames {first} to {last} are not all"
        raise FrameRangeError(f"{clip}: {asked} in the clip, which has {n_frames} frames (0 to {n_frames - 1})")
    if first > last:
        raise FrameRangeError(f"{clip}: frames {first} to {last}: the first comes after the last; the clip has "
                              f"{n_frames} frames (0 to {n_frames - 1})")
    return range(first, last + 1)


def _even(frame: np.ndarray) -> np.ndarray:
    """H.264 in 4:2:0 wants even sizes: an odd one padded by a row or column of the edge colour rather than
    rescaled. Padding to whole 16-pixel macro blocks, as before, wrote a 1920 x 1080 export 1088 tall."""
    h, w = frame.shape[:2]
    return np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
