"""A host map rehearsed on this machine (docs/hosts.md; deploy/rehearsal/): three hosts, each
in a network namespace of its own, the ground host (the hub router, the ground, the sim and the
recorder) and two spacecraft hosts, every link 2 ms one way through the rehearsal's switch.

The run gives the summary of the same scenario flown in one process; a stranger in another
namespace (this test's own, on the hosts' network), with no credentials or with sc2's trying
to publish as sc1 and the others, changes nothing and is counted refused by the routers; and
nothing the rehearsal made is left: namespaces, links, processes.  Skipped, with the reason,
where namespaces cannot be made."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
import zenoh

from deploy.host_map import load_host_map
from deploy.rehearsal import netns
from deploy.rehearsal.netns import unavailable
from deploy.rehearsal.network import RehearsedNetwork
from harness.archive.reader import load_run
from interfaces.contracts import catalogue as cat
from tests.conftest import REPO, settle, small_scenario, write_scenario
from tests.missions.test_access_run import _forgeries, _open_when_up

M = "acc"  # the forgeries' mission
TRIO = REPO / "deploy" / "hosts" / "trio.toml"
LAUNCHER = [sys.executable, str(REPO / "deploy" / "run_constellation.py"), "--no-report"]
VARYING = {"wall_s", "real_time_factor", "messages", "exec", "access", "transport"}
"""Summary fields that differ between two identical runs (wall clock), or count the attack."""


needs_namespaces = pytest.mark.skipif(unavailable() is not None, reason=str(unavailable()))


def _open(config: dict[str, Any]) -> zenoh.Session:
    return zenoh.open(zenoh.Config.from_json5(json.dumps(config)))


def _as(out: Path, host: str, account: str, address: str) -> dict[str, Any]:
    """``account``'s credentials (from ``host``'s folder) on the TLS endpoint ``address``."""
    config = json.loads((out / "access" / host / f"{account}.json5").read_text())
    tlm = json.loads((out / "access" / "tlm.json5").read_text())
    config["connect"]["endpoints"] = [f"tls/{address}:7447"]
    config["transport"]["link"] = tlm["transport"]["link"]
    return config


def _stranger(out: Path) -> int:
    """Once the run is under way, from this namespace: refused without credentials on every
    router and with sc2's on the hub (not its host); with sc2's on its own host's router,
    every forgery sent 20 times.  Returns the forgeries sent."""
    settle(lambda: (out / "access" / "tlm.json5").is_file(), timeout_s=60.0)
    tlm = json.loads((out / "access" / "tlm.json5").read_text())
    watcher = _open_when_up(tlm, timeout_s=60.0)
    running: list[int] = []
    watcher.declare_subscriber(cat.NAV_ESTIMATE.key(M, "sc1"), lambda s: running.append(1))
    settle(lambda: len(running) >= 3, timeout_s=120.0)
    assert running, "the run never got going"
    for address in ("10.78.0.1", "10.78.0.11", "10.78.0.12"):
        anonymous = _as(out, "scb", "sc2", address)
        del anonymous["transport"]["auth"]
        with pytest.raises(zenoh.ZError):
            _open(anonymous)
    with pytest.raises(zenoh.ZError):  # sc2 has no account on the hub
        _open(_as(out, "scb", "sc2", "10.78.0.1"))
    attacker = _open(_as(out, "scb", "sc2", "10.78.0.12"))
    try:
        for key, msg in _forgeries():
            for _ in range(20):
                attacker.put(key, msg.model_dump_json().encode())
        time.sleep(2.0)  # closing a session drops what it has not sent yet
    finally:
        attacker.close()
        watcher.close()
    return 20 * len(_forgeries())


@needs_namespaces
def test_a_rehearsed_map_flies_as_in_one_process_and_leaves_nothing(tmp_path: Path) -> None:
    sc = small_scenario(M, duration_s=150.0, observers={"count": 2},
                        fdir={"floor": 0.05, "persistence": 2})
    path = write_scenario(tmp_path / "hosts.toml", sc)
    one = subprocess.run([*LAUNCHER, "--scenario", str(path), "--out", str(tmp_path / "one"),
                          "--transport", "inproc"], cwd=REPO, capture_output=True, text=True,
                         timeout=300)
    assert one.returncode == 0, one.stderr
    rehearsal = subprocess.Popen(
        [*LAUNCHER, "--scenario", str(path), "--out", str(tmp_path / "hosts"), "--hosts",
         str(TRIO), "--rehearse", "--audit-access", "--realtime", "20"],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        forged = _stranger(tmp_path / "hosts")
    finally:
        _, err = rehearsal.communicate(timeout=300)
    assert rehearsal.returncode == 0, err
    a, b = (json.loads((tmp_path / r / "summary.json").read_text()) for r in ("one", "hosts"))
    assert b["sim"].pop("pace")["ceiling"] == 20.0  # paced, in lockstep: the same results
    for field in sorted(set(a) | set(b)):
        if field not in VARYING:
            assert a.get(field) == b.get(field), field
    refused = b["access"]["refused"]
    assert sum(n for kind, n in refused.items() if kind.endswith(" by sc2")) >= (
        forged - len(_forgeries()))  # a publisher's first put may go uncounted
    assert sum(n for kind, n in refused.items() if kind.startswith("login")) >= 4
    wire = json.loads((tmp_path / "hosts" / "logs" / "wire.json").read_text())
    assert all(wire[h]["sent"] > 100 for h in ("ground", "sca", "scb"))  # they talked over it
    assert netns.ours(rehearsal.pid) == []
    links = subprocess.run(["ip", "-o", "link"], capture_output=True, text=True).stdout
    assert f"i{rehearsal.pid % 100000}." not in links


@needs_namespaces
def test_a_spacecraft_hosts_link_cut_for_30_s_is_a_link_fault_of_its_spacecraft_alone(
        tmp_path: Path) -> None:
    """sca's link cut at 40 s for 30 s: sc1 is lost from the tick after 40 s and rejoins at the
    tick after 70 s (the sim holds the clock for the network at both), sc2 flies on, and the
    ground names a link fault on sc1 and nothing else; nothing is lost from the archive."""
    sc = small_scenario(M, duration_s=150.0, observers={"count": 2},
                        fdir={"floor": 0.05, "persistence": 2})
    path = write_scenario(tmp_path / "cut.toml", sc)
    done = subprocess.run([*LAUNCHER, "--scenario", str(path), "--out", str(tmp_path / "cut"),
                           "--hosts", str(TRIO), "--rehearse", "--link-event", "sca:cut:40:30"],
                          cwd=REPO, capture_output=True, text=True, timeout=300)
    assert done.returncode == 1, done.stderr  # degraded: sc1 was lost
    summary = json.loads((tmp_path / "cut" / "summary.json").read_text())
    assert summary["status"] == "degraded" and summary["t_sim_final_s"] == 150.0
    assert summary["sim"]["participants"] == {"sc1": [{"what": "lost", "t_sim": 40.0},
                                                      {"what": "rejoined", "t_sim": 70.0}]}
    assert [(d["spacecraft"], d["class"]) for d in summary["detections"]] == [(1, "link")]
    assert load_run(tmp_path / "cut" / "run.mcap").lost == {}
    events = json.loads((tmp_path / "cut" / "logs" / "link-events.json").read_text())
    assert [(e["started_t_s"], e["ended_t_s"]) for e in events] == [(40.0, 70.0)]


@needs_namespaces
def test_a_launcher_killed_outright_leaves_namespaces_the_next_removes(tmp_path: Path) -> None:
    trio = load_host_map(TRIO)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    left = [netns.namespace(dead.pid, h.name) for h in trio.hosts]
    for name in left:
        netns.add(name)
    try:
        with RehearsedNetwork(trio.hosts, trio.network, tmp_path / "logs", seed=1) as net:
            assert not any(n in os.listdir(netns.NETNS_DIR) for n in left)
            assert sorted(netns.ours(os.getpid())) == sorted(
                net.netns(h.name) for h in trio.hosts)
        assert netns.ours(os.getpid()) == []
    finally:
        for name in left:
            netns.remove(name)


@pytest.mark.skipif(shutil.which("setpriv") is None, reason="needs util-linux's setpriv")
def test_without_the_privilege_a_rehearsal_stops_at_once_naming_it(tmp_path: Path) -> None:
    out = tmp_path / "out"
    drop = ["setpriv", "--bounding-set", "-sys_admin,-net_admin", "--inh-caps",
            "-sys_admin,-net_admin"]
    done = subprocess.run([*drop, *LAUNCHER, "--hosts", str(REPO / "deploy" / "hosts" / "lab.toml"),
                           "--rehearse", "--out",
                           str(out)], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    assert "needs CAP_SYS_ADMIN and CAP_NET_ADMIN" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and not out.exists()
