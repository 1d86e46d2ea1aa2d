"""The MCAP file of a run archive, as the recorder lays it out (Foxglove opens it as is).

* one MCAP **channel per key** (topic = key, ``message_encoding="json"``); a key that carries
  more than one type name (a confused or hostile sender) gets one channel per (key, type), all
  with the same topic;
* one **schema per type name**, ``encoding="jsonschema"``, data = the pydantic JSON schema of the
  model from :func:`interfaces.contracts.messages.registry`.  A type name that is *not* in the
  registry is recorded all the same (the archive is evidence) under a schema with that name,
  encoding ``"jsonschema"`` and the permissive schema ``{"type": "object", "title": <name>,
  ...}``.  (Encoding ``""`` was rejected: Foxglove refuses a ``json`` channel whose schema
  encoding is not ``jsonschema``.)
* **log time** = the message's own sim time ``t_sim`` in ns, so the Foxglove timeline is mission
  elapsed time; a message without a usable ``t_sim`` takes the last sim time seen.
* **metadata** records (``name -> {str: str}``), e.g. ``"run"`` and ``"scenario"``.
* schema and channel ids are uint16: past 65535 of either, new ones are dropped (counted).

Crash safety: messages are grouped in zstd chunks of about ``chunk_size`` bytes (uncompressed).
The file is written without a user-space buffer, so each chunk reaches the operating system the
moment it is complete: after a SIGKILL every complete chunk is in the file and
:func:`harness.archive.reader.load_run` recovers it (``truncated=True``).  The chunk in progress is
lost unless :meth:`McapFile.flush` closes it early.  No fsync (a process kill does not need it; a
power loss does).
"""

from __future__ import annotations

import io
import json
from collections import deque
from pathlib import Path
from typing import Final

from mcap.writer import CompressionType, IndexType, Writer

from interfaces.contracts.messages import Message, json_schema, registry

LIBRARY: Final = "insp-recorder"
"""Library name written in the MCAP header."""

PROFILE: Final = ""
"""MCAP profile (none: JSON messages with JSON schemas)."""

MESSAGE_ENCODING: Final = "json"
SCHEMA_ENCODING: Final = "jsonschema"

_MAX_ID: Final = 0xFFFF
"""Schema and channel ids are uint16 in MCAP (0 is reserved): at most 65535 of each."""

Pending = tuple[str, str, bytes, int | None, bool, int | None, int, int]
"""A sample waiting to be written: key, type name, payload, explicit log time, is a JSON object,
t_sim in ns, MCAP sequence, publish time."""


class _UnbufferedSink:
    """Append-only binary file without a user-space buffer, for :class:`mcap.writer.Writer`.

    The MCAP writer only writes the stream when a chunk (or metadata, or the summary) is complete,
    in a few large writes, so writing straight to the file descriptor costs nothing and puts every
    complete chunk in the OS page cache at once, where it survives a SIGKILL of the process.
    (Handing the writer a raw ``FileIO`` would not do: it wraps any ``RawIOBase`` in a
    ``BufferedWriter``.)  ``tell`` is tracked here rather than asked of the OS.
    """

    def __init__(self, path: Path) -> None:
        self._file = io.FileIO(path, "wb")
        self._pos = 0

    def write(self, data: bytes | bytearray | memoryview) -> int:
        """Write all of ``data``; return its length."""
        view = memoryview(data).cast("B")
        total = len(view)
        while view:
            n = self._file.write(view)
            if n is None or n <= 0:  # pragma: no cover - only on a non-blocking descriptor
                raise OSError("short write to the MCAP file")
            view = view[n:]
        self._pos += total
        return total

    def tell(self) -> int:
        """Bytes written so far (the writer uses it for its indexes)."""
        return self._pos

    def flush(self) -> None:
        """Nothing to flush: every write went to the OS already."""

    def close(self) -> None:
        """Close the file descriptor (idempotent)."""
        self._file.close()


