"""Run one scenario: the sim, one flight-software process per observer, the ground and the
recorder as separate OS processes over Zenoh (default), or all in one process (--transport inproc).

    python deploy/run_constellation.py [--scenario deploy/scenarios/default.toml] --out runs/x
        [--transport zenoh|inproc] [--seed N] [--duration S] [--realtime SPEED]
        [--compare-recovery] [--live PORT] [--endpoint tcp/127.0.0.1:7447|tls/HOST:PORT]
        [--audit-access] [--external NODE --advertise tls/HOST:PORT --tls-host HOST]

Writes <out>/run.mcap (every bus message, JSON schemas; opens in Foxglove), <out>/run.foxglove.json
(the Foxglove layout that reads it: harness/foxglove_layout.py), <out>/summary.json,
<out>/report.md with PNG plots, and <out>/logs/ (one log per process).

Over Zenoh the network is closed (deploy/access.py): the launcher starts the run's router
(deploy/router.py) on the endpoint (default tcp/127.0.0.1:7447), every process joins it as a
client with an account of its own, and access-control rules let each publish only in its own key
space.  The accounts are made for the run in <out>/access/ (owner-only files); the read-only
telemetry account <out>/access/tlm.json5 lets any Zenoh client watch the run
(``python -m ground.tools.tlm --zenoh-config <out>/access/tlm.json5``).  A ``tls/`` endpoint serves
TLS with a certificate made for the run (its authority is <out>/access/tls/authority.pem).
--audit-access counts the router's refusals (failed logins, denied messages) into
<out>/logs/access.json and summary.json's ``access``.  Across hosts: listen on all interfaces
(--endpoint tls/0.0.0.0:7447), give the address the other hosts use (--advertise
tls/HOST:7447, also put in the certificate), and name the nodes that run elsewhere
(--external sc3): the launcher does not start them, and prints how to start each on its host
with its account file.
With --live PORT the run is streamed to Foxglove (Foxglove WebSocket protocol, loopback;
ground/tools/live.py): every bus message on a channel named by its key, and the truth poses in 3D.
With --compare-recovery the same scenario and seed is run a second time, in-process, with the
ground's fault recovery switched the other way ([fdir] recovery), into <out>/counterfactual/,
and summary.json's ``recovery`` section compares the final H of the two.
Exits 0 when the run completed; 1, with the reason, when it ended degraded (a flight or ground
process lost, or with --restart-on-crash the recorder restarted: see _Watch) or failed (the
sim or recorder died, the run could not start).
"""

from __future__ import annotations

import argparse
import logging
import signal
import subprocess
import sys
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

import zenoh

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:  # run as a script from a checkout
    sys.path.insert(0, str(REPO))

from deploy.access import RunAccess, write_run_access  # noqa: E402
from deploy.disk_space import DiskSpaceError, Reserve, check_space, disk_full_logged  # noqa: E402
from deploy.host_map import HostMap, HostMapError, load_host_map, parse_link_event  # noqa: E402
from deploy.interrupts import Interrupts  # noqa: E402
from deploy.link_events import LinkEvents, check_cuts  # noqa: E402
from deploy.out_folder import OutFolderError, written  # noqa: E402
from deploy.out_folder import prepare as prepare_out  # noqa: E402
from deploy.placement import (  # noqa: E402
    Placement,
    across_hosts,
    host_processes,
    one_host,
)
from deploy.processes import Child, Incident, Supervisor, host_cores  # noqa: E402
from deploy.progress_line import progress_line  # noqa: E402
from deploy.recorder_guard import RecorderGuard  # noqa: E402
from deploy.rehearsal.netns import RehearsalError, require_privilege  # noqa: E402
from deploy.rehearsal.network import RehearsedNetwork  # noqa: E402
from deploy.router import address_taken, endpoint_taken  # noqa: E402
from ground.archive.metadata import run_metadata  # noqa: E402
from ground.archive.recorder_process import RecorderDied, RecorderProcess  # noqa: E402
from ground.archive.segments import remove_segments, run_archive  # noqa: E402
from harness.archive.reader import ArchiveError  # noqa: E402
from harness.summary import AccessAudit, RunSummary  # noqa: E402
from harness.summary.build import add_recovery_comparison, write_summary  # noqa: E402
from harness.summary.digest import LiveDigest, RunDigest, digest_run  # noqa: E402
from harness.summary.verdict import verdict  # noqa: E402
from interfaces.contracts import catalogue as cat  # noqa: E402
from interfaces.contracts import topics  # noqa: E402
from interfaces.contracts.messages import Heartbeat, SimStatus  # noqa: E402
from interfaces.contracts.scenario import Scenario, ScenarioError, load_scenario  # noqa: E402
from interfaces.contracts.topology import (  # noqa: E402
    RECORDER,
    ROUTER,
    SIM,
    NodeProcess,
    hosting,
    topology,
)
from interfaces.runtime.arguments import (  # noqa: E402
    add_log_level,
    command_help,
    endpoint,
    mission_name,
)
from interfaces.runtime.cds import read_starts, write_run_key  # noqa: E402
from interfaces.runtime.kernels import compile_kernels, kernels_cached  # noqa: E402
from interfaces.runtime.transport import Sample  # noqa: E402
from interfaces.runtime.zenoh_transport import DEFAULT_ENDPOINT, ZenohSettings, ZenohTransport  # noqa: E402
from links.data_budget import budget  # noqa: E402

if TYPE_CHECKING:
    from ground.tools.live import LiveView

