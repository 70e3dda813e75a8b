"""A caption band under an exported image (clip, frame, method, target), so a PNG or a video frame
says what it shows when it is passed around without the window."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from s2h_viewer.wording import counted

BAND = 28  # pixels
FONT_PX = 15  # the caption's text in a band of BAND pixels; a taller band's is as much larger
MIN_FONT_SHARE = 0.6  # the smallest a caption's text is made to fit a narrow picture (9 pixels in a BAND band)


def band_within(height: int) -> int:
    """The caption band of a picture ``height`` pixels tall, band included (an export at a chosen size is that
    size): BAND up to 900 + BAND pixels, in proportion above (1080: 33, 2160: 65), so its text reads as large."""
    return max(BAND, round(BAND * height / (900 + BAND)))


def add_caption(image: np.ndarray, text: str, band: int = BAND) -> np.ndarray:
    """(H, W, 3) uint8 -> (H + band, W, 3): the image over a white band holding ``text`` in black, sized with
    the band, and smaller where it would not fit the width (down to `MIN_FONT_SHARE` of that; past it, its end
    elided): a long clip and target name ran off a narrow picture's edge."""
    scale = band / BAND
    width, margin = image.shape[1], round(8 * scale)
    size = round(FONT_PX * scale)
    font = ImageFont.load_default(size=size)
    while font.getlength(text) > width - 2 * margin and size > MIN_FONT_SHARE * FONT_PX * scale:
        size -= 1
        font = ImageFont.load_default(size=size)
    if font.getlength(text) > width - 2 * margin:
        while text and font.getlength(text + "...") > width - 2 * margin:
            text = text[:-1]
        text += "..."
    strip = Image.new("RGB", (width, band), "white")
    ImageDraw.Draw(strip).text((margin, round(6 * scale + (FONT_PX * scale - size) / 2)), text, fill="black",
                               font=font)
    return np.concatenate([np.asarray(image)[..., :3], np.asarray(strip)], 0)


def frame_readout(frame: int, n_frames: int, fps: float) -> str:
    """Frame index over the last index with the frame count, then the frame's time over the clip's length:
    '0/509 (510 frames)  0.00 s / 17.00 s' (indices from 0, as the frame box, the curve and file names)."""
    return f"{frame}/{n_frames - 1} ({counted(n_frames, 'frame')})  {frame / fps:.2f} s / {n_frames / fps:.2f} s"


def clip_at(name: str, labels, frame: int) -> str:
    """The clip's name, with the pose it holds at ``frame`` where its frames are labelled ("gestures, pose fist")."""
    label = labels[frame] if labels is not None and frame < len(labels) else ""
    return f"{name}, pose {label}" if label else name


def caption_text(clip: str, frame: int, n_frames: int, fps: float, method: str, target: str) -> str:
    """One line: the clip, the frame as the timeline reads it, the selected retarget."""
    return f"{clip}   frame {frame_readout(frame, n_frames, fps)}   selected: {method} -> {target}"


def page_caption(clip: str, frame: int, n_frames: int, fps: float, targets: list[str]) -> str:
    """One line: the clip, the frame, the targets pictured (a page of them without the selected retarget)."""
    return f"{clip}   frame {frame_readout(frame, n_frames, fps)}   targets: {', '.join(targets)}"
