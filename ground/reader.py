"""Reading a run archive written by :class:`ground.recorder.McapRecorder`.

:func:`load_run` reads the whole MCAP file **sequentially** (``mcap.stream_reader.StreamReader``)
rather than through the summary/index at the end, so one code path serves a finished file and a
file whose writer was killed:

* a finished file is read up to its footer and closing magic: ``truncated=False``;
* an unfinished file (no summary, no footer; the recorder was SIGKILLed) is read record by record
  until the first record that is incomplete or damaged; everything before it is kept and
  ``truncated=True`` (``stop_reason`` says why reading stopped).  Because the recorder writes
  messages only inside chunks and a chunk is decoded (decompressed and CRC-checked) as a whole
  before any of its messages is taken, the recovered messages are exactly those of the complete
  chunks (a chunk cut short fails its length, zstd frame or CRC check and is dropped whole).
  Two guards make the stop explicit: every read must return the number of bytes asked for
  (``mcap``'s ``ReadDataStream`` treats only an *empty* read as the end of the file, so a record
  whose last field is cut could otherwise come back shorter), and a record may not claim to be
  longer than the file (no giant allocation from a garbage length).
* a file that does not start with the MCAP magic raises :class:`ArchiveError`.

The archive is held in memory: :class:`Record` s ordered by log time (mission elapsed time, ns),
ties in file order.  Records are filtered by key expression with
:func:`interfaces.topics.matches` (``*`` one chunk, ``**`` any number) and decoded through the
message registry on demand.
"""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass
from operator import attrgetter
from pathlib import Path
from typing import IO, Final, TypeVar, overload

import zstandard
from mcap.exceptions import EndOfFile, McapError, RecordLengthLimitExceeded
from mcap.records import Channel, Footer, Header, Message as McapMessage, Metadata, Schema
from mcap.stream_reader import StreamReader
from pydantic import ValidationError

from interfaces.messages import Message, registry
from interfaces.topics import matches

MCAP_MAGIC: Final = b"\x89MCAP0\r\n"

M = TypeVar("M", bound=Message)


class ArchiveError(Exception):
    """The file is not an MCAP archive, or a record cannot be decoded as its message type."""


@dataclass(frozen=True, slots=True)
class Record:
    """One archived bus sample: its key, message type name, times (ns) and raw JSON payload."""

    key: str
    type_name: str
    log_time_ns: int
    """Sim time of the message (ns of mission elapsed time), as chosen by the recorder."""
    publish_time_ns: int
    """Wall clock at receipt by the recorder, UNIX ns."""
    payload: bytes

    def message(self) -> Message:
        """Decode the payload with the registry model of :attr:`type_name`.

        Raises :class:`ArchiveError` for a type name not in the registry or a payload that does
        not validate (the pydantic error is chained).
        """
        model = registry().get(self.type_name)
        if model is None:
            raise ArchiveError(f"{self.key}: unknown message type {self.type_name!r}")
        return _decode(self, model)


@dataclass(frozen=True, slots=True)
class SchemaInfo:
    """A schema record of the archive."""

    name: str
    encoding: str
    data: bytes


def _decode(record: Record, model: type[M]) -> M:
    """``model.model_validate_json(record.payload)``, with errors as :class:`ArchiveError`."""
    try:
        return model.model_validate_json(record.payload)
    except ValidationError as exc:
        raise ArchiveError(
            f"{record.key} at {record.log_time_ns} ns: payload is not a valid "
            f"{model.__name__}: {exc.error_count()} error(s)"
        ) from exc


