"""An archived topic as a DataFrame (harness/archive/frame.py) and as Parquet (the archive CLI),
checked against the reader's decoded messages of a real recorded run."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from harness.archive.cli import main as archive_main
from harness.archive.frame import INDEX_NAME, topic_frame
from harness.archive.reader import ArchiveError, RunArchive, load_run
from interfaces.contracts.messages import (
    ExecStats,
    Message,
    StateEstimate,
    TruthState,
)
from tests.conftest import recorded_run, small_scenario

NAV_1 = "insp/fr/sc/1/nav/estimate"
NAV_ALL = "insp/fr/sc/*/nav/estimate"


@pytest.fixture(scope="module")
def archive_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("frame")
    recorded_run(small_scenario("fr", duration_s=10.0, observers={"count": 2}), out)
    return out / "run.mcap"


@pytest.fixture(scope="module")
def archive(archive_path: Path) -> RunArchive:
    return load_run(archive_path)


def _same(value: Any, expected: Any) -> bool:
    """A frame cell equals a message value (None and NaN both stand for a missing value)."""
    if expected is None:
        return value is None or (isinstance(value, float) and math.isnan(value))
    return bool(value == expected)


def test_frame_has_the_readers_messages_indexed_by_sim_time(
        archive_path: Path, archive: RunArchive) -> None:
    frame = topic_frame(archive_path, NAV_1)
    messages = archive.messages(NAV_1, StateEstimate)
    assert len(frame) == len(messages) > 5
    assert frame.index.name == INDEX_NAME
    assert frame.index.is_monotonic_increasing
    assert list(frame.index) == [m.t_sim for m in messages]
    assert "t_sim" not in frame.columns and "key" not in frame.columns
    for name in ("sender", "seq", "t_wall", "spacecraft", "resets"):
        assert list(frame[name]) == [getattr(m, name) for m in messages], name
    assert all(_same(v, m.nis) for v, m in zip(frame["nis"], messages, strict=True))


def test_fixed_vectors_get_one_column_per_element(archive_path: Path,
                                                  archive: RunArchive) -> None:
    frame = topic_frame(archive_path, NAV_1)
    messages = archive.messages(NAV_1, StateEstimate)
    assert [c for c in frame.columns if c.startswith("x.")] == [f"x.{i}" for i in range(6)]
    assert sum(c.startswith("P.") for c in frame.columns) == 36
    for i in range(6):
        assert frame[f"x.{i}"].tolist() == [m.x[i] for m in messages]
        for j in range(6):
            assert frame[f"P.{i}.{j}"].tolist() == [m.P[i][j] for m in messages]


def test_nested_models_in_a_dict_get_dotted_columns(archive_path: Path,
                                                    archive: RunArchive) -> None:
    key = "insp/fr/sc/1/exec/stats"
    frame = topic_frame(archive_path, key)
    messages = archive.messages(key, ExecStats)
    assert len(frame) == len(messages) > 0
    groups = sorted({g for m in messages for g in m.groups})
    assert groups
    for g in groups:
        for field in ("runs", "cycle_slips", "max_exec_ms", "budget_ms"):
            want = [getattr(m.groups[g], field) if g in m.groups else None for m in messages]
            column = frame[f"groups.{g}.{field}"]
            assert all(_same(v, w) for v, w in zip(column, want, strict=True)), (g, field)


def test_lists_of_varying_length_stay_whole(archive_path: Path, archive: RunArchive) -> None:
    key = "insp/fr/sim/truth/state"
    frame = topic_frame(archive_path, key)
    messages = archive.messages(key, TruthState)
    assert frame["r_lvlh_m"].tolist() == [m.r_lvlh_m for m in messages]
    assert frame["spacecraft"].tolist() == [m.spacecraft for m in messages]
    assert not any(c.startswith("r_lvlh_m.") for c in frame.columns)


def test_a_pattern_over_several_spacecraft_keeps_key_and_spacecraft(
        archive_path: Path, archive: RunArchive) -> None:
    frame = topic_frame(archive_path, NAV_ALL)
    keys = [k for k in archive.topics() if k.endswith("/nav/estimate")]
    assert len(keys) == 2
    assert list(frame.columns[:2]) == ["key", "spacecraft"]
    assert sorted(set(frame["key"])) == keys
    assert len(frame) == sum(len(archive.records(k)) for k in keys)
    assert all(k == f"insp/fr/sc/{sc}/nav/estimate"
               for k, sc in zip(frame["key"], frame["spacecraft"], strict=True))
    assert frame.index.is_monotonic_increasing
    # equal times keep the archive's order (the reader's: log time, then file order)
    records = archive.records(NAV_ALL)
    expected = [(m.t_sim, r.key, m.seq) for r in records
                for m in [r.decode(StateEstimate)]]
    assert list(zip(frame.index, frame["key"], frame["seq"], strict=True)) == expected
    assert frame.index.has_duplicates  # the two spacecraft publish at the same sim times


def test_a_loaded_archive_gives_the_same_frame(archive_path: Path, archive: RunArchive) -> None:
    pd.testing.assert_frame_equal(topic_frame(archive, NAV_ALL),
                                  topic_frame(archive_path, NAV_ALL))


def test_a_pattern_over_several_types_has_a_type_column(archive_path: Path,
                                                        archive: RunArchive) -> None:
    frame = topic_frame(archive_path, "insp/fr/sc/1/**")
    held = archive.records("insp/fr/sc/1/**")
    assert len(frame) == len(held)
    assert list(frame.columns[:3]) == ["key", "type", "spacecraft"]
    assert sorted(set(frame["type"])) == sorted({r.type_name for r in held})


def test_parquet_export_reads_back_equal(archive_path: Path, tmp_path: Path) -> None:
    out = tmp_path / "nav.parquet"
    assert archive_main(["export", str(archive_path), "--topic", NAV_ALL,
                         "--out", str(out)]) == 0
    pd.testing.assert_frame_equal(pd.read_parquet(out), topic_frame(archive_path, NAV_ALL))


def _plain(value: Any) -> Any:
    """Parquet gives lists back as numpy arrays (and structs as dicts): make them lists."""
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def test_every_topic_round_trips_through_parquet(archive: RunArchive, tmp_path: Path) -> None:
    for key in archive.topics():
        frame = topic_frame(archive, key)
        frame.to_parquet(tmp_path / "t.parquet")
        back = pd.read_parquet(tmp_path / "t.parquet")
        assert list(back.columns) == list(frame.columns), key
        assert back.index.equals(frame.index) and back.index.name == INDEX_NAME, key
        for column in frame.columns:
            if frame[column].dtype == object:
                assert [_plain(v) for v in back[column]] == frame[column].tolist(), (key, column)
            else:
                pd.testing.assert_series_equal(back[column], frame[column], obj=key)


def test_csv_export_still_works(archive_path: Path, tmp_path: Path) -> None:
    out = tmp_path / "nav.csv"
    assert archive_main(["export", str(archive_path), "--topic", NAV_1, "--out", str(out)]) == 0
    csv = pd.read_csv(out)
    assert csv["x.0"].tolist() == topic_frame(archive_path, NAV_1)["x.0"].tolist()


@pytest.mark.parametrize("pattern", ["", "insp/fr/sc/1/nav/est*", "insp//nav", "/insp/**",
                                     "insp/fr/sc/1/nav estimate"])
def test_a_malformed_pattern_is_a_clear_error(archive_path: Path, pattern: str) -> None:
    with pytest.raises(ValueError, match="bad topic pattern"):
        topic_frame(archive_path, pattern)


def test_a_pattern_matching_nothing_names_the_keys_like_it(archive_path: Path,
                                                           archive: RunArchive) -> None:
    for source in (archive_path, archive):
        with pytest.raises(ArchiveError, match="no key matches") as err:
            topic_frame(source, "insp/fr/sc/9/nav/estimate")
        assert NAV_1 in str(err.value) and "list" in str(err.value)


def test_missing_or_foreign_file_is_a_clear_error(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(FileNotFoundError, match="no such archive"):
        topic_frame(tmp_path / "none.mcap", NAV_1)
    (tmp_path / "notes.mcap").write_text("not an archive")
    with pytest.raises(ArchiveError, match="not an MCAP file"):
        topic_frame(tmp_path / "notes.mcap", NAV_1)
    out = tmp_path / "x.parquet"
    assert archive_main(["export", str(tmp_path / "none.mcap"), "--topic", NAV_1,
                         "--out", str(out)]) == 2
    assert "no such file or folder" in capsys.readouterr().err and not out.exists()


def test_invalid_payloads_raise_or_are_skipped(archive: RunArchive, tmp_path: Path) -> None:
    from ground.archive.recorder import McapRecorder

    good = archive.records(NAV_1)
    path = tmp_path / "bad.mcap"
    with McapRecorder(path, {}) as rec:
        for r in good:
            rec.record(r.key, r.type_name, r.payload)
        rec.record(NAV_1, "StateEstimate", b'{"t_sim": 99.0, "sender": "sc1"}')
    with pytest.raises(ArchiveError, match="not a valid StateEstimate"):
        topic_frame(path, NAV_1)
    frame = topic_frame(path, NAV_1, skip_invalid=True)
    assert list(frame.index) == [r.decode(StateEstimate).t_sim for r in good]


def test_message_base_fields_are_all_columns_or_index(archive_path: Path) -> None:
    frame = topic_frame(archive_path, NAV_1)
    header = set(Message.model_fields) - {"t_sim"}
    assert header <= set(frame.columns)
