"""A finished campaign re-judged under other detector settings, without re-simulating.

Every run of ``<out>/runs/`` is replayed (``harness.replay``: the ground station itself
on the run's archive) with the settings given; its ``summary.json`` is rewritten with the
replay's FDIR fields (detections, scores, baselines, series, settings) and a ``replay`` section
(settings, ``archive_end_s``, ``faithful_until_s``, ``matches_live``, replay wall time) into
``<dest>/runs/<id>/``, and the campaign report is written over them in ``<dest>``.  A sweep
does the same for every value of one setting and adds one table: detection, isolation,
identification, latency median/p90 and false alarms with their counts, per value.

Runs go to a local process pool (one worker per core) or an existing Dask scheduler.
"""

from __future__ import annotations

import csv
import json
import logging
import shutil
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path
from typing import Any

from deploy.cluster import dask_client
from harness.archive.reader import ArchiveError
from harness.archive.run_scenario import archived_scenario
from harness.campaign.report import write_campaign_report
from harness.campaign.rescore import detector_figures
from harness.replay import replay_run, with_settings
from harness.summary import ReplaySection, RunSummary
from interfaces.contracts.scenario import ScenarioError

log = logging.getLogger("insp.campaign")


def replay_job(run_dir: str, settings: dict[str, str], dest_root: str) -> dict[str, Any]:
    """Replay one run directory into ``<dest_root>/runs/<id>/`` (runs on a worker, whose
    log keeps the ground's errors only: its declarations are in the summaries).  The run's
    summary is rewritten with the replay's FDIR sections (``FdirResults``) and ``replay``."""
    logging.getLogger("insp").setLevel(logging.ERROR)
    src = Path(run_dir)
    dest = Path(dest_root) / "runs" / src.name
    dest.mkdir(parents=True, exist_ok=True)
    summary = RunSummary.read(src / "summary.json")
    for meta in ("campaign.json", "drawn.json"):  # its group, software version, drawn set-up
        if (src / meta).exists():
            shutil.copyfile(src / meta, dest / meta)
    if summary.status == "completed":
        try:
            replay = replay_run(src, settings)
        except (ArchiveError, OSError) as e:
            summary.status, summary.error = "failed", f"replay: {e}"
        else:
            res = replay.results()
            summary.set_fdir(res)
            summary.replay = ReplaySection(settings=settings, wall_s=res.replay_wall_s,
                                           archive_end_s=res.archive_end_s,
                                           faithful_until_s=res.faithful_until_s,
                                           matches_live=res.matches_live,
                                           scores_faithful=res.scores_faithful)
    (dest / "summary.json").write_text(summary.to_json(indent=1))
    return {"id": src.name, "status": summary.status,
            "matches_live": summary.replay.matches_live if summary.replay else None}


def _local(jobs: list[tuple[str, dict[str, str], str]], workers: int
           ) -> Iterator[dict[str, Any]]:
    with ProcessPoolExecutor(max_workers=max(1, workers), mp_context=get_context("spawn")) as pool:
        for f in as_completed([pool.submit(replay_job, *job) for job in jobs]):
            yield f.result()


def _dask(jobs: list[tuple[str, dict[str, str], str]], address: str
          ) -> Iterator[dict[str, Any]]:
    from distributed import as_completed as dask_completed

    with dask_client(address) as client:
        futures = [client.submit(replay_job, *job, pure=False) for job in jobs]
        for f in dask_completed(futures):
            yield f.result()


def rejudge(out: Path, settings: dict[str, str], dest: Path, workers: int = 1,
            cluster: str | None = None, progress: Callable[[int, int], None] | None = None
            ) -> Path:
    """Replay every run of the campaign in ``out`` under ``settings`` into ``dest`` and write
    the campaign report there; returns the report's path.  Raises ScenarioError for a setting
    a replay may not change (checked on the first run before any work)."""
    index = json.loads((out / "campaign.json").read_text())
    ids = [i for i in index["runs"] if (out / "runs" / i / "summary.json").exists()]
    if not ids:
        raise ScenarioError(f"{out}: no finished run to replay")
    _check_settings(out / "runs" / ids[0], settings)
    dest.mkdir(parents=True, exist_ok=True)
    jobs = [(str(out / "runs" / i), settings, str(dest)) for i in ids]
    results = _dask(jobs, cluster) if cluster else _local(jobs, workers)
    for n, _ in enumerate(results, 1):
        if progress is not None:
            progress(n, len(jobs))
    label = ", ".join(f"{k}={v}" for k, v in settings.items()) or "the runs' own settings"
    (dest / "campaign.json").write_text(json.dumps({"name": index["name"], "runs": ids,
                                                    "replay_of": str(out),
                                                    "settings": settings}, indent=1) + "\n")
    return write_campaign_report(dest, f"{index['name']} (replayed with {label})", ids)


