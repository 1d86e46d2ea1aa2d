"""Calibrate the FDIR threshold floor from nominal runs (docs/fdir.md: "a floor calibrated from
nominal runs for a chosen false-alarm rate").

    python -m harness.campaign.calibrate runs/nominal [runs/nominal-seed2 ...] [--rate 1e-3]
        [--persistence 2] [--skip-s 0]

Reads every ``ground/fdir/window`` verdict of the given runs (each a run folder holding
``run.mcap``, or the archive itself; the segments after it too; windows overlapping a fault of
their spacecraft, as listed in the ``summary.json`` beside the archive, are left out), prints the
distribution of the nominal metric H_m,i, the floor that gives the chosen false-alarm probability
per FDI window under the persistence rule (:func:`threshold.calibrate_floor`), and how far the
largest nominal metric is below each run's configured floor.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ground.fdir.threshold import calibrate_floor
from harness.archive.locate import ArchivePathError, archive_file
from harness.archive.reader import ArchiveError, load_run
from harness.summary import RunSummary
from interfaces.contracts.messages import FdirWindow
from interfaces.contracts.scenario import Fault


def nominal_metrics(run: Path, skip_s: float = 0.0) -> list[FdirWindow]:
    """The judged FDIR windows of a run (its folder or its archive) that end after ``skip_s``
    (s) and overlap no fault of their spacecraft (``summary.json`` ``injected_faults``, when
    the run has one).  Raises ArchiveError (ArchivePathError for a path naming no archive)."""
    file = archive_file(run)
    archive = load_run(file)
    faults: list[Fault] = []
    if (file.parent / "summary.json").exists():
        faults = RunSummary.read(file.parent / "summary.json").injected_faults

    def faulty(w: FdirWindow) -> bool:
        return any(f.spacecraft == w.spacecraft and f.start_s < w.t_end_s
                   and (f.end_s is None or w.t_start_s < f.end_s) for f in faults)

    keys = [k for k, (t, _) in archive.topics().items()
            if k.endswith("/ground/fdir/window") and t == "FdirWindow"]
    return [w for k in keys for w in archive.messages(k, FdirWindow)
            if w.metric is not None and w.t_end_s > skip_s and not faulty(w)]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m harness.campaign.calibrate", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("runs", type=Path, nargs="+",
                   help="nominal runs: run folders (holding run.mcap) or archive files")
    p.add_argument("--rate", type=float, default=1e-3,
                   help="false-alarm probability per FDI window (default 1e-3)")
    p.add_argument("--persistence", type=int, default=2, help="windows in a row (default 2)")
    p.add_argument("--skip-s", type=float, default=0.0, help="ignore windows ending before")
    args = p.parse_args(argv)
    try:
        for run in args.runs:
            archive_file(run)
    except ArchivePathError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    windows: list[FdirWindow] = []
    for run in args.runs:
        try:
            windows += nominal_metrics(run, args.skip_s)
        except (ArchiveError, OSError, ValueError) as e:
            print(f"error: {run}: {e}", file=sys.stderr)
            return 2
    values = [w.metric for w in windows if w.metric is not None]
    if not values:
        print("error: no judged nominal FDIR window in these runs", file=sys.stderr)
        return 2
    try:
        floor = calibrate_floor(values, args.rate, args.persistence)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    m = np.array(values)
    print(f"{m.size} nominal windows: H_m median {np.median(m):.4g}, p90 "
          f"{np.quantile(m, 0.9):.4g}, p99 {np.quantile(m, 0.99):.4g}, max {m.max():.4g}")
    print(f"floor for {args.rate:g} false alarms per window with persistence "
          f"{args.persistence}: {floor:.4g}")
    floors = sorted({w.threshold for w in windows if w.threshold is not None})
    if floors:
        print(f"margin: the smallest threshold these runs applied ({floors[0]:.4g}) is "
              f"{floors[0] / m.max():.2g}x the largest nominal H_m")
    if m.size * args.rate ** (1.0 / args.persistence) < 1.0:
        print(f"note: {m.size} windows are too few to resolve that quantile; the floor is near "
              "the sample maximum: add nominal runs (other seeds)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
