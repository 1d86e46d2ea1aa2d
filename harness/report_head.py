"""The opening of a run's report.md: the verdict (``harness.summary.verdict``), then the
settings the run was made with, then how it ran."""

from __future__ import annotations

from collections.abc import Mapping

from harness.summary import RunSummary
from harness.summary.verdict import verdict
from interfaces.contracts.scenario import Scenario


def head_lines(scenario: Scenario, summary: RunSummary,
               metadata: Mapping[str, Mapping[str, str]],
               settings: Mapping[str, str] | None = None) -> list[str]:
    """The title, the verdict, the settings and the run's status line.  ``metadata``: the
    archive's (``run``: software version and start time; empty when unread); ``settings``:
    what the launcher was given beyond the scenario (its file, overrides), as given."""
    return ([f"# Run report: {scenario.name}", ""] + verdict(summary).markdown()
            + settings_lines(scenario, summary, metadata, settings or {})
            + _status_lines(summary))


def settings_lines(scenario: Scenario, summary: RunSummary,
                   metadata: Mapping[str, Mapping[str, str]],
                   settings: Mapping[str, str]) -> list[str]:
    """The settings the run was made with, as a table: the scenario's name, seed, duration,
    observers and detector, the launcher's ``settings``, the software that ran and, for a
    replay written into the summary, the replay's settings."""
    run = metadata.get("run", {})
    rows: list[tuple[str, str]] = [
        ("scenario", scenario.name), *settings.items(), ("seed", str(scenario.seed)),
        ("duration (s)", f"{scenario.duration_s:g}"),
        ("observers", str(scenario.observers.count)),
        ("FDI window (s)", f"{scenario.rates.fdi_period_s:g}"),
        ("FDIR detector", scenario.fdir.detector),
        ("transport", summary.transport or "-"),
        ("software", run.get("software_version", "not recorded")),
        ("started (UTC)", run.get("started_utc", "not recorded"))]
    if summary.replay is not None:
        rows.append(("replayed with", ", ".join(f"{k}={v}" for k, v in
                                                 summary.replay.settings.items()) or "as run"))
    return ["## Settings", "", "| setting | value |", "|---|---|",
            *(f"| {k} | {v} |" for k, v in rows), ""]


def _status_lines(summary: RunSummary) -> list[str]:
    """How the run went: status, time simulated and wall time, and its error."""
    rtf = summary.real_time_factor
    lines = ["## Run", "",
             f"Status **{summary.status}**, {summary.t_sim_final_s or 0:.0f} s simulated in "
             f"{summary.wall_s or 0.0:.1f} s wall" + (f" ({rtf:.0f}× real time)." if rtf else "."),
             ""]
    if summary.error:
        lines += ["```", summary.error, "```", ""]
    return lines
