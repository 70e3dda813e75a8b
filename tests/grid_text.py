"""The compare grid's labels as a user reads them, from VTK's text measures and the grid's pixels (no Qt: the
window's tests and the off-screen ones share it): each label's text box in its cell, and what else is drawn
in the text's rows."""

from __future__ import annotations

import numpy as np

WHITE = 235  # a channel above it: the background (text's anti-aliasing fades to it)
COLOURED = 40  # a pixel's channel spread above it: skin, error colours, contact dots (text is grey)


def text_actors(renderer) -> list:
    """The text actors drawn in ``renderer``'s cell (the labels; the colour bar is no text actor)."""
    return [prop for prop in renderer.GetViewProps() if prop.IsA("vtkTextActor")]


def text_box(actor, renderer) -> tuple[float, float, float, float]:
    """A text actor's box in its cell's pixels as VTK draws it: left, right, bottom, top (y up)."""
    box = [0.0] * 4
    actor.GetBoundingBox(renderer, box)  # about the text's anchor
    x, y = actor.GetPositionCoordinate().GetComputedViewportValue(renderer)
    return x + box[0], x + box[1], y + box[2], y + box[3]


def cell_pixels(image: np.ndarray, renderer) -> np.ndarray:
    """The part of a grid's (H, W, 3) image that ``renderer`` draws (rows from the top)."""
    h, w = image.shape[:2]
    x0, y0, x1, y1 = renderer.GetViewport()
    return image[int(round((1 - y1) * h)):int(round((1 - y0) * h)), int(round(x0 * w)):int(round(x1 * w))]


def inside(box: tuple[float, float, float, float], cell: np.ndarray) -> bool:
    """The text box lies in the cell (a pixel's rounding allowed)."""
    left, right, bottom, top = box
    return left >= -0.5 and bottom >= -0.5 and right <= cell.shape[1] + 0.5 and top <= cell.shape[0] + 0.5


def intruders(cell: np.ndarray, box: tuple[float, float, float, float]) -> int:
    """Pixels in the rows from the cell's top to the text's bottom that are not the text: anything not white
    beside the text, and coloured pixels within its box (the hand, its skeleton or its contact dots)."""
    left, right, bottom, _ = box
    rows = cell[:max(0, int(np.ceil(cell.shape[0] - bottom)))].astype(int)
    drawn = (rows < WHITE).any(-1)
    coloured = (rows.max(-1) - rows.min(-1)) > COLOURED
    beside = np.ones(rows.shape[1], dtype=bool)
    beside[max(0, int(left) - 1):int(np.ceil(right)) + 2] = False
    return int(drawn[:, beside].sum() + coloured[:, ~beside].sum())


def hand_drawn(cell: np.ndarray) -> int:
    """Pixels of a cell that are not the white background."""
    return int((cell < WHITE).any(-1).sum())