class RunArchive:
    """The content of one run archive (see the module docstring).

    Attributes: ``path``, ``metadata`` (name -> {key: value}; a later record with the same name
    replaces an earlier one), ``schemas`` (name -> :class:`SchemaInfo`), ``truncated``,
    ``stop_reason`` (None for a complete file), ``library`` and ``profile`` of the header.
    """

    def __init__(
        self,
        path: Path,
        records: list[Record],
        channel_types: dict[str, list[str]],
        metadata: dict[str, dict[str, str]],
        schemas: dict[str, SchemaInfo],
        truncated: bool,
        stop_reason: str | None,
        library: str,
        profile: str,
    ) -> None:
        """Build from parsed content; ``records`` must already be in log-time order."""
        self.path = path
        self.metadata = metadata
        self.schemas = schemas
        self.truncated = truncated
        self.stop_reason = stop_reason
        self.library = library
        self.profile = profile
        self._records = records
        self._channel_types = channel_types
        self._match_cache: dict[str, frozenset[str]] = {}
        self._decoded: dict[tuple[str, type[Message]], list[Message]] = {}

    def __len__(self) -> int:
        return len(self._records)

    def __repr__(self) -> str:
        state = f"truncated ({self.stop_reason})" if self.truncated else "complete"
        return f"RunArchive({str(self.path)!r}, {len(self._records)} records, {state})"

    def topics(self) -> dict[str, tuple[str, int]]:
        """Key -> (type name, message count), keys sorted.

        A key recorded with more than one type name (a misbehaving sender) shows the sorted
        type names joined by ``"|"``.
        """
        counts: dict[str, int] = dict.fromkeys(self._channel_types, 0)
        for rec in self._records:
            counts[rec.key] += 1
        return {
            key: ("|".join(sorted(set(self._channel_types[key]))), counts[key])
            for key in sorted(counts)
        }

    def _keys_matching(self, key_expr: str) -> frozenset[str]:
        keys = self._match_cache.get(key_expr)
        if keys is None:
            keys = frozenset(k for k in self._channel_types if matches(key_expr, k))
            self._match_cache[key_expr] = keys
        return keys

    def records(self, key_expr: str = "**") -> list[Record]:
        """Records whose key matches ``key_expr`` (e.g. ``"insp/m/sc/*/**"``), by log time then
        file order."""
        if key_expr == "**":
            return list(self._records)
        keys = self._keys_matching(key_expr)
        return [r for r in self._records if r.key in keys]

    @overload
    def messages(
        self, key_expr: str, msg_type: type[M], *, skip_invalid: bool = False
    ) -> list[M]: ...

    @overload
    def messages(
        self, key_expr: str = "**", msg_type: str | None = None, *, skip_invalid: bool = False
    ) -> list[Message]: ...

    def messages(
        self,
        key_expr: str = "**",
        msg_type: type[Message] | str | None = None,
        *,
        skip_invalid: bool = False,
    ) -> list[Message]:
        """Decoded messages of the matching keys, by log time then file order (decoded once per
        key expression and type: later calls return the same immutable messages in a new list).

        ``msg_type`` (a model class or a type name) keeps only records of that type and decodes
        them with it; None decodes every matching record through the registry.  A record that
        does not decode (unknown type, invalid payload) raises :class:`ArchiveError` unless
        ``skip_invalid``.
        """
        selected = self.records(key_expr)
        model: type[Message] | None = None
        if isinstance(msg_type, str):
            model = registry().get(msg_type)
            if model is None:
                raise ArchiveError(f"unknown message type {msg_type!r}")
        elif msg_type is not None:
            model = msg_type
        out: list[Message] = []
        if model is not None:
            cached = self._decoded.get((key_expr, model))
            if cached is not None:  # messages are immutable: the summary and report share them
                return list(cached)
            name = model.__name__
            complete = True
            for rec in selected:
                if rec.type_name != name:
                    continue
                try:
                    out.append(_decode(rec, model))
                except ArchiveError:
                    complete = False
                    if not skip_invalid:
                        raise
            if complete:
                self._decoded[(key_expr, model)] = out
            return list(out)
        models = registry()
        for rec in selected:
            rec_model = models.get(rec.type_name)
            try:
                if rec_model is None:
                    raise ArchiveError(f"{rec.key}: unknown message type {rec.type_name!r}")
                out.append(_decode(rec, rec_model))
            except ArchiveError:
                if not skip_invalid:
                    raise
        return out


