"""The project's speed figures in one run, each beside its target (issue 13, docs/targets.md).

    python benchmarks/run.py [--quick] [--only NAME ...] [--json FILE]

Measures, with the real commands a user runs (``deploy/run_constellation.py``,
``deploy/run_campaign.py``) in child processes:

* ``lockstep``: the raw lockstep limit over Zenoh (a ticker and 6 idle node processes);
* ``reference``: the reference mission (default scenario, two orbits = 11,354 s, FDIR and
  baselines on, full archive) in-process and over Zenoh: real-time factor, wall time, the time
  to write summary and report, peak memory of the whole process tree (proportional set size:
  a page shared by several processes counted once, split among them; the summed resident size,
  which counts every shared library once per process, beside it), archive MB per simulated
  hour;
* ``scaling``: the nominal set-up (FDIR on) with 5/10/20 observers × 5,000/50,000 POIs,
  in-process: real-time factor, and the wall time per simulated second per observer (the cost
  per observer, which should stay flat from 5 to 20 observers);
* ``twenty``: the 20-observer reference, the nominal set-up with 20 observers and 50,000 POIs
  for longer than the scaling grid (in-process; over Zenoh too without ``--quick``), with its
  peak memory and archive;
* ``passes``: ``deploy/scenarios/passes.toml`` (ground passes, the neighbours' FDIR aboard)
  in-process, with the neighbours' FDIR on and off: real-time factors and their ratio, the
  neighbours' cost;
* ``campaign``: wall time per run of ``deploy/campaigns/paper.toml`` with ``--workers 2``;
* ``budget``: the per-tick and per-call budgets in one process (``benchmarks/tick_budget.py``:
  the bare lockstep, the default mission's 10 Hz-only tick and what a 1 Hz and a 0.1 Hz tick
  add, the slower work per call);
* ``startup``: what a run costs beside its ticks (imports, kernel cache loads, the recorder's
  spawn, summary): the wall time of the default scenario for 1 simulated second in one process,
  without its report, the median of 3 runs.

``--quick`` shortens every workload (reference 1,200 s, scaling 60 s, the 20-observer
reference 300 s, passes 1,200 s, 4 campaign runs) so the whole set runs in a few minutes; its
ratios are indicative (start-up weighs more in short runs).  Real-time factors are simulated
seconds over the wall time of the whole command, start-up included.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import psutil

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from benchmarks.lockstep_limit import free_port  # noqa: E402
from benchmarks.lockstep_limit import measure as lockstep_rate  # noqa: E402
from benchmarks.tick_budget import CALLS  # noqa: E402
from benchmarks.tick_budget import TARGETS_MS as TICK_TARGETS_MS  # noqa: E402
from harness.summary import RunSummary  # noqa: E402
from interfaces.contracts.scenario import load_scenario  # noqa: E402

TWO_ORBITS_S = 11354.0
TARGETS = {
    "rtf_inproc": 100.0, "rtf_inproc_stretch": 150.0, "rtf_zenoh": 35.0,
    "report_s": 30.0, "archive_mb_per_h": 80.0, "peak_memory_gb": 1.5,
    "campaign_s_per_run": 3.5, "rtf_scaling": 25.0, "startup_s": 1.5,
}
"""The targets of docs/targets.md (issue 61's speed rows): in one process ≥ 100× real time
(150× the stretch); over Zenoh on this host ≥ 35× (the share of the bare lockstep limit measured
in the same run printed beside it); the paper campaign ≤ 3.5 s a run; 20 observers × 50,000 POIs
≥ 25×; a run's start-up and wrap-up ≤ 1.5 s; the archive ≤ 80 MB per simulated hour; peak
memory ≤ 1.5 GB."""


@dataclass
class Measured:
    wall_s: float
    peak_rss_mb: float
    peak_pss_mb: float
    summary: RunSummary


def run_tree(cmd: list[str], poll_s: float = 0.25) -> tuple[float, float, float]:
    """Run ``cmd``; return (wall s, peak summed RSS and peak summed PSS of its process tree,
    MB).  PSS (proportional set size) splits a shared page among the processes mapping it, so
    the tree's sum counts it once; RSS counts it in every process."""
    start = time.perf_counter()
    proc = psutil.Popen(cmd, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    peak_rss = peak_pss = 0
    while proc.poll() is None:
        try:
            sizes = [_sizes(p) for p in (proc, *proc.children(recursive=True))]
            peak_rss = max(peak_rss, sum(r for r, _ in sizes))
            peak_pss = max(peak_pss, sum(p for _, p in sizes))
        except psutil.NoSuchProcess:
            pass
        time.sleep(poll_s)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
        raise RuntimeError(f"{' '.join(cmd)} exited {proc.returncode}:\n{err[-2000:]}")
    return wall, peak_rss / 1e6, peak_pss / 1e6


def _sizes(p: psutil.Process) -> tuple[int, int]:
    """(RSS, PSS) of one process, bytes (0, 0 once it is gone)."""
    try:
        m = p.memory_full_info()
        return m.rss, m.pss
    except psutil.AccessDenied:  # no access to its page map: count its resident size whole
        try:
            rss = p.memory_info().rss
            return rss, rss
        except psutil.Error:
            return 0, 0
    except psutil.NoSuchProcess:
        return 0, 0


def constellation(scenario: Path, out: Path, transport: str, duration: float,
                  report: bool = False) -> Measured:
    cmd = [sys.executable, "deploy/run_constellation.py", "--scenario", str(scenario),
           "--out", str(out), "--transport", transport, "--duration", str(duration)]
    if transport == "zenoh":  # an in-process run refuses Zenoh-only options
        cmd += ["--endpoint", f"tcp/127.0.0.1:{free_port()}"]
    if not report:
        cmd.append("--no-report")
    wall, rss, pss = run_tree(cmd)
    return Measured(wall, rss, pss, RunSummary.read(out / "summary.json"))


def variant_scenario(tmp: Path, name: str, base: str = "nominal.toml",
                     **sections: dict) -> Path:
    """``deploy/scenarios/<base>`` named ``name`` with each given section's keys replaced
    (``observers={"count": 20}``), as resolved JSON in ``tmp``."""
    scenario = load_scenario(REPO / "deploy" / "scenarios" / base)
    data = scenario.model_dump()
    for section, keys in sections.items():
        data[section].update(keys)
    data["name"] = name
    path = tmp / f"{name}.json"
    path.write_text(type(scenario).model_validate(data).model_dump_json())
    return path


def scaled_scenario(tmp: Path, observers: int, pois: int) -> Path:
    """The nominal set-up with ``observers`` observers and ``pois`` POIs, as resolved JSON."""
    return variant_scenario(tmp, f"scale-{observers}x{pois}", observers={"count": observers},
                            target={"pois": pois})


def ratio(value: float, target: float, higher_is_better: bool = True) -> str:
    r = value / target if higher_is_better else target / max(value, 1e-9)
    return f"{r:5.2f} of target {'✓' if r >= 1.0 else '✗'}"


def bench_lockstep(quick: bool, rows: list[tuple[str, str, str]], res: dict) -> None:
    rate = lockstep_rate(6, 1000 if quick else 5000)
    res["lockstep_ticks_per_s"] = rate
    rtf = rate * 0.1
    rows.append(("lockstep limit over Zenoh, 6 idle nodes",
                 f"{rate:.0f} ticks/s ({rtf:.0f}x real time at 10 Hz)", ""))


def _rtf_ratio(transport: str, rtf: float, res: dict) -> str:
    """The reference mission's real-time factor against its target: ≥ 100× in one process
    (150× the stretch), ≥ 35× over Zenoh, with its share of the lockstep limit measured in this
    run beside it (only when the ``lockstep`` benchmark ran first)."""
    if transport == "inproc":
        stretch = rtf / TARGETS["rtf_inproc_stretch"]
        return f"{ratio(rtf, TARGETS['rtf_inproc'])} (stretch {stretch:.2f})"
    limit = res.get("lockstep_ticks_per_s")
    share = "" if limit is None else f" ({rtf / (0.1 * limit):.1%} of the lockstep limit)"
    return ratio(rtf, TARGETS["rtf_zenoh"]) + share  # the mission ticks at 10 Hz


def bench_reference(quick: bool, tmp: Path, rows: list, res: dict) -> None:
    duration = 1200.0 if quick else TWO_ORBITS_S
    scenario = REPO / "deploy" / "scenarios" / "default.toml"
    for transport in ("inproc", "zenoh"):
        out = tmp / f"ref-{transport}"
        m = constellation(scenario, out, transport, duration)
        rtf = duration / m.wall_s
        res[f"reference_{transport}"] = {"wall_s": m.wall_s, "rtf": rtf,
                                         "peak_rss_mb": m.peak_rss_mb,
                                         "peak_pss_mb": m.peak_pss_mb,
                                         "run_wall_s": m.summary.wall_s}
        rows.append((f"reference mission {duration:.0f} s, {transport}",
                     f"{rtf:.0f}x real time ({m.wall_s:.1f} s wall)", _rtf_ratio(transport, rtf,
                                                                         res)))
        rows.append((f"  peak memory, whole tree ({transport}), PSS", f"{m.peak_pss_mb:.0f} MB",
                     ratio(m.peak_pss_mb / 1e3, TARGETS["peak_memory_gb"], False)))
        rows.append(("  (summed RSS: shared pages once per process)", f"{m.peak_rss_mb:.0f} MB",
                     ""))
        if transport == "inproc":
            mb_h = (out / "run.mcap").stat().st_size / 1e6 / (duration / 3600.0)
            res["archive_mb_per_h"] = mb_h
            rows.append(("  archive", f"{mb_h:.0f} MB per simulated hour",
                         ratio(mb_h, TARGETS["archive_mb_per_h"], False)))
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-c", _REPORT_AGAIN, str(out), str(scenario),
                            str(duration)], cwd=REPO, check=True, capture_output=True)
            report_s = time.perf_counter() - t0
            res["summary_and_report_s"] = report_s
            target = TARGETS["report_s"] * duration / TWO_ORBITS_S  # the target is for two orbits
            rows.append(("  summary + report from the archive",
                         f"{report_s:.1f} s (target {target:.1f} s for {duration:.0f} s)",
                         ratio(report_s, target, False)))


