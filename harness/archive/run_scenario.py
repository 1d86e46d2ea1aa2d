"""The scenario a run ran with, read from its archive's metadata record ``scenario`` (written by
``ground.archive.metadata.run_metadata``)."""

from __future__ import annotations

import struct
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Chunk, Message, Metadata
from mcap.stream_reader import StreamReader

from harness.archive.reader import ArchiveError
from interfaces.contracts.scenario import Scenario


def scenario_from_metadata(metadata: dict[str, dict[str, str]],
                           source: object | None = None) -> Scenario:
    """The scenario a run ran with, from its ``scenario`` metadata record (every run and
    campaign writes it).  Raises ArchiveError (prefixed with ``source``) when there is none."""
    text = metadata.get("scenario", {}).get("resolved_json")
    if not text:
        prefix = "" if source is None else f"{source}: "
        raise ArchiveError(f"{prefix}no scenario in the archive's metadata")
    return Scenario.model_validate_json(text)


def archived_scenario(path: str | Path) -> Scenario:
    """The scenario of the archive at ``path``, read from its summary section (no message is
    read), or, for a file without one (its writer was killed: a restarted recorder's first
    segment), from the metadata records before its first chunk.  Raises ArchiveError for an
    archive whose metadata cannot be read or holds no scenario."""
    try:
        with open(path, "rb") as f:
            metadata = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    except (OSError, McapError, ValueError) as e:
        metadata = _leading_metadata(path, e)
    return scenario_from_metadata(metadata, path)


def _leading_metadata(path: str | Path, cause: Exception) -> dict[str, dict[str, str]]:
    """The metadata records written before the file's first chunk or message (where the
    recorder writes the run's), read in file order; ArchiveError (from ``cause``, why the
    summary could not be read) if none can be."""
    out: dict[str, dict[str, str]] = {}
    try:
        with open(path, "rb") as f:
            for rec in StreamReader(f, skip_magic=False, emit_chunks=True).records:
                if isinstance(rec, (Chunk, Message)):
                    break
                if isinstance(rec, Metadata):
                    out[rec.name] = dict(rec.metadata)
    except (OSError, McapError, ValueError, struct.error):  # cut inside a record
        pass
    if not out:
        raise ArchiveError(f"{path}: metadata unreadable: {cause}") from cause
    return out
