"""Replay: the live ground re-run on the telemetry in a run's archive, under the run's own or
other detector settings.

    python -m harness.replay RUN [RUN ...] [--set fdir.KEY=VALUE ...] [--out DIR] [--overwrite]

RUN is a run directory (holding ``run.mcap``) or an archive (its first segment: the segments
after it, a restarted recorder's, are read with it as one run); any other path is refused, one
line each, exit status 2, before anything is replayed (``harness/archive/locate.py``).

Each replay is written beside its archive as ``replay.json`` (the run's own settings) or
``replay-<settings>.json`` (``--set`` given: e.g. ``replay-fdir.persistence=3.json``, the
settings sorted by name, joined by ``+``), or into ``--out DIR`` as ``<run>.replay.json`` /
``<run>.replay-<settings>.json``: replays under other settings never replace each other.
Before anything is replayed, every run's settings are checked against its scenario, and every
destination must be writable (a read-only folder is refused, naming it and ``--out``) and must
not hold a replay with the same settings already (refused unless ``--overwrite``): one line,
exit status 2.  A replay that fails midway is said in one line; the exit status is then 1.

The ground node itself, built from the declared topology as a run builds it
(``interfaces.contracts.topology``: planner, telemetry monitor, FDIR, baselines -- the code the
live ground runs, not a copy) is fed, on the in-process bus, every archived message of the other
nodes that the ground subscribes to, in the lockstep's order: all messages of sim time t, then the
sim's Tick at t.  Its own channel model (the scenario's comms, seed, cuts and link faults) decides
again, in the same deterministic order, which of them reached it, so losses and range cuts replay
as they happened.  What it publishes -- FDI windows, fault reports, baseline verdicts -- is scored
as ``summary.json`` scores the live run (``harness.summary.build.fdir_results``);
``scores_faithful`` scores only what it declared and judged up to ``faithful_until_s``.

Faithfulness.  With the run's own settings the replay reproduces the live detections, their
times and classes, and every window and verdict exactly (``matches_live``).  The spacecraft's
data, however, is what they flew: once an uplink differs from the live one -- a recovery
replan after a declaration made at another time, or not made -- the replay judges a
trajectory that its own uplinks did not command.  ``faithful_until_s`` is the sim time of the
first such difference (the run's end when there is none); what the replay reports after it is
kept, and marked, and left out of ``scores_faithful``.

An archive that lost data.  A replay judges what the archive holds, and no further: its end,
``archive_end_s``, is the sim time of its last message (``RunArchive.end_s``).  When that is
before the run's end (its last tick, at ``duration_s``: a file cut short -- no footer, read up
to the cut -- or a whole file of a run that stopped early), the archive's last instant may
itself be torn (part of its messages in the lost bytes), so only what the ground did before it
counts: a window (and its baselines' verdicts) whose end plus ``fdir.latency_s`` is not before
``archive_end_s``, a report declared then, an uplink sent then, is dropped from both the replay
and the live run before they are compared and scored, and ``faithful_until_s`` is at most
``archive_end_s``.  The command line then says "archive ends at X s (run lasted Y s): judged
nothing past it".  The reader reports a file cut short too (a warning naming the byte it stops
at and the sim time its data ends at).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import logging
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from harness.archive.locate import archive_file
from harness.archive.reader import ArchiveError, Record, RunArchive
from harness.archive.run_scenario import archived_scenario
from harness.archive.span import ArchiveSpan
from harness.archive.stream import stream_run
from harness.destination import DestinationError, check_file, write_whole
from harness.summary import ReplayResults
from harness.summary.delay_bound import NisSeries
from harness.summary.fdir import archived_nis, fdir_results
from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.catalogue import Topic, topic_of
from interfaces.contracts.errors import describe, did_you_mean
from interfaces.contracts.messages import (
    BaselineVerdict,
    ConstellationWindow,
    FaultReport,
    FdirWindow,
    ProAssignments,
    StateEstimate,
)
from interfaces.contracts.scenario import Scenario, ScenarioError
from interfaces.contracts.topology import topology
from interfaces.runtime.arguments import command_help, prog_name
from interfaces.runtime.assembly import executive_of
from interfaces.runtime.blas_threads import one_blas_thread
from interfaces.runtime.bus import Bus
from interfaces.runtime.executive import TickClient
from interfaces.runtime.transport import InprocNetwork, Sample
from links.channel import ChannelModel

SETTABLE = ("fdir.", "rates.fdi_period_s")
"""Settings a replay may change: the ground's detector only.  Anything else changes what the
spacecraft flew, which only a new simulation can tell."""

UNREAD = (cat.CAMERA_IMAGE, cat.RELNAV, cat.ATTITUDE_SENSORS, cat.THRUST, cat.WHEELS,
          cat.POINTING, cat.TICK_DONE, cat.EXEC_STATS, cat.LINK_STATS, cat.DECISIONS,
          cat.TLM_STATUS)
"""Topics no ground app subscribes to and the comparison does not read: counted and dropped as
the archive is read (``tests/harness/test_replay.py`` checks the ground reads none of them).
The one exception is the ground's own link counters (``LINK_STATS``; its FDIR reads the
onboard stores' overflow from them with ground passes): the replay's ground makes them again,
its channel stage running the stores on the archive's messages."""


