"""A run's archive read in time order, in bounded memory.

:func:`harness.archive.reader.load_run` holds every record it keeps and sorts them by log time
at the end; the records of keys it streams go to their sinks in file order.  A replay needs the
bulk of an archive (the other nodes' messages) in time order, which held whole grows with the
run (one 1.2 GB archive of a long run under ground passes: past 17 GB).  :func:`stream_run`
reads the same archive into the same :class:`~harness.archive.reader.RunArchive`, but hands the
streamed records to their sinks in the held records' order (log time, ties in segment then file
order), holding only those that a chunk not yet read could still precede:

* a first pass reads each file's records without decompressing its chunks and notes, for each
  chunk (and each message outside one), the log time of its first message on each channel
  (:func:`~harness.archive.reader.unit_times`: from the message indexes written after it);
* the second reads the files as :func:`load_run` does (the same admission of each record in
  file order, a chunk decoded and checked whole, a file cut short read up to its cut) and hands
  a streamed record on once no chunk still to be read holds a streamed channel's record before
  it.  Held channels do not count (:class:`TimeOrder`).

The recorder writes messages as they come, so chunks follow one another in time: of a 6,000 s
passes archive's 1.38 million records, at most 10,907 waited at once.  A message found earlier
than one already handed on (a chunk whose recorded range is wrong: never written by this
project's recorder) is handed on at once, out of order, and counted in :attr:`TimeOrder.late`.
"""

from __future__ import annotations

import heapq
import logging
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from mcap.records import Channel, Chunk
from mcap.records import Message as McapMessage

from ground.archive.segments import segment_paths
from harness.archive.reader import (
    Record,
    RecordLoader,
    RecordSink,
    RunArchive,
    SegmentInfo,
    UnitTimes,
    read_segments,
    summary_topics,
    unit_times,
)

log = logging.getLogger("insp.archive")


class TimeOrder(RecordLoader):
    """A :class:`RecordLoader` whose streamed records wait in a heap, by (log time, order
    read), until no chunk still to be read can hold a streamed record before them.  ``units``:
    each segment's :func:`~harness.archive.reader.unit_times`; ``topics``: each segment's
    :func:`~harness.archive.reader.summary_topics`.  A channel whose records are held (its key
    streams to no sink) does not count, from the start where the segment's summary names it,
    else from its channel record on: the ground's judgements of a pass, stamped with the time of
    the data they judge, are archived long after it and would otherwise hold back everything
    between."""

    def __init__(self, sinks: Mapping[str, RecordSink | None], units: list[list[UnitTimes]],
                 topics: list[dict[int, str]]) -> None:
        super().__init__({e: (None if s is None else self._waiting(s)) for e, s in sinks.items()})
        self._first = [0]
        for seg in units:
            self._first.append(self._first[-1] + len(seg))
        rows = [(self._first[s] + i, s, channel, t) for s, seg in enumerate(units)
                for i, unit in enumerate(seg) for channel, t in unit]
        table = np.array(rows, dtype=np.float64).reshape(-1, 4)
        self._unit_of = table[:, 0].astype(np.int64)
        self._segment_of, self._channel_of, self._t_of = table[:, 1], table[:, 2], table[:, 3]
        self._held = np.zeros(len(rows), dtype=bool)
        for seg, known in enumerate(topics):  # channels a segment's summary names
            for channel, topic in known.items():
                if self.sink_of(topic) is None:
                    self._held |= (self._segment_of == seg) & (self._channel_of == channel)
        self._suffix_min = self._earliest_from_each_unit()
        self._unit = 0
        self._heap: list[tuple[int, int, Record, RecordSink]] = []
        self._order = 0
        self._last_out = -1
        self.late = 0
        """Records handed on after a later one (a chunk's recorded range was wrong)."""
        self.peak_waiting = 0
        """The most records that waited at once."""

    def _earliest_from_each_unit(self) -> np.ndarray:
        """For each unit, the earliest first log time of a channel not held in it or any unit
        after it (ns; inf past the last)."""
        earliest = np.full(self._first[-1] + 1, np.inf)
        counted = ~self._held
        np.minimum.at(earliest, self._unit_of[counted], self._t_of[counted])
        return np.minimum.accumulate(earliest[::-1])[::-1]

    def _channel(self, rec: Channel) -> None:
        super()._channel(rec)
        if self.channels[rec.id][2] is None:  # held: its times no longer hold anything back
            mine = (self._segment_of == self.segment) & (self._channel_of == rec.id)
            if (mine & ~self._held).any():
                self._held |= mine
                self._suffix_min = self._earliest_from_each_unit()

    def _waiting(self, sink: RecordSink) -> RecordSink:
        def wait(record: Record) -> None:
            self._order += 1
            heapq.heappush(self._heap, (record.log_time_ns, self._order, record, sink))
            self.peak_waiting = max(self.peak_waiting, len(self._heap))

        return wait

    def begin_segment(self, more_follow: bool) -> None:
        super().begin_segment(more_follow)
        self._unit = self._first[self.segment]  # a cut segment's unread chunks are passed over

    def end_record(self, rec: object) -> None:
        if isinstance(rec, (Chunk, McapMessage)):
            self._unit += 1
            self._hand_on(self._bound())

    def _bound(self) -> float:
        """The earliest log time a streamed record still to be read may have (ns); -inf past
        what the first pass saw of this segment (nothing is then known of the rest)."""
        if self._unit > self._first[self.segment + 1]:
            return -math.inf
        return float(self._suffix_min[self._unit])

    def _hand_on(self, bound: float) -> None:
        """Hand on, in order, every waiting record not after ``bound`` (ns)."""
        heap = self._heap
        while heap and heap[0][0] <= bound:
            t_ns, _, record, sink = heapq.heappop(heap)
            if t_ns < self._last_out:
                self.late += 1
                log.warning("%s at %d ns: read after a later message (count %d)",
                            record.key, t_ns, self.late)
            self._last_out = max(self._last_out, t_ns)
            sink(record)

    def archive(self, path: Path, segments: list[SegmentInfo]) -> RunArchive:
        self._hand_on(math.inf)
        return super().archive(path, segments)


def stream_run(path: str | Path, stream: Mapping[str, RecordSink | None]
               ) -> tuple[RunArchive, TimeOrder]:
    """:func:`harness.archive.reader.load_run` (the same arguments, the same archive), with
    each streamed record handed to its sink in time order (log time, ties in segment then file
    order: the order of the held records), in bounded memory (module docstring); and the
    order's account (:attr:`TimeOrder.late`, :attr:`TimeOrder.peak_waiting`)."""
    paths = segment_paths(path)
    order = TimeOrder(stream, [unit_times(p) for p in paths], [summary_topics(p) for p in paths])
    return read_segments(paths, order), order


__all__ = ["TimeOrder", "stream_run"]
