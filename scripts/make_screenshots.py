"""Regenerate the README's screenshots of the real window (needs an X display; `make screenshots`
starts Xvfb without one):

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python scripts/make_screenshots.py

docs/compare_mode.png: the default samples with the contact overlay (touching pads linked in green,
contacts a retarget lost in red) at a frame where the source's fingertips touch, TBS Copy onto laurel
loses the touch and ASRN onto laurel keeps it, the error curve under the timeline;
docs/compare_solo.png: ASRN onto laurel shown alone (double-click), and so selected; docs/compare_fixing.png: TBS Copy
onto laurel alone, its index PIP's ring being dragged (the button held: the cell, table and curve follow); docs/annotation_mode.png: the WebXR hand solved, its middle PIP selected.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np

from s2h_viewer.app.scripted import screen_image, scripted_window, wait_for
from s2h_viewer.samples import ASSETS_DIR

DOCS = Path(__file__).resolve().parent.parent / "docs"


def main() -> None:
    with scripted_window() as window, tempfile.TemporaryDirectory() as tmp:
        window.contact_overlay.trigger()
        copy, solo = 3, 4  # TBS Copy -> laurel, ASRN -> laurel
        hands = window.view._hands
        touching = hands[0].overlay.contacts.any(1)
        shown = np.flatnonzero(touching & hands[copy].overlay.lost.any(1) & ~hands[solo].overlay.lost.any(1))
        window.timeline.set_frame(int(shown[len(shown) // 2]) if len(shown) else int(np.argmax(touching)))
        screen_image(window, DOCS / "compare_mode.png")
        window.view.set_solo(solo)  # shown alone, it is selected: the heatmap, the curve and the table follow
        screen_image(window, DOCS / "compare_solo.png")
        window.view.set_solo(-1)
        window.view.set_solo(copy)
        drag_ring(window, "index_pip", 35.0, DOCS / "compare_fixing.png")
        window.view.set_solo(-1)

        hand = shutil.copy(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb", Path(tmp))
        window.annotate_file(str(hand))
        window.run_solver()
        wait_for(window.annotation_ready)
        window.annotate_view.select(7)  # middle_pip
        screen_image(window, DOCS / "annotation_mode.png")
    print(f"wrote {DOCS / 'compare_mode.png'}, {DOCS / 'compare_solo.png'}, {DOCS / 'compare_fixing.png'} and "
          f"{DOCS / 'annotation_mode.png'}")


def drag_ring(window, joint: str, degrees: float, picture: Path) -> None:
    """In the retarget shown alone: pick ``joint`` and drag its ring ``degrees`` with the mouse, the picture taken
    with the button still held, then released (a correction key)."""
    from PySide6.QtCore import QPoint, Qt
    from PySide6.QtTest import QTest
    from vtkmodules.vtkRenderingCore import vtkCoordinate

    fixing, widget = window.compare.fixing, window.view.interactor
    fixing.pick(joint)
    wait_for(seconds=0.3)
    ring = fixing.ring
    radial = np.asarray(ring.mesh.points[0]) - ring.centre  # any point of the tube: its way out in the ring's plane
    radial -= (radial @ ring.axis) * ring.axis
    u = radial / np.linalg.norm(radial)
    v = np.cross(ring.axis, u)

    def pixel(angle: float) -> QPoint:
        coordinate = vtkCoordinate()
        coordinate.SetCoordinateSystemToWorld()
        coordinate.SetValue(*(ring.centre + ring.radius * (np.cos(angle) * u + np.sin(angle) * v)))
        x, y = coordinate.GetComputedDoubleDisplayValue(ring.renderer)
        scale = widget.devicePixelRatioF()
        return QPoint(round(x / scale), round(widget.height() - 1 - y / scale))
    turn = np.radians(degrees)
    start = max(np.radians(np.arange(0, 360, 15)), key=lambda a: (pixel(a) - pixel(a + turn)).manhattanLength())
    path = [pixel(start + t) for t in np.linspace(0.0, turn, 16)]
    QTest.mousePress(widget, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, path[0])
    for point in path[1:]:
        QTest.mouseMove(widget, point)
        wait_for(seconds=0.04)
    screen_image(window, picture)
    QTest.mouseRelease(widget, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, path[-1])


if __name__ == "__main__":
    main()
