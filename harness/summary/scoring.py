"""summary.json's ``scores`` (and each baseline's): a detector scored against the injected
faults (docs/contracts.md, summary.json ``detections`` and ``scores``), its records and the
scoring.

Definitions (one run):

* A fault is *detected* when any alarm is raised at or after its onset and before it ends
  (plus ``grace_s``, one FDI window by default: a window closing after the end still holds
  faulty data); its *latency* is the time from onset to the first such alarm.
* It is *isolated* when such an alarm names its spacecraft (0 for a common-mode fault: the
  constellation); ``latency_s`` is then measured to the first alarm on that spacecraft, and
  ``identified_class`` is the class of the first such alarm that names one (the detector may
  identify a window after it detects), at ``identification_latency_s`` from onset.
  ``declared_latency_s`` is the time from onset to when that first alarm was declared (the
  window judged: with ground passes, after its data came down).
* A *false alarm* is an alarm on a spacecraft with no fault active at its time (within the
  same grace).  ``nominal_cycles`` counts the FDI windows judged (a decision was possible) that
  do not overlap a fault of their spacecraft; ``false_alarm_rate`` is false alarms per nominal
  cycle, and ``false_alarms_per_hour`` per hour of nominal spacecraft time.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Literal

from pydantic import Field

from harness.summary.records import Figure, SummaryRecord
from interfaces.contracts.scenario import Fault, FaultKind

DeclaringTest = Literal["window", "sequential", "nis_scan", "pointing_scan"]
"""What declared a fault: a window's tests, the image scan, the NIS scan or the pointing run
(``gnc.image_scan.POINTING_RUN``)."""

EXPECTED_CLASS: dict[str, FaultClass] = {
    "thruster_bias": "actuator", "pointing_actuator": "actuator",
    "camera_degradation": "camera", "camera_misalignment": "camera",
    "nav_sensor_bias": "state_sensor", "link_loss": "link", "packet_loss": "link",
    "faulty_data": "data_integrity", "camera_calibration": "common_mode",
    "state_disturbance": "actuator",
}
"""The class each fault kind should be identified as (docs/contracts.md)."""


@dataclass(frozen=True)
class Alarm:
    """A declared fault: spacecraft, time (s), identified class (None: not identified)."""

    spacecraft: int
    t_s: float
    fault_class: FaultClass | None
    declared_s: float | None = None
    """when it was declared (s; None: not known)"""
    detector: DeclaringTest | None = None
    """what declared it, where the sequential test runs: a window's tests, the image scan,
    the NIS scan or the pointing run (None: the window test alone)"""

    @property
    def at_s(self) -> float:
        """When the alarm counts, s: its window's end, but for a link fault when it was
        declared (with ground passes a silence is declared in the pass after it, and may be a
        window's end before the cut that kept that window's data aboard)."""
        if self.fault_class == "link" and self.declared_s is not None:
            return self.declared_s
        return self.t_s


@dataclass(frozen=True)
class Judged:
    """One FDI window on one spacecraft where the detector could decide: [t_start, t_end)."""

    spacecraft: int
    t_start_s: float
    t_end_s: float


def _active(f: Fault, t: float, grace_s: float) -> bool:
    return f.start_s <= t and (f.end_s is None or t <= f.end_s + grace_s)


def overlaps_fault(faults: Sequence[Fault], spacecraft: int, t_start_s: float,
                   t_end_s: float) -> bool:
    """Whether a fault of ``spacecraft`` (or a common-mode one, spacecraft 0) overlaps the
    window [t_start_s, t_end_s)."""
    return any(f.spacecraft in (0, spacecraft) and f.start_s < t_end_s
               and (f.end_s is None or t_start_s < f.end_s) for f in faults)


def score(faults: Sequence[Fault], alarms: Sequence[Alarm], judged: Sequence[Judged],
          grace_s: float) -> Scores:
    """The ``scores`` section: ``per_fault`` (in scenario order) and the false-alarm figures."""
    per_fault = []
    for f in faults:
        during = sorted((a for a in alarms if _active(f, a.at_s, grace_s)), key=lambda a: a.at_s)
        on_it = [a for a in during if a.spacecraft == f.spacecraft]
        first = on_it[0] if on_it else (during[0] if during else None)
        classed = [a for a in on_it if a.fault_class is not None]
        identified = classed[0].fault_class if classed else None
        per_fault.append(FaultScore(
            spacecraft=f.spacecraft, kind=f.kind, start_s=f.start_s,
            detected=bool(during), isolated=bool(on_it),
            latency_s=None if first is None else first.at_s - f.start_s,
            identified_class=identified, expected_class=EXPECTED_CLASS[f.kind],
            identified_correctly=identified == EXPECTED_CLASS[f.kind],
            identification_latency_s=classed[0].at_s - f.start_s if classed else None,
            declared_latency_s=(first.declared_s - f.start_s
                                if first is not None and first.declared_s is not None else None),
            **({"detector": first.detector}
               if first is not None and first.detector is not None else {}),
        ))

    def overlaps(j: Judged) -> bool:
        return overlaps_fault(faults, j.spacecraft, j.t_start_s, j.t_end_s)

    false_alarms = false_alarms_of(faults, alarms, grace_s)
    nominal = [j for j in judged if not overlaps(j)]
    hours = sum(j.t_end_s - j.t_start_s for j in nominal) / 3600.0
    return Scores(
        per_fault=per_fault,
        false_alarms=len(false_alarms),
        nominal_cycles=len(nominal),
        false_alarm_rate=len(false_alarms) / len(nominal) if nominal else None,
        false_alarms_per_hour=len(false_alarms) / hours if hours > 0 else None,
    )


def false_alarms_of(faults: Sequence[Fault], alarms: Sequence[Alarm], grace_s: float
                    ) -> list[Alarm]:
    """The ``alarms`` on a spacecraft with no fault active at their time (a common-mode
    fault, spacecraft 0, acts on every observer), in their order."""
    return [a for a in alarms
            if not any(f.spacecraft in (0, a.spacecraft) and _active(f, a.at_s, grace_s)
                       for f in faults)]


FaultClass = Literal["actuator", "camera", "state_sensor", "link", "data_integrity",
                     "common_mode"]
"""The classes the ground identifies a fault as (``FaultReport.fault_class``)."""


class FaultScore(SummaryRecord):
    """How a detector did on one injected fault (harness/summary/scoring.py)."""

    FILLABLE: ClassVar[tuple[str, ...]] = ("identification_latency_s",)

    spacecraft: int = Field(ge=0, description="the faulty observer; 0: common mode")
    kind: FaultKind
    start_s: float = Field(description="onset, sim s")
    detected: bool = Field(description="any alarm while the fault was active")
    isolated: bool = Field(description="an alarm naming its spacecraft")
    latency_s: float | None = Field(description="onset to the first (isolating) alarm, s")
    identified_class: FaultClass | None = Field(
        description="class of the first isolating alarm that names one")
    expected_class: FaultClass
    identified_correctly: bool
    identification_latency_s: float | None = Field(
        default=None, description="onset to the first alarm naming its class, s")
    declared_latency_s: float | None = Field(
        default=None, description="onset to the first (isolating) alarm's declaration, s: "
                                  "what the ground knew when (with ground passes, the gap "
                                  "to the pass is in it)")
    detector: DeclaringTest | None = Field(
        default=None, description="what declared the first (isolating) alarm, where the "
                                  "sequential test runs: a window's tests, the image scan "
                                  "(sequential), the NIS scan or the pointing run")
    image_divergence: float | None = Field(
        default=None, ge=0.0,
        description="where the sequential test runs: the fault's per-image Kullback-Leibler "
                    "divergence D = δ²/2σ² (nats), δ its observer's mean relative shift of the "
                    "information ratio over the first whole window after onset, σ one image's "
                    "nominal 1σ (harness/summary/delay_bound.py)")
    nis_divergence: float | None = Field(
        default=None, ge=0.0,
        description="where the sequential test runs: the Kullback-Leibler divergence per nav "
                    "update of the NIS's growth over the same window, nats (3(λ − 1))")
    delay_bound_s: float | None = Field(
        default=None, ge=0.0,
        description="when the divergence summed from the onset first reaches log γ, s, at "
                    "least one step (γ: the scans' mean time to a false alarm, steps; "
                    "harness/summary/delay_bound.py): the smallest worst-case mean delay of "
                    "any test as quick to false-alarm (Lorden 1971)")


class Scores(SummaryRecord):
    """A detector's scores over a run: per injected fault and false alarms."""

    per_fault: list[FaultScore] = Field(description="in scenario order")
    false_alarms: int = Field(ge=0, description="alarms on a spacecraft with no active fault")
    nominal_cycles: int = Field(ge=0, description="judged FDI windows overlapping no fault")
    false_alarm_rate: Figure = Field(description="false alarms per nominal cycle")
    false_alarms_per_hour: Figure = Field(description="per hour of nominal spacecraft time")
