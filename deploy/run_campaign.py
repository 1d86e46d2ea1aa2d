"""Run a fault campaign: many scenarios (seeds, fault kinds, spacecraft, onsets, magnitudes)
from one campaign file, on a local process pool or a Dask cluster, resumable.

    python deploy/run_campaign.py --campaign deploy/campaigns/paper.toml --out runs/paper
        [--workers N] [--limit N] [--cluster tcp://HOST:PORT] [--transport inproc|zenoh]
        [--set SECTION.KEY=VALUE ...] [--report-only]
    python deploy/run_campaign.py --out runs/paper --replay [--set fdir.KEY=VALUE ...]
        [--out-report DIR] [--workers N] [--cluster ...]
    python deploy/run_campaign.py --out runs/paper --sweep fdir.KEY=V1,V2,... [--set ...]

Each run goes in-process (deploy/inproc.py; --transport zenoh: multi-process, each run on its
own loopback port and key space) into <out>/runs/<id>/ (run.mcap, summary.json,
run.log, and drawn.json when the campaign draws the set-up); a run directory appears only
when its run has finished (each attempt writes its own <id>.partial-<random>, then renames
it), so a campaign started again with the same --out skips finished runs and redoes
half-written ones.  A run that crashes is recorded as failed, with its error, and the campaign
goes on.  ``--set`` changes a scenario setting of every run flown (e.g.
``onboard_fdir.enabled=true``: the same campaign with the onboard FDIR on; use another --out;
a setting the campaign draws per run is refused).
SIGINT or SIGTERM stops the campaign: running runs are abandoned (redone next time)
and the report is written over what has finished.  --cluster sends the runs to an existing
Dask distributed scheduler (its workers must import this repository and see --out).
At the end <out>/report.md, PNG plots and results.csv are written
(harness/campaign/report.py);
--report-only rewrites them from the run directories without running anything (given only
--out, from the run list saved there).  --replay re-judges the finished runs under other
detector settings without simulating (deploy/campaign_replay.py) and writes the full report in
--out-report; --sweep does it once per value of one setting and writes one table, sweep.md.
The exit status is 1 when a run failed, 130 when interrupted, 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import fcntl
import hashlib
import json
import logging
import math
import os
import shutil
import signal
import sys
import time
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, CancelledError, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import replace
from multiprocessing import get_context
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:  # run as a script from a checkout
    sys.path.insert(0, str(REPO))

from deploy.campaign import (  # noqa: E402
    CampaignError,
    RunSpec,
    execute_run,
    finished,
    load_campaign,
    record_failure,
    record_retry,
)
from deploy.campaign_file import Campaign  # noqa: E402
from deploy.campaign_replay import print_progress, rejudge, sweep  # noqa: E402
from deploy.cluster import CONNECT_TIMEOUT_S, ClusterError, dask_client  # noqa: E402
from deploy.disk_space import (  # noqa: E402
    RESERVE_BYTES,
    DiskSpaceError,
    Reserve,
    check_space,
    estimate_archive_bytes,
    free_bytes,
    megabytes,
)
from deploy.out_folder import OutFolderError  # noqa: E402
from deploy.recorder_guard import disk_full_cause  # noqa: E402
from harness.campaign.formation_study import write_formation_study  # noqa: E402
from harness.campaign.neighbours_study import write_neighbours_study  # noqa: E402
from harness.campaign.report import write_campaign_report  # noqa: E402
from harness.destination import DestinationError, check_folder, write_whole  # noqa: E402
from harness.replay import parse_settings, scenario_with  # noqa: E402
from harness.summary import RunSummary  # noqa: E402
from interfaces.contracts.scenario import ScenarioError  # noqa: E402
from interfaces.runtime.arguments import command_help, positive_int  # noqa: E402
from interfaces.runtime.kernels import compile_kernels, kernels_cached  # noqa: E402

log = logging.getLogger("insp.campaign")


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=command_help(__doc__,
                                                         "docs/campaigns-and-replay.md"),
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--campaign", type=Path,
                   help="campaign TOML (not needed with --report-only on an existing --out)")
    p.add_argument("--out", type=Path,
                   help="campaign directory (default when flying: runs/<campaign>-<time>; "
                        "required with --report-only without --campaign, --replay, --sweep)")
    p.add_argument("--overwrite", action="store_true",
                   help="fly into an --out whose finished runs were flown with other settings "
                        "or another campaign file, replacing them; with --replay/--sweep, "
                        "replace a replay already in its folder")
    p.add_argument("--skip-disk-check", action="store_true",
                   help="start even when --out's disk looks too small for one run")
    p.add_argument("--workers", type=positive_int, default=os.cpu_count() or 1,
                   help="local worker processes, at least 1 (default: one per core)")
    p.add_argument("--limit", type=positive_int, help="run only the first N runs of the list")
    p.add_argument("--cluster", help="Dask scheduler address, e.g. tcp://127.0.0.1:8786 (an "
                                     f"error if none answers within {CONNECT_TIMEOUT_S:g} s)")
    p.add_argument("--transport", choices=("inproc", "zenoh"), default="inproc",
                   help="each run in one process (default), or multi-process over Zenoh on "
                        "its own loopback port and key space")
    p.add_argument("--report-only", action="store_true",
                   help="rewrite the report from the run directories, run nothing")
    p.add_argument("--replay", action="store_true",
                   help="re-judge the finished runs of --out under --set detector settings "
                        "(harness.replay), simulating nothing")
    p.add_argument("--set", dest="settings", action="append", default=[],
                   metavar="SECTION.KEY=VALUE",
                   help="with --replay/--sweep: a detector setting; when flying: any scenario "
                        "setting, on every run (e.g. onboard_fdir.enabled=true)")
    p.add_argument("--sweep", metavar="fdir.KEY=V1,V2,...",
                   help="replay the campaign once per value and write one table (sweep.md)")
    p.add_argument("--out-report", type=Path,
                   help="with --replay/--sweep: where to write (default: <out>/replay-<settings>)")
    return p.parse_args(argv)


class Progress:
    """Runs done, failed and the estimated time left, on stderr."""

    def __init__(self, total: int, skipped: int) -> None:
        self.total, self.skipped = total, skipped
        self.done = self.failed = 0
        self.retry: dict[str, str] = {}
        """The runs stopped by their host this time, each with its cause: flown on resume."""
        self.t0 = time.monotonic()

    def update(self, result: dict[str, Any]) -> None:
        self.done += 1
        if result["status"] == "retry":
            self.retry[result["id"]] = result["error"]
        else:
            self.failed += result["status"] != "completed"
        left = self.total - self.skipped - self.done
        rate = self.done / max(time.monotonic() - self.t0, 1e-9)
        eta = left / rate if rate > 0 else math.inf
        bar = "#" * int(30 * (self.skipped + self.done) / max(self.total, 1))
        tty = sys.stderr.isatty()
        start = "\r" if tty else ""
        print(f"{start}[{bar:<30}] {self.skipped + self.done}/{self.total} runs "
              f"({self.failed} failed, {len(self.retry)} to retry) ETA {eta / 60:5.1f} min  "
              f"last {result['id']} "
              f"{result['status']}", end="\n" if left == 0 or not tty else "", file=sys.stderr,
              flush=True)


def _interrupt(signum: int, _frame: object) -> None:
    raise KeyboardInterrupt(signum)


def _interrupted_status(e: KeyboardInterrupt) -> int:
    """128 + the signal's number: 143 for SIGTERM (raised by :func:`_interrupt`), 130 for
    Ctrl-C."""
    return 128 + (e.args[0] if e.args and isinstance(e.args[0], int) else signal.SIGINT)


def _local(todo: list[RunSpec], out: Path, workers: int, transport: str
           ) -> Iterator[dict[str, Any]]:
    """Run on a spawn process pool, one worker per core asked, each running its runs one after
    another with its imports and compiled kernels loaded once, and one BLAS thread
    (:func:`one_blas_thread`).  A job that dies outside its run is recorded as failed;
    a pool broken by a dead worker (killed, out of memory) is replaced and its pending runs
    resubmitted once (a run that breaks the pool twice is recorded as failed)."""
    queue = list(reversed(todo))
    broke: set[str] = set()
    one_blas_thread()
    while queue:
        pool = ProcessPoolExecutor(max_workers=max(1, workers), mp_context=get_context("spawn"))
        pending: dict[Future[dict[str, Any]], RunSpec] = {}
        try:
            while queue or pending:
                while queue and len(pending) < 2 * max(1, workers):
                    spec = queue.pop()
                    pending[pool.submit(execute_run, spec, str(out), transport)] = spec
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for f in finished:
                    spec = pending.pop(f)
                    try:
                        yield f.result()
                    except BrokenProcessPool as e:
                        if spec.id in broke:
                            yield record_retry(spec, str(out), f"worker died: {e}")
                        else:
                            broke.add(spec.id)
                            queue.append(spec)
                    except Exception as e:  # noqa: BLE001 - recorded, the campaign goes on
                        yield record_failure(spec, str(out), f"{type(e).__name__}: {e}")
                if any(spec.id in broke for spec in queue):
                    queue.extend(pending.values())
                    break  # replace the broken pool
        finally:
            for proc in list(getattr(pool, "_processes", {}).values()):
                proc.terminate()  # an interrupted run is abandoned: redone next time
            pool.shutdown(wait=True, cancel_futures=True)


BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""The thread counts of the BLAS libraries numpy and scipy may load."""


