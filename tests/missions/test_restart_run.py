"""Host faults that change no result (issue 27): over Zenoh with --restart-on-crash, a flight
process, the ground, the router and the recorder killed in turn mid-run, each restarted (the
nodes restored from their critical-data stores, the router on its endpoint, the recorder in a
next segment) while the sim holds the clock: every message of the clean run of the same
scenario and seed is in the killed run's archive, with the same content, and none is lost
(the nodes keep what the recorder has not archived yet, whatever the sim flew before it held
the clock, and the recorder asks every node again once the router is back:
``interfaces.runtime.recent``)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import threading
import time
from pathlib import Path
from typing import Any

from harness.archive.reader import load_run
from interfaces.contracts import topics
from interfaces.contracts.messages import StateEstimate, registry
from interfaces.runtime.zenoh_transport import ZenohSettings, ZenohTransport
from tests.conftest import small_scenario, write_scenario
from tests.missions.test_constellation import _fsw_pid, _launch, _wait_pid

M = "chaos"
SC = small_scenario(
    M, duration_s=300.0, target={"pois": 1000}, rates={"high_hz": 5.0, "fdi_period_s": 50.0},
    observers={"count": 3, "initial_attitude": "lvlh"},
    phases=[{"name": "move", "start_s": 100.0, "transfer_s": 600.0, "rho_x_m": 22.0,
             "rho_z_m": 20.0}],
    faults=[{"spacecraft": 3, "kind": "camera_degradation", "start_s": 130.0, "magnitude": 0.5},
            {"spacecraft": 1, "kind": "faulty_data", "start_s": 220.0, "magnitude": 2.0}])
"""A transfer, and two faults, each injected after a kill."""
PATIENCE_S = 300.0
"""The longest wall time any step of a run is waited for: a run starting, reaching a kill's
time, ending (on a loaded 2-core machine a step may take minutes; only a failure waits it
out)."""
NOT_COMPARED = {"Tick", "TickDone", "SimStatus", "ExecStats"}
"""The sim's ticks and the nodes' answers (the open tick is sent again after each kill, and
answered again), the sim's status (it names the participants lost and back) and the
executives' statistics (wall-clock execution times)."""


def _run(tmp_path: Path, port: int, name: str, kills: list[tuple[float, str]]
         ) -> tuple[dict[str, Any], Path]:
    """Fly SC with --restart-on-crash (the default hosting, 2 processes: sc1 and sc2 share one),
    killing at each sim time (s) the process of the node named (``sc<N>``: the flight process
    hosting it); with no kills, the clean run, in one process (the same messages as over Zenoh:
    ``test_constellation.test_same_seed_same_messages_on_zenoh_and_inproc``).  The summary and
    the run's folder."""
    path = write_scenario(tmp_path / f"{M}.toml", SC)
    out = tmp_path / name
    how = (["--realtime", "20", "--restart-on-crash", "--processes", "2"] if kills else
           ["--transport", "inproc"])
    p = _launch(path, out, port, *how)
    try:
        for t_kill, victim in kills:
            _until(out, t_kill)
            os.kill(_pid_of(victim, path, out), signal.SIGKILL)
    finally:
        stdout, stderr = p.communicate(timeout=2 * PATIENCE_S)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["t_sim_final_s"] == SC.duration_s, stderr
    return summary, out


def _pid_of(victim: str, path: Path, out: Path) -> int:
    """The pid of the process of ``victim`` (sc<N>, ground, router, recorder) in the run of
    scenario ``path`` writing to ``out``."""
    if victim.startswith("sc"):
        return _fsw_pid(path, int(victim[2:]), 10.0)[0]
    argv = {"ground": ["ground", "--scenario", str(path)],
            "router": ["deploy.router", "--config", str(out / "access" / "router.json5")],
            "recorder": ["ground.archive.record", "--scenario", str(path)]}[victim]
    return _wait_pid(argv, 10.0)


def _until(out: Path, t_sim: float) -> None:
    """Block until sc1's nav estimate of ``t_sim`` (s) is on the bus."""
    reached = threading.Event()
    deadline = time.monotonic() + PATIENCE_S
    while True:
        try:
            watcher = ZenohTransport(ZenohSettings(config_file=str(out / "access" / "tlm.json5")))
            break
        except Exception:  # noqa: BLE001 - the launcher is still writing the accounts
            assert time.monotonic() < deadline, "the run never started"
            time.sleep(0.2)
    try:
        watcher.subscribe(topics.key(M, "sc1", "nav", "estimate"), lambda _k, _t, p: (
            reached.set() if StateEstimate.model_validate_json(p).t_sim >= t_sim else None))
        assert reached.wait(PATIENCE_S), f"the run never reached t={t_sim} s"
    finally:
        watcher.close()


def _messages(out: Path) -> dict[tuple[str, int], dict[str, Any]]:
    """Every compared message of the run's archive by (key, number), without wall-clock
    fields."""
    got = {}
    for r in load_run(out / "run.mcap").records():
        if r.type_name in NOT_COMPARED:
            continue
        d = json.loads(r.payload)
        for f in registry()[r.type_name].WALL_CLOCK_FIELDS:
            d.pop(f)
        got[(r.key, d["seq"])] = d
    return got


def test_killed_and_restarted_processes_change_no_result(tmp_path: Path, free_port: int) -> None:
    clean, clean_out = _run(tmp_path, free_port, "clean", [])
    assert clean["status"] == "completed"
    kills = [(60.0, "sc2"), (110.0, "ground"), (160.0, "router"), (210.0, "recorder")]
    chaos, chaos_out = _run(tmp_path, free_port, "chaos", kills)
    assert chaos["status"] == "degraded"
    for name in ("sc2", "ground", "router", "recorder"):
        assert f"{name} killed by SIGKILL" in chaos["error"]
    assert "sc2 killed by SIGKILL at" in chaos["error"] and "restored after tick" in chaos["error"]
    assert chaos["archive"]["lost"]["total"] == 0
    assert len(chaos["archive"]["segments"]) == 2
    assert _messages(chaos_out) == _messages(clean_out)
    volatile = {"status", "error", "wall_s", "real_time_factor", "archive", "messages", "sim",
                "exec", "ticks", "transport"}
    assert {k: v for k, v in chaos.items() if k not in volatile} == \
        {k: v for k, v in clean.items() if k not in volatile}
    assert {(d["spacecraft"], d["class"]) for d in clean["detections"]} >= {(3, "camera")}
    assert chaos["detections"] == clean["detections"] and chaos["scores"] == clean["scores"]
    assert chaos["gnc"] == clean["gnc"] and chaos["coverage"] == clean["coverage"]
    assert subprocess.run(["pgrep", "-f", str(tmp_path)], capture_output=True).stdout == b""