@dataclass
class GroundOutput:
    """What a ground published (live, from the archive; or replayed)."""

    windows: list[FdirWindow] = field(default_factory=list)
    reports: list[FaultReport] = field(default_factory=list)
    verdicts: list[BaselineVerdict] = field(default_factory=list)
    assignments: list[ProAssignments] = field(default_factory=list)
    constellation: list[ConstellationWindow] = field(default_factory=list)

    def add(self, msg: object) -> None:
        for kind, holder in ((FdirWindow, self.windows), (FaultReport, self.reports),
                             (BaselineVerdict, self.verdicts), (ProAssignments, self.assignments),
                             (ConstellationWindow, self.constellation)):
            if type(msg) is kind:
                holder.append(msg)  # type: ignore[attr-defined]

    @classmethod
    def of_archive(cls, archive: RunArchive, mission: str) -> GroundOutput:
        return cls(archive.of(cat.FDIR_WINDOW, mission), archive.of(cat.FAULT_REPORT, mission),
                   archive.of(cat.BASELINE, mission), archive.of(cat.ASSIGNMENTS, mission),
                   archive.of(cat.CONSTELLATION_WINDOW, mission))

    def within(self, span: ArchiveSpan, latency_s: float) -> GroundOutput:
        """What the ground did while ``span`` holds its inputs: windows (and the verdicts and
        constellation windows on them) due, their end plus ``latency_s`` (s), reports declared
        (their window's end plus ``latency_s`` when not stamped) and uplinks sent by then."""
        def due(t_end_s: float) -> bool:
            return span.holds(t_end_s + latency_s)

        return GroundOutput(
            [w for w in self.windows if due(w.t_end_s)],
            [r for r in self.reports
             if span.holds(r.declared_s if r.declared_s is not None else r.t_sim + latency_s)],
            [v for v in self.verdicts if due(v.t_end_s)],
            [a for a in self.assignments if span.holds(a.t_sim)],
            [c for c in self.constellation if due(c.t_end_s)])


