"""Reading a run archive written by :class:`ground.archive.recorder.McapRecorder`.

:func:`load_run` reads the whole MCAP file **sequentially** (``mcap.stream_reader.StreamReader``)
rather than through the summary/index at the end, so one code path serves a finished file and a
file whose writer was killed:

* a finished file is read up to its footer and closing magic: ``truncated=False``;
* an unfinished file (no summary, no footer; the recorder was SIGKILLed) is read record by record
  until the first record that is incomplete or damaged; everything before it is kept and
  ``truncated=True`` (``stop_reason`` says why reading stopped, and at which byte: the end of
  the last record read whole, :attr:`SegmentInfo.cut_at_byte`; a warning is logged naming it
  and the sim time the archive then ends at).  Because the recorder writes
  messages only inside chunks and a chunk is decoded (decompressed and CRC-checked) as a whole
  before any of its messages is taken, the recovered messages are exactly those of the complete
  chunks (a chunk cut short fails its length, zstd frame or CRC check and is dropped whole).
  Two guards make the stop explicit: every read must return the number of bytes asked for
  (``mcap``'s ``ReadDataStream`` treats only an *empty* read as the end of the file, so a record
  whose last field is cut could otherwise come back shorter), and a record may not claim to be
  longer than the file (no giant allocation from a garbage length).
* a file that does not start with the MCAP magic raises :class:`ArchiveError`.

The archive is held in memory: :class:`Record` s ordered by log time (mission elapsed time, ns),
ties in file order; :attr:`RunArchive.end_s` is the sim time of its last message (streamed ones
included), where a cut archive's data ends.  Keys given to ``load_run(stream=...)`` are not held:
their records go, in file order, to a sink as they are read (a two-orbit run's camera images alone
are 1.7 GB of JSON); they are counted all the same.  Records are filtered by key expression with
:func:`interfaces.contracts.topics.matches` (``*`` one chunk, ``**`` any number) and decoded
through the message registry on demand.

A run whose recorder was restarted is archived in segments (``run.mcap``, ``run-1.mcap``, ...:
:mod:`ground.archive.segments`); :func:`load_run` given the first reads them all, in order, as
one run.  Each segment is read as above (a killed recorder's is truncated, and a later one
that is not MCAP at all is reported, not raised); the records of every segment are merged in
log-time order, ties in segment then file order; a message a later segment repeats (its key,
sequence number and sim time) is kept once; the messages lost between (in flight when the
recorder died, sent while it was down) are counted per key from the gaps in the sequence
numbers (:mod:`harness.archive.sequences`).
"""

from __future__ import annotations

import io
import logging
import os
import struct
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from operator import attrgetter
from pathlib import Path
from typing import IO, Final, TypeVar, overload

import numpy as np
import zstandard
from mcap.data_stream import ReadDataStream
from mcap.exceptions import EndOfFile, McapError, RecordLengthLimitExceeded
from mcap.opcode import Opcode
from mcap.reader import make_reader
from mcap.records import (
    Channel,
    Chunk,
    Footer,
    Header,
    Metadata,
    Schema,
)
from mcap.records import Message as McapMessage
from mcap.stream_reader import StreamReader, get_chunk_data_stream
from pydantic import ValidationError

from ground.archive.segments import SEGMENT_RECORD, segment_paths
from harness.archive.sequences import SequenceLedger
from interfaces.contracts.catalogue import TICK, Topic, topic_of
from interfaces.contracts.errors import reason
from interfaces.contracts.messages import Message, registry
from interfaces.contracts.topics import matches

MCAP_MAGIC: Final = b"\x89MCAP0\r\n"

log = logging.getLogger("insp.archive")

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

    def decode(self, model: type[M]) -> M:
        """Decode the payload as ``model`` (:class:`ArchiveError` if it does not validate)."""
        return _decode(self, model)


@dataclass(frozen=True, slots=True)
class SchemaInfo:
    """A schema record of the archive."""

    name: str
    encoding: str
    data: bytes


