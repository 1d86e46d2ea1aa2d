"""Forged messages sent during a real multi-process run over TLS (deploy/access.py), by a client
without credentials and by a client with another node's credentials, change nothing, and the
router counts them."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest
import zenoh

from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    FaultReport,
    InfoCostTelemetry,
    Message,
    ProAssignments,
    RelNavMeasurement,
    SimStatus,
    ThrustCommand,
    Tick,
    TickDone,
)
from tests.conftest import REPO, settle, small_scenario, write_scenario
from tests.deploy.test_access import M, _open

LAUNCHER = [sys.executable, str(REPO / "deploy" / "run_constellation.py"), "--no-report"]


def _forgeries() -> list[tuple[str, Message]]:
    """The forged messages of issue 16's table, each on the key its victim listens to."""
    sc1_tick = 100.0
    return [
        (cat.THRUST.key(M, "sc1"), ThrustCommand(sender="sc1", t_sim=sc1_tick, spacecraft=1,
                                                 force_body_n=[0.02, 0, 0], duration_s=60.0)),
        (cat.ASSIGNMENTS.key(M), ProAssignments(sender="ground", seq=10**6, t_sim=sc1_tick,
                                                assignments=[])),
        (cat.FAULT_REPORT.key(M), FaultReport(sender="ground", t_sim=sc1_tick, spacecraft=2,
                                              fault_class="camera", window_end_s=sc1_tick)),
        (cat.INFO_COST.key(M, "sc1"), InfoCostTelemetry(
            sender="sc1", t_sim=sc1_tick, spacecraft=1, h_i=0.0, h_local=0.0, prior_term=0.0,
            pois_seen_own=0, pois_seen_fused=0, images=0, shared_received=0)),
        (cat.SIM_STATUS.key(M), SimStatus(sender="sim", t_sim=sc1_tick, state="finished")),
        (cat.TICK.key(M), Tick(sender="sim", t_sim=5e5, k=10**6, dt_s=0.5)),
        (cat.TICK_DONE.key(M, "sc1"), TickDone(sender="sc1", t_sim=sc1_tick, k=200)),
        (cat.RELNAV.key(M, "sc1"), RelNavMeasurement(
            sender="sim", seq=10**9, t_sim=sc1_tick, spacecraft=1, r_m=[9e4, 0, 0],
            v_mps=[0, 0, 0], sigma_r_m=0.1, sigma_v_mps=0.01)),
    ]


def _attack(out: Path, endpoint: str) -> int:
    """Once the run is under way: a stranger without credentials is refused; with sc2's
    credentials every forgery is sent 20 times, then 2000 messages dated t = 1e6 s and a jump to
    sequence number 1e12 on sc2's own heartbeat key.  Returns the messages the router must
    refuse."""
    settle(lambda: (out / "access" / "router.json5").is_file(), timeout_s=30.0)
    attacker = _open_when_up(out / "access" / "sc2.json5")
    config = json.loads((out / "access" / "tlm.json5").read_text())
    del config["transport"]["auth"]
    with pytest.raises(zenoh.ZError):
        _open(config)
    try:
        running: list[int] = []
        attacker.declare_subscriber(cat.NAV_ESTIMATE.key(M, "sc1"), lambda s: running.append(1))
        settle(lambda: len(running) >= 3, timeout_s=60.0)
        assert running, "the run never got going"
        for key, msg in _forgeries():
            for _ in range(20):
                attacker.put(key, msg.model_dump_json().encode())
        heartbeat = cat.HEARTBEAT.key(M, "sc2")
        for i in range(2000):
            attacker.put(heartbeat, json.dumps({"sender": "sc2", "seq": 10**6 + i, "t_sim": 1e6,
                                                "node": "sc2", "apps": [], "k": 1}).encode())
        attacker.put(heartbeat, json.dumps({"sender": "sc2", "seq": 10**12, "t_sim": 1.0,
                                            "node": "sc2", "apps": [], "k": 1}).encode())
        time.sleep(2.0)  # closing a session drops what it has not sent yet
    finally:
        attacker.close()
    return 20 * len(_forgeries())


def _open_when_up(config: Path | dict, timeout_s: float = 30.0) -> zenoh.Session:
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return _open(config)
        except zenoh.ZError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def _launch(scenario: Path, out: Path, endpoint: str) -> subprocess.Popen[str]:
    return subprocess.Popen([*LAUNCHER, "--scenario", str(scenario), "--out", str(out),
                             "--endpoint", endpoint, "--audit-access"],
                            cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


VARYING = {"wall_s", "real_time_factor", "messages", "exec", "access"}
"""Summary fields that differ between two identical runs (wall clock) or count the attack."""


def test_forged_messages_change_nothing_over_tls(tmp_path: Path, free_port: int) -> None:
    sc = small_scenario(M, duration_s=150.0, observers={"count": 2},
                        fdir={"floor": 0.05, "persistence": 2})
    path = write_scenario(tmp_path / "acc.toml", sc)
    endpoint = f"tls/127.0.0.1:{free_port}"
    clean = _launch(path, tmp_path / "clean", endpoint)
    _, err = clean.communicate(timeout=300)
    assert clean.returncode == 0, err
    attacked = _launch(path, tmp_path / "attacked", endpoint)
    try:
        forged = _attack(tmp_path / "attacked", endpoint)
    finally:
        _, err = attacked.communicate(timeout=300)
    assert attacked.returncode == 0, err
    a, b = (json.loads((tmp_path / r / "summary.json").read_text())
            for r in ("clean", "attacked"))
    for field in sorted(set(a) | set(b)):
        if field not in VARYING:
            assert a.get(field) == b.get(field), field
    refused = b["access"]["refused"]
    by_router = sum(n for kind, n in refused.items() if kind.endswith(" by sc2"))
    assert by_router >= forged - len(_forgeries())  # a publisher's first put may go uncounted
    assert a["access"]["total"] == 0
    # what sc2 may publish reached the ground and was refused there (dated 1e6 s, seq 1e12): as
    # much of the burst as arrived before the ground's last statistics
    assert 0 < b["exec"]["ground"]["refused"] <= 2001 and a["exec"]["ground"]["refused"] == 0