@dataclass
class Replay:
    """One replayed run: the scenario it ran with, the replay's and the live ground's output
    (both only as far as the archive holds the ground's inputs: ``span``)."""

    scenario: Scenario
    live: GroundOutput
    replayed: GroundOutput
    wall_s: float
    span: ArchiveSpan
    nis: NisSeries | None = None
    """the nav updates the ground judged, where the sequential test runs (delay bounds)"""

    def faithful_until_s(self) -> float:
        """Sim time of the first uplink that differs from the live run's (s); the run's end
        when none does; never past the archive's end."""
        return min(self._diverged_s(), self.span.end_s)

    def _diverged_s(self) -> float:
        """Sim time of the first uplink that differs from the live run's (s); the run's end
        when none does."""
        live = [_plan(m) for m in self.live.assignments]
        mine = [_plan(m) for m in self.replayed.assignments]
        for a, b in zip(live, mine, strict=False):  # then the longer one's next differs
            if a != b:
                return min(a[0], b[0])
        if len(live) != len(mine):
            return (live if len(live) > len(mine) else mine)[min(len(live), len(mine))][0]
        return self.scenario.duration_s

    def matches_live(self) -> bool:
        """Every window, report and verdict equal to the live ground's (sender-stamped wall
        times aside)."""
        return all(_same(a, b) for a, b in (
            (self.live.windows, self.replayed.windows), (self.live.reports, self.replayed.reports),
            (self.live.verdicts, self.replayed.verdicts),
            (self.live.constellation, self.replayed.constellation)))

    def results(self) -> ReplayResults:
        """``summary.json``'s FDIR fields for the replay, with its faithfulness."""
        mine = self.replayed
        out = fdir_results(mine.reports, mine.windows, mine.verdicts, self.scenario, self.nis)
        horizon = self.faithful_until_s()
        for d in out.detections:
            d.faithful = d.time_s <= horizon
        faithful = fdir_results([r for r in mine.reports if r.t_sim <= horizon],
                                [w for w in mine.windows if w.t_end_s <= horizon],
                                [v for v in mine.verdicts if v.t_end_s <= horizon],
                                self.scenario, self.nis)
        census = {"fdir_thresholds": faithful.fdir_thresholds}  # the census: faithful span
        return ReplayResults(scenario=self.scenario.name, seed=self.scenario.seed,
                             replay_wall_s=round(self.wall_s, 3),
                             archive_end_s=self.span.end_s, faithful_until_s=horizon,
                             matches_live=self.matches_live(), **(dict(out) | census),
                             scores_faithful=faithful.scores)


def _plan(msg: ProAssignments) -> tuple[float, list[dict[str, Any]]]:
    return msg.t_sim, [a.model_dump() for a in msg.assignments]


def _same(a: list[Any], b: list[Any]) -> bool:
    skip = {"t_wall"}
    return len(a) == len(b) and all(x.model_dump(exclude=skip) == y.model_dump(exclude=skip)
                                    for x, y in zip(a, b, strict=True))


# --- settings ---------------------------------------------------------------------------------


def with_settings(scenario: Scenario, settings: dict[str, str]) -> Scenario:
    """``scenario`` with ``section.key = value`` settings (values parsed as JSON where they
    are, else kept as text); only detector settings (``SETTABLE``).  Raises ScenarioError."""
    for name in settings:
        section = name.partition(".")[0]
        if section not in Scenario.model_fields:
            raise ScenarioError(f"--set {name}: the scenario has no [{section}]"
                                f"{did_you_mean(section, Scenario.model_fields)}")
        if not name.startswith(SETTABLE[0]) and name not in SETTABLE[1:]:
            raise ScenarioError(f"--set {name}: a replay re-runs the ground's detector only "
                                f"(fdir.*, rates.fdi_period_s); {name} changes what was flown, "
                                "simulate it instead")
    return scenario_with(scenario, settings)


def scenario_with(scenario: Scenario, settings: dict[str, str]) -> Scenario:
    """``scenario`` with any ``section.key = value`` settings (values parsed as JSON where they
    are, else kept as text).  Raises ScenarioError naming a setting that is not one."""
    data = scenario.model_dump()
    for name, text in settings.items():
        section, _, key = name.partition(".")
        if not isinstance(data.get(section), dict) or key not in data[section]:
            known = data[section] if isinstance(data.get(section), dict) else data
            raise ScenarioError(f"--set {name}: no such setting in [{section}]"
                                f"{did_you_mean(key if section in data else section, known)}")
        data[section][key] = _value(text)
    try:
        return Scenario.model_validate(data)
    except ValidationError as e:
        raise ScenarioError(describe(e, "--set", Scenario, data)) from None


def _value(text: str) -> Any:
    """A ``--set`` value: JSON where it is (a number, true, a list...), else the text."""
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


# --- the replay ---------------------------------------------------------------------------------


