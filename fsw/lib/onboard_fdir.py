"""Agent-level FDIR onboard (Fig. 5: network-level FDI informs the agent-level FDIR, which
recovers), in the style of cFS's Limit Checker and Stored Command apps: pure functions and
tables that ``fsw/apps/fdir.py`` runs.

**Watchpoints** (``[onboard_fdir.watchpoints]``, ``interfaces/contracts/scenario/onboard.py``):
each samples one onboard value; :func:`watch` counts samples over the limit in a row and trips
once at the persistence, and clears when a sample is back within it.  The values:

* ``nav_nis``: the nav filter's NIS of each measurement update (χ², 6 dof);
* ``pointing_deg``: the attitude estimate's pointing error against the attitude plan, deg,
  once tracking has settled (:func:`pointing_deg`);
* ``wheel_momentum_frac``: the largest wheel momentum over its limit (:func:`momentum_frac`);
* ``thrust_duty_excess``: while holding a PRO (where the plan asks no thrust), the commanded
  acceleration's largest axis over the MPC's limit (:func:`thrust_duty`);
* ``star_tracker_gap_s``: time since the last star-tracker attitude, s;
* ``blank_image_frac``: the share of the last ``BLANK_WINDOW`` own images that saw no POI,
  while tracking (:class:`BlankImages`).

**Stored sequences** (:data:`SEQUENCES`): what a trip's ``action`` or a ground declaration
starts, as commands to this spacecraft's apps (``OnboardCommand``); ``request_plan`` sends no
command but asks the ground for a new plan (an ``OnboardFdirEvent``).
**Classes** (:data:`CLASS_SEQUENCES`): what a ground FaultReport naming this spacecraft starts,
by its identified class.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from interfaces.contracts.messages import AttitudeEstimate, GuidanceStatus
from interfaces.contracts.scenario import Watchpoint

SEQUENCES: dict[str, tuple[str, ...]] = {
    "safe_hold": ("safe_hold", "point_target"),
    "camera_off": ("camera_off",),
    "nav_reset": ("nav_reset",),
    "request_plan": (),
    "none": (),
}
"""Each stored sequence's commands, in order (``OnboardCommand.command``):

* ``safe_hold``: guidance stops thrusting and transferring, and flies on the PRO it is on,
  until an assignment newer than the one in force; the camera aims at the target's centre;
* ``camera_off``: the camera app shares no more observations (images stop);
* ``nav_reset``: the nav filter restarts from its next measurement;
* ``request_plan``: no command; the ground is asked for a new plan (from safe hold, the
  ground answers with an assignment if its own recovery has not: ground/apps/planner.py).
"""

CLASS_SEQUENCES: dict[str, tuple[str, ...]] = {
    "actuator": ("safe_hold", "request_plan"),
    "camera": ("camera_off",),
    "state_sensor": ("nav_reset",),
}
"""What a ground FaultReport naming this spacecraft starts, by identified class (none for
``link``, ``data_integrity``, ``common_mode`` or no class: nothing onboard would help)."""

WATCHPOINT_CLASS: dict[str, str] = {
    "pointing_deg": "actuator", "thrust_duty_excess": "actuator",
    "wheel_momentum_frac": "actuator", "nav_nis": "state_sensor",
    "star_tracker_gap_s": "state_sensor", "blank_image_frac": "camera",
}
"""The class a trip points at, named in the plan request it may start (the ground logs it;
its FDIR decides: ground/apps/planner.py)."""

BLANK_WINDOW = 10
"""Own images the blank-image watchpoint looks back over."""


@dataclass
class WatchState:
    """A watchpoint's samples over its limit in a row, and whether it has tripped."""

    over: int = 0
    tripped: bool = False


def watch(wp: Watchpoint, state: WatchState, value: float) -> Literal["trip", "clear"] | None:
    """Sample ``value`` against ``wp``: ``"trip"`` on the sample that brings the count over the
    limit to the persistence, ``"clear"`` on the first sample back within the limit after a
    trip, None otherwise.  A non-finite value counts as over the limit."""
    if not math.isfinite(value) or value > wp.limit:
        state.over += 1
        if not state.tripped and state.over >= wp.persistence:
            state.tripped = True
            return "trip"
        return None
    state.over = 0
    if state.tripped:
        state.tripped = False
        return "clear"
    return None


def pointing_deg(att: AttitudeEstimate, tracked_s: float, settle_s: float) -> float | None:
    """The pointing error against the plan, deg, once the attitude loop has tracked for
    ``settle_s`` (``tracked_s``: for how long it has); None while slewing, initialising or
    settling (a slew hands over to tracking with some rate left: measured, up to 4.9° of
    overshoot over the following 20-25 s in nominal flight)."""
    if att.mode != "track" or tracked_s < settle_s:
        return None
    return math.degrees(att.pointing_error_rad)


def momentum_frac(att: AttitudeEstimate, h_max_nms: float) -> float | None:
    """The largest wheel momentum over the wheels' limit (None when not reported)."""
    if att.wheel_momentum_nms is None:
        return None
    return float(np.max(np.abs(att.wheel_momentum_nms))) / h_max_nms


def thrust_duty(status: GuidanceStatus, u_max_mps2: float) -> float | None:
    """The commanded acceleration's largest LVLH axis over the MPC's limit, while holding a PRO
    (None otherwise: a transfer's plan thrusts)."""
    if status.mode != "hold":
        return None
    return float(np.max(np.abs(status.accel_lvlh_mps2))) / u_max_mps2


@dataclass
class BlankImages:
    """The last ``BLANK_WINDOW`` own images taken while tracking: whether each saw no POI."""

    blank: deque[bool] = field(default_factory=lambda: deque(maxlen=BLANK_WINDOW))

    def add(self, seen: int) -> float | None:
        """Add an image that saw ``seen`` POIs; the blank share once the window is full."""
        self.blank.append(seen == 0)
        if len(self.blank) < BLANK_WINDOW:
            return None
        return sum(self.blank) / BLANK_WINDOW


def class_sequences(fault_class: str | None) -> tuple[str, ...]:
    """The sequences a ground declaration of ``fault_class`` starts."""
    return CLASS_SEQUENCES.get(fault_class or "", ())
