"""Archive tools: list, summarize and export any run archive (run.mcap).

    python -m harness.archive list RUN [RUN2 ...]
    python -m harness.archive summary RUN
    python -m harness.archive export RUN --topic KEY_EXPR [--out FILE.csv|.parquet] [--overwrite]

RUN is a run folder (holding ``run.mcap``) or an archive file; anything else (a missing path, a
folder without ``run.mcap``, a file that is not MCAP) is refused with one line saying so, exit
status 2 (``harness/archive/locate.py``).

``list`` prints each key with its message type, count and sim-time span; ``summary`` the
metadata the recorder wrote (scenario, seed, transport, software version), the message counts
per type, the injected faults and the FDIR's declarations; ``export`` writes the messages of
a key expression (``*`` one chunk, ``**`` any number) as CSV, one row per message, nested
fields flattened (``r_m.0``, ``P.2.3``), to ``--out`` or stdout; an ``--out`` ending in
``.parquet`` (or ``.pq``) gets instead the topic's DataFrame (harness/archive/frame.py: indexed
by sim time ``t_sim_s``, lists of varying length kept whole) as Parquet, which
``pandas.read_parquet`` reads back as it was.  Refused before any work, one line and exit
status 2: an ``--out`` of another suffix (the suffix chooses the format), an ``--out`` that
exists (unless ``--overwrite``) or cannot be written; and, either format, a key expression
that matches nothing (nothing is written).  A damaged archive is read up to its last
complete chunk (harness/archive/reader.py) and said so: where the file was cut and the sim time
its data ends at.  ``RUN.mcap`` is a run's first segment:
the segments after it (``run-1.mcap``, ...: a restarted recorder's) are read with it as one
run, and ``list`` and ``summary`` name them and the messages lost, by topic.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TextIO

from harness.archive.frame import topic_frame
from harness.archive.locate import ArchivePathError, archive_file
from harness.archive.reader import ArchiveError, RunArchive, load_run
from harness.archive.sequences import by_topic
from harness.archive.span import cut_of, seconds
from harness.destination import DestinationError, check_file
from interfaces.runtime.arguments import command_help, prog_name

PARQUET_SUFFIXES = (".parquet", ".pq")
"""``export --out`` file suffixes that choose Parquet over CSV."""
EXPORT_SUFFIXES = (".csv", *PARQUET_SUFFIXES)
"""Every ``export --out`` file suffix (any case)."""


def flatten(value: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    """(dotted name, scalar) pairs of a JSON value: dicts by key, lists by index."""
    if isinstance(value, dict):
        for k, v in value.items():
            yield from flatten(v, f"{prefix}.{k}" if prefix else str(k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from flatten(v, f"{prefix}.{i}" if prefix else str(i))
    else:
        yield prefix, value


def _span(archive: RunArchive, key: str) -> tuple[float, float]:
    times = [r.log_time_ns for r in archive.records(key)]
    return (min(times) / 1e9, max(times) / 1e9) if times else (0.0, 0.0)


def _continuity(archive: RunArchive, out: TextIO) -> None:
    """The archive's segments and the messages lost, when it has several or lost some."""
    if len(archive.segments) == 1 and not archive.lost:
        return
    out.write("  segments: " + ", ".join(s.path.name + (" (truncated)" if s.truncated else "")
                                         for s in archive.segments) + "\n")
    lost = by_topic(archive.lost)
    out.write(f"  lost: {sum(lost.values())} messages"
              + "".join(f", {t} {n}" for t, n in lost.items()) + "\n")


def extent(archive: RunArchive) -> str:
    """Where the archive's data ends (s), and for a file cut short where it was cut."""
    ends = "no message" if archive.end_s is None else f"ends at {seconds(archive.end_s)} s"
    cut = cut_of(archive)
    return ends if cut is None else f"{ends}, TRUNCATED ({cut})"


def list_topics(archive: RunArchive, out: TextIO) -> None:
    out.write(f"{archive.path}: {len(archive)} messages, {extent(archive)}\n")
    _continuity(archive, out)
    for key, (type_name, count) in archive.topics().items():
        t0, t1 = _span(archive, key)
        out.write(f"  {key}  {type_name}  {count}  [{t0:.1f}, {t1:.1f}] s\n")


