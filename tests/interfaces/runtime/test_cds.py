"""The critical-data store file: written atomically and owner-only, read back whole, and
refused (never unpickled) when truncated, corrupted, or of another run, node, seed or
scenario."""

from __future__ import annotations

import stat
from pathlib import Path

import numpy as np
import pytest

from interfaces.runtime.cds import (
    CriticalDataStore,
    StartRecord,
    StoreRefused,
    read_starts,
    write_run_key,
)
from tests.conftest import small_scenario

SC = small_scenario("cds")


def _store(directory: Path, node: str = "sc1", seed: int | None = None) -> CriticalDataStore:
    return CriticalDataStore.open(directory, "m", node, SC.with_overrides(seed, None))


def _state() -> dict[str, object]:
    return {"tick": 40, "apps": {"nav": {"x": np.arange(6.0)}}, "rng": np.random.default_rng(1)}


def test_a_store_reads_back_what_was_written_owner_only_and_atomically(tmp_path: Path) -> None:
    key = write_run_key(tmp_path / "cds")
    store = _store(tmp_path / "cds")
    with pytest.raises(StoreRefused, match="no store"):
        store.load()
    store.save(_state(), tick=40, t_sim=20.0)
    store.save(_state() | {"tick": 42}, tick=42, t_sim=21.0)  # over the first, by rename
    state, header = store.load()
    assert state["tick"] == 42 and header["tick"] == 42 and header["t_sim"] == 21.0
    assert np.array_equal(state["apps"]["nav"]["x"], np.arange(6.0))
    assert state["rng"].random() == np.random.default_rng(1).random()
    for path in (key, store.path, key.parent):
        mode = stat.S_IMODE(path.stat().st_mode)
        assert mode & 0o077 == 0, f"{path} is readable by others ({oct(mode)})"
    assert sorted(p.name for p in key.parent.iterdir()) == ["key", "sc1.cds"]  # no temp left


@pytest.mark.parametrize("damage, why", [
    (lambda b: b[: len(b) // 2], "truncated"),
    (lambda b: b[:10], "truncated or corrupted"),
    (lambda b: b[:-5] + bytes(x ^ 0xFF for x in b[-5:]), "corrupted: its seal"),
    (lambda b: b"", "not a store"),
])
def test_a_damaged_store_is_refused(tmp_path: Path, damage, why: str) -> None:  # noqa: ANN001
    write_run_key(tmp_path)
    store = _store(tmp_path)
    store.save(_state(), 40, 20.0)
    store.path.write_bytes(damage(store.path.read_bytes()))
    with pytest.raises(StoreRefused, match=why):
        store.load()


def test_a_store_of_another_run_node_or_seed_is_refused(tmp_path: Path) -> None:
    write_run_key(tmp_path / "a")
    write_run_key(tmp_path / "b")  # another run: another key
    theirs = _store(tmp_path / "a")
    theirs.save(_state(), 40, 20.0)
    ours = _store(tmp_path / "b")
    ours.path.write_bytes(theirs.path.read_bytes())
    with pytest.raises(StoreRefused, match="another run"):
        ours.load()
    other_seed = _store(tmp_path / "a", seed=99)
    with pytest.raises(StoreRefused, match="another seed"):
        other_seed.load()
    sc2 = _store(tmp_path / "a", node="sc2")
    sc2.path.write_bytes(theirs.path.read_bytes())
    with pytest.raises(StoreRefused, match="another node"):
        sc2.load()


def test_the_starts_record_says_how_each_start_went(tmp_path: Path) -> None:
    write_run_key(tmp_path)
    store = _store(tmp_path)
    assert not store.restarted() and read_starts(store.starts_path) == []
    store.record_start(StartRecord("fresh"))
    store.record_start(StartRecord("cold", reason="store corrupted"))
    with store.starts_path.open("a") as f:
        f.write("not json\n")
    assert store.restarted()
    starts = read_starts(store.starts_path)
    assert [s.outcome for s in starts] == ["fresh", "cold"]
    assert starts[1].describe() == "cold start (store corrupted)"
    assert StartRecord("restored", tick=7, t_sim=3.5).describe() == \
        "restored after tick 7 (t=3.5 s)"
