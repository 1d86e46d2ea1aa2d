"""The sim's own settings (``sim/``): lockstep timeouts, pacing, cycle budgets."""

from __future__ import annotations

from pydantic import Field

from interfaces.contracts.scenario.base import Section


class SimSettings(Section):
    lockstep_timeout_s: float = Field(
        default=60.0, gt=0.0,
        description="per-tick answer timeout, s (wall): a participant alive but slow (a kernel "
                    "compiled on first use, a loaded machine) is waited for, so results stay "
                    "deterministic; a dead or stalled one is dropped as soon as the network "
                    "notices (at once, or after the 10 s Zenoh lease)")
    startup_timeout_s: float = Field(default=60.0, gt=0.0)
    substeps: int = Field(default=1, ge=1, le=1000,
                          description="RK4 steps per tick (at most 1,000: 10 kHz at 10 Hz ticks; "
                                      "more would run for ever rather than be refused)")
    cycle_budget_scale: float = Field(
        default=1.0, gt=0.0,
        description="a rate group overruns when its wall time exceeds its period times this",
    )
