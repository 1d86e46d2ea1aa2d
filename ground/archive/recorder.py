"""MCAP recorder of a mission: every bus sample, as received, in one chunked zstd MCAP file.

The recorder process subscribes to ``insp/<mission>/**`` and hands each raw sample to
:meth:`McapRecorder.record` as ``(key, type_name, payload)``; ``payload`` is the JSON of the
message exactly as it travelled on the bus and is stored byte for byte (no re-encoding).

The file's layout (a channel per key, a schema per type name, log time = sim time, metadata) and
its crash safety are :mod:`ground.archive.mcap_file`'s.  Here, per sample: the log time is the
payload's ``t_sim`` in ns when it is usable (present, a finite non-negative number that fits
64-bit ns), else the last sim time seen; **publish time** = wall clock (UNIX ns) at receipt; the
MCAP ``sequence`` is the bus sequence count ``seq`` of the message (0 if absent).  A type name
not in the registry is recorded all the same and counted in :attr:`McapRecorder.unknown_type`.

Payloads that are not a JSON object (not JSON, NaN/Infinity, an array, ...) are stored as received
and counted in :attr:`McapRecorder.invalid`; payloads are not validated against their model here
(that is the reader's :meth:`~harness.archive.reader.Record.message`).

A killed recorder loses at most the chunk in progress (``chunk_size`` bytes of messages); call
:meth:`McapRecorder.flush` to close it early.
"""

from __future__ import annotations

import time
from collections import deque
from pathlib import Path
from types import TracebackType
from typing import Final

from pydantic_core import from_json

from ground.archive.flat_combining import FlatCombiner
from ground.archive.mcap_file import (
    LIBRARY,
    MESSAGE_ENCODING,
    PROFILE,
    SCHEMA_ENCODING,
    McapFile,
    Pending,
)
from interfaces.runtime.transport import Sample

_MAX_KEY_CHARS: Final = 1024
"""Longer keys are cut to this length (bounds memory under hostile keys)."""
_MAX_TYPE_CHARS: Final = 128
"""Longer type names are cut to this length (bounds memory under hostile type names)."""
_MAX_T_SIM_S: Final = 9.2e9
"""Largest sim time that still fits a signed 64-bit ns count."""
_MAX_U32: Final = 0xFFFFFFFF
_MAX_U64: Final = 0xFFFFFFFFFFFFFFFF
_MAX_PENDING: Final = 10_000
"""Samples waiting for the writing thread above which ``record`` blocks (back-pressure)."""


def prepare_sample(sample: Sample) -> Pending | None:
    """A sample that carries its validated message (in-process transport), ready to write: its
    sim time and sequence number are the message's own, its JSON bytes encoded once for every
    raw consumer.  None for bytes alone (or out-of-range times), which take
    :meth:`McapRecorder.record`'s path: parsed, never trusted."""
    msg = sample.message
    if msg is None or not 0.0 <= msg.t_sim <= _MAX_T_SIM_S or msg.seq > _MAX_U32:
        return None
    return (sample.key[:_MAX_KEY_CHARS], sample.type_name[:_MAX_TYPE_CHARS], sample.payload,
            None, True, round(msg.t_sim * 1e9), msg.seq, time.time_ns())


def prepared(sample: Sample) -> Pending:
    """``sample`` ready to write: :func:`prepare_sample`'s, or :func:`prepare_raw`'s for bytes
    alone."""
    pending = prepare_sample(sample)
    return pending if pending is not None else prepare_raw(sample.key, sample.type_name,
                                                           sample.payload)


def prepare_raw(key: str, type_name: str, payload: bytes) -> Pending:
    """A raw sample ready to write (its payload parsed for t_sim and seq, never trusted)."""
    is_object, t_ns, sequence = _parse_payload(payload)
    return (key[:_MAX_KEY_CHARS], type_name[:_MAX_TYPE_CHARS], payload, None, is_object, t_ns,
            sequence, time.time_ns())


def _parse_payload(payload: bytes) -> tuple[bool, int | None, int]:
    """Cheap look into a payload: (is a JSON object, t_sim in ns or None, MCAP sequence).

    ``t_sim`` is used only if it is a finite, non-negative number that fits 64-bit ns; the
    sequence is the message's ``seq`` if it is an int in uint32 range, else 0.
    """
    try:
        obj = from_json(payload, allow_inf_nan=False)
    except ValueError:
        return False, None, 0
    if not isinstance(obj, dict):
        return False, None, 0
    t_sim = obj.get("t_sim")
    t_ns: int | None = None
    if type(t_sim) is float or type(t_sim) is int:  # not bool
        if 0.0 <= t_sim <= _MAX_T_SIM_S:
            t_ns = round(t_sim * 1e9)
    seq = obj.get("seq")
    sequence = seq if type(seq) is int and 0 <= seq <= _MAX_U32 else 0
    return True, t_ns, sequence