_REPORT_AGAIN = """
import sys
from pathlib import Path
from harness.summary.digest import digest_run
from harness.report import write_report
from harness.summary.build import write_summary
from interfaces.contracts.scenario import load_scenario
out, scen, dur = Path(sys.argv[1]), load_scenario(sys.argv[2]), float(sys.argv[3])
scen = scen.with_overrides(None, dur)
digest = digest_run(out / "run.mcap", scen, scen.name)
write_summary(out, scen, transport="inproc", wall_s=1.0, status="completed", error=None,
              mission=scen.name, digest=digest)
write_report(out, scen, scen.name, digest=digest)
"""


def bench_scaling(quick: bool, tmp: Path, rows: list, res: dict) -> None:
    duration = 60.0 if quick else 300.0
    grid, per_observer = {}, {}
    for observers in (5, 10, 20):
        for pois in (5000, 50000):
            path = scaled_scenario(tmp, observers, pois)
            m = constellation(path, tmp / path.stem, "inproc", duration)
            rtf = duration / m.wall_s
            grid[f"{observers}x{pois}"] = rtf
            cost = per_observer[f"{observers}x{pois}"] = 1e3 * m.wall_s / duration / observers
            target = TARGETS["rtf_scaling"] if (observers, pois) == (20, 50000) else None
            rows.append((f"scaling {observers} observers x {pois} POIs, inproc, {duration:.0f} s",
                         f"{rtf:.1f}x real time, {cost:.1f} ms per sim-s per observer",
                         ratio(rtf, target) if target else ""))
    for pois in (5000, 50000):
        growth = per_observer[f"20x{pois}"] / per_observer[f"5x{pois}"]
        rows.append((f"  cost per observer, 20 against 5 observers, {pois} POIs",
                     f"{growth:.2f}x", "flat: 1.00x"))
    res["scaling_rtf"], res["scaling_ms_per_observer"] = grid, per_observer


