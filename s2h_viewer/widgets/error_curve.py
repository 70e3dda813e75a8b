"""A per-frame curve under the timeline (the selected retarget's ASM error, or a tracked source's fit
residual): a click jumps to that frame (a drag scrubs), the worst frames are marked, the current frame is a
vertical line, the pointer's frame and value are in its tooltip."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QEvent, QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QPainter, QPen, QPixmap, QPolygonF
from PySide6.QtWidgets import QToolTip, QWidget

from s2h_viewer.wording import counted

WORST = 5  # frames marked
#: for Help's list
MOUSE = (("click the error curve (or drag along it)", "jump to that frame (scrub)"),
         ("hover over the error curve", "the frame under the pointer and its value (the source's beside it)"))
MISSING_COLOUR = QColor("#d9d9d9")
OUTSIDE_RANGE_COLOUR, RANGE_COLOUR = QColor("#eeeeee"), QColor("#2e7d32")
REFERENCE_COLOUR = QColor("#9e9e9e")
#: a curve within this of its reference everywhere (their units: degrees for a joint's bend) is the same, as shown
SAME_WITHIN = 0.05
KEY_COLOUR = QColor("#e8a317")  # a correction's keyed frames (the rotation ring's colour)
MARGIN = 6  # pixels around the curve: a worst frame's ring (radius 3) at either end stays whole


def worst_frames(error: np.ndarray, count: int = WORST, spacing: int | None = None) -> np.ndarray:
    """The ``count`` highest-error frames, at least ``spacing`` frames apart (one peak, one mark)."""
    spacing = spacing if spacing is not None else max(1, len(error) // 50)
    chosen: list[int] = []
    for frame in np.argsort(-error, kind="stable"):
        if all(abs(int(frame) - c) >= spacing for c in chosen):
            chosen.append(int(frame))
        if len(chosen) == count:
            break
    return np.array(sorted(chosen), dtype=int)


def frame_ticks(n_frames: int, width: float, spacing: float = 60.0) -> list[int]:
    """Frame numbers for the curve's axis: multiples of a 1-2-5 step, at least ``spacing`` pixels apart over
    ``width`` pixels, the clip's first frame always among them."""
    last = max(1, n_frames - 1)
    wanted = max(1.0, last * spacing / max(width, 1.0))  # frames per tick at the closest allowed spacing
    step = next(m * 10 ** k for k in range(0, 10) for m in (1, 2, 5) if m * 10 ** k >= wanted)
    return list(range(0, last + 1, step))


def next_worst(worst: np.ndarray, frame: int, direction: int, within: range | None = None
               ) -> tuple[int, bool] | None:
    """The marked worst frame after ``frame`` (``direction`` +1) or before it (-1), and whether it wrapped round
    the clip (or round ``within``, the timeline's marked range, which playback keeps to); None where none is
    marked there (the Playback menu's worst-frame keys)."""
    if within is not None:
        worst = worst[(worst >= within.start) & (worst < within.stop)]
    if len(worst) == 0:
        return None
    later = worst[worst > frame] if direction > 0 else worst[worst < frame][::-1]
    if len(later):
        return int(later[0]), False
    return int(worst[0] if direction > 0 else worst[-1]), True


