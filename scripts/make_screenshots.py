"""Regenerate the README's screenshots of the real window (needs an X display; `make screenshots`
starts Xvfb without one):

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python scripts/make_screenshots.py

docs/compare_mode.png: the default samples at frame 120 with the contact overlay (touching pads
linked in green, contacts a retarget lost in red) and the error curve under the timeline;
docs/compare_solo.png: one retarget shown alone (double-click); docs/annotation_mode.png: the WebXR
hand solved, its middle PIP selected.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from s2h_viewer.app.scripted import screen_image, scripted_window, wait_for
from s2h_viewer.samples import ASSETS_DIR

DOCS = Path(__file__).resolve().parent.parent / "docs"


def main() -> None:
    with scripted_window() as window, tempfile.TemporaryDirectory() as tmp:
        window.contact_overlay.trigger()
        window.timeline.set_frame(120)
        screen_image(window, DOCS / "compare_mode.png")
        window.scores.selectRow(3)  # ASRN -> laurel: the heatmap, the curve and the solo view follow
        window.view.set_solo(4)
        screen_image(window, DOCS / "compare_solo.png")
        window.view.set_solo(-1)

        hand = shutil.copy(ASSETS_DIR / "hands" / "webxr" / "generic-hand-right.glb", Path(tmp))
        window.annotate_file(str(hand))
        window.run_solver()
        wait_for(window.annotation_ready)
        window.annotate_view.select(7)  # middle_pip
        screen_image(window, DOCS / "annotation_mode.png")
    print(f"wrote {DOCS / 'compare_mode.png'}, {DOCS / 'compare_solo.png'} and {DOCS / 'annotation_mode.png'}")


if __name__ == "__main__":
    main()