def _check_settings(run_dir: Path, settings: dict[str, str]) -> None:
    """Refuse bad settings before any work, against the run's own scenario (read from its
    archive's metadata alone)."""
    if RunSummary.read(run_dir / "summary.json").status == "completed":
        with_settings(archived_scenario(run_dir / "run.mcap"), settings)


def sweep(out: Path, name: str, values: Sequence[str], dest: Path, base: dict[str, str],
          workers: int = 1, cluster: str | None = None,
          progress: Callable[[int, int], None] | None = None) -> Path:
    """Re-judge the campaign for every value of setting ``name`` (with ``base`` settings
    too), each into ``dest/<name>=<value>/``, and write ``dest/sweep.md`` and ``sweep.csv``:
    the main detector's figures per value.  Returns the table's path."""
    rows = []
    for value in values:
        settings = {**base, name: value}
        sub = dest / f"{name}={value}"
        start = time.perf_counter()
        rejudge(out, settings, sub, workers, cluster, progress)
        ids = json.loads((sub / "campaign.json").read_text())["runs"]
        rows.append({name: value, **detector_figures(sub, ids),
                     "wall_s": round(time.perf_counter() - start, 1)})
    return _write_sweep(dest, name, rows)


SWEEP_COLUMNS = ("detected", "isolated", "identified", "latency_median_s", "latency_p90_s",
                 "false_alarms", "nominal_cycles", "false_alarms_faithful",
                 "nominal_cycles_faithful", "faithful_runs", "runs", "wall_s")


def _write_sweep(dest: Path, name: str, rows: list[dict[str, Any]]) -> Path:
    dest.mkdir(parents=True, exist_ok=True)
    with open(dest / "sweep.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=[name, "faults", *SWEEP_COLUMNS])
        w.writeheader()
        w.writerows(rows)
    lines = [f"# Sweep of {name} (replayed, main detector)", "",
             f"| {name} | detected | isolated | identified | latency median / p90 (s) | "
             "false alarms / nominal cycles, faithful span | same, whole runs | "
             "runs faithful to the end | replay wall (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        n = r["faults"]
        lines.append(
            f"| {r[name]} | {_pct(r['detected'], n)} | {_pct(r['isolated'], n)} | "
            f"{_pct(r['identified'], n)} | {_num(r['latency_median_s'])} / "
            f"{_num(r['latency_p90_s'])} | {r['false_alarms_faithful']} / "
            f"{r['nominal_cycles_faithful']} | {r['false_alarms']} / {r['nominal_cycles']} | "
            f"{r['faithful_runs']}/{r['runs']} | {r['wall_s']} |")
    lines += ["", "Each value's full campaign report is in its own directory "
              f"(`{name}=<value>/report.md`).  A replay is faithful until the first uplink that "
              "differs from the live run's (a recovery made at another time): what it declares "
              "after that rests on a trajectory its own uplinks did not command.  Detection and "
              "latency are decided before it (a declaration is what starts a recovery); false "
              "alarms are given over the faithful span of each run and over whole runs."]
    path = dest / "sweep.md"
    path.write_text("\n".join(lines) + "\n")
    return path


def _pct(n: int, d: int) -> str:
    return "-" if d == 0 else f"{100.0 * n / d:.0f}% ({n}/{d})"


def _num(v: float | None) -> str:
    return "-" if v is None else f"{v:.0f}"


def print_progress(done: int, total: int) -> None:
    """Runs replayed so far, on stderr (one updating line on a terminal)."""
    tty = sys.stderr.isatty()
    start = "\r" if tty else ""
    print(f"{start}replayed {done}/{total} runs",
          end="\n" if done == total or not tty else "", file=sys.stderr, flush=True)
