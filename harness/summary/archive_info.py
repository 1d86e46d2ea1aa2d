"""summary.json's ``archive`` (its files, whether one is truncated, the messages lost) and
``messages`` (the count of each type) sections, from the archive read back."""

from __future__ import annotations

from pydantic import (
    Field,
)

from harness.archive.reader import RunArchive
from harness.archive.sequences import by_topic
from harness.archive.span import ArchiveSpan, cut_of
from harness.summary.records import SummaryRecord
from interfaces.contracts.scenario import Scenario

BUS_HEADER = frozenset({"sender", "seq", "t_wall"})
"""A message's fields the bus stamps: the summary's copies of messages leave them out."""


class SegmentRecord(SummaryRecord):
    """One file of a run's archive (``ground/archive/segments.py``)."""

    file: str = Field(description="its name, beside summary.json")
    truncated: bool = Field(description="it ends in a damaged record or before its footer "
                                        "(its recorder died; what precedes is kept)")


class LostMessages(SummaryRecord):
    """Messages sent and never archived, from the gaps in each key's sequence numbers
    (``harness/archive/sequences.py``)."""

    total: int = Field(ge=0)
    by_topic: dict[str, int] = Field(
        description="by catalogue topic (app/name, every publisher's keys together; a key "
                    "outside the catalogue by itself), in name order, topics with none left out")


class ArchiveInfo(SummaryRecord):
    """``archive``: the state of the run's archive as read back.  ``segments`` and ``lost``
    are given together, only when the archive has several segments (the recorder was
    restarted) or lost messages: absent, the run is one file, run.mcap, and nothing sent is
    missing from it.  ``end_s`` (and ``cut``, for a file cut short) only when the archive ends
    before the run did: absent, it holds the whole run."""

    truncated: bool = Field(description="a file of it ends in a damaged record (what precedes "
                                        "is kept)")
    end_s: float | None = Field(
        default=None, description="sim time of its last message, s, when it ends before the "
                                  "run did (a file cut short, a run stopped early): the "
                                  "summary's figures cover what it holds, up to there "
                                  "(absent: it holds the whole run)")
    cut: str | None = Field(
        default=None, description="the first file cut short: its name, the byte it was read "
                                  "up to (of its size) and why reading stopped there (absent: "
                                  "none is)")
    segments: list[SegmentRecord] | None = Field(
        default=None, description="each file, in order (absent: run.mcap alone)")
    lost: LostMessages | None = Field(default=None, description="(absent: none lost)")


class MessageCounts(SummaryRecord):
    """``messages``: the records archived."""

    total: int = Field(ge=0)
    by_type: dict[str, int] = Field(description="by message type, in name order")


def archive_info(archive: RunArchive, scenario: Scenario | None = None) -> ArchiveInfo:
    """``archive``: whether a file of it is truncated; where it ends, only when it ends before
    the run of ``scenario`` did (without one: when a file is truncated); its segments and the
    messages lost, only when it has several segments or lost messages (a clean run of one file
    says nothing more than it always did)."""
    info = ArchiveInfo(truncated=archive.truncated)
    short = archive.truncated if scenario is None else ArchiveSpan.of(archive, scenario).short
    if short:
        info.end_s = archive.end_s
        info.cut = cut_of(archive)
    if len(archive.segments) > 1 or archive.lost:
        lost = by_topic(archive.lost)
        info.segments = [SegmentRecord(file=s.path.name, truncated=s.truncated)
                         for s in archive.segments]
        info.lost = LostMessages(total=sum(lost.values()), by_topic=lost)
    return info


def counts_by_type(archive: RunArchive) -> dict[str, int]:
    out: dict[str, int] = {}
    for type_name, count in archive.topics().values():
        out[type_name] = out.get(type_name, 0) + count
    return dict(sorted(out.items()))