@dataclass(frozen=True, slots=True)
class SegmentInfo:
    """One file of a run's archive as read back (``ground/archive/segments.py``)."""

    path: Path
    truncated: bool
    """It ends before its footer, or in a damaged record (what precedes is kept)."""
    stop_reason: str | None
    """Why reading it stopped early (None: read to its footer)."""
    cut_at_byte: int | None = None
    """Where reading stopped: the offset (bytes) just past its last record read whole, what is
    kept (None: read to its footer, or not read at all)."""
    size_bytes: int | None = None
    """Its size when read (bytes; None: not read)."""


def _decode(record: Record, model: type[M]) -> M:
    """``model.model_validate_json(record.payload)``, with errors as :class:`ArchiveError`."""
    try:
        return model.model_validate_json(record.payload)
    except ValidationError as exc:
        raise ArchiveError(
            f"{record.key} at {record.log_time_ns} ns: payload is not a valid "
            f"{model.__name__}: {reason(exc)}"
        ) from exc


RecordSink = Callable[["Record"], None]
"""Receives a streamed record (``load_run(stream=...)``)."""


def _stop_reason(segments: list[SegmentInfo]) -> str | None:
    """Why the first truncated segment stopped early, naming it when there are several."""
    cut = next((s for s in segments if s.truncated), None)
    if cut is None:
        return None
    return cut.stop_reason if len(segments) == 1 else f"{cut.path.name}: {cut.stop_reason}"


class RunArchive:
    """The content of one run archive, every segment of it (see the module docstring).

    Attributes: ``path`` (the first segment), ``metadata`` (name -> {key: value}; a later
    record with the same name replaces an earlier one; a later segment adds only the names the
    earlier lack), ``schemas`` (name -> :class:`SchemaInfo`), ``segments`` (each file read,
    :class:`SegmentInfo`), ``truncated`` (some segment is), ``stop_reason`` (the first
    truncated segment's, named when there are several; None when none is), ``lost`` (messages
    lost per key, from the sequence numbers: ``harness/archive/sequences.py``), ``duplicates``
    (messages a later segment repeated, kept once), ``library`` and ``profile`` of the header,
    ``end_s`` (the sim time of its last message, s).
    """

    def __init__(
        self,
        path: Path,
        records: list[Record],
        channel_types: dict[str, list[str]],
        metadata: dict[str, dict[str, str]],
        schemas: dict[str, SchemaInfo],
        segments: list[SegmentInfo],
        library: str,
        profile: str,
        streamed: dict[str, int] | None = None,
        lost: dict[str, int] | None = None,
        duplicates: int = 0,
        end_ns: int | None = None,
    ) -> None:
        """Build from parsed content; ``records`` must already be in log-time order;
        ``streamed``: records per key handed to a sink at load and not held; ``end_ns``: the
        latest log time of every record read, streamed ones too (ns; default: the last held
        record's)."""
        self.path = path
        self.metadata = metadata
        self.schemas = schemas
        self.segments = segments
        self.truncated = any(s.truncated for s in segments)
        self.stop_reason = _stop_reason(segments)
        self.lost = dict(lost or {})
        self.duplicates = duplicates
        self.library = library
        self.profile = profile
        self._records = records
        self._channel_types = channel_types
        self._match_cache: dict[str, frozenset[str]] = {}
        self._decoded: dict[tuple[str, type[Message]], list[Message]] = {}
        self._streamed = dict(streamed or {})
        self._end_ns = end_ns if end_ns is not None else (
            records[-1].log_time_ns if records else None)

    @property
    def end_s(self) -> float | None:
        """Sim time of the archive's last message (s): where its data ends, the run's end for a
        whole archive.  None when it holds no message."""
        return None if self._end_ns is None else self._end_ns / 1e9

    def __len__(self) -> int:
        return len(self._records) + sum(self._streamed.values())

    def __repr__(self) -> str:
        state = f"truncated ({self.stop_reason})" if self.truncated else "complete"
        return f"RunArchive({str(self.path)!r}, {len(self._records)} records, {state})"

    def mission(self) -> str:
        """The run's mission (key-space name), from its lockstep ticks' key; ArchiveError when
        no tick was archived (streamed ticks count: their keys are known)."""
        tick = next((k for k in self.topics() if topic_of(k) is TICK), None)
        if tick is None:
            raise ArchiveError(f"{self.path}: no lockstep ticks archived: its mission is unknown")
        return tick.split("/")[1]

    def topics(self) -> dict[str, tuple[str, int]]:
        """Key -> (type name, message count), keys sorted.

        A key recorded with more than one type name (a misbehaving sender) shows the sorted
        type names joined by ``"|"``.
        """
        counts: dict[str, int] = dict.fromkeys(self._channel_types, 0)
        counts.update(self._streamed)
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
        file order.  Keys streamed at load are not held: asking for one raises ArchiveError."""
        gone = [k for k in self._streamed if matches(key_expr, k)]
        if gone:
            raise ArchiveError(f"{gone[0]} was streamed when the archive was read, not kept "
                               f"(load_run(stream=...)); read the file again without it")
        if key_expr == "**":
            return list(self._records)
        keys = self._keys_matching(key_expr)
        return [r for r in self._records if r.key in keys]

    def held(self) -> list[Record]:
        """Every record held, by log time then file order (those of streamed keys are not)."""
        return list(self._records)

    def of(self, topic: Topic[M], mission: str) -> list[M]:
        """Decoded messages of a catalogued topic from every publisher of ``mission``."""
        return self.messages(topic.every(mission), topic.type)

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
        self.offset = 0
        """Bytes read so far: the offset of the next byte."""

    def read(self, n: int = -1) -> bytes:
        """Read exactly ``n`` bytes (``n < 0``: the rest of the file)."""
        data = self._file.read(n)
        if n >= 0 and len(data) != n:
            raise EndOfFile()
        self.offset += len(data)
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


_U64 = struct.Struct("<Q")
_MESSAGE_HEAD = struct.Struct("<HIQQ")
"""A Message record's fixed fields: channel id, sequence, log time, publish time (MCAP spec)."""

