"""Compare mode's viewport: the compare grid (`render.compare_scene`) in one render window with
linked cameras, rendered off screen and shown as an image (`widgets.vtk_widget`), redrawn on ``show_frame``.

A new frame asks for a repaint (``update``): one render per frame for the whole grid. While the timeline
plays, each skin of the grid is drawn with fewer faces; paused or shown alone, the full display mesh. A click
on a retarget selects it; a double-click on a hand shows its viewport alone (solo), a second one brings the
grid back; a cell's warning banner has its whole text as a tooltip. ``drawn`` fires after every render, so the
timeline can show the frames actually drawn per second. While playing, the frame expected next is posed on a
worker thread (numpy alone) while the current one is drawn (`prefetch`): the GUI thread then only copies it
in. The worker starts when the render does: VTK lets go of Python's lock while it draws, where the GUI
thread's own Python (the heatmap, the curve, the paint) would wait for the worker to let go of it."""

from __future__ import annotations

import dataclasses
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, QObject, Qt, QTimer, Signal
from PySide6.QtWidgets import QHBoxLayout, QLabel, QToolButton, QToolTip, QVBoxLayout, QWidget
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

from s2h_viewer.render.compare_scene import (PLAYING_FACES, CellLabel, Framing, Ghost, PosedHand, PosedSkin,
                                             ViewOptions, apply_options, contact_words, fit_cells, grid_layout,
                                             populate, result_label, show_alone, solo_ghost)
from s2h_viewer.retarget.comparison import Comparison, target_ids, target_page
from s2h_viewer.widgets.rotation_handle import is_click
from s2h_viewer.widgets.tooltips import wrapped
from s2h_viewer.widgets.vtk_widget import PlotterWidget, window_plotter

#: the mouse in the grid beyond the camera (`vtk_widget.MOUSE`), for Help's list
MOUSE = (("click a retarget in the grid", "select it (the heatmap, the curve, the table and the exports follow)"),
         ("double-click a hand", "show it alone and select it; double-click again for the grid"),
         ("rest the pointer on a cell's orange banner", "its whole warning"))
#: pixels a target's row needs at least (its label band and a hand that reads): more targets than fit page
MIN_ROW_PX = 130
#: the pointer names a contact link (its tooltip) within this many pixels of it
LINK_REACH_PX = 6
FRAME_FILL = 0.9  # View > Frame the hand: the share of the cell the hand's box fills
REFIT_MS = 200  # after a resize, the rows that fit are counted again once it has settled