def _check_metadata(name: str, data: dict[str, str]) -> dict[str, str]:
    """Validate a metadata record before it reaches the writer; return a plain-dict copy."""
    if not isinstance(name, str):
        raise TypeError(f"metadata name must be str, got {type(name).__name__}")
    if not isinstance(data, dict):
        raise TypeError(f"metadata {name!r} must be a dict[str, str], got {type(data).__name__}")
    out: dict[str, str] = {}
    for k, v in data.items():
        if not isinstance(k, str) or not isinstance(v, str):
            raise TypeError(
                f"metadata {name!r}: keys and values must be str, got {k!r}: {type(v).__name__}"
            )
        out[k] = v
    try:
        name.encode("utf-8")
        for k, v in out.items():
            k.encode("utf-8")
            v.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise ValueError(f"metadata {name!r} is not valid UTF-8 text: {exc}") from exc
    return out


class McapRecorder:
    """Thread-safe MCAP writer of raw bus samples (the file: :mod:`ground.archive.mcap_file`).

    Use as a context manager or call :meth:`close`; an unclosed file (process killed) is still
    readable up to its last complete chunk with :func:`harness.archive.reader.load_run`.

    Counters (read-only properties): :attr:`recorded`, :attr:`invalid`, :attr:`unknown_type`,
    :attr:`dropped`, :attr:`after_close`, :attr:`counts` (messages per key).

    Threads: :meth:`record` may be called from any number of threads.  When another thread is
    writing at that moment, the sample is handed to it (it is written before that thread lets go
    of the file: :mod:`ground.archive.flat_combining`) and ``record`` returns at once, so the
    counters can lag a concurrent ``record`` by a few microseconds; file order is the order in
    which samples were handed in, and one thread's samples keep their order.  :meth:`close`
    writes every sample handed in before it.
    """

    def __init__(
        self,
        path: str | Path,
        metadata: dict[str, dict[str, str]] | None = None,
        chunk_size: int = 4 * 1024 * 1024,
    ) -> None:
        """Create (truncate) ``path`` and start the MCAP file.

        ``metadata`` maps a record name to its key/value strings, e.g.
        ``{"run": {"scenario": ..., "seed": ..., "transport": ..., "version": ...},
        "scenario": {"toml": text}}``.  ``chunk_size`` is the uncompressed chunk size in bytes
        that triggers a chunk write (and bounds the data lost on a kill).  The default, 4 MiB,
        holds a camera image and the observations that repeat it in one compression window:
        zstd keeps that fact once, and the archive is half the size it is with 256 KiB chunks
        (and compresses faster).
        """
        if chunk_size <= 0:
            raise ValueError(f"chunk_size must be positive, got {chunk_size}")
        checked = {n: _check_metadata(n, d) for n, d in (metadata or {}).items()}
        self._path = Path(path)
        self._after_close = 0
        self._closed = False
        self._queue: FlatCombiner[Pending] = FlatCombiner(self._write_pending, _MAX_PENDING)
        self._file = McapFile(self._path, checked, chunk_size)

    # --- recording -----------------------------------------------------------------------------

    def record(
        self, key: str, type_name: str, payload: bytes, log_time_ns: int | None = None
    ) -> None:
        """Record one raw sample (thread-safe; never raises on hostile content).

        ``log_time_ns`` overrides the log time (default: the payload's ``t_sim`` in ns, else the
        last sim time seen).  After :meth:`close` the call is ignored and counted in
        :attr:`after_close`.  Raises ``TypeError``/``ValueError`` only for caller errors (wrong
        argument types, log time outside uint64) and ``OSError`` if the file cannot be written.
        """
        publish_ns = time.time_ns()
        if not isinstance(key, str) or not isinstance(type_name, str):
            raise TypeError("key and type_name must be str")
        if not isinstance(payload, bytes):
            if not isinstance(payload, (bytearray, memoryview)):
                raise TypeError(f"payload must be bytes, got {type(payload).__name__}")
            payload = bytes(payload)
        if log_time_ns is not None and (
            type(log_time_ns) is not int or not 0 <= log_time_ns <= _MAX_U64
        ):
            raise ValueError(f"log_time_ns must be an int in [0, 2**64), got {log_time_ns!r}")
        if len(key) > _MAX_KEY_CHARS:
            key = key[:_MAX_KEY_CHARS]
        if len(type_name) > _MAX_TYPE_CHARS:
            type_name = type_name[:_MAX_TYPE_CHARS]
        is_object, t_ns, sequence = _parse_payload(payload)  # outside the lock: pure
        self._queue.put(
            (key, type_name, payload, log_time_ns, is_object, t_ns, sequence, publish_ns)
        )

    def record_sample(self, sample: Sample) -> None:
        """Record one bus sample (thread-safe).  A sample that carries its validated message
        (in-process transport) is stored from the message's own sim time and sequence number,
        with the JSON bytes encoded once for every raw consumer; bytes alone take
        :meth:`record`'s path (parsed, never trusted)."""
        pending = prepare_sample(sample)
        if pending is None:
            self.record(sample.key, sample.type_name, sample.payload)
            return
        self._queue.put(pending)

    def take(self, pending: Pending) -> None:
        """Record one sample already prepared by :func:`prepare_sample`."""
        self._queue.put(pending)

    def record_prepared(self, batch: list[Pending]) -> None:
        """Record samples already prepared by :func:`prepare_sample` (the recorder process)."""
        self._queue.put_all(batch)

    def _write_pending(self, pending: deque[Pending]) -> None:
        """Write (or, once closed, count as ``after_close``) every pending sample; the samples
        are handed over by flat combining (``ground.archive.flat_combining``), lock held."""
        if not self._closed:
            self._file.write_all(pending)
            return
        while pending:
            try:
                pending.popleft()
            except IndexError:  # pragma: no cover - only this thread pops
                break
            self._after_close += 1

    # --- metadata, flush, close ----------------------------------------------------------------

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        """Write a metadata record now (written immediately, outside chunks).

        Raises ``TypeError``/``ValueError`` for non-string content and ``RuntimeError`` after
        :meth:`close`.
        """
        checked = _check_metadata(name, data)
        with self._queue.exclusive():  # then the samples queued meanwhile
            if self._closed:
                raise RuntimeError(f"McapRecorder({self._path}) is closed")
            self._write_pending(self._queue.pending)
            self._file.add_metadata(name, checked)

    def flush(self) -> None:
        """Close the chunk in progress now (if it holds messages) so it survives a kill.

        Smaller chunks compress worse; call it on a timer (e.g. every few seconds) rather than
        per message.  No-op after :meth:`close`.
        """
        with self._queue.exclusive():
            if not self._closed:
                self._write_pending(self._queue.pending)
                self._file.flush()

    def close(self) -> None:
        """Write the last chunk, the summary and the footer, and close the file (idempotent)."""
        with self._queue.exclusive():  # then the samples queued meanwhile count as after_close
            if self._closed:
                return
            try:
                self._write_pending(self._queue.pending)
            finally:
                self._closed = True
                self._file.finish()

    def __enter__(self) -> McapRecorder:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # --- counters ------------------------------------------------------------------------------

    @property
    def path(self) -> Path:
        """The MCAP file."""
        return self._path

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return self._closed

    @property
    def recorded(self) -> int:
        """Messages written (including invalid and unknown-type ones)."""
        return self._file.recorded

    @property
    def invalid(self) -> int:
        """Recorded payloads that are not a JSON object (stored as received)."""
        return self._file.invalid

    @property
    def unknown_type(self) -> int:
        """Recorded messages whose type name is not in the registry."""
        return self._file.unknown_type

    @property
    def dropped(self) -> int:
        """Messages not written because the file ran out of schema or channel ids (65535)."""
        return self._file.dropped

    @property
    def after_close(self) -> int:
        """``record`` calls ignored because the recorder was closed."""
        return self._after_close

    @property
    def counts(self) -> dict[str, int]:
        """Messages recorded per key (a snapshot copy)."""
        with self._queue.exclusive():
            return dict(self._file.counts)

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"McapRecorder({str(self._path)!r}, {state}, recorded={self.recorded})"


__all__ = ["LIBRARY", "McapRecorder", "MESSAGE_ENCODING", "Pending", "PROFILE", "SCHEMA_ENCODING",
           "prepare_raw", "prepare_sample", "prepared"]