class ErrorCurve(QWidget):
    """Emits ``frame_clicked(frame)``; ``set_curve`` gives the (T,) values, a title and what they measure."""

    frame_clicked = Signal(int)

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.setMinimumHeight(76)  # the curve over its frame axis, the axis' numbers and the caption
        self.setMaximumHeight(96)
        self.setMouseTracking(True)  # the tooltip follows the pointer's frame
        self.error = np.zeros(1)
        self.missing = np.zeros(1, dtype=bool)
        self.worst = np.zeros(0, dtype=int)
        self.frame = 0
        self.title = ""
        self.marked: range | None = None  # the timeline's in and out points
        self.reference: np.ndarray | None = None
        self.gap: np.ndarray | None = None
        self.keys = np.zeros(0, dtype=int)  # frames keyed by the retarget's corrections (`set_keys`)
        self.quantity = "ASM error per frame"
        self.decimals = 3  # how its figures are written (`set_curve`)
        self._curve: QPixmap | None = None  # the curve and its marks, drawn once per curve and size

    def set_curve(self, error: np.ndarray, title: str, quantity: str = "ASM error per frame",
                  note: str = "", reference: np.ndarray | None = None, decimals: int = 3) -> None:
        """``error`` (T,); NaN frames (none measured there: a recording's filled frames) are shaded grey, drawn
        at 0 and never marked worst. ``decimals``: how its figures are written (an ASM error's 0.021, a bend's 89.0)."""
        self.decimals = decimals
        values = np.asarray(error, dtype=float)
        self.missing = ~np.isfinite(values)
        self.error, self.title, self.quantity = np.nan_to_num(values), title, quantity
        #: a curve to read it against (the source's joint angle beside the retarget's), grey, on the same axis
        self.reference = None if reference is None else np.nan_to_num(np.asarray(reference, dtype=float))
        #: how far the curve parts from its reference, frame by frame (None without one)
        self.gap = None if self.reference is None else np.abs(self.error - self.reference)
        if self.gap is None:
            self.worst = worst_frames(self.error)
        else:  # where the two part most; nowhere where they do not part (red marks on a copy's exact bends misled)
            self.worst = worst_frames(self.gap) if self.gap.max() >= SAME_WITHIN else np.zeros(0, dtype=int)
        self._curve = None
        QToolTip.hideText()  # one shown over the old curve read its values (another clip's) until the pointer moved
        self.setToolTip(f"{title}: {quantity}; worst frames (red): "
                        f"{', '.join(str(f) for f in self.worst) or 'none'}. {note}Click to jump; ] and [ step "
                        f"between the worst frames.")
        self.update()

    def value_at(self, frame: int) -> str:
        """The tooltip's first line: "frame 120: 45.2, the source's 44.9 (apart by 0.3)"; the curve's own value
        is drawn under the grey band where the two are close, and a 1-3 deg gap on a 90 deg axis hid there."""
        if self.missing[frame]:
            return f"frame {frame}: not measured"
        text = f"frame {frame}: {self._figure(self.error[frame])}"
        if self.reference is not None:
            text += f", the source's {self._figure(self.reference[frame])} (apart by {self._figure(self.gap[frame])})"
        return text

    def event(self, event) -> bool:
        if event.type() == QEvent.Type.ToolTip:
            QToolTip.showText(event.globalPos(), self._tooltip_at(event.pos().x()), self)
            return True
        return super().event(event)

    def mouseMoveEvent(self, event) -> None:
        if event.buttons() & Qt.MouseButton.LeftButton:  # dragged: it scrubs, as the timeline's slider does
            self.frame_clicked.emit(self.frame_at(event.position().x()))
        elif QToolTip.isVisible():  # shown: it follows the pointer from frame to frame
            QToolTip.showText(event.globalPosition().toPoint(), self._tooltip_at(event.position().x()), self)
        super().mouseMoveEvent(event)

    def _tooltip_at(self, x: float) -> str:
        return f"{self.value_at(self.frame_at(x))}\n{self.toolTip()}"

    def apart(self) -> str:
        """How far the curve and its reference part at most, and where (empty without a reference): TBS Copy's
        bends are the source's, so its curve covers the grey one, and a user saw no grey curve at all."""
        if self.gap is None:
            return ""
        frame = int(self.gap.argmax())
        if self.gap[frame] < SAME_WITHIN:
            return ", the same as the source's throughout"
        return f", apart by at most {self._figure(self.gap[frame])} (frame {frame})"

    def set_keys(self, frames: np.ndarray) -> None:
        """Mark the frames the shown retarget's corrections key (diamonds on the frame axis)."""
        self.keys = np.asarray(frames, dtype=int)
        self._curve = None
        self.update()

    def set_range(self, marked: range | None) -> None:
        """Shade the frames outside the timeline's marked range (None: nothing marked)."""
        self.marked = marked
        self._curve = None
        self.update()

    def set_frame(self, frame: int) -> None:
        """Move the cursor: only the strips under the old and the new cursor are repainted."""
        for x in (self._x(self.frame), self._x(frame)):
            self.update(int(x) - 2, 0, 5, self.height())
        self.frame = frame

    def resizeEvent(self, event) -> None:
        self._curve = None
        super().resizeEvent(event)

    def _left(self) -> float:
        """Where frame 0 is drawn: right of the value axis' widest number."""
        return MARGIN + self.fontMetrics().horizontalAdvance(self._figure(self.top)) + 4

    def axis_y(self) -> float:
        """The frame axis' line: the curve's 0, above a row of frame numbers and the caption's row."""
        return self.height() - 2 * self.fontMetrics().height() - 4

    def frame_at(self, x: float) -> int:
        width = max(1.0, self.width() - MARGIN - self._left())
        return int(round(np.clip((x - self._left()) / width, 0.0, 1.0) * (len(self.error) - 1)))

    @property
    def top(self) -> float:
        """The value axis' top: the curve's maximum, or its reference's where higher."""
        return float(max(self.error.max(), 0.0 if self.reference is None else self.reference.max()))

    def _x(self, frame: float) -> float:
        return self._left() + frame / max(1, len(self.error) - 1) * (self.width() - MARGIN - self._left())

    def _y(self, value: float) -> float:
        """The curve between the top margin and the frame axis (it used to run through the caption)."""
        top = max(self.top, 1e-9)
        return self.axis_y() - value / top * (self.axis_y() - MARGIN)

    def ticks(self) -> list[int]:
        """The frames numbered on the axis."""
        return frame_ticks(len(self.error), self.width() - MARGIN - self._left())

    def mousePressEvent(self, event) -> None:
        self.frame_clicked.emit(self.frame_at(event.position().x()))

    def _draw_curve(self) -> QPixmap:
        pixmap = QPixmap(self.size())
        pixmap.fill(QColor("white"))
        painter = QPainter(pixmap)
        painter.setRenderHint(QPainter.RenderHint.Antialiasing)
        if self.missing.any():  # frames with nothing measured: a grey band, not a low stretch of the curve
            width = max(1.0, (self.width() - 2 * MARGIN) / max(1, len(self.error) - 1))
            for frame in np.flatnonzero(self.missing):
                painter.fillRect(QRectF(self._x(frame) - width / 2, 0, width, self.height()), MISSING_COLOUR)
        if self.marked is not None:  # the timeline's marked range: outside it shaded, its ends drawn
            left, right, axis = self._x(self.marked.start), self._x(self.marked[-1]), self.axis_y()
            painter.fillRect(QRectF(0, 0, left, axis), OUTSIDE_RANGE_COLOUR)
            painter.fillRect(QRectF(right, 0, self.width() - right, axis), OUTSIDE_RANGE_COLOUR)
            painter.setPen(QPen(RANGE_COLOUR, 2))
            for x in (left, right):
                painter.drawLine(QPointF(x, 0), QPointF(x, axis))
        step = max(1, len(self.error) // max(1, self.width()))  # at most one point per pixel
        if self.reference is not None:
            painter.setPen(QPen(REFERENCE_COLOUR, 5))  # a band under the curve: seen where the two agree too
            painter.drawPolyline(QPolygonF([QPointF(self._x(f), self._y(self.reference[f]))
                                            for f in range(0, len(self.reference), step)]))
        points = [QPointF(self._x(f), self._y(self.error[f])) for f in range(0, len(self.error), step)]
        painter.setPen(QPen(QColor("#3b4cc0"), 1.5))
        painter.drawPolyline(QPolygonF(points))
        painter.setPen(QPen(QColor("#d62728"), 2))
        for frame in self.worst:
            x = self._x(frame)
            painter.drawLine(QPointF(x, MARGIN), QPointF(x, MARGIN + 8))
            painter.drawEllipse(QPointF(x, self._y(self.error[frame])), 3, 3)
        self._draw_axes(painter)
        painter.setPen(QPen(KEY_COLOUR.darker(130), 1))
        painter.setBrush(KEY_COLOUR)
        for frame in self.keys:  # a correction key: a diamond on the frame axis
            x, y = self._x(frame), self.axis_y()
            painter.drawPolygon(QPolygonF([QPointF(x, y - 5), QPointF(x + 4, y), QPointF(x, y + 5), QPointF(x - 4, y)]))
        painter.setPen(QPen(QColor("black"), 1))
        painter.drawText(MARGIN + 2, self.height() - 4, self.caption())
        painter.end()
        return pixmap

    def _figure(self, value: float) -> str:
        """A value as the caption and the tooltip write it (the axis' "0.0215" beside "max 0.021" read as two)."""
        return f"{value:.{self.decimals}f}"

    def caption(self) -> str:
        """The line under the curve: what it measures, whose, its maximum, how far it parts from its reference, keys."""
        keyed = f", keys at {counted(len(self.keys), 'frame')} (orange)" if len(self.keys) else ""
        return f"{self.quantity} ({self.title})   max {self._figure(self.error.max())}{self.apart()}{keyed}"

    def _draw_axes(self, painter: QPainter) -> None:
        """The value axis (0 and the maximum) on the left, the frame axis with numbered ticks below the curve."""
        metrics = self.fontMetrics()
        left, axis, right = self._left(), self.axis_y(), self.width() - MARGIN
        painter.setPen(QPen(QColor("#808080"), 1))
        painter.drawLine(QPointF(left, MARGIN), QPointF(left, axis))
        painter.drawLine(QPointF(left, axis), QPointF(right, axis))
        for value, y in ((0.0, axis), (self.top, float(MARGIN))):
            text = self._figure(value)
            painter.drawText(QPointF(left - 3 - metrics.horizontalAdvance(text), y + metrics.ascent() / 2), text)
        painter.setPen(QPen(QColor("black"), 1))
        for frame in self.ticks():
            x = self._x(frame)
            painter.drawLine(QPointF(x, axis), QPointF(x, axis + 3))
            text = str(frame)
            half = metrics.horizontalAdvance(text) / 2
            painter.drawText(QPointF(min(max(x - half, 0.0), self.width() - 2 * half), axis + 3 + metrics.ascent()),
                             text)

    def paintEvent(self, event) -> None:
        if self._curve is None or self._curve.size() != self.size():
            self._curve = self._draw_curve()
        painter = QPainter(self)
        painter.drawPixmap(event.rect(), self._curve, event.rect())
        painter.setPen(QPen(QColor("black"), 1))
        x = self._x(self.frame)
        painter.drawLine(QPointF(x, 0), QPointF(x, self.axis_y()))  # stops at the axis: clear of the caption