class _ExactReader:
    """File wrapper whose ``read(n)`` returns exactly ``n`` bytes or raises ``EndOfFile``.

    ``mcap``'s ``ReadDataStream`` only treats an *empty* read as the end of the file; a short
    read would turn a record cut by a kill into a shorter, wrong record.
    """

    def __init__(self, file: IO[bytes]) -> None:
        self._file = file

    def read(self, n: int = -1) -> bytes:
        """Read exactly ``n`` bytes (``n < 0``: the rest of the file)."""
        data = self._file.read(n)
        if n >= 0 and len(data) != n:
            raise EndOfFile()
        return data


_READ_ERRORS: Final = (
    McapError,  # EndOfFile, InvalidMagic, RecordLengthLimitExceeded, unsupported compression
    ValueError,  # CRC mismatch, bad UTF-8 in strings, bad enum values
    struct.error,
    zstandard.ZstdError,
    OverflowError,
    MemoryError,
)
"""What a damaged or cut MCAP stream can raise while being parsed."""


def load_run(path: str | Path) -> RunArchive:
    """Read a run archive (complete or cut short by a kill); see the module docstring.

    Raises :class:`ArchiveError` if the file is not MCAP, ``OSError`` if it cannot be read.
    """
    path = Path(path)
    with open(path, "rb") as file:
        head = file.read(len(MCAP_MAGIC))
        if head != MCAP_MAGIC:
            raise ArchiveError(
                f"{path}: not an MCAP file (starts with {head!r}, expected {MCAP_MAGIC!r})"
            )
        file.seek(0)
        size = os.fstat(file.fileno()).st_size
        reader = StreamReader(
            _ExactReader(file),  # type: ignore[arg-type]  # duck-typed binary stream
            skip_magic=False,
            emit_chunks=False,
            validate_crcs=True,
            record_size_limit=max(size, 1),
        )

        schemas_by_id: dict[int, Schema] = {}
        channels: dict[int, tuple[str, str]] = {}  # id -> (topic, schema name)
        channel_types: dict[str, list[str]] = {}
        metadata: dict[str, dict[str, str]] = {}
        records: list[Record] = []
        header: Header | None = None
        footer_seen = False
        stop_reason: str | None = None

        stream = iter(reader.records)
        while True:
            try:
                rec = next(stream)
            except StopIteration:
                break
            except (EndOfFile, RecordLengthLimitExceeded):  # the limit is the file size
                stop_reason = "file ends before its footer (writer killed or still running)"
                break
            except _READ_ERRORS as exc:
                stop_reason = f"damaged record: {type(exc).__name__}: {exc}"
                break
            if isinstance(rec, McapMessage):
                channel = channels.get(rec.channel_id)
                if channel is None:  # a message before its channel: not MCAP-conformant
                    stop_reason = f"message on unknown channel {rec.channel_id}"
                    break
                records.append(
                    Record(channel[0], channel[1], rec.log_time, rec.publish_time, rec.data)
                )
            elif isinstance(rec, Channel):
                schema = schemas_by_id.get(rec.schema_id)
                type_name = schema.name if schema is not None else ""
                if rec.id not in channels:
                    channel_types.setdefault(rec.topic, []).append(type_name)
                channels[rec.id] = (rec.topic, type_name)
            elif isinstance(rec, Schema):
                schemas_by_id[rec.id] = rec
            elif isinstance(rec, Metadata):
                metadata[rec.name] = dict(rec.metadata)
            elif isinstance(rec, Header):
                header = rec
            elif isinstance(rec, Footer):
                footer_seen = True

    truncated = stop_reason is not None or not footer_seen
    if truncated and stop_reason is None:  # pragma: no cover - StreamReader stops at the footer
        stop_reason = "no footer"
    records.sort(key=attrgetter("log_time_ns"))  # stable: ties keep file order
    schemas = {s.name: SchemaInfo(s.name, s.encoding, s.data) for s in schemas_by_id.values()}
    return RunArchive(
        path=path,
        records=records,
        channel_types=channel_types,
        metadata=metadata,
        schemas=schemas,
        truncated=truncated,
        stop_reason=stop_reason,
        library=header.library if header is not None else "",
        profile=header.profile if header is not None else "",
    )


__all__ = ["ArchiveError", "MCAP_MAGIC", "Record", "RunArchive", "SchemaInfo", "load_run"]
