"""Reading the archive of a real (in-process) run once for summary and report: streamed keys,
the chunk reader, the digest."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from deploy.inproc import run_inproc
from ground.archive.recorder import McapRecorder
from harness.archive.reader import ArchiveError, Record, load_run
from harness.summary.build import RunOutcome, build_summary
from harness.summary.digest import (
    LiveDigest,
    RunDigest,
    digest_archive,
    digest_run,
    unread_keys,
)
from interfaces.contracts.scenario import Scenario, load_scenario
from tests.conftest import REPO

OUTCOME = RunOutcome("inproc", 1.0, "completed")


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Scenario, RunDigest]:
    """A 40 s nominal run recorded through the in-process fast path, in small chunks, and
    digested as it went."""
    sc = load_scenario(REPO / "deploy" / "scenarios" / "nominal.toml").with_overrides(None, 40.0)
    path = tmp_path_factory.mktemp("digest") / "run.mcap"
    live = LiveDigest(sc, sc.name, path, {"run": {"note": "digest test"}})
    with McapRecorder(path, {"run": {"note": "digest test"}}, chunk_size=64 * 1024) as rec:
        run_inproc(sc, sample_tap=live.tap(rec))
    return path, sc, live.finish()


@pytest.fixture(scope="module")
def run(recorded: tuple[Path, Scenario, RunDigest]) -> tuple[Path, Scenario]:
    return recorded[0], recorded[1]


def test_chunk_reader_matches_the_mcap_library(run: tuple[Path, Scenario]) -> None:
    path, _ = run
    with open(path, "rb") as f:
        lib = [(ch.topic, m.log_time, m.publish_time, m.data)
               for _, ch, m in make_reader(f).iter_messages(log_time_order=False)]
    ours = load_run(path)
    in_file_order = sorted(ours.records(), key=lambda r: r.publish_time_ns)
    assert len(lib) > 1000 and len(ours) == len(lib)
    assert sorted(lib) == sorted((r.key, r.log_time_ns, r.publish_time_ns, r.payload)
                                 for r in in_file_order)


def test_streamed_keys_are_counted_not_kept(run: tuple[Path, Scenario]) -> None:
    path, sc = run
    seen: list[Record] = []
    whole = load_run(path)
    part = load_run(path, stream={e: seen.append for e in unread_keys(sc.name)})
    assert len(part) == len(whole) and part.topics() == whole.topics()
    streamed_keys = {r.key for r in seen}
    assert any(k.endswith("/camera/observations") for k in streamed_keys)
    assert len(seen) == sum(n for k, (_, n) in whole.topics().items() if k in streamed_keys)
    held = sum(len(part.records(k)) for k in whole.topics() if k not in streamed_keys)
    assert held == len(whole) - len(seen)  # the rest is held, nothing lost
    assert sorted(seen, key=lambda r: r.publish_time_ns) == sorted(
        (r for r in whole.records() if r.key in streamed_keys), key=lambda r: r.publish_time_ns)
    with pytest.raises(ArchiveError, match="streamed"):
        part.records(f"insp/{sc.name}/sc/*/camera/observations")


def test_digest_gives_the_summary_of_the_whole_archive(run: tuple[Path, Scenario]) -> None:
    path, sc = run
    streamed = digest_run(path, sc, sc.name)
    whole = digest_archive(load_run(path), sc, sc.name)
    assert streamed.coverage.t_s == whole.coverage.t_s
    assert streamed.coverage.h == whole.coverage.h
    assert streamed.coverage.h[-1] < streamed.coverage.h_initial  # the cameras saw something
    assert streamed.counters.counts == whole.counters.counts
    assert build_summary(streamed, sc, sc.name, OUTCOME) \
        == build_summary(whole, sc, sc.name, OUTCOME)


def test_the_digest_built_as_the_run_went_is_the_files(
        recorded: tuple[Path, Scenario, RunDigest]) -> None:
    """What a one-process run digests as it goes is what a read of its finished archive gives:
    the same records, counts, metadata, coverage, truth and summary."""
    path, sc, live = recorded
    read = digest_run(path, sc, sc.name)
    assert [(r.key, r.type_name, r.log_time_ns, r.payload) for r in live.archive.held()] == [
        (r.key, r.type_name, r.log_time_ns, r.payload) for r in read.archive.held()]
    assert live.archive.topics() == read.archive.topics()
    assert live.archive.metadata == read.archive.metadata
    assert set(live.archive.schemas) == set(read.archive.schemas)
    assert not live.archive.truncated and len(live.archive) == len(read.archive) > 1000
    assert live.coverage.h == read.coverage.h and live.coverage.t_s == read.coverage.t_s
    for field in ("t_s", "r_m", "v_mps", "q_lvlh_body", "dv_mps"):
        assert np.array_equal(getattr(live.truth, field), getattr(read.truth, field))
    assert live.counters.counts == read.counters.counts
    assert build_summary(live, sc, sc.name, OUTCOME) == build_summary(read, sc, sc.name, OUTCOME)
