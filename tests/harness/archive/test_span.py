"""How far an archive reaches (harness/archive/span.py): a whole archive holds everything up
to its end; one short of its run (cut, or of a run stopped early) only what came before its
last instant, which may be torn."""

from __future__ import annotations

from harness.archive.span import ArchiveSpan, seconds


def test_a_whole_archive_holds_up_to_its_end() -> None:
    whole = ArchiveSpan(end_s=400.0, run_s=400.0)
    assert not whole.short and whole.note() == ""
    assert whole.holds(400.0) and not whole.holds(400.2)


def test_a_short_archive_holds_only_what_came_before_its_last_instant() -> None:
    stopped = ArchiveSpan(end_s=1149.0, run_s=2400.0)
    assert stopped.short and stopped.holds(1148.8) and not stopped.holds(1149.0)
    assert stopped.note() == "archive ends at 1149 s (run lasted 2400 s): judged nothing past it"
    cut = ArchiveSpan(end_s=400.0, run_s=400.0, cut=True)  # the footer lost, the data whole
    assert cut.short and not cut.holds(400.0)


def test_seconds_are_given_to_a_tenth() -> None:
    assert (seconds(220.0), seconds(219.8), seconds(0.04)) == ("220", "219.8", "0")
