"""What a batch of builds did, whatever the scene: the result every vectorised build map returns
(each scene's `Scene.run_builds`) and
the input of the yield and of the sensitivity."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the spec loader imports this package: numpy comes with the arrays
    import numpy as np


@dataclass(frozen=True)
class BuildOutcome:
    """N builds, one entry each.

    stages_passed: stages (steps, handovers) completed, int.
    failure: the failure's name as the event simulator names it; "" for a build that passed
        every stage asked.
    min_margin: the smallest margin over the run (the normalised slack of
        `pdm_design.analysis.result`: 1 - demand/capacity while a condition holds, 0 at its
        limit); < 0 exactly for the builds that failed, >= 0 for those that passed.
    closed_form: False where a build left what the closed forms describe (a slip, a lift-off,
        a graze ...): its stages and failure are the map's best account, to be decided by the
        event simulator.
    """

    stages_passed: np.ndarray
    failure: np.ndarray
    min_margin: np.ndarray
    closed_form: np.ndarray

    def __post_init__(self):
        n = len(self.stages_passed)
        for name in ("failure", "min_margin", "closed_form"):
            if len(getattr(self, name)) != n:
                raise ValueError(f"BuildOutcome: {name} has {len(getattr(self, name))} entries, "
                                 f"stages_passed {n}")

    def __len__(self) -> int:
        return len(self.stages_passed)

    @property
    def builds(self) -> int:
        return len(self.stages_passed)

    @property
    def passed(self) -> np.ndarray:
        """True for the builds that passed every stage asked."""
        return self.failure == ""