DEFAULT_SCENARIO = REPO / "deploy" / "scenarios" / "default.toml"
INTERRUPTED = "interrupted by the user (SIGINT or SIGTERM)"
"""The error of a run stopped by a signal before its sim finished (status ``interrupted``)."""
log = logging.getLogger("insp.launcher")
T = TypeVar("T")


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=command_help(__doc__, "docs/contracts.md, "
                                                         "docs/bus-and-security.md", 2),
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scenario", type=Path, default=DEFAULT_SCENARIO,
                   help="scenario TOML (default %(default)s)")
    p.add_argument("--out", type=Path, help="output directory, refused when it holds anything "
                                            "(default runs/<scenario>-<time>)")
    p.add_argument("--overwrite", action="store_true",
                   help="remove the run already in --out wholly before this one is written")
    p.add_argument("--transport", choices=("zenoh", "inproc"), default="zenoh",
                   help="zenoh: one process per node over a Zenoh router (default); inproc: "
                        "every node in this process, same results")
    p.add_argument("--seed", type=int, help="override the scenario seed")
    p.add_argument("--duration", type=float, help="override duration_s (s)")
    p.add_argument("--realtime", type=float, metavar="SPEED",
                   help="run at most SPEED times real time, still in lockstep: a host that "
                        "cannot hold it runs slower, never differently (default: as fast as "
                        "the lockstep goes)")
    p.add_argument("--hard-deadline", action="store_true",
                   help="with --realtime: keep the wall clock; an answer later than the next "
                        "tick is a missed tick of its node (hardware-in-the-loop style)")
    p.add_argument("--endpoint", default=DEFAULT_ENDPOINT, type=endpoint,
                   help="Zenoh endpoint of the run's router (default %(default)s; tls/HOST:PORT "
                        "for TLS)")
    p.add_argument("--advertise", metavar="ENDPOINT", type=endpoint,
                   help="endpoint the clients connect to (default: --endpoint); for nodes on "
                        "other hosts")
    p.add_argument("--hosting", choices=("packed", "one-per-process"), default="packed",
                   help="packed: the spacecraft share as many processes as this host has "
                        "cores, stepping together (default); one-per-process: a process per "
                        "node, as on separate computers (interfaces/contracts/topology.py)")
    p.add_argument("--processes", type=int, metavar="N",
                   help="with --hosting packed: the processes the spacecraft share (default: "
                        "this host's cores)")
    p.add_argument("--external", action="append", default=[], metavar="NODE",
                   help="a node (sc<N> or ground) started by hand on another host; repeatable")
    p.add_argument("--tls-host", action="append", default=[], metavar="NAME",
                   help="another name or address of this host in the TLS certificate (for "
                        "nodes on other hosts); repeatable")
    p.add_argument("--hosts", type=Path, metavar="MAP",
                   help="run across the hosts of a host map (deploy/hosts/<name>.toml, "
                        "docs/hosts.md): a router per host, linked to the ground host's over "
                        "TLS; without --rehearse, print each host's command and files")
    p.add_argument("--rehearse", action="store_true",
                   help="with --hosts: rehearse the map on this machine, a network namespace "
                        "per host, their links delayed, lossy or cut as the map says (needs "
                        "CAP_SYS_ADMIN and CAP_NET_ADMIN); everything made is removed at the "
                        "end")
    p.add_argument("--link-delay-ms", type=float, metavar="MS",
                   help="with --hosts: every host's link delays what it sends by MS (one way)")
    p.add_argument("--link-loss-pct", type=float, metavar="PCT",
                   help="with --hosts: every host's link loses PCT percent of what it sends")
    p.add_argument("--link-event", action="append", default=[], metavar="EVENT",
                   help="with --rehearse: HOST:cut|delay=MS|loss=PCT:AT_S:DURATION_S, a host's "
                        "link cut, or its delay or loss raised, from sim time AT_S for "
                        "DURATION_S; repeatable (the map's [[events]] too)")
    p.add_argument("--restart-on-crash", action="store_true",
                   help="start a process again if it dies, the sim holding the clock: a flight "
                        "or ground process restores its critical-data store, the router comes "
                        "back on its endpoint, the recorder continues in run-1.mcap, ...")
    p.add_argument("--audit-access", action="store_true",
                   help="count the router's refusals into logs/access.json and the summary "
                        "(traces every routed message: slower)")
    p.add_argument("--mission", type=mission_name,
                   help="key-space name: letters, digits, '_' or '-' (default: scenario name)")
    p.add_argument("--no-report", action="store_true", help="skip report.md and plots")
    p.add_argument("--skip-disk-check", action="store_true",
                   help="start even when --out's disk looks too small for the run's estimated "
                        "archive (the run then ends 'failed: disk full' where the disk fills)")
    p.add_argument("--live", type=int, metavar="PORT", default=0,
                   help="stream the run to Foxglove on ws://127.0.0.1:PORT (off by default)")
    p.add_argument("--compare-recovery", action="store_true",
                   help="also run the scenario with [fdir] recovery flipped (in-process) and "
                        "compare final H in summary.json")
    add_log_level(p)
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    logging.basicConfig(level=getattr(logging, args.log_level),
                        format="%(asctime)s launcher %(levelname)s %(message)s", datefmt="%H:%M:%S")
    try:
        scenario = load_scenario(args.scenario, seed=args.seed, duration_s=args.duration)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    data_budget = budget(scenario)
    for warning in data_budget.warnings() if data_budget is not None else []:
        log.warning("%s", warning)
    if args.processes is not None and args.processes < 1:
        print(f"error: --processes takes a count of at least 1, not {args.processes}",
              file=sys.stderr)
        return 2
    zenoh_only = _zenoh_only(args)
    if args.transport == "inproc" and zenoh_only:
        print(f"error: {', '.join(zenoh_only)} apply only to --transport zenoh",
              file=sys.stderr)
        return 2
    if args.realtime is not None and not args.realtime > 0.0:
        print(f"error: --realtime takes a positive speed (times real time), not {args.realtime}",
              file=sys.stderr)
        return 2
    try:
        host_map = _host_map(args, scenario)
    except (HostMapError, RehearsalError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    taken = endpoint_taken(args.endpoint) if args.transport == "zenoh" and host_map is None \
        else None
    if taken:
        print(f"error: {taken}", file=sys.stderr)
        return 2
    known = set(topology(scenario).participants)
    if set(args.external) - known or (args.external and args.transport == "inproc"):
        print(f"error: --external takes nodes of a Zenoh run ({', '.join(sorted(known))}), not "
              f"{', '.join(args.external)}", file=sys.stderr)
        return 2
    try:
        out = prepare_out(args.out, REPO / "runs" / f"{scenario.name}-"
                          f"{time.strftime('%Y%m%d-%H%M%S')}", args.overwrite,
                          inputs=(args.scenario,))
    except OutFolderError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if host_map is not None and not args.rehearse:
        return _print_hosts(scenario, args.mission or scenario.name, out, args, host_map)
    try:
        if not args.skip_disk_check:
            check_space(out, scenario)
    except DiskSpaceError as e:
        print(f"error: {e.strerror}", file=sys.stderr)
        return 2
    with Reserve(out) as reserve:
        return _fly(scenario, out, args, host_map, reserve)


def _fly(scenario: Scenario, out: Path, args: argparse.Namespace, host_map: HostMap | None,
         reserve: Reserve) -> int:
    """Fly the run into ``out`` and write it (``reserve`` released first): its exit status."""
    mission = args.mission or scenario.name
    scenario_text = args.scenario.read_text(encoding="utf-8")
    if not kernels_cached():  # the first run after an install or an edit of a kernel
        compile_kernels(log.info)
    wall0 = time.monotonic()
    digest: RunDigest | None = None
    stop = threading.Event()
    # SIGINT or SIGTERM: the sim stops at the next tick (in process) or the children are
    # stopped (over Zenoh), and the archive and summary are written
    with Interrupts(lambda signum: _stopping(stop, signum)) as caught:
        if args.transport == "inproc":
            status, error, digest = _run_inproc(scenario, mission, out, scenario_text, args,
                                                stop)
        else:
            status, error = _run_zenoh(scenario, mission, out, args, stop, host_map)
        if status == "interrupted" and caught.signum is not None:
            error = f"interrupted by {signal.Signals(caught.signum).name}"
        reserve.release()
        summary, layout = _write_run(scenario, mission, out, args, time.monotonic() - wall0,
                                     (status, error), digest)
    print(_closing_line(summary, scenario, args)
          + "".join(f"\n  {p}" for p in written(out, layout, not args.no_report))
          + (f"\n{verdict(summary).line()}" if summary.t_sim_final_s else ""))
    if error:
        print(f"error: {_first_line(error)}" + (" (the whole error: summary.json)"
                                                   if "\n" in error.strip() else ""),
              file=sys.stderr)
    if summary.status == "interrupted":
        return caught.exit_status or 130
    return 0 if summary.status == "completed" else 1


def _write_run(scenario: Scenario, mission: str, out: Path, args: argparse.Namespace,
               wall_s: float, outcome: tuple[str, str | None], digest: RunDigest | None
               ) -> tuple[RunSummary, Path | None]:
    """The run's summary, layout, counterfactual and report, each written whatever the others
    do: a file that cannot be written is named in the log, in one line, and the run goes on
    to the next.  The summary and the layout's path (None: not written)."""
    from harness.foxglove_layout import write_layout  # the wrap-up's: not at start-up

    status, error = outcome
    digest = digest or _read_archive(out, scenario, mission)
    summary = write_summary(out, scenario, transport=args.transport, wall_s=wall_s,
                            status=status, error=error, mission=mission, digest=digest,
                            access=_access_audit(out))
    layout = _attempt("the Foxglove layout", lambda: write_layout(out, scenario, mission))
    if args.compare_recovery and status == "completed":
        summary = _compare_recovery(scenario, mission, out, args.scenario.read_text(
            encoding="utf-8"), args, summary)
    if not args.no_report:
        from harness.report import write_report  # matplotlib: only when a report is written

        _attempt("report.md", lambda: write_report(out, scenario, mission, digest=digest,
                                                   settings=_launch_settings(args)))
    return summary, layout


def _launch_settings(args: argparse.Namespace) -> dict[str, str]:
    """What the run was launched with beyond the scenario, for the report."""
    given = {"scenario file": str(args.scenario),
             "--seed": args.seed, "--duration": args.duration, "--realtime": args.realtime,
             "--hosts": args.hosts, "--hosting": None if args.transport == "inproc"
             else args.hosting}
    return {k: f"{v:g}" if isinstance(v, float) else str(v) for k, v in given.items()
            if v is not None}


def _attempt(what: str, write: Callable[[], T]) -> T | None:
    """``write()``, or None with one line in the log when the disk refuses it."""
    try:
        return write()
    except OSError as e:
        log.error("%s not written: %s", what, e.strerror or e)
        return None


def _first_line(text: str) -> str:
    """The first line of an error (the rest, log tails, stays in summary.json)."""
    return text.strip().splitlines()[0] if text.strip() else text


def _closing_line(summary: RunSummary, scenario: Scenario, args: argparse.Namespace) -> str:
    """The console's line on how the run went: status, how far, how fast."""
    rtf = summary.real_time_factor
    reached = ("" if summary.status == "completed"
               else f"{summary.t_sim_final_s or 0.0:.0f} of ")
    speed = ((f" ({rtf:.0f}x real time" + (f", at most {args.realtime:g}x" if args.realtime
                                            else "") + ")") if rtf else "")
    return (f"{summary.status}: {scenario.name} seed {scenario.seed}, {reached}"
            f"{scenario.duration_s:.0f} s simulated in {summary.wall_s or 0.0:.1f} s wall{speed}")


def _host_map(args: argparse.Namespace, scenario: Scenario) -> HostMap | None:
    """The run's host map (``--hosts``, with the link options applied), checked against the
    run; with ``--rehearse``, the privilege checked at once.  None on one host."""
    links = {"--rehearse": args.rehearse, "--link-delay-ms": args.link_delay_ms is not None,
             "--link-loss-pct": args.link_loss_pct is not None,
             "--link-event": bool(args.link_event)}
    if args.hosts is None:
        given = [name for name, on in links.items() if on]
        if given:
            raise ValueError(f"{', '.join(given)} apply only with --hosts")
        return None
    clash = [o for o, on in (("--transport inproc", args.transport == "inproc"),
                             ("--external", args.external), ("--advertise", args.advertise),
                             ("--tls-host", args.tls_host),
                             ("--restart-on-crash (not rehearsed across hosts)",
                              args.restart_on_crash),
                             ("--endpoint", args.endpoint != DEFAULT_ENDPOINT)) if on]
    if clash:
        raise ValueError(f"--hosts places every node and router itself; not with "
                         f"{', '.join(clash)}")
    if args.link_event and not args.rehearse:
        raise ValueError("--link-event applies only to a rehearsal (--rehearse)")
    events = [parse_link_event(e) for e in args.link_event]
    host_map = load_host_map(args.hosts).with_links(args.link_delay_ms, args.link_loss_pct)
    host_map = host_map.with_events(events)
    host_map.check_run(topology(scenario).participants, scenario.duration_s)
    check_cuts(host_map)
    if args.rehearse:
        require_privilege()
    return host_map


def _zenoh_only(args: argparse.Namespace) -> list[str]:
    """The options given that only a Zenoh run uses."""
    given = {"--endpoint": args.endpoint != DEFAULT_ENDPOINT, "--advertise": args.advertise,
             "--tls-host": args.tls_host, "--restart-on-crash": args.restart_on_crash,
             "--audit-access": args.audit_access, "--processes": args.processes is not None,
             "--hosting": args.hosting != "packed"}
    return [name for name, on in given.items() if on]


def _stopping(stop: threading.Event, signum: int) -> None:
    """The run's reaction to SIGINT or SIGTERM: ``stop`` is set, and the in-process sim stops
    at the next tick, the launcher's watch over its processes at its next look (a run whose
    sim had finished is complete)."""
    log.warning("signal %d: stopping; the archive and summary are written", signum)
    stop.set()


def _read_archive(out: Path, scenario: Scenario, mission: str) -> RunDigest | None:
    """The run's archive, read once for the summary and the report (None if it cannot be read:
    the summary then reports why)."""
    try:
        return digest_run(out / "run.mcap", scenario, mission)
    except (ArchiveError, OSError):
        return None


def _run_inproc(scenario: Scenario, mission: str, out: Path, scenario_text: str,
                args: argparse.Namespace, stop: threading.Event
                ) -> tuple[str, str | None, RunDigest | None]:
    """Run in this process, recording into ``<out>/run.mcap`` (the recorder in a child
    process) and digesting the run for its summary as it goes; ``stop`` set stops it at the
    next tick boundary (``interrupted``).  A recorder that dies (a full disk: "disk full at
    t = ... s") fails the run, whose summary is then read from the archive (no digest)."""
    from deploy.inproc import run_inproc

    if args.realtime:
        log.warning("--realtime is ignored with --transport inproc (lockstep only)")
    live = _live_view(args)
    metadata = run_metadata(scenario, "inproc", scenario_text)
    remove_segments(run_archive(out))  # an earlier run's in this directory: not this run's
    digest = LiveDigest(scenario, mission, out / "run.mcap", metadata)
    try:
        with RecorderProcess(out / "run.mcap", metadata) as rec:
            guard = RecorderGuard(digest.tap(rec), stop)

            def tap(sample: Sample) -> None:
                guard(sample)
                if live is not None:
                    live.forward(sample.key, sample.type_name, sample.payload)

            try:
                sim, _ = run_inproc(scenario, mission, sample_tap=tap, stop=stop)
            finally:
                if live is not None:
                    live.close()
    except RecorderDied as e:  # at the close: the archive's end was not written
        guard.error = guard.error or e
    if guard.cause is not None:  # the summary is read from what the archive holds
        log.error("%s", guard.cause)
        return "failed", guard.cause, None
    if not sim.completed:
        return "interrupted", INTERRUPTED, digest.finish()
    return "completed", None, digest.finish()


def _live_view(args: argparse.Namespace) -> LiveView | None:
    """The Foxglove live view when --live PORT is given (ground/tools/live.py), else None."""
    if not getattr(args, "live", None):
        return None
    from ground.tools.live import LiveView

    return LiveView(args.live)


def _compare_recovery(scenario: Scenario, mission: str, out: Path, scenario_text: str,
                      args: argparse.Namespace, summary: RunSummary) -> RunSummary:
    """Run the counterfactual (recovery flipped) in-process and add the comparison."""
    from harness.foxglove_layout import write_layout

    flipped = scenario.model_copy(update={"fdir": scenario.fdir.model_copy(
        update={"recovery": not scenario.fdir.recovery})})
    other = out / "counterfactual"
    other.mkdir(exist_ok=True)
    log.info("counterfactual run: recovery %s", "on" if flipped.fdir.recovery else "off")
    wall0 = time.monotonic()
    note = f"\n# counterfactual run: [fdir] recovery = {str(flipped.fdir.recovery).lower()}\n"
    digest: RunDigest | None = None
    try:
        status, error, digest = _run_inproc(flipped, mission, other, scenario_text + note, args,
                                            threading.Event())
    except Exception as e:  # noqa: BLE001 - the primary run's results must still be written
        log.exception("counterfactual run failed")
        status, error = "failed", f"{type(e).__name__}: {e}"
    counter = write_summary(other, flipped, transport="inproc", wall_s=time.monotonic() - wall0,
                            status=status, error=error, mission=mission, digest=digest)
    write_layout(other, flipped, mission)
    return add_recovery_comparison(out, summary, counter, scenario.fdir.recovery)


def _run_zenoh(scenario: Scenario, mission: str, out: Path, args: argparse.Namespace,
               stop: threading.Event, host_map: HostMap | None = None) -> tuple[str, str | None]:
    """Over Zenoh: on this host (one router), or rehearsing ``host_map`` (a router per
    host, each host in its network namespace, torn down at the end)."""
    if host_map is None:
        try:
            access = _write_access(out, mission, scenario, args)
        except ValueError as e:
            return "failed", str(e)
        return _run_placed(scenario, mission, out, args, stop, one_host(access))
    from deploy.host_access import write_host_access  # cryptography: only across hosts

    try:
        access_h = write_host_access(out / "access", mission, scenario.observers.count,
                                     host_map, processes=_hosted(scenario, args, host_map))
        with RehearsedNetwork(host_map.hosts, host_map.network, out / "logs",
                              seed=scenario.seed) as net:
            placement = across_hosts(access_h, host_map,
                                     {h.name: net.netns(h.name) for h in host_map.hosts})
            with LinkEvents(net, host_map) as events:
                status, error = _run_placed(scenario, mission, out, args, stop, placement,
                                            events)
            (out / "logs" / "link-events.json").write_text(events.report(), encoding="utf-8")
            if events.failures and status != "failed":  # not the run the map asked for
                return "failed", "; ".join([*events.failures, *([error] if error else [])])
            return status, error
    except (RehearsalError, OSError, subprocess.SubprocessError) as e:
        return "failed", f"the rehearsal failed: {type(e).__name__}: {e}"


def _run_placed(scenario: Scenario, mission: str, out: Path, args: argparse.Namespace,
                stop: threading.Event, placement: Placement,
                events: LinkEvents | None = None) -> tuple[str, str | None]:
    """Start the routers, join the run (the launcher's own session) and supervise it, with a
    rehearsal's link ``events``."""
    sup = Supervisor(REPO)
    try:
        routers = [sup.start(Child(r.name, [*ROUTER.command, "--config", str(r.config),
                                            *_audit_args(args, out, r.name)],
                                   out / "logs" / f"{r.name}.log", r.netns))
                   for r in placement.routers]
    except BaseException:
        sup.stop_all()  # the routers already started
        raise
    hub = _join(placement.watch_config, routers, timeout_s=30.0)
    if hub is None:
        sup.stop_all()
        dead = next((r for r in routers if r.returncode is not None), routers[0])
        place = next(p for p in placement.routers if p.name == dead.name)
        clash = "; is another run using it?" if address_taken(dead.log_tail()) else ""
        return "failed", (f"{dead.name} did not start on {place.endpoint} "
                          f"({dead.describe_exit()}{clash}):\n{dead.log_tail()}")
    progress = _Progress(scenario, events)
    live = None
    try:
        hub.session.declare_subscriber(cat.HEARTBEAT.key(mission, topics.GROUND),
                                       progress.on_heartbeat)
        hub.session.declare_subscriber(cat.SIM_STATUS.key(mission), progress.on_status)
        live = _live_view(args)
        if live is not None:
            hub.subscribe(topics.mission_wildcard(mission), live.forward)
        awaits = [x for a in (events.awaits() if events else []) for x in ("--await-link", a)]
        return _supervise(scenario, mission, out, args, progress, hub, sup, placement, stop,
                          awaits)
    finally:
        hub.close()
        if live is not None:
            live.close()
        for r in placement.routers:  # the ones running: a restart replaced the first
            sup.named(r.name).stop()


def _common_args(args: argparse.Namespace, mission: str, scenario: str) -> list[str]:
    """The options every node process of the run takes (``scenario``: its file)."""
    common = ["--scenario", scenario, "--mission", mission, "--log-level", args.log_level]
    if args.seed is not None:
        common += ["--seed", str(args.seed)]
    if args.duration is not None:
        common += ["--duration", str(args.duration)]
    return common


def _print_hosts(scenario: Scenario, mission: str, out: Path, args: argparse.Namespace,
                 host_map: HostMap) -> int:
    """``--hosts`` on real machines: write every host's access files and print, host by
    host, what to copy there and the commands to run (routers first, the ground host's
    before the others')."""
    from deploy.host_access import write_host_access  # cryptography: only across hosts

    access = write_host_access(out / "access", mission, scenario.observers.count, host_map,
                               portable=True, processes=_hosted(scenario, args, host_map))
    placement = across_hosts(access, host_map)
    common = _common_args(args, mission, args.scenario.name)
    topo = topology(scenario)
    processes = placement.processes(topo, args.hosting, 1)
    lines = [f"{scenario.name} across {len(host_map.hosts)} hosts ({args.hosts}); on each "
             f"host, from a checkout of this repository with {args.scenario.name} beside it:"]
    hub = host_map.hub
    for h in [hub, *(h for h in host_map.hosts if h.name != hub.name)]:
        folder = access.hosts[h.name].directory
        lines += ["", f"host {h.name} ({h.address}): copy {folder}/ to access/ (owner only), "
                      "then run, each in its own shell:",
                  "  python -m deploy.router --config access/router.json5"]
        mine = [p for p in processes if p.nodes[0].name in h.nodes]
        lines += [f"  python {' '.join(p.command)} {' '.join(common)} --zenoh-config "
                  + ("access/{node}.json5" if len(p.nodes) > 1 else f"access/{p.name}.json5")
                  for p in mine]
        for service, argv in ((SIM.name, SIM.command), (RECORDER.name, [
                *RECORDER.command, "--out", "run.mcap", "--transport-name", "zenoh"])):
            if service in h.nodes:
                lines.append(f"  python {' '.join(argv)} {' '.join(common)} --zenoh-config "
                             f"access/{service}.json5")
    lines += ["", f"watch it from any host of the network: python -m ground.tools.tlm "
                  f"--zenoh-config {access.tlm_config}"]
    print("\n".join(lines))
    return 0


def _write_access(out: Path, mission: str, scenario: Scenario,
                  args: argparse.Namespace) -> RunAccess:
    """The run's accounts, rules and (for a tls/ endpoint) certificates, in <out>/access/."""
    tls = None
    if args.endpoint.startswith("tls/"):
        from deploy.certificates import write_tls_files

        advertised = _host_of(args.advertise) if args.advertise else None
        tls = write_tls_files(out / "access" / "tls",
                              tuple(args.tls_host) + ((advertised,) if advertised else ()))
    return write_run_access(out / "access", mission, scenario.observers.count, args.endpoint,
                            tls, clients_connect=args.advertise,
                            processes=_hosted(scenario, args, None))


def _hosted(scenario: Scenario, args: argparse.Namespace,
            host_map: HostMap | None) -> list[list[str]]:
    """The node names each process of the run hosts (as ``_supervise`` starts them): the
    bundles their accounts may publish (``deploy.access.bundle_keys``)."""
    topo = topology(scenario)
    processes = (host_processes(host_map, topo, args.hosting) if host_map is not None else
                 hosting(topo, args.hosting, args.processes or host_cores(), args.external))
    return [[n.name for n in p.nodes] for p in processes]


def _host_of(endpoint: str) -> str:
    """``HOST`` of ``proto/HOST:PORT`` (an IPv6 address in brackets loses them)."""
    host = endpoint.split("/", 1)[-1].rsplit(":", 1)[0]
    return host.strip("[]")


def _join(config: Path, routers: list[Child], timeout_s: float) -> ZenohTransport | None:
    """The launcher's own session (read-only account, ``config``), once the hub's router
    accepts it; None if a router died or none came up."""
    deadline = time.monotonic() + timeout_s
    settings = ZenohSettings(config_file=str(config))
    while time.monotonic() < deadline and all(r.returncode is None for r in routers):
        try:
            return ZenohTransport(settings)
        except Exception:  # noqa: BLE001 - zenoh raises ZError while the router starts
            time.sleep(0.1)
    return None


def _audit_args(args: argparse.Namespace, out: Path, router: str) -> list[str]:
    """With --audit-access: the router's refusal counts go to ``logs/access.json`` (the run's
    one router) or ``logs/access-<router>.json`` (a router per host)."""
    if not args.audit_access:
        return []
    name = "access.json" if router == ROUTER.name else f"access-{router}.json"
    return ["--audit", str(out / "logs" / name)]


def _access_audit(out: Path) -> AccessAudit | None:
    """The routers' refusal counts, summed over the routers, if the run was audited (and they
    can be read)."""
    paths = sorted((out / "logs").glob("access*.json"))
    refused: Counter[str] = Counter()
    try:
        for path in paths:
            refused.update(AccessAudit.model_validate_json(path.read_bytes()).refused)
    except (OSError, ValueError):
        return None
    if not paths:
        return None
    return AccessAudit(refused=dict(refused), total=sum(refused.values()))


def _supervise(scenario: Scenario, mission: str, out: Path, args: argparse.Namespace,
               progress: _Progress, hub: ZenohTransport, sup: Supervisor,
               placement: Placement, stop: threading.Event,
               sim_extra: list[str] | None = None) -> tuple[str, str | None]:
    common = _common_args(args, mission, str(args.scenario.resolve()))

    def account(who: str | NodeProcess) -> list[str]:
        """The account options of a service, a node or a host (each of its nodes its own:
        ``{node}`` in the path)."""
        if isinstance(who, NodeProcess) and len(who.nodes) > 1:
            for n in who.nodes:
                placement.config(n.name)  # a clear error for a missing account
            folder = placement.config(who.nodes[0].name).parent
            return [*common, "--zenoh-config", str(folder / "{node}.json5")]
        name = who.name if isinstance(who, NodeProcess) else who
        return [*common, "--zenoh-config", str(placement.config(name))]

    logs = out / "logs"
    remove_segments(run_archive(out))  # else the recorder continues an earlier run's archive
    recorder_up = _Appearances(hub, topics.recorder_token(mission))
    recorder = sup.start(Child(RECORDER.name, [*RECORDER.command, *account(RECORDER.name),
                                               "--out", str(run_archive(out)),
                                               "--transport-name", "zenoh"],
                               logs / "recorder.log", placement.netns(RECORDER.name)))
    if not _wait_token(hub, topics.recorder_token(mission), recorder, timeout_s=RECORDER_READY_S):
        sup.stop_all(exclude={r.name for r in placement.routers})
        return "failed", (f"recorder did not start ({recorder.describe_exit()}):\n"
                          f"{recorder.log_tail()}")
    sim_argv = [*SIM.command, *account(SIM.name)] + (
        ["--realtime", str(args.realtime)] if args.realtime is not None else []) + (
        ["--hard-deadline"] if args.realtime is not None and args.hard_deadline else []) + (
        ["--hold-lost", str(RESTART_HOLD_S)] if args.restart_on_crash else []) + (
        sim_extra or [])
    sup.start(Child(SIM.name, sim_argv, logs / "sim.log", placement.netns(SIM.name)))
    topo = topology(scenario)
    cds = _store_args(out, args.restart_on_crash)
    processes = placement.processes(topo, args.hosting, args.processes or host_cores(),
                                    alone=args.external)
    for process in processes:
        if process.name in args.external:
            config = placement.config(process.name)
            there = [config.name if a == str(config) else a
                     for a in [*process.command, *account(process.name), *cds]]
            log.info("%s runs elsewhere: on its host, with this run's scenario and %s there, "
                     "run: python %s", process.name, config, " ".join(there))
        else:
            sup.start(Child(process.name, [*process.command, *account(process), *cds],
                            logs / f"{process.name}.log",
                            placement.netns(process.nodes[0].name)))
    watch = _Watch(sup, progress, flight={h.name: [n.name for n in h.nodes] for h in processes
                                          if h.name not in args.external},
                   restart=args.restart_on_crash, recorder_up=recorder_up.count,
                   sim_up=_Appearances(hub, topics.alive_token(mission, SIM.name)).count,
                   stop=stop, routers=tuple(r.name for r in placement.routers))
    error = watch.run()
    progress.report(final=True)
    watch.read_restores(out / "cds")
    # Stop the flight side first, then the recorder, so the archive holds everything sent.
    sup.stop_all(order=[SIM.name, *(h.name for h in processes)],
                 exclude={RECORDER.name, *(r.name for r in placement.routers)})
    time.sleep(0.2)
    recorder = sup.named(RECORDER.name)
    if recorder.returncode is None:
        recorder.stop(timeout_s=10.0)
        if recorder.returncode != 0 and error is None:
            error = f"recorder {recorder.describe_exit()}:\n{recorder.log_tail()}"
    if error == INTERRUPTED:
        return "interrupted", error
    if error:
        return "failed", error
    lost = progress.lost_participants()
    if watch.incidents or lost:
        return "degraded", "; ".join([*(str(i) for i in watch.incidents), *lost])
    return "completed", None


def _store_args(out: Path, restart: bool) -> list[str]:
    """With restarts supervised: the nodes' critical-data stores go to ``<out>/cds/`` under a
    key made for the run (``interfaces/runtime/cds.py``); a restarted node restores from its
    own."""
    if not restart:
        return []
    for old in [*(out / "cds").glob("*.cds"), *(out / "cds").glob("*.starts"),
                *(out / "cds").glob(".*.tmp")]:  # an earlier run's, in a reused folder
        old.unlink()
    write_run_key(out / "cds")
    return ["--cds", str(out / "cds")]


RESTART_WINDOW_S = 120.0
"""Wall time over which restarts of one process are counted against ``MAX_RESTARTS``."""
MAX_RESTARTS = 3
"""Restarts of one process (--restart-on-crash) within ``RESTART_WINDOW_S`` after which its next
death is a crash loop: a flight or ground process is left down, the router's or recorder's
stops the run.  Deaths further apart are restarted every time (a long soak kills each process
many times)."""
RECORDER_READY_S = 30.0
"""How long the recorder, started, has to announce it records (its liveliness token), wall s."""
SERVICE_READY_S = 30.0
"""How long a restarted router or recorder has to be back, wall s: the recorder announcing it
records, the router carrying the sim's token to the launcher again."""
RESTART_HOLD_S = 60.0
"""With --restart-on-crash: how long the sim holds the clock for a lost participant to come
back (its restart: a process start, the compiled kernels from their cache, the bus), wall s."""


class _Watch:
    """The launcher's watch over a running constellation.  The sim stopping early ends the
    run at once (no time without it), naming it and the sim time it stopped at; so do the
    router (no bus) and the recorder (no record) unless ``restart``.  A flight or ground
    process stopping early is an incident: the sim flies on with its last commands, the ground
    declares the silent spacecraft a link fault, and with ``restart`` the process is started
    again (unless it was restarted ``MAX_RESTARTS`` times within ``RESTART_WINDOW_S``: a
    crash loop), restored from its critical-data store, while the sim
    holds the clock.

    With ``restart`` the router's and the recorder's deaths are incidents too: each is started
    again with the same command (the router on the same endpoint with the same accounts, and
    the clients reconnect, the sim holding the clock; the recorder continues the archive in the
    next segment, ``run-1.mcap``, ...).  The run stops, naming it, only when one cannot come
    back: in a crash loop (as above), dead once the sim has finished, or not
    back ``SERVICE_READY_S`` after a restart (the count of appearances of its token,
    ``recorder_up``, or of the sim's through it, ``sim_up``, not grown)."""

    def __init__(self, sup: Supervisor, progress: _Progress, flight: dict[str, list[str]],
                 restart: bool, recorder_up: Callable[[], int] = lambda: 0,
                 sim_up: Callable[[], int] = lambda: 0,
                 stop: threading.Event | None = None,
                 routers: tuple[str, ...] = (ROUTER.name,)) -> None:
        self.sup, self.progress, self.flight, self.restart = sup, progress, flight, restart
        """``flight``: the flight and ground processes, each with the nodes it hosts"""
        self.recorder_up, self.sim_up = recorder_up, sim_up
        self.stop = stop or threading.Event()
        """set by SIGINT or SIGTERM: the watch ends at its next look"""
        self.routers = routers
        """the run's routers' processes (``router``, or ``router-<host>`` across hosts)"""
        self.incidents: list[Incident] = []
        self.restarts: dict[str, int] = {}
        """Restarts so far, per process."""
        self._restarted_at: dict[str, list[float]] = {}
        """Per process, the wall times (monotonic s) of its restarts in the last window."""
        self.down: set[str] = set()
        self._back: dict[str, tuple[int, float]] = {}
        """Per service restarted and not yet back: the count of its appearances before the
        restart, and the wall time (monotonic s) by which it must have grown."""

    def run(self) -> str | None:
        """Watch until every process has finished, or ``stop`` is set; the error that ended
        the run, or None (a run whose sim had finished when stopped is complete)."""
        done_since: float | None = None
        while True:
            sim_done = (self.progress.finished.is_set()
                        or self.sup.named(SIM.name).returncode == 0)
            if self.stop.is_set():
                return None if sim_done else INTERRUPTED
            error = self._essential_stopped() or self._services_stopped(sim_done)
            if error is not None:
                return error
            self._flight_stopped(sim_done)
            running = [n for n in self.flight
                       if n not in self.down and self.sup.named(n).returncode is None]
            if sim_done and not running:
                return None
            if sim_done:
                done_since = done_since or time.monotonic()
                if time.monotonic() - done_since > 15.0:
                    return ("processes still running 15 s after the run finished: "
                            + ", ".join(running))
            self.stop.wait(0.1)
            self.progress.report()

    def read_restores(self, directory: Path) -> None:
        """Name in each restart's incident how the process came back (restored from its
        critical-data store, or cold and why), from the nodes' starts records."""
        seen: dict[str, int] = {}
        for incident in self.incidents:
            if not incident.restarted:
                continue
            n = seen[incident.node] = seen.get(incident.node, 0) + 1
            starts = read_starts(directory / f"{incident.node}.starts")
            if n < len(starts):
                incident.came_back = starts[n].describe()

    def _essential_stopped(self) -> str | None:
        sim = self.sup.named(SIM.name)
        essential = [(sim, "no time without it; stopping the constellation")]
        if not self.restart:
            essential += [(c, consequence) for c, _, consequence in self._services()]
        for child, consequence in essential:
            if child.returncode is not None and (child is not sim or child.returncode != 0):
                return self._stopped(child, consequence)
        return None

    def _services(self) -> list[tuple[Child, Callable[[], int], str]]:
        """The services a run cannot go on without, each with the count of appearances that
        says it is back after a restart, and what follows its loss: the router (back when the
        sim's token reappears, seen through it) and the recorder (its own token)."""
        routers = [c for c in (self.sup.find(n) for n in self.routers) if c is not None]
        return [*((r, self.sim_up, _NO_BUS) for r in routers),
                (self.sup.named(RECORDER.name), self.recorder_up, _NO_RECORD)]

    def _stopped(self, child: Child, consequence: str) -> str:
        """The error naming ``child``, how it stopped, when, and what follows; first, when its
        log says so, that the disk is full."""
        tail = child.log_tail()
        full = (f"disk full at t ≈ {self.progress.t_sim:.1f} s: " if disk_full_logged(tail)
                else "")
        return (f"{full}{child.name} (pid {child.proc.pid if child.proc else '?'}) "
                f"{child.describe_exit()} at sim t≈{self.progress.t_sim:.1f} s: "
                f"{consequence}.\n--- last lines of {child.log_path}:\n{tail}")

    def _services_stopped(self, sim_done: bool) -> str | None:
        """With ``restart``: start a dead router or recorder again, or the error if it cannot
        come back (see the class docstring)."""
        if not self.restart:
            return None
        for child, up, consequence in self._services():
            error = (self._service_silent(child, up, consequence) if child.returncode is None
                     else self._service_restart(child, up, consequence, sim_done))
            if error is not None:
                return error
        return None

    def _service_restart(self, child: Child, up: Callable[[], int], consequence: str,
                         sim_done: bool) -> str | None:
        n = self.restarts.get(child.name, 0)
        if sim_done or self._looping(child.name) or disk_full_logged(child.log_tail()):
            return self._stopped(child, consequence + (f" (restarted {n} times)" if n else ""))
        incident = Incident(child.name, child.describe_exit(), self.progress.t_sim, True)
        self.incidents.append(incident)
        log.error("%s; starting it again (%s)", incident,
                  _AGAIN[ROUTER.name if child.name in self.routers else child.name])
        self._back[child.name] = (up(), time.monotonic() + SERVICE_READY_S)
        self._restart(child)
        return None

    def _looping(self, name: str) -> bool:
        """Whether ``name`` was restarted ``MAX_RESTARTS`` times in the last
        ``RESTART_WINDOW_S``: a crash loop, not to be fed."""
        now = time.monotonic()
        recent = [t for t in self._restarted_at.get(name, []) if now - t < RESTART_WINDOW_S]
        self._restarted_at[name] = recent
        return len(recent) >= MAX_RESTARTS

    def _restart(self, child: Child) -> None:
        n = self.restarts[child.name] = self.restarts.get(child.name, 0) + 1
        self._restarted_at.setdefault(child.name, []).append(time.monotonic())
        self.sup.restart(child, n)

    def _service_silent(self, child: Child, up: Callable[[], int],
                        consequence: str) -> str | None:
        """The error if a restarted service, running, is not back in time."""
        back = self._back.get(child.name)
        if back is None:
            return None
        seen, deadline = back
        if up() > seen:
            log.info("%s restarted and back (pid %s)", child.name,
                     child.proc.pid if child.proc else "?")
            del self._back[child.name]
        elif time.monotonic() > deadline:
            return self._stopped(child, f"restarted, it was not back within "
                                        f"{SERVICE_READY_S:.0f} s; {consequence}")
        return None

    def _flight_stopped(self, sim_done: bool) -> None:
        """A flight or ground process stopped early: each node it hosted is an incident (see
        the class docstring)."""
        for name, nodes in self.flight.items():
            child = self.sup.named(name)
            if name in self.down or child.returncode is None:
                continue
            if sim_done and child.returncode == 0:
                continue
            again = self.restart and not sim_done and not self._looping(name)
            for node in nodes:
                incident = Incident(node, child.describe_exit(), self.progress.t_sim, again)
                self.incidents.append(incident)
                log.error("%s; %s", incident, "starting it again" if again else
                          "the constellation flies on without it")
            if again:
                self._restart(child)
            else:
                self.down.add(name)


_NO_RECORD = "nothing after it is recorded; stopping the run"
"""What follows the recorder's death when it is not (or cannot be) started again."""
_NO_BUS = ("the bus is down: no process reaches another, and nothing after it is recorded; "
           "stopping the run")
"""What follows the router's death when it is not (or cannot be) started again."""
_AGAIN = {RECORDER.name: "the archive continues in its next segment",
          ROUTER.name: "same endpoint and accounts; the clients reconnect, the sim holds the "
                       "clock meanwhile"}


class _Appearances:
    """Counts the appearances of a liveliness token on the run's bus (the recorder's, seen
    from the launcher's session): a restarted recorder is back when the count grows."""

    def __init__(self, hub: ZenohTransport, token: str) -> None:
        self._count = 0
        self._lock = threading.Lock()
        self._subscriber = hub.session.liveliness().declare_subscriber(token, self._on_sample)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        if sample.kind == zenoh.SampleKind.PUT:
            with self._lock:
                self._count += 1

    def count(self) -> int:
        """Appearances so far."""
        with self._lock:
            return self._count


def _wait_token(hub: ZenohTransport, token: str, child: Child, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if child.returncode is not None:
            return False
        if any(r.ok is not None for r in hub.session.liveliness().get(token, timeout=0.5)):
            return True
        time.sleep(0.1)
    return False


class _Progress:
    """Progress of the run (one line every few seconds)."""

    def __init__(self, scenario: Scenario, events: LinkEvents | None = None) -> None:
        self.events = events
        """a rehearsal's link events: told the time of each heartbeat, and the sim's waits"""
        self.n_ticks = scenario.n_ticks
        self.duration = scenario.duration_s
        self.t_sim = 0.0
        self.k = 0
        self.finished = threading.Event()
        self.final: SimStatus | None = None
        self._wall0 = time.monotonic()
        self._last = 0.0

    def on_heartbeat(self, sample: object) -> None:
        """Progress from the ground's heartbeat (ω_mid), not from every tick: no per-tick work."""
        try:
            hb = Heartbeat.model_validate_json(sample.payload.to_bytes())  # type: ignore[attr-defined]
        except Exception:  # noqa: BLE001 - progress display only
            return
        self.k, self.t_sim = hb.k, hb.t_sim
        if self.events is not None:
            self.events.on_time(hb.t_sim)

    def on_status(self, sample: object) -> None:
        try:
            status = SimStatus.model_validate_json(sample.payload.to_bytes())  # type: ignore[attr-defined]
        except Exception:  # noqa: BLE001
            return
        if (status.state == "waiting" and status.reason.startswith("link ")
                and self.events is not None):
            self.events.on_waiting(status.reason, status.t_sim)
        if status.state in ("finished", "aborted"):
            self.final = status
            self.finished.set()

    def lost_participants(self) -> list[str]:
        """What the sim's final status says of participants lost from the lockstep."""
        if self.final is None:
            return []
        return [f"{node} " + ", ".join(f"{e.what} at t≈{e.t_sim:.1f} s" for e in events)
                for node, events in sorted(self.final.participants.items())]

    def report(self, final: bool = False) -> None:
        now = time.monotonic()
        if not final and now - self._last < 5.0:
            return
        self._last = now
        log.info("%s", progress_line(self.t_sim, self.duration, now - self._wall0))


if __name__ == "__main__":
    raise SystemExit(main())
