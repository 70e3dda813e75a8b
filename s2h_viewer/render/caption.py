"""A caption band under an exported image (clip, frame, method, target), so a PNG or a video frame
says what it shows when it is passed around without the window."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont

BAND = 28  # pixels


def add_caption(image: np.ndarray, text: str) -> np.ndarray:
    """(H, W, 3) uint8 -> (H + BAND, W, 3): the image over a white band holding ``text`` in black."""
    band = Image.new("RGB", (image.shape[1], BAND), "white")
    ImageDraw.Draw(band).text((8, 6), text, fill="black", font=ImageFont.load_default(size=15))
    return np.concatenate([np.asarray(image)[..., :3], np.asarray(band)], 0)


def frame_readout(frame: int, n_frames: int, fps: float) -> str:
    """Frame index over the last index with the frame count, then the frame's time over the clip's length:
    '0/509 (510 frames)  0.00 s / 17.00 s' (indices from 0, as the frame box, the curve and file names)."""
    return f"{frame}/{n_frames - 1} ({n_frames} frames)  {frame / fps:.2f} s / {n_frames / fps:.2f} s"


def caption_text(clip: str, frame: int, n_frames: int, fps: float, method: str, target: str) -> str:
    """One line: the clip, the frame as the timeline reads it, the selected retarget."""
    return f"{clip}   frame {frame_readout(frame, n_frames, fps)}   selected: {method} -> {target}"


def page_caption(clip: str, frame: int, n_frames: int, fps: float, targets: list[str]) -> str:
    """One line: the clip, the frame, the targets pictured (a page of them without the selected retarget)."""
    return f"{clip}   frame {frame_readout(frame, n_frames, fps)}   targets: {', '.join(targets)}"