def _utf8_safe(text: str) -> str:
    """``text`` unchanged if it encodes to UTF-8, else with lone surrogates backslash-escaped
    (the MCAP writer encodes strings as UTF-8 and would fail halfway through a record)."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return text.encode("utf-8", "backslashreplace").decode("utf-8")
    return text


def _unknown_type_schema(name: str) -> bytes:
    """Permissive JSON schema for a type name the registry does not know."""
    return json.dumps(
        {
            "type": "object",
            "title": name,
            "description": "unknown message type "
                           "(not in interfaces.contracts.messages.registry()); "
            "payload stored as received",
        }
    ).encode("utf-8")


class McapFile:
    """One archive being written (module docstring), with its counts.  Not thread-safe: its
    user serialises the calls (:class:`ground.archive.recorder.McapRecorder`)."""

    def __init__(self, path: Path, metadata: dict[str, dict[str, str]], chunk_size: int) -> None:
        """Create (truncate) ``path`` and write the header and the ``metadata`` records (checked
        by the caller: strings, valid UTF-8); ``chunk_size``: uncompressed bytes per chunk."""
        self._registry: dict[str, type[Message]] = registry()
        self._schema_ids: dict[str, int] = {}
        self._channels: dict[tuple[str, str], tuple[int, str]] = {}
        self.counts: dict[str, int] = {}
        """Messages written per key."""
        self.last_log_ns = 0
        """Last sim time seen, ns (the log time of a message without one)."""
        self.recorded = 0
        """Messages written (including invalid and unknown-type ones)."""
        self.invalid = 0
        """Written payloads that are not a JSON object (stored as received)."""
        self.unknown_type = 0
        """Written messages whose type name is not in the registry."""
        self.dropped = 0
        """Messages not written because the file ran out of schema or channel ids."""
        self._sink = _UnbufferedSink(path)
        try:
            self._writer = Writer(
                self._sink,  # type: ignore[arg-type]  # duck-typed binary stream
                chunk_size=chunk_size,
                compression=CompressionType.ZSTD,
                index_types=IndexType.ALL,
                use_chunking=True,
            )
            self._writer.start(profile=PROFILE, library=LIBRARY)
            for name, data in metadata.items():
                self._writer.add_metadata(name, data)
        except BaseException:
            self._sink.close()
            raise

    def write_all(self, pending: deque[Pending]) -> None:
        """Write every sample of ``pending``, taking them from its left end (others may append
        at its right meanwhile)."""
        writer = self._writer
        channels = self._channels
        counts = self.counts
        known = self._registry
        while pending:
            try:
                key, type_name, payload, log_time_ns, is_object, t_ns, sequence, publish_ns = (
                    pending.popleft()
                )
            except IndexError:  # pragma: no cover - only this thread pops
                break
            if t_ns is not None:
                self.last_log_ns = t_ns
            channel = channels.get((key, type_name))
            if channel is None:
                channel = self._new_channel(key, type_name)
                if channel is None:
                    self.dropped += 1
                    continue
            channel_id, topic = channel
            writer.add_message(
                channel_id,
                log_time=self.last_log_ns if log_time_ns is None else log_time_ns,
                data=payload,
                publish_time=publish_ns,
                sequence=sequence,
            )
            self.recorded += 1
            counts[topic] = counts.get(topic, 0) + 1
            if not is_object:
                self.invalid += 1
            if type_name not in known:
                self.unknown_type += 1

    def _new_channel(self, key: str, type_name: str) -> tuple[int, str] | None:
        """Register the channel of (key, type) (and the type's schema if new); None if the
        file has run out of uint16 ids."""
        schema_id = self._schema_ids.get(type_name)
        if schema_id is None:
            if len(self._schema_ids) >= _MAX_ID:
                return None
            schema_id = self._register_schema(type_name)
            self._schema_ids[type_name] = schema_id
        if len(self._channels) >= _MAX_ID:
            return None
        topic = _utf8_safe(key)
        channel_id = self._writer.register_channel(
            topic=topic, message_encoding=MESSAGE_ENCODING, schema_id=schema_id
        )
        self._channels[(key, type_name)] = (channel_id, topic)
        return channel_id, topic

    def _register_schema(self, type_name: str) -> int:
        """Write the schema record of ``type_name``; return its id."""
        name = _utf8_safe(type_name)
        model = self._registry.get(type_name)
        if model is not None:
            data = json.dumps(json_schema(model), separators=(",", ":")).encode("utf-8")
        else:
            data = _unknown_type_schema(name)
        return self._writer.register_schema(name=name, encoding=SCHEMA_ENCODING, data=data)

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        """Write a metadata record now (outside chunks; checked by the caller)."""
        self._writer.add_metadata(name, data)

    def flush(self) -> None:
        """Close the chunk in progress now (if it holds messages) so it survives a kill."""
        self._writer.flush()

    def finish(self) -> None:
        """Write the last chunk, the summary and the footer, and close the file."""
        try:
            self._writer.finish()
        finally:
            self._sink.close()
