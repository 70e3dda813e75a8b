"""Compare mode (its own tab): a motion on its source hand retargeted onto targets with methods, on a
timeline, with the ASM heatmap and the scores table beside it. Retargets run off the GUI thread."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field

from PySide6.QtCore import Signal
from PySide6.QtWidgets import QComboBox, QSplitter, QVBoxLayout, QWidget

from s2h_viewer.app.tasks import TaskRunner
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.retarget.comparison import Comparison, build_comparison
from s2h_viewer.retarget.methods import METHODS
from s2h_viewer.widgets.asm_heatmap import AsmHeatmap
from s2h_viewer.widgets.compare_view import CompareView
from s2h_viewer.widgets.scores_table import ScoresTable
from s2h_viewer.widgets.timeline import Timeline


@dataclass
class CompareSetup:
    """What compare mode shows: a motion on its source hand, retargeted onto targets with methods."""

    motion: Motion
    source: HandModel
    targets: list[HandModel]
    methods: list[str] = field(default_factory=lambda: ["tbs_copy", "asrn"])


def default_setup() -> CompareSetup:
    """The shipped samples: the gestures clip on birch, onto a realistic and a stylised held-out hand."""
    from s2h_viewer import samples
    motion = next(m for m in samples.load_sample_motions() if m.name == "gestures")
    return CompareSetup(motion, samples.load_sample_hand(motion.hand_name),
                        [samples.load_sample_hand("iris"), samples.load_sample_hand("laurel")])


class CompareMode(QWidget):
    """The Compare tab: the grid, the timeline, the heatmap and the scores of one ``CompareSetup``."""

    comparison_ready = Signal()

    def __init__(self, setup: CompareSetup, runner: TaskRunner, status: Callable[[str], None],
                 parent: QWidget | None = None):
        super().__init__(parent)
        self.setup, self.runner, self.status = setup, runner, status
        self.comparison: Comparison | None = None
        self.view = CompareView()
        self.timeline = Timeline()
        self.heatmap = AsmHeatmap()
        self.heatmap_choice = QComboBox()
        self.scores = ScoresTable()
        side = QWidget()
        side_layout = QVBoxLayout(side)
        side_layout.addWidget(self.heatmap_choice)
        side_layout.addWidget(self.heatmap)
        side_layout.addWidget(self.scores)
        splitter = QSplitter()
        splitter.addWidget(self.view)
        splitter.addWidget(side)
        splitter.setStretchFactor(0, 3)
        layout = QVBoxLayout(self)
        layout.addWidget(splitter, 1)
        layout.addWidget(self.timeline)
        self.timeline.frame_changed.connect(self.show_frame)
        self.heatmap_choice.currentIndexChanged.connect(lambda _: self.show_frame(self.timeline.frame))

    def start_comparison(self) -> None:
        s = self.setup
        self.timeline.set_playing(False)
        self.runner.start(lambda progress: build_comparison(s.motion, s.source, s.targets, s.methods, progress),
                          "Retargeting...", len(s.targets) * len(s.methods), self._on_comparison)

    def change_setup(self, **changes) -> None:
        """Replace parts of the setup (motion, source, targets, methods) and recompute."""
        self.setup = dataclasses.replace(self.setup, **changes)
        self.start_comparison()

    def _on_comparison(self, comparison: Comparison) -> None:
        self.comparison = comparison
        self.view.set_comparison(comparison)
        self.scores.show_comparison(comparison)
        self.heatmap_choice.blockSignals(True)
        self.heatmap_choice.clear()
        self.heatmap_choice.addItems([f"{METHODS[r.method].label} -> {r.target.name}" for r in comparison.results])
        self.heatmap_choice.blockSignals(False)
        self.timeline.set_clip(comparison.n_frames, comparison.motion.fps)
        self.status(f"{comparison.motion.name}: {comparison.n_frames} frames, {len(comparison.results)} retargets")
        self.comparison_ready.emit()

    def selected_result(self):
        """The retarget the heatmap shows (and a motion export writes)."""
        return self.comparison.results[max(self.heatmap_choice.currentIndex(), 0)]

    def show_frame(self, frame: int) -> None:
        if self.comparison is None:
            return
        self.view.show_frame(frame)
        result = self.selected_result()
        self.heatmap.show_matrix(result.cell_error[frame], f"ASM error, {METHODS[result.method].label} -> "
                                                           f"{result.target.name}, frame {frame}")

    def set_see_through(self, checked: bool) -> None:
        self.view.set_mesh_opacity(0.4 if checked else 1.0)
