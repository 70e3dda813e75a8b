"""Compare mode's state as plain data: what is loaded, which targets and methods are asked for, what
is computed (a cache of results per (motion, source, target, method)) and which retarget is selected.
The app changes it only through its actions; this module says what is missing and what to show."""

from __future__ import annotations

from dataclasses import dataclass, field

import torch

from s2h_viewer.hand.kinematics import HandPose
from s2h_viewer.hand.model import HandModel
from s2h_viewer.hand.motion import Motion
from s2h_viewer.retarget.comparison import Comparison, MethodResult


@dataclass(frozen=True)
class ResultKey:
    """One retarget: ids of the objects held by the state (stale ids are pruned with their results)."""

    motion: int
    source: int
    target: int
    method: str


@dataclass
class CompareState:
    """The motion on its source hand, the targets and methods asked for, and the results computed."""

    motion: Motion
    source: HandModel
    targets: list[HandModel]
    methods: list[str]
    results: dict[ResultKey, MethodResult] = field(default_factory=dict)
    #: FK and ASM of a clip on its source hand, per (motion id, source id)
    semantics: dict[tuple[int, int], tuple[HandPose, torch.Tensor]] = field(default_factory=dict)
    selected: ResultKey | None = None  # the retarget the heatmap, scores and exports follow

    def key(self, target: HandModel, method: str) -> ResultKey:
        return ResultKey(id(self.motion), id(self.source), id(target), method)

    def wanted(self) -> list[ResultKey]:
        """Every retarget the menus ask for, target-major (the grid's order)."""
        return [self.key(t, m) for t in self.targets for m in self.methods]

    def missing(self) -> list[ResultKey]:
        return [k for k in self.wanted() if k not in self.results]

    def target_of(self, key: ResultKey) -> HandModel:
        return next(t for t in self.targets if id(t) == key.target)

    def prune(self) -> None:
        """Drop results nothing asks for any more, and a selection that went with them."""
        wanted = set(self.wanted())
        self.results = {k: r for k, r in self.results.items() if k in wanted}
        if self.selected not in wanted:
            self.selected = None

    def comparison(self) -> Comparison | None:
        """Everything asked for, once all of it is computed; None while anything is missing."""
        semantics = self.semantics.get((id(self.motion), id(self.source)))
        if self.missing() or semantics is None or not self.targets or not self.methods:
            return None
        return Comparison(self.source, self.motion, semantics[0], [self.results[k] for k in self.wanted()])

    def selected_result(self) -> MethodResult | None:
        key = self.selected if self.selected in self.results else next(
            (k for k in self.wanted() if k in self.results), None)
        return self.results.get(key) if key is not None else None