def replay_run(path: Path, settings: dict[str, str] | None = None,
               scenario: Scenario | None = None) -> Replay:
    """Replay the ground of the run archived at ``path`` (its archive or its folder; module
    docstring), judging nothing past the archive's end.  ``scenario``: the run's scenario when
    its archive carries none; ``settings``: detector settings changed from the run's.
    The archive streams past in time order (``harness.archive.stream``): what the replay
    holds is the ground's own output and the nav estimates, not the archive.
    Raises ArchiveError (ArchivePathError for a path naming no archive), ScenarioError.  This
    process's BLAS runs on one thread from then on (``interfaces.runtime.blas_threads``)."""
    one_blas_thread()
    start = time.perf_counter()
    file = archive_file(path)
    flown = scenario or archived_scenario(file)
    replay_scenario = with_settings(flown, settings or {})
    feed = GroundFeed(replay_scenario)
    archive, _ = stream_run(file, {**{t.any_mission(): _drop for t in UNREAD},
                                   OWN_OUTPUT: None, "**": feed})
    feed.finish()
    mission = archive.mission()
    span = ArchiveSpan.of(archive, flown)
    replayed = feed.out.within(span, replay_scenario.fdir.latency_s)
    live = GroundOutput.of_archive(archive, mission).within(span, flown.fdir.latency_s)
    return Replay(replay_scenario, live, replayed, time.perf_counter() - start, span,
                  archived_nis(feed.estimates(), replay_scenario))


OWN_OUTPUT = f"{topics.ROOT}/*/{topics.GROUND}/**"
"""The live ground's own messages: held for the comparison, never played to the replay's."""


class GroundFeed:
    """The replay's sink: the other nodes' records, as they stream past in time order, played
    to a ground station built as a run builds it (``interfaces.contracts.topology``: the code
    the live ground runs), in lockstep order: per sim time, every message, then the Tick.  The
    station is built at the first Tick (its key names the mission); the nav estimates are also
    kept (the delay bounds read them)."""

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.out = GroundOutput()
        self._nav: list[Record] = []
        self._group: list[Record] = []
        self._waiting: list[list[Record]] = []  # instants before the first Tick
        self._player: Any = None
        self._topics: dict[str, Topic | None] = {}

    def __call__(self, rec: Record) -> None:
        if self._group and rec.log_time_ns != self._group[0].log_time_ns:
            self._instant(self._group)
            self._group = []
        self._group.append(rec)
        if self._topic(rec.key) is cat.NAV_ESTIMATE:
            self._nav.append(rec)

    def _topic(self, key: str) -> Topic | None:
        """The catalogued topic of ``key`` (looked up once per key)."""
        if key not in self._topics:
            self._topics[key] = topic_of(key)
        return self._topics[key]

    def finish(self) -> None:
        """Play the last instant (none is played without a Tick: the archive's mission is
        then unknown, which reading it says)."""
        self._instant(self._group)
        self._group = []

    def estimates(self) -> list[StateEstimate]:
        """The nav estimates streamed past."""
        model = cat.NAV_ESTIMATE.type
        return [r.decode(model) for r in self._nav if r.type_name == model.__name__]

    def _instant(self, group: list[Record]) -> None:
        """Play one sim time's records (those before the first Tick wait for it)."""
        instants = [group]
        if self._player is None:
            self._waiting.append(group)
            tick = next((r for r in group if self._topic(r.key) is cat.TICK), None)
            if tick is None:
                return
            self._player = self._ground(tick.key)
            instants, self._waiting = self._waiting, []
        for instant in instants:
            _send_group(instant, self._player)

    def _ground(self, key: str) -> Any:
        """The ground station of the mission ``key`` lies in, built as a run builds it, whose
        output goes to :attr:`out`; the endpoint that plays to it."""
        mission = key.split("/")[1]
        net = InprocNetwork()
        bus = Bus(topics.GROUND, mission, net.endpoint(),
                  channel=ChannelModel.of(topics.GROUND, self.scenario))
        executive = executive_of(topology(self.scenario).node(topics.GROUND), bus,
                                 self.scenario)
        executive.barrier_timeout_s = 0.0  # everything archived is delivered before a tick
        TickClient(executive, synchronous=True)
        own = topics.node_prefix(mission, topics.GROUND)
        net.endpoint().subscribe_samples(own + "/**", lambda s: self.out.add(s.message))
        return net.endpoint()


def _drop(_rec: Record) -> None:
    """Sink of the records a replay does not read."""


def _send_group(group: list[Record], player: Any) -> None:
    tick = cat.TICK.type.__name__
    for rec in sorted(group, key=lambda r: r.type_name == tick):
        player.send(Sample(rec.key, rec.type_name, payload=rec.payload))


# --- command line -------------------------------------------------------------------------------


