"""summary.json of a run (docs/contracts.md; its type: ``harness.summary``),
computed from the archive read back."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal, TypeVar

from ground.archive.segments import run_archive
from harness.archive.reader import ArchiveError
from harness.summary.access import AccessAudit
from harness.summary.archive_info import (
    BUS_HEADER,
    MessageCounts,
    archive_info,
    counts_by_type,
)
from harness.summary.control import gnc_summary
from harness.summary.coverage import coverage_summary
from harness.summary.digest import RunDigest, digest_run
from harness.summary.document import RunSummary
from harness.summary.execution import exec_record, sim_record
from harness.summary.fault_events import FaultEventRecord
from harness.summary.fdir import fdir_summary
from harness.summary.ground_contact import ground_contact
from harness.summary.nav import nav_stats
from harness.summary.neighbours import neighbours_summary
from harness.summary.onboard import onboard_summary
from harness.summary.records import given_copies
from harness.summary.recovery import RecoveryComparison
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    ExecStats,
    LinkStats,
    Message,
    Tick,
)
from interfaces.contracts.scenario import Scenario

M = TypeVar("M", bound=Message)

NAV_SETTLE_S = 10.0
"""Nav statistics skip the filter's first seconds (initial transient)."""


@dataclass(frozen=True)
class RunOutcome:
    """How a run went, from outside its archive: its transport, wall time (s), status and
    error (None if none)."""

    transport: Literal["inproc", "zenoh"]
    wall_s: float
    status: Literal["completed", "degraded", "failed", "interrupted"]
    error: str | None = None


def summary_head(scenario: Scenario, outcome: RunOutcome) -> RunSummary:
    """The fields every run's summary has, from its scenario and outcome."""
    return RunSummary(scenario=scenario.name, seed=scenario.seed, transport=outcome.transport,
                      duration_s=scenario.duration_s, wall_s=round(outcome.wall_s, 3),
                      status=outcome.status, error=outcome.error,
                      injected_faults=given_copies(scenario.faults))


def build_summary(digest: RunDigest, scenario: Scenario, mission: str,
                  outcome: RunOutcome) -> RunSummary:
    """The run's summary: its head, then its figures from its archive."""
    archive = digest.archive
    tick_key = (cat.TICK.key(mission), Tick.__name__)
    last_tick = digest.counters.last.get(tick_key)
    execs = _last_of(digest, ExecStats)
    links = _last_of(digest, LinkStats)
    tlm = archive.of(cat.TLM_STATUS, mission)
    summary = summary_head(scenario, outcome)
    summary.archive = archive_info(archive, scenario)
    summary.ticks = digest.counters.counts.get(tick_key, 0)
    t_final = last_tick.decode(Tick).t_sim if last_tick is not None else 0.0
    summary.t_sim_final_s = t_final
    summary.messages = MessageCounts(total=len(archive), by_type=counts_by_type(archive))
    summary.nav = {str(sc): nav_stats(e.stats(skip_s=NAV_SETTLE_S))
                   for sc, e in digest.nav_errors(mission).items()}
    summary.gnc = gnc_summary(digest.gnc_series(scenario, mission))
    summary.coverage = coverage_summary(digest.coverage)
    summary.links = given_copies([c for node in sorted(links) for c in links[node].links],
                            exclude_none=True)
    contact = ground_contact(scenario, summary.links)
    if contact is not None:  # unset otherwise: not written
        summary.ground_contact = contact
    summary.exec = {node: exec_record(m) for node, m in sorted(execs.items())}
    summary.telemetry = given_copies(tlm[-1].entries) if tlm else []
    summary.sim = sim_record(archive.of(cat.SIM_STATUS, mission))
    summary.fault_events = [FaultEventRecord.model_validate(e.model_dump(exclude=BUS_HEADER))
                            for e in archive.of(cat.FAULT_EVENTS, mission)]
    summary.set_fdir(fdir_summary(archive, scenario, mission))
    if scenario.onboard_fdir.enabled:
        summary.onboard_fdir = onboard_summary(archive, mission, scenario.faults, summary.scores)
    if scenario.neighbours.enabled:
        summary.neighbours, found = neighbours_summary(archive, scenario, mission,
                                                       summary.detections or [])
        summary.detections = [*(summary.detections or []), *found]
    summary.real_time_factor = round(t_final / outcome.wall_s, 2) if outcome.wall_s > 0 else None
    return summary


def _last_of(digest: RunDigest, model: type[M]) -> dict[str, M]:
    """The last ``model`` message of each key, by node (cumulative counters)."""
    msgs = [rec.decode(model) for (_, type_name), rec in digest.counters.last.items()
            if type_name == model.__name__]
    return {m.node: m for m in msgs}  # type: ignore[attr-defined]


def write_summary(out: Path, scenario: Scenario, transport: Literal["inproc", "zenoh"],
                  wall_s: float, status: Literal["completed", "degraded", "failed", "interrupted"],
                  error: str | None = None, mission: str | None = None,
                  digest: RunDigest | None = None,
                  access: AccessAudit | None = None) -> RunSummary:
    """Write ``<out>/summary.json`` and return it.  A damaged or missing archive is reported in
    the summary (``archive_error``), never hidden.  ``digest``: the run's archive already read
    (``harness.summary.digest``; the report then reuses it), else ``<out>/run.mcap`` (and the
    segments after it) is read.
    ``access``: the router's audit (from outside the archive)."""
    outcome = RunOutcome(transport, wall_s, status, error)
    try:
        digest = digest or digest_run(run_archive(out), scenario, mission or scenario.name)
        summary = build_summary(digest, scenario, mission or scenario.name, outcome)
    except (ArchiveError, OSError) as e:
        summary = summary_head(scenario, outcome)
        if digest is not None:  # read, then found damaged
            summary.archive = archive_info(digest.archive, scenario)
        summary.archive_error = str(e)
    if access is not None:
        summary.access = access
    summary.write(out / "summary.json")
    return summary


def add_recovery_comparison(out: Path, summary: RunSummary, counter: RunSummary,
                            recovery: bool) -> RunSummary:
    """Add ``recovery`` to ``<out>/summary.json``: the recovery actions of the run that had
    recovery on, and the final H with and without recovery for the same scenario and seed
    (``counter``: the summary of the same scenario with recovery flipped)."""
    with_r, without = (summary, counter) if recovery else (counter, summary)
    h_with = with_r.coverage.H_final if with_r.coverage else None
    h_without = without.coverage.H_final if without.coverage else None
    summary.recovery = RecoveryComparison(
        enabled=recovery,
        actions=[d for d in (with_r.coverage.assignment_decisions if with_r.coverage else [])
                 if d.reason == "recovery"],
        H_final_with_recovery=h_with,
        H_final_without_recovery=h_without,
        H_final_ratio=h_with / h_without if h_with is not None and h_without else None,
        counterfactual="counterfactual/summary.json",
        counterfactual_status=counter.status)
    summary.write(out / "summary.json")
    return summary
