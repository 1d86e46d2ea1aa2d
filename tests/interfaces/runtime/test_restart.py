"""A node process's start with a critical-data store (``interfaces.runtime.restart``): first
start fresh, a restart restored (and the store kept at every ω_mid boundary), a refused store
a logged and recorded cold start."""

from __future__ import annotations

import logging
from pathlib import Path

from interfaces.contracts.messages import Tick
from interfaces.contracts.topology import topology
from interfaces.runtime.assembly import executive_of
from interfaces.runtime.bus import Bus
from interfaces.runtime.cds import CriticalDataStore, read_starts, write_run_key
from interfaces.runtime.executive import TickClient
from interfaces.runtime.restart import resume
from interfaces.runtime.transport import InprocNetwork
from links.channel import ChannelModel
from tests.conftest import small_scenario

SC = small_scenario("rs", duration_s=30.0)
LOG = logging.getLogger("test.restart")


def _process(directory: Path) -> tuple[TickClient, CriticalDataStore]:
    """What a start of sc1's process builds: its node and its store."""
    bus = Bus("sc1", SC.name, InprocNetwork().endpoint(), channel=ChannelModel.of("sc1", SC))
    client = TickClient(executive_of(topology(SC).node("sc1"), bus, SC), synchronous=True)
    return client, CriticalDataStore.open(directory, SC.name, "sc1", SC)


def _run(client: TickClient, ticks: range) -> None:
    for k in ticks:
        client.catch_up(Tick(sender="sim", t_sim=k * SC.rates.dt_s, k=k, dt_s=SC.rates.dt_s))


def test_a_restarted_process_goes_on_from_its_last_boundary(tmp_path: Path) -> None:
    write_run_key(tmp_path)
    first, store = _process(tmp_path)
    assert resume(first, store, [], LOG).outcome == "fresh"
    _run(first, range(0, 5))  # ω_mid is every 2nd tick: stored after ticks 0, 2, 4
    assert store.writes == 3
    again, store = _process(tmp_path)
    record = resume(again, store, [], LOG)
    assert (record.outcome, record.tick) == ("restored", 4)
    assert again.last_k == 4 and again.executive.ticks == first.executive.ticks
    nav = [a for a in again.executive.apps if a.NAME == "nav"][0]
    assert nav.t_est == [a for a in first.executive.apps if a.NAME == "nav"][0].t_est
    assert [s.outcome for s in read_starts(store.starts_path)] == ["fresh", "restored"]


def test_a_refused_store_gives_a_recorded_cold_start(tmp_path: Path, caplog) -> None:  # noqa: ANN001
    write_run_key(tmp_path)
    first, store = _process(tmp_path)
    resume(first, store, [], LOG)
    _run(first, range(0, 3))
    store.path.write_bytes(store.path.read_bytes()[:-100])  # torn
    again, store = _process(tmp_path)
    record = resume(again, store, [], LOG)
    assert record.outcome == "cold" and "truncated" in record.reason
    assert again.last_k == -1 and again.executive.ticks == 0
    assert "restarted cold" in caplog.text
    assert read_starts(store.starts_path)[-1].reason == record.reason
    _run(again, range(3, 5))  # a cold node runs, and keeps its store again
    assert CriticalDataStore.open(tmp_path, SC.name, "sc1", SC).load()[1]["tick"] == 4