def bench_twenty(quick: bool, tmp: Path, rows: list, res: dict) -> None:
    """The 20-observer reference (module docstring)."""
    duration = 300.0 if quick else 1200.0
    path = variant_scenario(tmp, "twenty", observers={"count": 20}, target={"pois": 50000})
    for transport in ("inproc",) if quick else ("inproc", "zenoh"):
        out = tmp / f"twenty-{transport}"
        m = constellation(path, out, transport, duration)
        rtf = duration / m.wall_s
        mb_h = (out / "run.mcap").stat().st_size / 1e6 / (duration / 3600.0)
        res[f"twenty_{transport}"] = {"wall_s": m.wall_s, "rtf": rtf, "archive_mb_per_h": mb_h,
                                      "peak_pss_mb": m.peak_pss_mb}
        rows.append((f"20 observers x 50000 POIs, {duration:.0f} s, {transport}",
                     f"{rtf:.1f}x real time, {m.peak_pss_mb:.0f} MB PSS, {mb_h:.0f} MB/h",
                     ratio(rtf, TARGETS["rtf_scaling"])))


def bench_passes(quick: bool, tmp: Path, rows: list, res: dict) -> None:
    """passes.toml with the neighbours' FDIR on and off (module docstring)."""
    duration = 1200.0 if quick else 6400.0
    rtf = {}
    for on in (True, False):
        name = f"passes-neighbours-{'on' if on else 'off'}"
        path = variant_scenario(tmp, name, "passes.toml", neighbours={"enabled": on})
        m = constellation(path, tmp / name, "inproc", duration)
        rtf[on] = duration / m.wall_s
        rows.append((f"passes.toml {duration:.0f} s, inproc, neighbours' FDIR "
                     f"{'on' if on else 'off'}", f"{rtf[on]:.0f}x real time ({m.wall_s:.1f} s)",
                     ""))
    res["passes_rtf"] = {"on": rtf[True], "off": rtf[False]}
    rows.append(("  the neighbours' FDIR costs", f"{rtf[False] / rtf[True]:.2f}x the run time",
                 ""))