_ChunkItem = tuple[int, int, int, int, bytes] | Channel | Schema
"""What a chunk holds: a message as (channel id, sequence, log time, publish time, data), or a
record."""


def _chunk_items(chunk: Chunk) -> list[_ChunkItem]:
    """The records of a chunk, decompressed and CRC-checked by the mcap library, split here with
    one ``struct`` call per message (the library's per-field reads cost ~15 µs a message, most
    of a long run's reading time).  A record that overruns the chunk raises: the chunk is
    damaged and dropped whole."""
    stream, size = get_chunk_data_stream(chunk, validate_crc=True)
    data = stream.read(size)
    items: list[_ChunkItem] = []
    pos = 0
    while pos < size:
        opcode = data[pos]
        (length,) = _U64.unpack_from(data, pos + 1)
        start, pos = pos + 9, pos + 9 + length
        if pos > size:
            raise McapError("a record overruns its chunk")
        if opcode == Opcode.MESSAGE:
            channel_id, sequence, log_time, publish_time = _MESSAGE_HEAD.unpack_from(data, start)
            items.append((channel_id, sequence, log_time, publish_time,
                          data[start + _MESSAGE_HEAD.size:pos]))
        elif opcode in (Opcode.CHANNEL, Opcode.SCHEMA):
            body = ReadDataStream(io.BytesIO(data[start:pos]))
            items.append(Channel.read(body) if opcode == Opcode.CHANNEL else Schema.read(body))
    return items