def one_blas_thread() -> None:
    """One BLAS thread in each worker the pool starts from now (they inherit the environment;
    a run's matrices are small, and the workers already fill the cores: threads only contend).
    A count the user set is kept."""
    for name in BLAS_THREADS:
        os.environ.setdefault(name, "1")


def _dask(todo: list[RunSpec], out: Path, address: str, transport: str
          ) -> Iterator[dict[str, Any]]:
    from distributed import as_completed

    tag = hashlib.sha256(str(out.resolve()).encode()).hexdigest()[:8]
    with dask_client(address) as client:
        futures = {client.submit(execute_run, spec, str(out), transport,
                                 key=f"run-{tag}-{spec.id}", pure=False): spec for spec in todo}
        try:
            for f in as_completed(list(futures)):
                try:
                    yield f.result()
                except Exception as e:  # noqa: BLE001 - a lost worker: flown again on resume
                    record = record_retry if _host_lost(e) else record_failure
                    yield record(futures[f], str(out), f"{type(e).__name__}: {e}")
        finally:
            client.cancel([f for f in futures if not f.done()])


def _host_lost(e: BaseException) -> bool:
    """Whether a Dask task failed because its worker or the network was lost (a fault of the
    host), not in the run (``execute_run`` records the run's own crashes itself)."""
    return (isinstance(e, (OSError, TimeoutError, CancelledError))
            or type(e).__module__.startswith("distributed") or type(e).__name__ == "KilledWorker")


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s campaign %(levelname)s %(message)s",
                        datefmt="%H:%M:%S")
    try:
        if args.replay or args.sweep or args.campaign is None:
            return _replay(args) if args.replay or args.sweep else _report_again(args)
        campaign, runs, settings = _load(args)
        args.out = _campaign_folder(args, campaign.name, runs, settings)
    except (CampaignError, ScenarioError, OutFolderError, DestinationError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.campaign.resolve() != (args.out / "campaign.toml").resolve():
        shutil.copyfile(args.campaign, args.out / "campaign.toml")
    write_whole(args.out / "campaign.json", json.dumps(
        {"name": campaign.name, "runs": [r.id for r in runs], "study": campaign.study,
         "settings": settings}, indent=1) + "\n")
    status = 0
    if not args.report_only:
        status = _run(runs, args)
        if status == 2:  # refused before any run: nothing to report
            return status
    if not _reports(args.out, campaign.name, [r.id for r in runs], campaign.study):
        return status or 1
    if status == 0 and any(_failed(args.out, r.id) for r in runs):
        return 1
    return status


def _load(args: argparse.Namespace) -> tuple[Campaign, list[RunSpec], dict[str, str]]:
    """The campaign's runs as they will fly (``--set`` applied, ``--limit`` taken) and the
    settings given; CampaignError or ScenarioError names what is wrong."""
    campaign, runs = load_campaign(args.campaign)
    settings = parse_settings(args.settings)
    _refuse_drawn(settings, runs)
    runs = [replace(r, scenario=scenario_with(r.scenario, settings)) for r in runs]
    return campaign, runs[:args.limit] if args.limit is not None else runs, settings


def _campaign_folder(args: argparse.Namespace, name: str, runs: list[RunSpec],
                     settings: dict[str, str]) -> Path:
    """The campaign's folder (``--out``, or ``runs/<name>-<time>``), made and writable; a
    folder whose finished runs this command would replace is refused unless ``--overwrite``
    (OutFolderError naming the difference)."""
    out = args.out or REPO / "runs" / f"{name}-{time.strftime('%Y%m%d-%H%M%S')}"
    if args.out is None:
        log.info("campaign folder: %s", out)
    check_folder(out, "--out")
    if not args.overwrite:
        _refuse_reuse(out, name, runs, settings)
    return out


def _refuse_reuse(out: Path, name: str, runs: list[RunSpec], settings: dict[str, str]) -> None:
    """OutFolderError when ``out``'s finished runs differ from those this command flies: other
    ``--set`` settings, another campaign, or another version of its file."""
    try:
        saved = json.loads((out / "campaign.json").read_text())
    except (OSError, ValueError):
        return
    replaced = [r.id for r in runs
                if (out / "runs" / r.id).is_dir() and not finished(r, out)]
    if saved.get("name") != name:
        why = f"holds campaign {saved.get('name')!r}, not {name!r}"
    elif (saved.get("settings") or {}) != settings:
        why = (f"was flown with {_settings_text(saved.get('settings') or {})}; this command "
               f"sets {_settings_text(settings)}")
    elif replaced:
        why = (f"holds {len(replaced)} finished runs flown from another version of the "
               f"campaign file (first: {replaced[0]})")
    else:
        return
    raise OutFolderError(f"--out {out} {why}: give another --out, or --overwrite to replace "
                         "its runs")


def _settings_text(settings: dict[str, str]) -> str:
    """``--set a=1 --set b=2``, or ``no --set``."""
    return " ".join(f"--set {k}={v}" for k, v in settings.items()) or "no --set"


def _report_again(args: argparse.Namespace) -> int:
    """--report-only on a campaign folder, from the run list saved there."""
    if args.out is None or not args.report_only or not (args.out / "campaign.json").exists():
        print("error: --campaign is required (except --report-only --out on a campaign "
              "folder)", file=sys.stderr)
        return 2
    check_folder(args.out, "--out")
    saved = json.loads((args.out / "campaign.json").read_text())
    return 0 if _reports(args.out, saved["name"], saved["runs"], saved.get("study")) else 1


def _refuse_drawn(settings: dict[str, str], runs: list[RunSpec]) -> None:
    """A ``--set`` of a setting the campaign draws would fly every run with one value while
    the runs' records say otherwise: refused."""
    drawn = {k for r in runs for k in r.drawn}
    clash = sorted(k for k in settings if k in drawn)
    if clash:
        raise CampaignError(f"--set {clash[0]}: the campaign draws this setting per run")


def _reports(out: Path, name: str, ids: list[str], study: str | None) -> bool:
    """The campaign's report, and its study's (``study = "formations"``) when it names one;
    False, with one line, when the disk refuses them."""
    try:
        write_campaign_report(out, name, ids)
        print(f"report: {out / 'report.md'}", file=sys.stderr)
        if study == "formations":
            print(f"study: {write_formation_study(out, ids)}", file=sys.stderr)
        elif study == "neighbours":
            print(f"study: {write_neighbours_study(out, ids)}", file=sys.stderr)
    except OSError as e:
        print(f"error: the report could not be written in {out}: {e.strerror or e}",
              file=sys.stderr)
        return False
    return True


def _replay(args: argparse.Namespace) -> int:
    """--replay / --sweep: re-judge a finished campaign (deploy/campaign_replay.py)."""
    if args.out is None or not (args.out / "campaign.json").exists():
        print(f"error: --out {args.out or '(not given)'} holds no campaign to replay (no "
              "campaign.json)", file=sys.stderr)
        return 2
    try:
        settings = parse_settings(args.settings)
        name, values = _sweep_values(args.sweep) if args.sweep else ("", [])
        slug = "_".join(f"{k}={v}" for k, v in settings.items())
        dest = args.out_report or args.out / (f"sweep-{name}" if args.sweep else
                                              f"replay-{slug or 'own-settings'}")
        option = "--out-report" if args.out_report else "another --out-report"
        if (dest / "report.md").exists() and not args.overwrite:
            raise DestinationError(f"{dest} holds a replay already: give --overwrite to replace "
                                   f"it, or {option}")
        check_folder(dest, option)
        kw = {"workers": args.workers, "cluster": args.cluster, "progress": print_progress}
        path = (sweep(args.out, name, values, dest, settings, **kw) if args.sweep
                else rejudge(args.out, settings, dest, **kw))
    except (ScenarioError, ClusterError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(f"report: {path}", file=sys.stderr)
    return 0


def _sweep_values(text: str) -> tuple[str, list[str]]:
    name, sep, values = text.partition("=")
    out = [v.strip() for v in values.split(",") if v.strip()]
    if not sep or not name or not out:
        raise ScenarioError(f"--sweep {text!r}: expected SECTION.KEY=V1,V2,...")
    return name.strip(), out


def _failed(out: Path, run_id: str) -> bool:
    p = out / "runs" / run_id / "summary.json"
    return p.exists() and RunSummary.read(p).status != "completed"


def _run(runs: list[RunSpec], args: argparse.Namespace) -> int:
    runs_dir = args.out / "runs"
    runs_dir.mkdir(exist_ok=True)
    lock = open(args.out / ".lock", "w")  # noqa: SIM115 - held for the whole campaign
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        print(f"error: another campaign is running in {args.out}", file=sys.stderr)
        return 2
    try:
        for partial in [*runs_dir.glob("*.partial*"), *runs_dir.glob("*.failed-*")]:
            shutil.rmtree(partial, ignore_errors=True)  # half-written by an interrupted campaign
        todo = [r for r in runs if not finished(r, args.out)]
        if todo and not args.skip_disk_check:
            _check_disk(args.out, todo)
        with Reserve(args.out):  # released before the report is written
            return _run_locked(runs, todo, args)
    except DiskSpaceError as e:
        print(f"error: {e.strerror}", file=sys.stderr)
        return 2
    finally:
        lock.close()


def _check_disk(out: Path, todo: list[RunSpec]) -> None:
    """DiskSpaceError when ``out`` cannot hold the largest run left; a warning when it cannot
    hold them all (the campaign then stops cleanly where the disk fills)."""
    largest = max(todo, key=lambda r: estimate_archive_bytes(r.scenario))
    check_space(out, largest.scenario)
    need = sum(estimate_archive_bytes(r.scenario) for r in todo) + RESERVE_BYTES
    free = free_bytes(out)
    if free < need:
        log.warning("%s has %s free; the %d runs left need about %s: the campaign stops "
                    "cleanly when the disk fills, and the same command then flies the rest",
                    out, megabytes(free), len(todo), megabytes(need))


def _run_locked(runs: list[RunSpec], todo: list[RunSpec], args: argparse.Namespace) -> int:
    log.info("%d runs, %d already finished, %d to run on %s", len(runs), len(runs) - len(todo),
             len(todo), args.cluster or f"{args.workers} local workers")
    if todo and not kernels_cached():  # once here, not in every worker
        compile_kernels(log.info)
    progress = Progress(len(runs), len(runs) - len(todo))
    main_thread = signal.getsignal(signal.SIGTERM)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        results = _dask(todo, args.out, args.cluster, args.transport) if args.cluster else \
            _local(todo, args.out, args.workers, args.transport)
        status = _follow(results, progress)
    except ClusterError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as e:
        print("", file=sys.stderr)
        log.warning("interrupted: %d runs finished this time; start again with the same --out "
                    "to go on", progress.done - len(progress.retry))
        status = _interrupted_status(e)
    finally:
        signal.signal(signal.SIGTERM, main_thread)
    _write_retries(args.out, progress.retry)
    if status == 0 and progress.retry:
        print(f"error: {len(progress.retry)} runs were stopped by their host, not by "
              f"themselves ({args.out / 'retry.json'}): run the same command again to fly them",
              file=sys.stderr)
        return 1
    return status


def _follow(results: Iterator[dict[str, Any]], progress: Progress) -> int:
    """Follow the runs as they finish; stop at the first full disk (0, or 1 with one line when
    the disk filled)."""
    for result in results:
        progress.update(result)
        if result["status"] == "retry" and disk_full_cause(result["error"]):
            print(f"error: {result['error']} (run {result['id']}): the campaign stopped; "
                  "free some space and run the same command again to fly the runs left",
                  file=sys.stderr)
            return 1
    return 0


def _write_retries(out: Path, retry: dict[str, str]) -> None:
    """``<out>/retry.json``: the runs stopped by their host this time, each with its cause
    (flown again by the next run of the same command); removed when there are none."""
    path = out / "retry.json"
    try:
        if retry:
            write_whole(path, json.dumps(retry, indent=1) + "\n")
            log.warning("%d runs to fly again (stopped by their host, not by themselves): %s",
                        len(retry), path)
        else:
            path.unlink(missing_ok=True)
    except OSError as e:
        log.error("retry.json not written: %s", e.strerror or e)


if __name__ == "__main__":
    raise SystemExit(main())
