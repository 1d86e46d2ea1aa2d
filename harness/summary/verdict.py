"""A run's verdict at a glance, from its summary.json: each injected fault, whether the ground
declared it, on whom, when, by which test and with which class; then the false alarms.  The
launcher's last console line is :meth:`Verdict.line`; report.md opens on
:meth:`Verdict.markdown`.

The figures are the main detector's scores (``harness/summary/scoring.py``): a fault is
declared when an alarm names its spacecraft while it is active (``per_fault[].isolated``),
at the first such alarm; a false alarm is an alarm on a spacecraft with no fault active.
"""

from __future__ import annotations

from dataclasses import dataclass

from harness.summary.declaring import LABELS
from harness.summary.document import RunSummary
from harness.summary.fdir import Detection, detection_test
from harness.summary.scoring import Alarm, FaultScore, false_alarms_of

NAMED_MOST = 4
"""Faults and false alarms named one by one on the console line; the rest are counted."""

TIME_MATCH_S = 1e-6
"""How close a detection's time must be to a score's first alarm to be that alarm, s."""


@dataclass(frozen=True)
class FaultOutcome:
    """One injected fault and the first alarm that named its spacecraft (None: none did)."""

    score: FaultScore
    alarm: Detection | None

    def words(self) -> str:
        """The fault's outcome as the console line gives it."""
        f = self.score
        injected = f"{f.kind} at {f.start_s:.1f} s"
        if not f.isolated:
            why = "detected on another spacecraft, not isolated" if f.detected else \
                "not declared"
            return f"{who(f.spacecraft)} {injected}: {why}"
        return (f"{who(f.spacecraft)} at t={self.time_s:.1f} s (+{f.latency_s or 0.0:.1f} s, "
                f"{self.test_name}, {class_words(f)}; injected {injected})")

    @property
    def time_s(self) -> float:
        """When the first alarm naming the spacecraft counts, s (NaN: none did)."""
        f = self.score
        return float("nan") if f.latency_s is None else f.start_s + f.latency_s

    @property
    def test_name(self) -> str:
        """The declaring test's name ("-": not known)."""
        return "-" if self.alarm is None else LABELS[detection_test(self.alarm)].name


@dataclass(frozen=True)
class Verdict:
    """What the ground declared in a run against what was injected."""

    faults: tuple[FaultOutcome, ...]
    false_alarms: tuple[Detection, ...]
    false_alarm_count: int
    nominal_windows: int
    unjudged: str | None = None
    """why there is no verdict (the archive was not read), else None"""

    def line(self) -> str:
        """The verdict on one line: faults declared of those injected (the first
        ``NAMED_MOST`` named), then the false alarms."""
        if self.unjudged is not None:
            return f"no FDIR verdict: {self.unjudged}"
        declared = sum(f.score.isolated for f in self.faults)
        head = (f"{declared} of {len(self.faults)} faults declared: "
                + _named([f.words() for f in self.faults])) if self.faults else \
            "no fault injected"
        alarms = f"{self.false_alarm_count} false alarm" + \
            ("" if self.false_alarm_count == 1 else "s") + \
            f" in {self.nominal_windows} nominal windows"
        named = [f"{who(d.spacecraft)} {d.fault_class or 'unidentified'} at t={d.time_s:.1f} s "
                 f"({LABELS[detection_test(d)].name})" for d in self.false_alarms]
        return f"{head}. {alarms}" + (f": {_named(named)}" if named else "") + "."

    def markdown(self) -> list[str]:
        """report.md's opening section: the line, the injected faults' table and the false
        alarms' table."""
        lines = ["## Verdict", "", f"**{self.line()}**", ""]
        if self.unjudged is not None:
            return lines
        if self.faults:
            lines += ["| injected fault | onset (s) | declared | on | by test | at (s) | "
                      "latency (s) | class (expected) |", "|---|---|---|---|---|---|---|---|"]
            lines += [_fault_row(f) for f in self.faults] + [""]
        if self.false_alarms:
            lines += ["| false alarm on | at (s) | by test | class |", "|---|---|---|---|"]
            lines += [f"| {who(d.spacecraft)} | {d.time_s:.1f} | "
                      f"{LABELS[detection_test(d)].name} | {d.fault_class or 'unidentified'} |"
                      for d in self.false_alarms] + [""]
        return lines


def verdict(summary: RunSummary) -> Verdict:
    """The run's verdict from its summary (module docstring)."""
    scores = summary.scores
    if scores is None:
        return Verdict((), (), 0, 0, unjudged=summary.archive_error or "no FDIR scores")
    ground = [d for d in summary.detections or []  # the alarms scored
              if d.declared_by == "ground" and d.cause is None]
    grace_s = summary.fdir_settings.fdi_period_s if summary.fdir_settings else 0.0
    alarms = [_alarm(d) for d in ground]
    false = false_alarms_of(summary.injected_faults, alarms, grace_s)
    outcomes = tuple(FaultOutcome(f, _first_alarm(f, ground)) for f in scores.per_fault)
    return Verdict(outcomes, tuple(ground[alarms.index(a)] for a in false),
                   scores.false_alarms, scores.nominal_cycles)


def _alarm(d: Detection) -> Alarm:
    return Alarm(d.spacecraft, d.time_s, d.fault_class, d.declared_s)


def _first_alarm(f: FaultScore, ground: list[Detection]) -> Detection | None:
    """The detection that is ``f``'s first alarm naming its spacecraft (None: none)."""
    if not f.isolated or f.latency_s is None:
        return None
    at = f.start_s + f.latency_s
    return next((d for d in ground if d.spacecraft == f.spacecraft
                 and abs(_alarm(d).at_s - at) <= TIME_MATCH_S), None)


def _fault_row(f: FaultOutcome) -> str:
    s = f.score
    if not s.isolated:
        return (f"| {who(s.spacecraft)} {s.kind} | {s.start_s:.1f} | "
                f"{'detected, not isolated' if s.detected else '**no**'} | - | - | - | - | "
                f"- ({s.expected_class}) |")
    on = who(f.alarm.spacecraft) if f.alarm is not None else who(s.spacecraft)
    return (f"| {who(s.spacecraft)} {s.kind} | {s.start_s:.1f} | yes | {on} | {f.test_name} | "
            f"{f.time_s:.1f} | {s.latency_s or 0.0:.1f} | "
            f"{s.identified_class or 'unidentified'} ({s.expected_class}) |")


def class_words(f: FaultScore) -> str:
    """The class the fault was identified as, against the one expected."""
    if f.identified_class is None:
        return f"unidentified, expected {f.expected_class}"
    if f.identified_class == f.expected_class:
        return f.identified_class
    return f"{f.identified_class}, expected {f.expected_class}"


def who(spacecraft: int) -> str:
    """An observer's name, or the constellation's (0: common mode)."""
    return f"sc{spacecraft}" if spacecraft else "the constellation"


def _named(items: list[str]) -> str:
    """The first ``NAMED_MOST`` of ``items``, then how many more."""
    more = len(items) - NAMED_MOST
    return "; ".join(items[:NAMED_MOST]) + (f" and {more} more" if more > 0 else "")