def parse_settings(pairs: list[str]) -> dict[str, str]:
    """``SECTION.KEY=VALUE`` strings as a settings dict (ScenarioError if malformed)."""
    out = {}
    for p in pairs:
        name, sep, value = p.partition("=")
        if not sep or not name:
            raise ScenarioError(f"--set {p!r}: expected SECTION.KEY=VALUE")
        out[name.strip()] = value.strip()
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog=prog_name("python -m harness.replay"),
                                description=command_help(__doc__,
                                                         "docs/campaigns-and-replay.md", 2),
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", nargs="+", type=Path, help="run directories or run.mcap files")
    p.add_argument("--set", dest="settings", action="append", default=[],
                   metavar="fdir.KEY=VALUE", help="a detector setting (repeatable)")
    p.add_argument("--out", type=Path, default=None,
                   help="directory for <run>.replay[-SETTINGS].json (default: beside each "
                        "archive, replay[-SETTINGS].json)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace a replay already written with the same settings")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    try:
        settings = parse_settings(args.settings)
        files = [archive_file(run) for run in args.runs]
        dests = [_checked(run, file, args.out, settings, args.overwrite)
                 for run, file in zip(args.runs, files, strict=True)]
    except (ArchiveError, ScenarioError, DestinationError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    failed = 0
    for run, file, dest in zip(args.runs, files, dests, strict=True):
        try:
            replay = replay_run(file, settings)
            _write(replay, run, dest)
        except (ArchiveError, ScenarioError, OSError) as e:
            print(f"{run}: {e}", file=sys.stderr)
            failed += 1
    return 1 if failed else 0


def output_name(values: dict[str, Any]) -> str:
    """The replay's file name for settings set to ``values`` (as the scenario holds them, so
    that ``3``, ``3.0`` and ``3.00`` name one file): ``replay`` with none (the run's own), else
    ``replay-`` and the settings, sorted, as ``KEY=VALUE`` (the value as JSON writes it)
    joined by ``+``, each character a file name should not hold as ``_``; a name over 120
    characters cut, with a digest of the whole."""
    if not values:
        return "replay"
    text = "+".join(f"{k}={json.dumps(v)}".replace('"', "") for k, v in sorted(values.items()))
    safe = re.sub(r"[^A-Za-z0-9._=+,-]", "_", text)
    if len(safe) > 120:
        safe = f"{safe[:100]}-{hashlib.sha256(text.encode()).hexdigest()[:12]}"
    return f"replay-{safe}"


def output_path(run: Path, file: Path, out: Path | None, values: dict[str, Any]) -> Path:
    """Where the replay of ``run`` (its archive ``file``) with settings at ``values`` is
    written: ``<name>.json`` beside the archive, or ``<run>.<name>.json`` in ``out``."""
    name = output_name(values)
    if out is None:
        return file.parent / f"{name}.json"
    return out / f"{(run if run.is_dir() else run.parent).name or 'run'}.{name}.json"


def _checked(run: Path, file: Path, out: Path | None, settings: dict[str, str],
             overwrite: bool) -> Path:
    """Before any replay: the run's scenario takes ``settings``, and its replay's file can be
    written and replaces none unless ``overwrite``; where it goes.  ScenarioError,
    ArchiveError, DestinationError."""
    try:
        scenario = with_settings(archived_scenario(file), settings)
    except ScenarioError as e:
        raise ScenarioError(f"{run}: {e}") from None
    values = {name: getattr(getattr(scenario, name.partition(".")[0]), name.partition(".")[2])
              for name in settings}
    dest = output_path(run, file, out, values)
    check_file(dest, overwrite, "--out DIR" if out is None else "another --out")
    return dest


def _write(replay: Replay, run: Path, dest: Path) -> None:
    """Write the replay's results to ``dest`` and say what it found in one line."""
    res = replay.results()
    write_whole(dest, res.to_json(indent=1))
    dets = ", ".join(f"sc{d.spacecraft} {d.fault_class or 'unidentified'} at {d.time_s:.0f} s"
                     + ("" if d.faithful else " (after divergence)")
                     for d in res.detections) or "no detection"
    note = replay.span.note()
    print(f"{run}: {note + '; ' if note else ''}{dets}; "
          f"{'matches the live run' if res.matches_live else 'differs from the live run'}"
          f"; faithful until {res.faithful_until_s:.0f} s; "
          f"{res.replay_wall_s:.1f} s -> {dest}")


if __name__ == "__main__":
    raise SystemExit(main())
