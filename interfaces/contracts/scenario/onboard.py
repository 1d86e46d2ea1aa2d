"""The agent-level FDIR onboard (``fsw/apps/fdir.py``, Fig. 5 of the chapter): its watchpoint
table and switch (``[onboard_fdir]``).

Each watchpoint (cFS Limit Checker style) compares one onboard value with ``limit`` every time
the value is sampled, and trips after ``persistence`` samples in a row over it; a trip starts
the stored sequence named by ``action`` (``"none"``: an event only).  The table has defaults
for every watchpoint; a scenario states only what differs::

    [onboard_fdir]
    enabled = true
    [onboard_fdir.watchpoints.pointing_deg]
    limit = 3.0
    persistence = 4

An unknown watchpoint, field or action is refused at load, naming the entry.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, ValidationError, model_validator

from interfaces.contracts.errors import lines
from interfaces.contracts.scenario.base import Section

SequenceName = Literal["safe_hold", "camera_off", "nav_reset", "request_plan", "none"]
"""The stored sequences a watchpoint may start (``fsw/lib/onboard_fdir.py``: what each holds)."""


class Watchpoint(Section):
    """One watchpoint: over ``limit`` (the value's unit) for ``persistence`` samples in a row
    trips it; ``action`` is the sequence a trip starts."""

    limit: float = Field(gt=0.0)
    persistence: int = Field(ge=1, le=1000)
    action: SequenceName = "none"


DEFAULT_WATCHPOINTS: dict[str, Watchpoint] = {
    "nav_nis": Watchpoint(limit=60.0, persistence=5),
    "pointing_deg": Watchpoint(limit=1.0, persistence=2, action="request_plan"),
    "wheel_momentum_frac": Watchpoint(limit=0.9, persistence=10),
    "thrust_duty_excess": Watchpoint(limit=0.25, persistence=3, action="request_plan"),
    "star_tracker_gap_s": Watchpoint(limit=10.0, persistence=1),
    "blank_image_frac": Watchpoint(limit=0.5, persistence=3),
}
"""The defaults, with their units (``fsw/lib/onboard_fdir.py`` says how each is sampled):

* ``nav_nis``: the nav filter's normalized innovation squared (χ², 6 dof; p = 1e-10 at 60),
  per measurement update (ω_mid).  An event only: an unmodelled force trips it as surely as a
  biased sensor (it tripped on all 32 thruster leaks of the paper campaign, where a nav reset,
  its first default action, was the wrong one);
* ``pointing_deg``: the attitude estimate's pointing error against the attitude plan, deg,
  while tracking, at ω_mid (each attitude estimate);
* ``wheel_momentum_frac``: the largest wheel momentum as a fraction of its limit, at ω_mid;
* ``thrust_duty_excess``: the commanded thrust's duty (|a|∞ / a_max) over the last ω_low cycle
  beyond the plan's, while holding a PRO, at ω_low;
* ``star_tracker_gap_s``: time since the last star-tracker attitude, s, at ω_mid;
* ``blank_image_frac``: the share of the last 10 own images that saw no POI while tracking, at
  ω_mid.
"""


class OnboardFdir(Section):
    """The agent-level FDIR onboard (``fsw/apps/fdir.py``): off by default, so that a scenario
    without it flies as before."""

    enabled: bool = False
    watchpoints: dict[str, dict[str, float | int | str]] = Field(default_factory=dict)
    """Overrides of ``DEFAULT_WATCHPOINTS``, by name: any of limit, persistence, action."""

    @model_validator(mode="after")
    def _known(self) -> OnboardFdir:
        for name, values in self.watchpoints.items():
            if name not in DEFAULT_WATCHPOINTS:
                raise ValueError(f"onboard_fdir.watchpoints.{name}: unknown watchpoint (known: "
                                 f"{', '.join(DEFAULT_WATCHPOINTS)})")
            try:
                Watchpoint.model_validate({**DEFAULT_WATCHPOINTS[name].model_dump(), **values})
            except ValidationError as e:
                why = "; ".join(lines(e, model=Watchpoint))
                raise ValueError(f"onboard_fdir.watchpoints.{name}: {why}") from None
        return self

    def table(self) -> dict[str, Watchpoint]:
        """Every watchpoint, the defaults with this scenario's overrides."""
        return {name: Watchpoint.model_validate({**wp.model_dump(),
                                                 **self.watchpoints.get(name, {})})
                for name, wp in DEFAULT_WATCHPOINTS.items()}