class RecordLoader:
    """The state of one archive read: channels, schemas, kept records, streamed counts and the
    sequence accounting (fed record by record from the files of a run here, segment by segment,
    or sample by sample as a run is recorded: ``harness.archive.live``)."""

    def __init__(self, sinks: Mapping[str, RecordSink | None]) -> None:
        self.sinks = dict(sinks)
        self.schemas_by_id: dict[int, Schema] = {}
        """The schemas of the segment being read, by their id in it."""
        self.schemas: dict[str, SchemaInfo] = {}
        """The schemas of the segments read before, by name."""
        self.channels: dict[int, tuple[str, str, RecordSink | None]] = {}
        self.channel_types: dict[str, list[str]] = {}
        self.metadata: dict[str, dict[str, str]] = {}
        self.records: list[Record] = []
        self.streamed: dict[str, int] = {}
        self.sequences = SequenceLedger()
        self.header: Header | None = None
        self.footer_seen = False
        self.segment = -1
        """Index of the segment being read (-1 before the first)."""
        self.end_ns: int | None = None
        """The latest log time taken so far (ns; None before the first message)."""

    def begin_segment(self, more_follow: bool) -> None:
        """Start reading the next file of the run (its channel and schema ids are its own);
        ``more_follow``: another file comes after it."""
        self.schemas.update(self._schema_infos())
        self.schemas_by_id, self.channels = {}, {}
        self.footer_seen = False
        self.segment += 1
        self.sequences.begin_segment(more_follow)

    def message(self, channel_id: int, sequence: int, log_time: int, publish_time: int,
                data: bytes) -> str | None:
        """Keep or stream one message; a stop reason if its channel is unknown."""
        channel = self.channels.get(channel_id)
        if channel is None:  # a message before its channel: not MCAP-conformant
            return f"message on unknown channel {channel_id}"
        self.take(Record(channel[0], channel[1], log_time, publish_time, data), channel[2],
                  sequence)
        return None

    def take(self, record: Record, sink: RecordSink | None, sequence: int = 0) -> None:
        """Keep ``record``, or hand it to its key's ``sink`` (counted, not kept); a duplicate of
        a record of an earlier segment (its key, ``sequence`` and log time) is dropped."""
        if not self.sequences.admit(record.key, sequence, record.log_time_ns):
            return
        if self.end_ns is None or record.log_time_ns > self.end_ns:
            self.end_ns = record.log_time_ns
        if sink is None:
            self.records.append(record)
        else:
            self.streamed[record.key] = self.streamed.get(record.key, 0) + 1
            sink(record)

    def sink_of(self, key: str) -> RecordSink | None:
        """The sink of ``key`` (the first matching expression), or None to keep its records
        (also where the first matching expression's sink is None)."""
        return next((f for e, f in self.sinks.items() if matches(e, key)), None)

    def end_record(self, rec: object) -> None:
        """A record of the file (a chunk: every item of it) was taken whole."""

    def _schema_infos(self) -> dict[str, SchemaInfo]:
        return {s.name: SchemaInfo(s.name, s.encoding, s.data)
                for s in self.schemas_by_id.values()}

    def archive(self, path: Path, segments: list[SegmentInfo]) -> RunArchive:
        """The archive read so far (records put in log-time order, ties in file order);
        ``path``: its first segment; ``segments``: the files read."""
        self.records.sort(key=attrgetter("log_time_ns"))
        header = self.header
        return RunArchive(
            path=path, records=self.records, channel_types=self.channel_types,
            metadata=self.metadata, schemas={**self.schemas, **self._schema_infos()},
            segments=segments, library=header.library if header is not None else "",
            profile=header.profile if header is not None else "", streamed=self.streamed,
            lost=self.sequences.lost, duplicates=self.sequences.duplicates, end_ns=self.end_ns)

    def item(self, rec: object) -> str | None:
        """Take one record or chunk item; a stop reason if reading must stop."""
        if isinstance(rec, tuple):
            return self.message(*rec)
        if isinstance(rec, McapMessage):
            return self.message(rec.channel_id, rec.sequence, rec.log_time, rec.publish_time,
                                rec.data)
        if isinstance(rec, Channel):
            self._channel(rec)
        elif isinstance(rec, Schema):
            self.schemas_by_id[rec.id] = rec
        elif isinstance(rec, Metadata):
            self._metadata(rec)
        elif isinstance(rec, Header):
            self.header = self.header or rec
        elif isinstance(rec, Footer):
            self.footer_seen = True
        return None

    def _channel(self, rec: Channel) -> None:
        """Register a channel of the segment (its key's type names are the run's)."""
        schema = self.schemas_by_id.get(rec.schema_id)
        type_name = schema.name if schema is not None else ""
        if rec.id not in self.channels:
            types = self.channel_types.setdefault(rec.topic, [])
            if self.segment <= 0 or type_name not in types:
                types.append(type_name)
        self.channels[rec.id] = (rec.topic, type_name, self.sink_of(rec.topic))

    def _metadata(self, rec: Metadata) -> None:
        """The first segment's records, then only the names a later one adds (its own
        ``segment`` record aside)."""
        if self.segment <= 0:
            self.metadata[rec.name] = dict(rec.metadata)
        elif rec.name != SEGMENT_RECORD:
            self.metadata.setdefault(rec.name, dict(rec.metadata))


