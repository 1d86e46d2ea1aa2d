"""Any archived topic as a pandas DataFrame: one row per message, one column per field.

    from harness.archive.frame import topic_frame
    nav = topic_frame("runs/x/run.mcap", "insp/*/sc/*/nav/estimate")
    nav.groupby("spacecraft")["x.0"].plot()
    nav.to_parquet("nav.parquet")

The rows are the messages of every key matching the pattern (``*`` one chunk, ``**`` any
number, as ``python -m harness.archive export`` takes them), decoded and validated through the
message registry (``harness.archive.reader``).  The index is the message header's sim time
``t_sim`` in seconds, named ``t_sim_s``, sorted; messages of equal time keep the archive's order
(file order).  The columns are the message's fields flattened as ``harness.archive.columns``
describes (``x.0`` ... ``x.5``, ``P.2.3``, ``groups.high.runs``; lists of varying length kept
whole) minus ``t_sim`` (the index); a ``key`` column leads when several keys match and a
``type`` column when several message types do; ``spacecraft`` comes next when the message has
one.  Reading a file holds in memory only the records of the matching keys.  A ``run.mcap``
path reads the run's segments after it too (a restarted recorder's: ``run-1.mcap``, ...,
``ground.archive.segments``), as one run.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Final

import pandas as pd

from harness.archive.columns import RowFlattener
from harness.archive.reader import ArchiveError, Record, RunArchive, load_run
from interfaces.contracts.messages import Message, registry

INDEX_NAME: Final = "t_sim_s"
"""Name of the index: the message header's sim time, s."""

_CHUNK: Final = re.compile(r"^(\*|\*\*|[A-Za-z0-9_\-]+)$")
"""A chunk of a topic pattern: ``*``, ``**`` or a key segment (interfaces.contracts.topics)."""

_LEADING: Final = ("key", "type", "spacecraft")
"""Columns put first, in this order, when present."""


def check_pattern(pattern: str) -> None:
    """Raise ``ValueError`` unless ``pattern`` is a key expression the archive can match:
    chunks separated by ``/``, each ``*``, ``**`` or letters, digits, ``_`` and ``-``."""
    bad = [c for c in pattern.split("/") if not _CHUNK.match(c)] if pattern else [""]
    if bad:
        raise ValueError(
            f"bad topic pattern {pattern!r}: chunk {bad[0]!r} is not '*', '**' or a key "
            f"segment (letters, digits, '_', '-'); e.g. 'insp/*/sc/1/nav/estimate'")


def _no_match(where: object, pattern: str, keys: list[str]) -> ArchiveError:
    """The error for a pattern matching no key, naming keys that look like what was meant."""
    last = pattern.rsplit("/", 1)[-1]
    near = [k for k in keys if k.rsplit("/", 1)[-1] == last] or keys
    shown = ", ".join(near[:5]) + (", ..." if len(near) > 5 else "")
    return ArchiveError(f"{where}: no key matches {pattern!r} ({len(keys)} keys"
                        + (f", e.g. {shown}" if shown else "")
                        + f"; `python -m harness.archive list {where}` shows them all)")


def _select(source: str | Path | RunArchive, pattern: str) -> list[Record]:
    """The records of the keys matching ``pattern``, in the archive's order (a file is read
    keeping only those: every other key is streamed past and dropped)."""
    if isinstance(source, RunArchive):
        archive = source
        records = archive.records(pattern)
    else:
        path = Path(source)
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such archive file")
        kept: list[Record] = []
        archive = load_run(path, stream={pattern: kept.append, "**": lambda _: None})
        records = sorted(kept, key=lambda r: r.log_time_ns)  # the reader's order
    if not records:
        raise _no_match(archive.path, pattern, list(archive.topics()))
    return records


def _decoded(records: list[Record], skip_invalid: bool) -> list[tuple[Record, Message]]:
    """Each record with its message (registry model of its type name); an undecodable record
    raises :class:`ArchiveError` unless ``skip_invalid``."""
    models = registry()
    out: list[tuple[Record, Message]] = []
    for rec in records:
        model = models.get(rec.type_name)
        try:
            if model is None:
                raise ArchiveError(f"{rec.key}: unknown message type {rec.type_name!r}")
            out.append((rec, rec.decode(model)))
        except ArchiveError:
            if not skip_invalid:
                raise
    return out


def _rows(decoded: list[tuple[Record, Message]]) -> list[dict[str, Any]]:
    """One flat row per message (``key``/``type`` when several), ``t_sim`` left out."""
    several_keys = len({rec.key for rec, _ in decoded}) > 1
    several_types = len({rec.type_name for rec, _ in decoded}) > 1
    flattener = RowFlattener()
    rows = []
    for rec, msg in decoded:
        row: dict[str, Any] = {}
        if several_keys:
            row["key"] = rec.key
        if several_types:
            row["type"] = rec.type_name
        row.update(flattener.row(msg))
        del row["t_sim"]
        rows.append(row)
    return rows


def topic_frame(source: str | Path | RunArchive, pattern: str, *,
                skip_invalid: bool = False) -> pd.DataFrame:
    """The messages of the keys matching ``pattern`` in an archive (a ``run.mcap`` path, with
    its later segments, or a loaded :class:`RunArchive`) as a DataFrame indexed by sim time, s
    (module docstring).

    Raises ``ValueError`` for a malformed pattern, ``FileNotFoundError`` for a missing file,
    :class:`ArchiveError` for a file that is not an archive, a pattern matching no key, or
    (unless ``skip_invalid``) a message that does not decode.
    """
    check_pattern(pattern)
    decoded = _decoded(_select(source, pattern), skip_invalid)
    decoded.sort(key=lambda item: item[1].t_sim)  # stable: equal times keep the archive's order
    index = pd.Index([msg.t_sim for _, msg in decoded], dtype="float64", name=INDEX_NAME)
    frame = pd.DataFrame(_rows(decoded), index=index)
    first = [c for c in _LEADING if c in frame.columns]
    return frame[first + [c for c in frame.columns if c not in first]]


__all__ = ["INDEX_NAME", "check_pattern", "topic_frame"]
