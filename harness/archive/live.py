"""The archive of a one-process run as it is recorded, for its summary without a second read.

:class:`LiveArchive` takes the samples the recorder is given, prepared once for both
(:func:`ground.archive.recorder.prepare_sample`), and keeps the records a read of the finished
file would give (:func:`harness.archive.reader.load_run`): the same keys, type names, log times
(the message's sim time in ns, or the last one for a message without), payloads and order, the
same streaming of chosen keys to sinks and the same sequence accounting.  A streamed record
still holds its message object, so a sink reads it without decoding its JSON (the camera
images are most of a run's bytes); a kept record holds only its bytes, as read from the file.
Only the wall-clock publish times differ from the file's (the recorder stamps its own; nothing
reads them).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from mcap.records import Header, Schema

from ground.archive.recorder import (
    LIBRARY,
    PROFILE,
    SCHEMA_ENCODING,
    Pending,
    prepared,
)
from harness.archive.reader import Record, RecordLoader, RecordSink, RunArchive, SegmentInfo
from interfaces.contracts.messages import Message, json_schema, registry
from interfaces.runtime.transport import Sample


@dataclass(frozen=True, slots=True)
class HeldRecord(Record):
    """A record that still holds the message it was encoded from (decoded without its JSON)."""

    held: Message

    def message(self) -> Message:
        return self.held

    def decode(self, model: type[Message]) -> Message:  # type: ignore[override]
        return self.held if type(self.held) is model else Record.decode(self, model)


class LiveArchive:
    """Records of the samples given, as :func:`load_run` would read them from the archive
    (``stream``: key expression -> sink, as there); :meth:`finish` gives the archive."""

    def __init__(self, path: Path, metadata: Mapping[str, Mapping[str, str]],
                 stream: Mapping[str, RecordSink]) -> None:
        self._path = path
        self._loader = RecordLoader(stream)
        self._loader.begin_segment(more_follow=False)
        self._loader.metadata = {name: dict(data) for name, data in metadata.items()}
        self._channels: dict[tuple[str, str], RecordSink | None] = {}
        self._last_log_ns = 0

    def record_sample(self, sample: Sample) -> None:
        """Take one bus sample (prepared here; see :meth:`take` to share the preparation)."""
        self.take(prepared(sample), sample.message)

    def take(self, pending: Pending, message: Message | None = None) -> None:
        """Take one prepared sample (and its message object, if the sample carried one)."""
        key, type_name, payload, log_time_ns, _obj, t_ns, seq, publish_ns = pending
        if t_ns is not None:
            self._last_log_ns = t_ns
        log_ns = self._last_log_ns if log_time_ns is None else log_time_ns
        channel = (key, type_name)
        if channel in self._channels:
            sink = self._channels[channel]
        else:
            self._loader.channel_types.setdefault(key, []).append(type_name)
            sink = self._channels[channel] = self._loader.sink_of(key)
        if sink is None:  # kept to the end of the run: a copy of its own size (an encoder's
            # bytes can sit in a larger block: orjson's hold 4 KiB whatever their length)
            record = Record(key, type_name, log_ns, publish_ns, memoryview(payload).tobytes())
        elif message is None:
            record = Record(key, type_name, log_ns, publish_ns, payload)
        else:
            record = HeldRecord(key, type_name, log_ns, publish_ns, payload, message)
        self._loader.take(record, sink, seq)

    def finish(self) -> RunArchive:
        """The archive as a read of the complete file gives it."""
        loader, known = self._loader, registry()
        names = sorted({t for _, t in self._channels})
        for i, name in enumerate(names, start=1):
            model = known.get(name)
            data = (json.dumps(json_schema(model), separators=(",", ":")).encode()
                    if model is not None else b"{}")
            loader.schemas_by_id[i] = Schema(id=i, name=name, encoding=SCHEMA_ENCODING,
                                             data=data)
        loader.header, loader.footer_seen = Header(profile=PROFILE, library=LIBRARY), True
        return loader.archive(self._path, [SegmentInfo(self._path, False, None)])