def _read_records(reader: StreamReader, loader: RecordLoader, source: _ExactReader
                  ) -> tuple[str | None, int]:
    """Feed every record of the file to ``loader``; the reason reading stopped early, if it
    did (a chunk is taken whole or not at all), and the offset just past the last record
    taken whole (bytes)."""
    stream = iter(reader.records)
    kept = 0
    while True:
        try:
            rec = next(stream)
            items = _chunk_items(rec) if isinstance(rec, Chunk) else [rec]
        except StopIteration:
            return None, kept
        except (EndOfFile, RecordLengthLimitExceeded):  # the limit is the file size
            return "file ends before its footer (writer killed or still running)", kept
        except _READ_ERRORS as exc:
            return f"damaged record: {type(exc).__name__}: {exc}", kept
        for item in items:
            stop = loader.item(item)
            if stop is not None:
                return stop, kept
        loader.end_record(rec)
        kept = source.offset


def _read_segment(path: Path, loader: RecordLoader) -> SegmentInfo:
    """Read one file of a run into ``loader``; a file cut short is read up to its cut, which a
    warning names.  Raises :class:`ArchiveError` if it is not MCAP, ``OSError`` if it cannot be
    read."""
    with open(path, "rb") as file:
        head = file.read(len(MCAP_MAGIC))
        if head != MCAP_MAGIC:
            raise ArchiveError(
                f"{path}: not an MCAP file (starts with {head!r}, expected {MCAP_MAGIC!r})"
            )
        reader, source, size = _records_of(file)
        stop_reason, kept = _read_records(reader, loader, source)
    if stop_reason is None and not loader.footer_seen:  # pragma: no cover - StreamReader
        stop_reason = "no footer"  # stops at the footer
    if stop_reason is None:
        return SegmentInfo(path, False, None, size_bytes=size)
    _warn_cut(path, stop_reason, kept, size, loader.end_ns)
    return SegmentInfo(path, True, stop_reason, cut_at_byte=kept, size_bytes=size)


def _records_of(file: IO[bytes]) -> tuple[StreamReader, _ExactReader, int]:
    """A reader of the records of ``file`` from its start (chunks not expanded), the exact
    reader under it (its offset: the bytes read) and the file's size (bytes)."""
    file.seek(0)
    size = os.fstat(file.fileno()).st_size
    source = _ExactReader(file)
    reader = StreamReader(source,  # type: ignore[arg-type]  # duck-typed binary stream
                          skip_magic=False, emit_chunks=True, validate_crcs=True,
                          record_size_limit=max(size, 1))
    return reader, source, size


_RECORD_HEAD = struct.Struct("<BQ")
"""A record's opcode and body length (MCAP spec: every record outside the magic)."""
_INDEX_HEAD = struct.Struct("<HI")
"""A message index's channel id and the byte length of its (log time, offset) pairs."""
_LOOSE_HEAD = struct.Struct("<HIQ")
"""A message's channel id, sequence and log time."""
UnitTimes = list[tuple[int, int]]
"""One chunk's (or loose message's) first log time per channel id, (channel id, ns); a
channel id of -1 stands for every channel of a chunk whose message indexes are missing."""


def unit_times(path: Path) -> list[UnitTimes]:
    """For each chunk of ``path`` (and each message outside one), in file order, the first log
    time of its messages on each channel: from the message indexes written after the chunk, or
    the chunk's own start time for all its channels where they are missing.  Each record's head
    is read and its body skipped (nothing decompressed), as far as whole records reach (nothing
    for a file that is not MCAP or cannot be read; the full read says why)."""
    units: list[UnitTimes] = []
    indexing = False  # reading the message indexes after a chunk
    try:
        with open(path, "rb") as file:
            if file.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
                return units
            size, pos = os.fstat(file.fileno()).st_size, len(MCAP_MAGIC)
            while pos + _RECORD_HEAD.size <= size:
                opcode, length = _RECORD_HEAD.unpack(file.read(_RECORD_HEAD.size))
                pos += _RECORD_HEAD.size + length
                if opcode == Opcode.FOOTER:  # a whole file: every chunk's indexes written
                    indexing = False
                    break
                if pos > size:
                    break
                body = file.read(length) if opcode != Opcode.CHUNK else file.read(8)
                indexing = _take_unit(units, opcode, body, indexing)
                file.seek(pos)
    except (OSError, struct.error):
        pass
    cut = len(units) - 1 if indexing else -1  # its indexes may have been cut: keep its start
    return [u[1:] if len(u) > 1 and i != cut and u[0][0] == -1 else u
            for i, u in enumerate(units)]


