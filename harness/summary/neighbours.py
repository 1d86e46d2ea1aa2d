"""summary.json's ``neighbours`` section and the neighbours' entries of ``detections``: what the
neighbours' FDIR aboard did (fsw/apps/neighbours.py), present when the scenario turns it on
(``[neighbours] enabled``): its declarations with the ground's rulings, its scores as a
detector of its own, its windows, and where it and the ground disagreed; from a run's archive
(what the neighbours sent, and the ground's rulings):

* a declaration is one (subject, window) however many observers applied the rule (each sends
  it); it is declared when the first of them sent it, by the union of their judges;
* its scores are the ground's scoring (``harness/summary/scoring.py``) with the declarations as
  alarms (stamped at the window's end, like the ground's) and the neighbour-windows (a
  subject's window at least one neighbour decided) as the judged windows;
* disagreements: declarations the ground overruled, and ground declarations on a spacecraft
  the neighbours had not declared before the ground did.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from pydantic import Field

from harness.archive.reader import RunArchive
from harness.summary.fdir import Detection
from harness.summary.records import SummaryRecord
from harness.summary.scoring import Alarm, Judged, Scores, overlaps_fault, score
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import NeighbourDeclaration
from interfaces.contracts.scenario import Scenario


class NeighbourWindows(SummaryRecord):
    """The neighbours' windows: a subject's FDI window that at least one neighbour decided
    (a neighbour-window), and each judge's decided verdict on one (a judge-window)."""

    neighbour_windows: int = Field(ge=0, description="subject windows decided, any fault")
    judge_windows: int = Field(ge=0, description="judges' decided verdicts, any fault")
    nominal_judge_windows: int = Field(ge=0, description="those on a subject with no fault")
    nominal_exceeded: int = Field(ge=0, description="of those, the verdicts that failed")


class Disagreements(SummaryRecord):
    """Where the ground and the neighbours disagreed: a declaration the ground overruled, and a
    fault the ground declared on a spacecraft the neighbours had not declared by then."""

    overruled: int = Field(ge=0)
    upheld: int = Field(ge=0)
    unruled: int = Field(ge=0, description="declarations the ground had not ruled on by the end")
    ground_only: int = Field(ge=0, description="ground declarations (first of each spacecraft's "
                                              "episode) the neighbours had not made")


class NeighboursSummary(SummaryRecord):
    """The neighbours' FDIR over the run.  Its declarations are also in ``detections``
    (``declared_by = "neighbours"``)."""

    agree: int = Field(description="the agreement rule's quorum ([neighbours] agree)")
    scores: Scores = Field(description="its declarations scored as the ground's are, per "
                                       "neighbour-window")
    windows: NeighbourWindows
    disagreements: Disagreements
    rulings: dict[str, Literal["upheld", "overruled"]] = Field(
        default_factory=dict, description="by 'subject@window end s'")


def declarations(msgs: Sequence[NeighbourDeclaration]) -> list[Detection]:
    """One detection per (subject, window): at the window's end (the ground's rulings are
    keyed by it), declared when first sent (mid-window where the judges' scans declared it),
    by every judge named."""
    by_key: dict[tuple[int, float], Detection] = {}
    for d in sorted(msgs, key=lambda m: (m.t_sim, m.spacecraft)):
        key = (d.subject, d.t_end_s)
        seen = by_key.get(key)
        if seen is None:
            by_key[key] = Detection(spacecraft=d.subject, time_s=d.t_end_s, declared_s=d.t_sim,
                                    fault_class=None, direction=None, metric=None,
                                    threshold=None, declared_by="neighbours",
                                    judges=sorted(d.judges))
        else:
            seen.judges = sorted(set(seen.judges or []) | set(d.judges))
    return sorted(by_key.values(), key=lambda x: (x.declared_s or 0.0, x.spacecraft))


def neighbours_summary(archive: RunArchive, scenario: Scenario, mission: str,
                       ground: Sequence[Detection]) -> tuple[NeighboursSummary, list[Detection]]:
    """The section and the neighbours' detections; ``ground``: the ground's detections."""
    found = declarations(archive.of(cat.NEIGHBOUR_DECLARATION, mission))
    rulings = {f"{r.subject}@{r.window_end_s:g}": r.verdict
               for r in archive.of(cat.NEIGHBOUR_RULING, mission)}
    verdicts = [(j.spacecraft, v.subject, j.t_start_s, j.t_end_s, v.exceeded)
                for j in archive.of(cat.NEIGHBOUR_JUDGEMENT, mission) for v in j.verdicts
                if v.exceeded is not None]
    windows = sorted({(s, a, b) for _, s, a, b, _ in verdicts})
    nominal = [v for v in verdicts if not overlaps_fault(scenario.faults, v[1], v[2], v[3])]
    scores: Scores = score(scenario.faults,
                           [Alarm(d.spacecraft, d.time_s, None, d.declared_s) for d in found],
                           [Judged(s, a, b) for s, a, b in windows],
                           grace_s=scenario.rates.fdi_period_s)
    return NeighboursSummary(
        agree=scenario.neighbours.agree, scores=scores,
        windows=NeighbourWindows(neighbour_windows=len(windows), judge_windows=len(verdicts),
                                 nominal_judge_windows=len(nominal),
                                 nominal_exceeded=sum(1 for v in nominal if v[4])),
        disagreements=_disagreements(found, rulings, ground), rulings=rulings), found


def _disagreements(found: list[Detection], rulings: dict[str, str],
                   ground: Sequence[Detection]) -> Disagreements:
    ruled = [rulings.get(f"{d.spacecraft}@{d.time_s:g}") for d in found]
    first_ground: dict[int, float] = {}
    for d in ground:
        if d.cause is None and d.spacecraft > 0 and d.declared_s is not None:
            first_ground.setdefault(d.spacecraft, d.declared_s)
    ground_only = sum(1 for sc, t in first_ground.items()
                      if not any(d.spacecraft == sc and (d.declared_s or 0.0) <= t
                                 for d in found))
    return Disagreements(overruled=ruled.count("overruled"), upheld=ruled.count("upheld"),
                         unruled=ruled.count(None), ground_only=ground_only)
