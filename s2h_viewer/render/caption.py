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


def caption_text(clip: str, frame: int, n_frames: int, fps: float, method: str, target: str) -> str:
    """One line: the clip, the frame of how many and its time, the selected retarget."""
    return f"{clip}   frame {frame}/{n_frames - 1}  ({frame / fps:.2f} s)   selected: {method} -> {target}"