def summary_topics(path: Path) -> dict[int, str]:
    """The topic of each channel id of ``path``, from its summary section (read from the end of
    the file, no message read); empty for a file without one (its writer was killed)."""
    try:
        with open(path, "rb") as file:
            summary = make_reader(file).get_summary()
    except (OSError, *_READ_ERRORS):
        return {}
    return {} if summary is None else {i: c.topic for i, c in summary.channels.items()}


def _take_unit(units: list[UnitTimes], opcode: int, body: bytes, indexing: bool) -> bool:
    """Note one record's times in ``units``; whether message indexes of a chunk may follow."""
    if opcode == Opcode.CHUNK:
        units.append([(-1, _U64.unpack_from(body)[0])])
        return True
    if opcode == Opcode.MESSAGE_INDEX and indexing:
        channel, nbytes = _INDEX_HEAD.unpack_from(body)
        times = np.frombuffer(body, "<u8", count=nbytes // 8, offset=_INDEX_HEAD.size)[0::2]
        if times.size:  # after the chunk's start time, which they stand for once complete
            units[-1].append((channel, int(times.min())))
        return True
    if opcode == Opcode.MESSAGE:
        channel, _seq, log_time = _LOOSE_HEAD.unpack_from(body)
        units.append([(channel, log_time)])
    return False


def _warn_cut(path: Path, reason: str, kept: int, size: int, end_ns: int | None) -> None:
    """Log where a file cut short stops: the byte its records were read whole up to, of its
    size, and the sim time its run's data then ends at."""
    ends = "no message" if end_ns is None else f"its data ends at t = {end_ns / 1e9:.1f} s"
    log.warning("%s: %s; read up to byte %d of %d, what precedes kept (%s)",
                path, reason, kept, size, ends)


def _read_later_segment(path: Path, loader: RecordLoader) -> SegmentInfo:
    """:func:`_read_segment` for a segment after the first: one that is not MCAP (a recorder
    that died before writing its header) or cannot be read is reported, not raised."""
    try:
        return _read_segment(path, loader)
    except (ArchiveError, OSError) as exc:
        return SegmentInfo(path, True, str(exc))


def load_run(path: str | Path, stream: Mapping[str, RecordSink | None] | None = None
             ) -> RunArchive:
    """Read a run archive (complete or cut short by a kill), every segment of it: ``path``
    (``run.mcap``) and the segments after it (``run-1.mcap``, ...:
    :func:`ground.archive.segments.segment_paths`), as one run; see the module docstring.

    ``stream`` maps key expressions to sinks: a record of a matching key (the first matching
    expression decides) goes to its sink as it is read, in file order, and is not kept; an
    expression mapped to None keeps its records (before a broader one that streams).
    :func:`harness.archive.stream.stream_run` hands them on in time order instead.

    Raises :class:`ArchiveError` if the (first) file is not MCAP, ``OSError`` if it cannot be
    read.
    """
    paths = segment_paths(path)
    return read_segments(paths, RecordLoader(stream or {}))


def read_segments(paths: list[Path], loader: RecordLoader) -> RunArchive:
    """The files of one run (its first, then each later segment) read into ``loader``, as
    :func:`load_run` reads them."""
    segments = []
    for index, segment in enumerate(paths):
        loader.begin_segment(more_follow=index + 1 < len(paths))
        read = _read_segment if index == 0 else _read_later_segment
        segments.append(read(segment, loader))
    return loader.archive(paths[0], segments)


__all__ = ["ArchiveError", "MCAP_MAGIC", "Record", "RecordLoader", "RecordSink", "RunArchive",
           "SchemaInfo", "SegmentInfo", "load_run", "read_segments", "summary_topics", "unit_times"]
