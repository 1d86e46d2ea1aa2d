"""A recorder process killed and started again loses nothing (ground/archive/record.py with
interfaces/runtime/recent.py): over a real Zenoh network, the nodes keep what the recorder has
not told them it archived, so the restarted recorder finds what it had not closed in a chunk
when it was killed and everything sent while it was down, though each node keeps only its last
tick otherwise; the run's archive, read back from its two segments, holds every message once
and counts none lost."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from harness.archive.reader import load_run
from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import Heartbeat, Tick
from interfaces.runtime.bus import Bus
from interfaces.runtime.recent import parse_reply
from interfaces.runtime.zenoh_transport import ZenohSettings, ZenohTransport
from tests.conftest import small_scenario, write_scenario

M = "recrestart"
REPO = Path(__file__).resolve().parents[3]
DT_S = 0.5
"""The scenario's tick (small_scenario: 2 Hz; the recorder closes a chunk every 2 ticks)."""


@dataclass
class Network:
    """A hub, and on it the run's nodes (the sim, sc1, the ground: each keeping one tick
    beyond the current one) and the count of the recorder's appearances."""

    hub: ZenohTransport
    sim: Bus
    sc1: Bus
    ground: Bus
    endpoint: str
    appeared: threading.Semaphore


@pytest.fixture
def network(free_port: int) -> Iterator[Network]:
    endpoint = f"tcp/127.0.0.1:{free_port}"
    hub = ZenohTransport(ZenohSettings.hub(endpoint))
    appeared = threading.Semaphore(0)
    hub.watch_alive(topics.recorder_token(M), lambda _n, alive: appeared.release()
                    if alive else None)
    buses = [Bus(n, M, ZenohTransport(ZenohSettings(connect=(endpoint,))), recent_ticks=1)
             for n in (topics.SIM, "sc1", topics.GROUND)]
    for bus in buses:
        bus.serve_recent()
    yield Network(hub, *buses, endpoint, appeared)
    for bus in buses:
        bus.close()
    hub.close()


def _recorder(net: Network, scenario: Path, out: Path) -> subprocess.Popen[bytes]:
    """The recorder process on ``net``, writing ``out`` (its next segment if it exists), once
    its token is seen (it is recording)."""
    p = subprocess.Popen([sys.executable, "-m", "ground.archive.record", "--scenario",
                          str(scenario), "--out", str(out), "--connect", net.endpoint],
                         cwd=REPO, stderr=subprocess.PIPE)
    assert net.appeared.acquire(timeout=60.0), "the recorder never announced itself"
    return p


def _fly(net: Network, ticks: range) -> None:
    """The sim's ticks of ``ticks`` and, in each, sc1's heartbeat; each node ends its tick (the
    ground sends nothing)."""
    for k in ticks:
        net.sim.publish(cat.TICK.key(M), Tick(sender=topics.SIM, t_sim=k * DT_S, k=k,
                                              dt_s=DT_S), announce=False)
        net.sc1.publish(cat.HEARTBEAT.key(M, "sc1"), Heartbeat(
            sender="sc1", t_sim=k * DT_S, node="sc1", apps=[], k=k))
        for bus in (net.sim, net.sc1, net.ground):
            bus.published_since_last()


def _fly_until_archived(net: Network, k: int) -> int:
    """Fly ticks from ``k``, 20 ms apart, until the recorder has told sc1 it archived the
    ticks before ``k`` (sc1 forgot them); the ticks flown."""
    first = k
    while min(json.loads(s.payload)["k"] for s in parse_reply(net.sc1.recent.reply())) < first:
        assert k < 500, "the recorder never said what it archived"
        _fly(net, range(k, k + 1))
        k += 1
        time.sleep(0.02)
    return k


def test_a_killed_recorder_restarted_loses_nothing(network: Network, tmp_path: Path) -> None:
    scenario = write_scenario(tmp_path / f"{M}.toml", small_scenario(M, observers={"count": 1}))
    out = tmp_path / "run.mcap"
    first = _recorder(network, scenario, out)
    _fly(network, range(0, 20))
    first.kill()  # at once: the chunk in progress is lost with it
    first.wait(timeout=30.0)
    _fly(network, range(20, 60))  # nobody records: 40 ticks, far more than each node's last
    second = _recorder(network, scenario, out)
    end = _fly_until_archived(network, 60)
    second.send_signal(signal.SIGINT)
    _, err = second.communicate(timeout=30.0)
    assert second.returncode == 0, err.decode()
    archive = load_run(out)
    assert [s.path.name for s in archive.segments] == ["run.mcap", "run-1.mcap"]
    assert archive.lost == {}
    by_key: dict[str, list[int]] = {}
    for r in archive.records():
        by_key.setdefault(r.key, []).append(json.loads(r.payload)["seq"])
    assert by_key == {cat.TICK.key(M): list(range(1, end + 1)),
                      cat.HEARTBEAT.key(M, "sc1"): list(range(1, end + 1))}