def summarize(archive: RunArchive, out: TextIO) -> None:
    out.write(f"{archive.path}: {len(archive)} messages, "
              + (extent(archive) if archive.truncated else f"complete, {extent(archive)}")
              + "\n")
    _continuity(archive, out)
    run = archive.metadata.get("run", {})
    for k in ("scenario", "seed", "transport", "duration_s", "software_version", "started_utc"):
        out.write(f"  {k}: {run.get(k, '-')}\n")
    counts: dict[str, int] = {}
    for type_name, count in archive.topics().values():
        counts[type_name] = counts.get(type_name, 0) + count
    out.write("  messages by type: " + ", ".join(f"{t} {n}" for t, n in sorted(counts.items()))
              + "\n")
    for r in archive.records("**"):
        if r.type_name == "FaultEvent":
            m = json.loads(r.payload)
            out.write(f"  fault {m['kind']} on sc{m['spacecraft']} "
                      f"{'on' if m['active'] else 'off'} at {m['t_sim']:.0f} s\n")
        elif r.type_name == "FaultReport":
            m = json.loads(r.payload)
            out.write(f"  declared: sc{m['spacecraft']} {m['fault_class'] or 'unidentified'} "
                      f"at {m['t_sim']:.0f} s\n")


def export_csv(archive: RunArchive, key_expr: str, out: TextIO) -> int:
    """Write the messages of ``key_expr`` as CSV; returns the number of rows."""
    rows = []
    for r in archive.records(key_expr):
        row = {"key": r.key, "type": r.type_name, "log_time_s": r.log_time_ns / 1e9}
        row.update(flatten(json.loads(r.payload)))
        rows.append(row)
    fields: dict[str, None] = {}
    for row in rows:
        fields.update(dict.fromkeys(row))
    w = csv.DictWriter(out, fieldnames=list(fields))
    w.writeheader()
    w.writerows(rows)
    return len(rows)


def check_export_out(out: Path | None, overwrite: bool) -> None:
    """Refuse an ``export --out`` with an unknown suffix, that exists (unless ``overwrite``)
    or cannot be written: DestinationError, one line."""
    if out is None:
        return
    if out.suffix.lower() not in EXPORT_SUFFIXES:
        raise DestinationError(f"--out {out}: the suffix chooses the format: one of "
                               f"{', '.join(EXPORT_SUFFIXES)}")
    check_file(out, overwrite, "another --out")


def export(run: Path, key_expr: str, out: Path | None) -> tuple[int, str | None]:
    """Export the messages of ``key_expr``: Parquet if ``out`` has a Parquet suffix, else CSV
    to ``out`` or stdout; returns the number of rows and, for an archive cut short, where it
    was cut (``span.cut_of``: the export ends there).  ArchiveError, writing nothing, when no
    key matches."""
    archive = load_run(run)
    cut = cut_of(archive)
    if not archive.records(key_expr):
        raise ArchiveError(f"{archive.path}: no key matches {key_expr!r} ("
                           f"{len(archive.topics())} keys; `python -m harness.archive list "
                           f"{archive.path}` shows them)")
    if out is not None and out.suffix.lower() in PARQUET_SUFFIXES:
        frame = topic_frame(archive, key_expr)
        frame.to_parquet(out)
        return len(frame), cut
    if out is None:
        return export_csv(archive, key_expr, sys.stdout), cut
    with open(out, "w", newline="") as f:
        return export_csv(archive, key_expr, f), cut


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog=prog_name("python -m harness.archive"),
                                description=command_help(__doc__,
                                                         "docs/campaigns-and-replay.md", 2),
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    run_help = "a run folder (holding run.mcap) or an archive file"
    sub.add_parser("list", help="keys, types, counts").add_argument("runs", nargs="+", type=Path,
                                                                    help=run_help)
    sub.add_parser("summary", help="metadata, counts, faults").add_argument("run", type=Path,
                                                                           help=run_help)
    e = sub.add_parser("export", help="CSV or Parquet of a key expression")
    e.add_argument("run", type=Path, help=run_help)
    e.add_argument("--topic", required=True, help="key expression, e.g. 'insp/*/sc/1/nav/**'")
    e.add_argument("--out", type=Path,
                   help="a .csv file (default: CSV to stdout), or Parquet for .parquet or .pq")
    e.add_argument("--overwrite", action="store_true", help="replace an --out that exists")
    args = p.parse_args(argv)
    try:
        runs = [archive_file(r) for r in (args.runs if args.command == "list" else [args.run])]
        if args.command == "export":
            check_export_out(args.out, args.overwrite)
    except (ArchivePathError, DestinationError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    try:
        if args.command == "list":
            for run in runs:
                list_topics(load_run(run), sys.stdout)
        elif args.command == "summary":
            summarize(load_run(runs[0]), sys.stdout)
        else:
            n, cut = export(runs[0], args.topic, args.out)
            print(f"{n} messages exported", file=sys.stderr)
            if cut is not None:
                print(f"warning: the archive is truncated ({cut}): the export ends where it "
                      "does", file=sys.stderr)
    except BrokenPipeError:  # e.g. piped into `head`
        return 0
    except (ArchiveError, OSError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