class CompareView(QWidget):
    """Source + targets x methods, synchronised on ``show_frame``."""

    drawn = Signal()
    solo_changed = Signal(int)  # the hand shown alone (index into the grid's hands), -1 for the grid
    hand_clicked = Signal(int)  # a click (not a camera drag) on a hand of the grid (index into its hands)
    double_clicked = Signal()  # a double-click, before it shows a hand alone or the grid (its first click was one)
    page_changed = Signal(int)  # the page of targets shown
    grid_built = Signal()  # a new render window and widget hold the grid (a new comparison, page or size)

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self._layout = QVBoxLayout(self)
        self._layout.setContentsMargins(0, 0, 0, 0)
        self._layout.addWidget(self._page_bar())
        self.interactor: PlotterWidget | None = None
        self.plotter: pv.Plotter | None = None
        self.full: Comparison | None = None  # every target's results
        self.comparison: Comparison | None = None  # the page of them in the grid
        self.page, self.rows, self.offset = 0, 1, 0  # the page, its targets at most, its first result's index
        self._refit = QTimer(self)
        self._refit.setSingleShot(True)
        self._refit.setInterval(REFIT_MS)
        self._refit.timeout.connect(self._fit_rows)
        self._hands: list[PosedHand] = []
        self._labels: list[CellLabel] = []
        self.options = ViewOptions()
        self.solo = -1
        self.selected = -1  # the retarget framed (the comparison's results' order)
        self._ghost: Ghost | None = None  # the source's ghost over the retarget shown alone
        self._viewports: list[tuple[float, ...]] = []
        self._grid_camera: tuple | None = None  # the camera before a hand alone was framed (F): the grid's again
        self._pressed_at: tuple[int, int] | None = None  # where the left button went down in the grid
        self.frame = 0
        self.playing = False
        self._posing = ThreadPoolExecutor(max_workers=1, thread_name_prefix="posing")
        self._ahead: tuple[int, Future] | None = None  # a frame being posed ahead, and its skins to come
        self._wanted: int | None = None  # the frame to pose ahead once the next render starts
        self.prefetched = self.posed_here = 0  # frames shown from the worker's skins / posed when shown

    @property
    def opacity(self) -> float:
        return self.options.opacity

    def _page_bar(self) -> QWidget:
        """"Targets 1-2 of 6" between Previous and Next: shown when more targets than fit share the grid."""
        self.pager = QWidget()
        self.page_label = QLabel()
        self.previous_page, self.next_page = QToolButton(), QToolButton()
        for button, text, step in ((self.previous_page, "< Previous", -1), (self.next_page, "Next >", 1)):
            button.setText(text)
            button.clicked.connect(lambda _=False, d=step: self.set_page(self.page + d))
        layout = QHBoxLayout(self.pager)
        layout.setContentsMargins(4, 2, 4, 2)
        layout.addWidget(self.previous_page)
        layout.addWidget(self.page_label, 1)
        layout.addWidget(self.next_page)
        self.pager.hide()
        return self.pager

    @property
    def page_count(self) -> int:
        return max(1, -(-len(target_ids(self.full)) // self.rows)) if self.full is not None else 1

    def rows_fitting(self) -> int:
        """The target rows the view's height holds at `MIN_ROW_PX` each (the page bar's height left out)."""
        return max(1, (self.height() - self.pager.sizeHint().height()) // MIN_ROW_PX)

    def set_comparison(self, comparison: Comparison) -> None:
        """Show ``comparison``: as many target rows as fit (`rows_fitting`), the rest on further pages."""
        self.full = comparison
        self.selected = -1  # an index of the previous results: the mode selects again
        self.rows = self.rows_fitting()
        self.page = min(self.page, self.page_count - 1)
        self._build()

    def set_page(self, page: int) -> None:
        """Show page ``page`` of the targets (clamped), the selected retarget framed if it is on it."""
        page = min(max(page, 0), self.page_count - 1)
        if self.full is None or page == self.page:
            return
        self.page = page
        self._build()
        self.page_changed.emit(page)

    def _page_of(self, index: int) -> int:
        """The page holding result ``index`` (of the whole comparison)."""
        return target_ids(self.full).index(id(self.full.results[index].target)) // self.rows

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        if self.full is not None and self.rows_fitting() != self.rows:
            self._refit.start()

    def _fit_rows(self) -> None:
        """The window's height changed the rows that fit: the grid again, on the page of the selected retarget
        (a hand shown alone stays so: the grid is laid out again when it comes back)."""
        if self.full is None or self.solo >= 0 or self.rows_fitting() == self.rows:
            return
        self.rows = self.rows_fitting()
        self.page = self._page_of(self.selected) if self.selected >= 0 else min(self.page, self.page_count - 1)
        self._build()
        self.page_changed.emit(self.page)

    def result_of_hand(self, hand: int) -> int:
        """The index in the whole comparison's results of the grid's hand ``hand`` (>= 1: a retarget)."""
        return self.offset + hand - 1

    def hand_of_result(self, index: int) -> int:
        """The grid's hand showing result ``index`` of the whole comparison, turning to its page first."""
        self.set_page(self._page_of(index))
        return 1 + index - self.offset

    def _build(self) -> None:
        """Lay out one subplot per hand of the page: the source, then a row per target, a column per method."""
        comparison, self.offset = target_page(self.full, self.page, self.rows)
        pages = self.page_count
        self.pager.setVisible(pages > 1)
        first = self.page * self.rows
        count = len(target_ids(self.full))
        last = min(first + self.rows, count)
        shown = f"target {first + 1}" if last == first + 1 else f"targets {first + 1}-{last}"
        self.page_label.setText(f"{shown} of {count} (page {self.page + 1} of {pages}: Ctrl+PgUp / Ctrl+PgDown)")
        self.previous_page.setEnabled(self.page > 0)
        self.next_page.setEnabled(self.page < pages - 1)
        kept = None
        if self.plotter is not None and self.comparison is not None and self.comparison.source is comparison.source:
            camera = self.plotter.camera  # the user's camera (dragged or a preset) outlives the grid
            kept = (camera.position, camera.focal_point, camera.up)
        self.comparison = comparison
        self.close_grid()  # pyvista fixes the subplot layout at construction: start afresh
        self.plotter = window_plotter(**grid_layout(comparison, self.rows if pages > 1 else None))
        self.interactor = PlotterWidget(self.plotter, self)
        self.interactor.installEventFilter(self)
        self.plotter.render_window.AddObserver("StartEvent", lambda *_: self._render_starts())
        self.plotter.render_window.AddObserver("EndEvent", lambda *_: self.drawn.emit())
        self._layout.addWidget(self.interactor)
        if self.isVisible():  # shown and sized now, not at the next event loop: a grab right after draws at its size
            self.interactor.show()
            self._layout.activate()
        self.interactor.Initialize()
        self._ghost = None  # it was in the grid being replaced
        self._hands, self._labels = populate(self.plotter, comparison, self.options.opacity,
                                             playing_faces=PLAYING_FACES)
        self._viewports = [tuple(r.GetViewport()) for r in self.plotter.renderers]
        self.solo = -1
        self._choose_skins()
        apply_options(self.plotter, self._hands, self.options)
        if kept is not None:  # one camera for every viewport still: the same scale for source and targets
            camera = self.plotter.camera
            camera.position, camera.focal_point, camera.up = kept
            for renderer in self.plotter.renderers:
                renderer.ResetCameraClippingRange()
        self._frame_selected()
        self.show_frame(min(self.frame, comparison.n_frames - 1))
        self.grid_built.emit()

    def add_bar(self, bar: QWidget) -> None:
        """A bar over the 3D view, under the page bar (its owner shows and hides it)."""
        self._layout.insertWidget(1, bar)

    def replace_result(self, index: int, comparison: Comparison) -> None:
        """Result ``index`` of ``comparison`` (the one shown, with that result changed: a corrected retarget) drawn
        in place, in its cell if it is on the page shown; nothing else is rebuilt."""
        self.full = comparison
        self.comparison, self.offset = target_page(comparison, self.page, self.rows)
        hand = 1 + index - self.offset
        if 1 <= hand < len(self._hands):
            result = comparison.results[index]
            self._hands[hand].set_result(result.pose, result.joint_error, result_label(result))
            if self._ghost is not None:
                self._ghost.follow()
            if self.interactor is not None:
                self.interactor.update()

    def frame_hand(self) -> bool:
        """Turn the camera onto the hand shown alone so that it fills the view (as a 3D tool's "frame selected"):
        a small hand's fingers readable, to fix them; False (nothing done) in the grid."""
        hand = self._hands[self.solo] if 0 <= self.solo < len(self._hands) else None
        if hand is None or self.plotter is None:
            return False
        shape = hand.mesh if hand.levels else hand.bones
        renderer = hand.renderer
        if self._grid_camera is None:  # the grid's camera, back when the grid is
            camera = self.plotter.camera
            self._grid_camera = (camera.position, camera.focal_point, camera.up)
        renderer.ResetCamera(*shape.bounds)  # the bounding sphere in view: a long hand fills little of it
        x0, x1, y0, y1, z0, z1 = shape.bounds
        corners = []
        for corner in ((x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)):
            renderer.SetWorldPoint(*corner, 1.0)
            renderer.WorldToView()  # -1 .. 1 across the cell
            corners.append(renderer.GetViewPoint()[:2])
        extent = np.ptp(np.asarray(corners), axis=0) / 2.0  # of the cell's half width and height
        renderer.GetActiveCamera().Dolly(FRAME_FILL / max(float(extent.max()), 1e-6))
        for each in self.plotter.renderers:
            each.ResetCameraClippingRange()
        self.interactor.update()
        return True

    def solo_hand(self) -> PosedHand | None:
        """The retarget shown alone, or None (the grid, or the source alone)."""
        return self._hands[self.solo] if self.solo >= 1 and self.solo < len(self._hands) else None

    def show_frame(self, frame: int) -> None:
        self.frame = frame
        ahead = self._take_ahead(frame)
        for index, hand in enumerate(self._hands):
            hand.show(frame, ahead[index] if ahead else None)
        if self._ghost is not None:
            self._ghost.follow()
        if self.interactor is not None:
            self.interactor.update()

    def prefetch(self, frame: int | None) -> None:
        """Pose ``frame``'s skins on the worker thread (the frame expected next while playing) from the start
        of the next render, so that showing it only copies them in. A frame asked for then that is another
        is posed when shown."""
        self._wanted = frame

    def _render_starts(self) -> None:
        """The render window starts drawing: the cells fitted to their size now (the widget's size and solo
        change it: labels, overlays, camera), and the worker poses the frame wanted next meanwhile."""
        fit_cells(self.plotter, self._hands, self._labels)
        frame, self._wanted = self._wanted, None
        if frame is None or not self._hands or (self._ahead is not None and self._ahead[0] == frame):
            return
        hands = list(self._hands)
        self._ahead = (frame, self._posing.submit(lambda: [hand.posed_skin(frame) for hand in hands]))

    def _take_ahead(self, frame: int) -> list[PosedSkin | None] | None:
        """The skins posed ahead for ``frame`` (waiting for the worker if it is still at them), or None."""
        ahead, self._ahead = self._ahead, None
        if ahead is None or ahead[0] != frame:
            self.posed_here += 1
            return None
        self.prefetched += 1
        return ahead[1].result()

    def set_playing(self, playing: bool) -> None:
        self.playing = playing
        self._choose_skins()
        if self.interactor is not None:
            self.interactor.update()

    def _choose_skins(self) -> None:
        """Lighter skins (`render.compare_scene.PLAYING_FACES`) while the grid plays; the full ones when
        paused, and for a hand shown alone (one hand draws fast enough at full detail)."""
        for hand in self._hands:
            hand.set_playing(self.playing and self.solo < 0)

    def set_options(self, **changes) -> None:
        """Change the camera preset, overlays or opacity (``ViewOptions`` fields) and redraw."""
        self.options = dataclasses.replace(self.options, **changes)
        if self.interactor is not None:  # the camera moves for a preset only, not for an overlay
            framed = "camera" in changes and self._grid_camera is not None
            apply_options(self.plotter, self._hands, self.options, camera="camera" in changes)
            if framed:  # a hand framed alone (F) stays framed, seen from the preset's side
                self._grid_camera = None  # the grid comes back seen from there too
                self.frame_hand()
            self._show_ghost()
            self.show_frame(self.frame)

    def _show_ghost(self) -> None:
        """The source's ghost over the retarget shown alone, when the options ask for it; none otherwise."""
        if self._ghost is not None:
            self._ghost.remove()
        self._ghost = solo_ghost(self._hands, self.options, self.solo) if self.interactor is not None else None

    def set_mesh_opacity(self, opacity: float) -> None:
        self.set_options(opacity=opacity)

    def hand_at(self, x: int, y: int) -> int:
        """The index of the hand whose viewport holds widget pixel (x, y), or -1."""
        w, h = max(1, self.interactor.width()), max(1, self.interactor.height())
        u, v = x / w, 1.0 - y / h
        for index, viewport in enumerate(self.hand_viewports()):
            if viewport[0] <= u < viewport[2] and viewport[1] <= v < viewport[3]:
                return index
        return -1

    def hand_viewports(self) -> list[tuple[float, ...]]:
        """Each hand's viewport in the grid (x0, y0, x1, y1 as fractions, y up), in ``_hands`` order."""
        renderers = list(self.plotter.renderers)
        return [self._viewports[renderers.index(hand.renderer)] for hand in self._hands]

    def set_selected(self, index: int, turn_page: bool = True) -> None:
        """Frame the cell of retarget ``index`` (the whole comparison's results' order), turning to its page
        unless ``turn_page`` is False (the grid shown again after a change keeps the page the user is on)."""
        self.selected = index
        if turn_page and self.full is not None and 0 <= index < len(self.full.results) and \
                self._page_of(index) != self.page:
            self.set_page(self._page_of(index))
        self._frame_selected()
        if self.interactor is not None:
            self.interactor.update()

    def _frame_selected(self) -> None:
        for hand_index, hand in enumerate(self._hands[1:]):
            hand.set_framed(self.result_of_hand(hand_index + 1) == self.selected)

    def framing(self) -> Framing:
        """The camera, solo and selection now, for an off-screen render of what the view shows."""
        camera = self.plotter.camera if self.plotter is not None else None
        return Framing(None if camera is None else (camera.position, camera.focal_point, camera.up), self.solo,
                       self.selected - self.offset if 0 <= self.selected - self.offset < len(self._hands) - 1 else -1)

    def set_solo(self, index: int) -> None:
        """Show hand ``index``'s viewport alone over the whole view; -1 restores the grid."""
        self.solo = index
        if index < 0 and self._grid_camera is not None:  # a hand framed alone (F) overflowed its cell in the grid
            camera = self.plotter.camera
            camera.position, camera.focal_point, camera.up = self._grid_camera
            for renderer in self.plotter.renderers:
                renderer.ResetCameraClippingRange()
        self._grid_camera = None if index < 0 else self._grid_camera
        self.pager.setVisible(index < 0 and self.page_count > 1)  # pages are the grid's: alone, over the Fix bar
        show_alone(self.plotter, self._hands, self._viewports, index)
        self._show_ghost()
        self._choose_skins()
        self.solo_changed.emit(index)
        self.interactor.update()
        if index < 0:
            self._refit.start()  # the window may have changed size while one hand was shown

    def _drawn_at(self, x: int, y: int) -> tuple[int, PosedHand] | None:
        """The hand (its index in ``_hands``) whose cell is drawn under widget pixel (x, y), in the grid or alone."""
        u, v = x / max(1, self.interactor.width()), 1.0 - y / max(1, self.interactor.height())
        for index, hand in enumerate(self._hands):
            x0, y0, x1, y1 = hand.renderer.GetViewport()
            if hand.renderer.GetDraw() and x0 <= u < x1 and y0 <= v < y1:
                return index, hand
        return None

    def banner_tip(self, x: int, y: int) -> str:
        """The whole warning of the banner drawn under widget pixel (x, y), in the grid or a hand alone ("" off
        any): a small cell draws it in fewer words ("! frames guessed: index")."""
        drawn = self._drawn_at(x, y)
        if drawn is None or drawn[1].banner is None:
            return ""
        hand, h = drawn[1], self.interactor.height()
        above = ((1.0 - y / max(1, h)) - hand.renderer.GetViewport()[1]) * h  # the cell's bottom to the pointer
        scale = self.interactor.devicePixelRatioF()  # the banner is measured in the window's pixels
        return hand.banner_tip if above * scale <= hand.banner.drawn_height() else ""

    def contact_tip(self, x: int, y: int) -> str:
        """What the contact link drawn under widget pixel (x, y) joins and means (`contact_words`), "" off any."""
        drawn = self._drawn_at(x, y)
        if drawn is None or drawn[1].overlay is None:
            return ""
        index, hand = drawn
        scale = self.interactor.devicePixelRatioF()  # VTK's display pixels, from the bottom
        found = hand.overlay.link_at(hand.renderer, x * scale, (self.interactor.height() - y) * scale, hand.frame,
                                     LINK_REACH_PX * scale)
        return "" if found is None else contact_words(*found, on_source=index == 0)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if watched is not self.interactor:
            return False
        if event.type() == QEvent.Type.MouseButtonDblClick:
            self._pressed_at = None
            self.double_clicked.emit()
            self.set_solo(-1 if self.solo >= 0 else self.hand_at(int(event.position().x()),
                                                                 int(event.position().y())))
            return True
        if event.type() in (QEvent.Type.MouseButtonPress, QEvent.Type.MouseButtonRelease) and \
                event.button() == Qt.MouseButton.LeftButton:
            at = (int(event.position().x()), int(event.position().y()))
            pressed, self._pressed_at = self._pressed_at, at if event.type() == QEvent.Type.MouseButtonPress else None
            if self._pressed_at is None and pressed is not None and self.solo < 0 and is_click(pressed, at):
                hand = self.hand_at(*at)
                if hand >= 0:
                    self.hand_clicked.emit(hand)
        if event.type() == QEvent.Type.ToolTip:
            tip = self.banner_tip(event.pos().x(), event.pos().y()) or self.contact_tip(event.pos().x(),
                                                                                          event.pos().y())
            if tip:
                QToolTip.showText(event.globalPos(), wrapped(tip), self.interactor)
            else:
                QToolTip.hideText()
            return True
        return False

    def grab_rgb(self) -> np.ndarray:
        """The current view as an (H, W, 3) uint8 image (what screenshot and video export save)."""
        window = self.plotter.render_window
        window.Render()
        grab = vtkWindowToImageFilter()
        grab.SetInput(window)
        grab.SetInputBufferTypeToRGB()
        grab.ReadFrontBufferOff()
        grab.Update()
        image = pv.wrap(grab.GetOutput())
        width, height, _ = image.dimensions
        return np.asarray(image.point_data.active_scalars).reshape(height, width, -1)[::-1, :, :3].copy()

    def close_grid(self) -> None:
        """Free the render window and its widget (a new grid, or the window closing)."""
        if self.interactor is not None:
            self.interactor.hide()
            self._layout.removeWidget(self.interactor)
            self.interactor.close_plotter()
            self.interactor.deleteLater()
            self.interactor = self.plotter = None
            self._hands, self._labels = [], []
            self._ahead = self._wanted = None

    def closeEvent(self, event) -> None:
        self.close_grid()
        self._posing.shutdown(cancel_futures=True)
        super().closeEvent(event)
