"""When a campaign's fault may begin, by the phase of the run's own set-up
(``start_s = { during = [...] }`` in a campaign file; ``deploy/campaign.py``).

The phases of a scenario, as spans of sim time (s):

* ``deployment``: the observers released from the target drift, from 0 to the first
  ``[[phases]]`` start (only with ``observers.start = "deploy"``);
* ``transfer``: each phase's transfer, [start_s, start_s + transfer_s] (cut short by the next
  phase);
* ``inspection``: holding a PRO: after each transfer until the next phase or the run's end,
  and from 0 to the first phase with ``observers.start = "pro"``;
* ``after_pass``: the ``AFTER_PASS_S`` after each loss of signal of a ground pass (ground
  passes only, ``gnc.passes.ContactPlan``).

Every span ends ``WINDOWS_AFTER`` FDI windows before the run's end at the latest, so a fault
always has windows to be judged in.

With ground passes the ground judges a window only once its data came down, in a pass after
it; :func:`heard_by_s` says how long a run must last for that (``extend_to_pass_s`` in a
campaign file lengthens the run to it).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np

from gnc.passes import ContactPlan
from interfaces.contracts.scenario import Scenario

OnsetPhase = Literal["deployment", "transfer", "inspection", "after_pass"]
ONSET_PHASES: tuple[OnsetPhase, ...] = ("deployment", "transfer", "inspection", "after_pass")
AFTER_PASS_S = 60.0
"""How long after a pass's loss of signal an ``after_pass`` onset may come, s."""
WINDOWS_AFTER = 3
"""FDI windows an onset leaves before the run's end."""

Span = tuple[float, float]


class OnsetError(ValueError):
    """None of the phases asked for occurs in the run's set-up; the message says why."""


def latest_onset_s(scenario: Scenario) -> float:
    """The latest onset the run leaves room to judge, s."""
    return scenario.duration_s - WINDOWS_AFTER * scenario.rates.fdi_period_s


def _phase_end(scenario: Scenario, k: int) -> float:
    """When phase ``k`` gives way to the next one (or the run ends), s."""
    phases = scenario.phases
    return phases[k + 1].start_s if k + 1 < len(phases) else scenario.duration_s


def _first_phase_s(scenario: Scenario) -> float:
    return scenario.phases[0].start_s if scenario.phases else scenario.duration_s


def _deployment(scenario: Scenario) -> list[Span]:
    return [(0.0, _first_phase_s(scenario))] if scenario.observers.start == "deploy" else []


def _transfer(scenario: Scenario) -> list[Span]:
    return [(p.start_s, min(p.start_s + p.transfer_s, _phase_end(scenario, k)))
            for k, p in enumerate(scenario.phases)]


def _inspection(scenario: Scenario) -> list[Span]:
    held = [(p.start_s + p.transfer_s, _phase_end(scenario, k))
            for k, p in enumerate(scenario.phases)]
    if scenario.observers.start == "pro":
        held.insert(0, (0.0, _first_phase_s(scenario)))
    return held


def _after_pass(scenario: Scenario) -> list[Span]:
    plan = ContactPlan.of(scenario)
    if plan is None:
        return []
    return [(los, los + AFTER_PASS_S) for _, los in plan.windows if los < scenario.duration_s]


SPANS = {"deployment": _deployment, "transfer": _transfer, "inspection": _inspection,
         "after_pass": _after_pass}
"""Each phase's spans in a scenario, before the end margin."""

ABSENT = {"deployment": 'the observers start on their PROs (observers.start = "pro")',
          "transfer": "the scenario has no [[phases]]",
          "inspection": "the observers never hold a PRO",
          "after_pass": "no ground pass ends in the run"}
"""Why a phase has no span at all."""


def phase_spans(scenario: Scenario, phase: OnsetPhase) -> list[Span]:
    """The spans of ``phase`` in ``scenario`` in which a fault may begin, s (none when the
    set-up does not have it)."""
    latest = latest_onset_s(scenario)
    return [(a, min(b, latest)) for a, b in SPANS[phase](scenario) if min(b, latest) > a]


def _why_not(scenario: Scenario, phase: OnsetPhase) -> str:
    if phase == "after_pass" and scenario.ground.contact == "continuous":
        return f'{phase}: the ground hears continuously (ground.contact = "continuous")'
    if not SPANS[phase](scenario):
        return f"{phase}: {ABSENT[phase]}"
    return (f"{phase}: none before {latest_onset_s(scenario):g} s ({WINDOWS_AFTER} FDI windows "
            "before the end)")


def draw_onset(scenario: Scenario, phases: Sequence[OnsetPhase], rng: np.random.Generator
               ) -> tuple[OnsetPhase, float]:
    """A phase drawn uniformly among ``phases`` that the set-up has, then an onset uniform
    over its spans (s); OnsetError when it has none of them."""
    spans = {p: phase_spans(scenario, p) for p in dict.fromkeys(phases)}
    have = [p for p in phases if spans[p]]
    if not have:
        raise OnsetError("no onset phase in this set-up: "
                         + "; ".join(_why_not(scenario, p) for p in spans))
    phase = have[int(rng.integers(len(have)))]
    return phase, _uniform_in(spans[phase], rng)


def heard_by_s(scenario: Scenario, onsets_s: Sequence[float], max_extension_s: float) -> float:
    """How long a run with ground passes must last (s) for the ground to hear what followed
    each of ``onsets_s``: until the loss of signal of the first pass that lasts
    ``WINDOWS_AFTER`` FDI windows past the onset, plus ``WINDOWS_AFTER`` windows (its dump
    judged; a silence is known only once the pass is over).  The run's own duration when it
    is long enough or the ground hears continuously; an onset that would lengthen the run by
    more than ``max_extension_s`` is left out (its fault is then one no window could judge)."""
    base = scenario.duration_s
    plan = ContactPlan.of(scenario.model_copy(update={"duration_s": base + max_extension_s}))
    if plan is None:
        return base
    margin = WINDOWS_AFTER * scenario.rates.fdi_period_s
    need = [base]
    for onset in onsets_s:
        los = [b for _, b in plan.windows if b > onset + margin]
        if los and los[0] + margin - base <= max_extension_s:
            need.append(los[0] + margin)
    return max(need)


def _uniform_in(spans: Sequence[Span], rng: np.random.Generator) -> float:
    """A time uniform over the union of disjoint ``spans``, s."""
    lengths = np.array([b - a for a, b in spans])
    u = float(rng.uniform(0.0, float(lengths.sum())))
    k = min(int(np.searchsorted(np.cumsum(lengths), u, side="right")), len(spans) - 1)
    return min(spans[k][0] + u - float(lengths[:k].sum()), spans[k][1])