def bench_campaign(quick: bool, tmp: Path, rows: list, res: dict) -> None:
    n = 4 if quick else 10
    out = tmp / "campaign"
    wall, *_ = run_tree([sys.executable, "deploy/run_campaign.py", "--campaign",
                         "deploy/campaigns/paper.toml", "--out", str(out), "--workers", "2",
                         "--limit", str(n)])
    per_run = wall / n
    res["campaign_s_per_run"] = per_run
    rows.append((f"paper campaign, first {n} runs, --workers 2",
                 f"{per_run:.1f} s per run ({per_run * 200 / 60:.0f} min for 200)",
                 ratio(per_run, TARGETS["campaign_s_per_run"], False)))


def bench_budget(quick: bool, tmp: Path, rows: list, res: dict) -> None:
    out = tmp / "budget.json"
    run_tree([sys.executable, "benchmarks/tick_budget.py", "--duration",
              "300" if quick else "1200", "--out", str(tmp / "budget"), "--json", str(out)])
    budget = res["budget"] = json.loads(out.read_text())
    rows.append(("bare lockstep in one process, 6 nodes", f"{budget['bare_ms']:.3f} ms per tick",
                 ratio(budget["bare_ms"], TICK_TARGETS_MS["bare"], False)))
    for key, what in (("high", "10 Hz-only tick"), ("mid", "a 1 Hz tick adds"),
                      ("low", "a 0.1 Hz tick adds")):
        ms = budget["by_rate_ms"][key]["mean"]
        rows.append((f"  default mission: {what}", f"{ms:.3f} ms (mean)",
                     ratio(ms, TICK_TARGETS_MS[key], False)))
    for _, name, what, target in CALLS:
        ms = budget["per_call_ms"][name]["mean"]
        rows.append((f"  per call: {what}", f"{ms:.3f} ms (mean)", ratio(ms, target, False)))


def bench_startup(quick: bool, tmp: Path, rows: list, res: dict) -> None:
    """A run's cost beside its ticks (module docstring): 1 simulated second of the default
    scenario in one process, no report, the median wall of 3 runs after one to warm the disk
    cache."""
    cmd = [sys.executable, "deploy/run_constellation.py", "--transport", "inproc",
           "--duration", "1", "--out", str(tmp / "startup"), "--overwrite", "--no-report"]
    walls = [_timed(cmd) for _ in range(4)][1:]
    wall = sorted(walls)[1]
    res["startup_s"] = wall
    rows.append(("start-up and wrap-up of a run (1 s simulated, no report, median of 3)",
                 f"{wall:.2f} s ({min(walls):.2f}-{max(walls):.2f})",
                 ratio(wall, TARGETS["startup_s"], False)))


def _timed(cmd: list[str]) -> float:
    """Wall time of ``cmd`` run from the repository, s (not polled: a memory poll costs CPU
    that a second-long run would feel)."""
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=REPO, check=True, capture_output=True)
    return time.perf_counter() - t0


BENCHES = {"lockstep": bench_lockstep, "reference": bench_reference, "scaling": bench_scaling,
           "twenty": bench_twenty, "passes": bench_passes, "campaign": bench_campaign,
           "budget": bench_budget, "startup": bench_startup}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="short workloads (a few minutes)")
    p.add_argument("--only", nargs="+", choices=list(BENCHES), help="run only these")
    p.add_argument("--json", type=Path, help="also write the figures as JSON here")
    p.add_argument("--keep", type=Path, help="keep the runs in this directory")
    args = p.parse_args()
    rows: list[tuple[str, str, str]] = []
    res: dict = {"quick": args.quick}
    tmp = args.keep or Path(tempfile.mkdtemp(prefix="insp-bench-"))
    tmp.mkdir(parents=True, exist_ok=True)
    try:
        for name in args.only or list(BENCHES):
            t0 = time.perf_counter()
            kwargs = {} if name == "lockstep" else {"tmp": tmp}
            BENCHES[name](args.quick, rows=rows, res=res, **kwargs)
            print(f"[{name} done in {time.perf_counter() - t0:.0f} s]", file=sys.stderr, flush=True)
    finally:
        if args.keep is None:
            shutil.rmtree(tmp, ignore_errors=True)
    width = max(len(r[0]) for r in rows)
    print(f"\n{'workload':<{width}}  {'measured':<44} ratio to target")
    for what, value, r in rows:
        print(f"{what:<{width}}  {value:<44} {r}")
    if args.json:
        args.json.write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
