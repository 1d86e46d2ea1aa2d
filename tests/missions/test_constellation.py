"""The constellation as real OS processes over a real Zenoh network
(deploy/run_constellation.py)."""

from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from mcap.reader import make_reader

from deploy.inproc import run_inproc
from harness.archive.reader import RunArchive, load_run
from harness.archive.sequences import by_topic
from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import ExecStats, LinkStats, StateEstimate, TruthState, registry
from interfaces.runtime.zenoh_transport import ZenohSettings, ZenohTransport
from tests.conftest import REPO, small_scenario, write_scenario

LAUNCHER = [sys.executable, str(REPO / "deploy" / "run_constellation.py"), "--no-report"]


def _launch(scenario_path: Path, out: Path, port: int, *extra: str) -> subprocess.Popen[str]:
    endpoint = [] if "inproc" in extra else ["--endpoint", f"tcp/127.0.0.1:{port}"]
    return subprocess.Popen(
        [*LAUNCHER, "--scenario", str(scenario_path), "--out", str(out), *endpoint, *extra],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _join(out: Path, account: str, timeout_s: float = 30.0) -> ZenohTransport:
    """A session on a running launcher's network with one of the run's accounts (written by the
    launcher to <out>/access/ when it starts)."""
    config = out / "access" / f"{account}.json5"
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return ZenohTransport(ZenohSettings(config_file=str(config)))
        except Exception:  # noqa: BLE001 - zenoh raises ZError; the file may not exist yet
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def _comparable(path: Path) -> dict[str, list[dict]]:
    """Per key, the payloads without wall-clock fields.  ExecStats is left out: it reports
    execution times, which are wall-clock measurements by nature."""
    out: dict[str, list[dict]] = {}
    for r in load_run(path).records("**"):
        if r.type_name == "ExecStats":
            continue
        d = json.loads(r.payload)
        for f in registry()[r.type_name].WALL_CLOCK_FIELDS:
            d.pop(f)
        out.setdefault(r.key, []).append(d)
    return out


def test_same_seed_same_messages_on_zenoh_and_inproc(tmp_path: Path, free_port: int) -> None:
    sc = small_scenario("det", duration_s=30.0,
                        comms={"range_m": 36.0, "packet_loss": 0.25,
                               "burst": {"mean_length_packets": 3.0}},
                        phases=[{"name": "move", "start_s": 10.0, "transfer_s": 600.0,
                                 "rho_x_m": 22.0, "rho_z_m": 20.0}])  # an SCP transfer + MPC
    path = write_scenario(tmp_path / "det.toml", sc)
    runs = {}
    for transport in ("zenoh", "inproc"):
        out = tmp_path / transport
        p = _launch(path, out, free_port, "--transport", transport)
        stdout, stderr = p.communicate(timeout=180)
        assert p.returncode == 0, stderr
        runs[transport] = _comparable(out / "run.mcap")
    z, i = runs["zenoh"], runs["inproc"]
    assert sorted(z) == sorted(i)
    for key in z:
        assert z[key] == i[key], f"{key} differs between transports"
    # the channel really acted (range and loss) on the compared traffic
    links = [c for m in z[topics.key("det", "ground", "bus", "link_stats")][-1:]
             for c in m["links"]]
    assert sum(c["dropped_loss"] for c in links) > 0 and sum(c["delivered"] for c in links) > 0
    # the transfer was planned (or refused) identically: compare the plans themselves
    assert any(k.endswith("/guidance/plan") for k in z)


def _under_way(out: Path, mission: str, estimates: int = 5) -> None:
    """Block until sc1's nav has published ``estimates`` times (the run is demonstrably going)."""
    seen = threading.Semaphore(0)
    watcher = _join(out, "tlm")
    try:
        watcher.subscribe(topics.key(mission, "sc1", "nav", "estimate"), lambda *_: seen.release())
        for _ in range(estimates):
            assert seen.acquire(timeout=60), "the run never got going"
    finally:
        watcher.close()


def _times(archive_path: Path, key: str) -> np.ndarray:
    return np.array([m.t_sim for m in load_run(archive_path).messages(key, StateEstimate)])


LINK_FAULT_BOUND_S = 2 * 30.0 + 3.0
"""The stated time to declare a dead spacecraft a link fault on a lossless link: two FDI
windows of 30 s (the one it died in, and one silent window, which decides alone) and the
FDIR's latency (docs/architecture.md, "A dead spacecraft is a fault, not the end")."""


def test_dead_and_stalled_processes_are_faults_not_the_end(tmp_path: Path, free_port: int) -> None:
    """sc2 killed (no restart): the sim flies on, the ground declares sc2 a link fault within the
    stated time, the others finish; sc3 stalled past the network's lease and resumed: it
    rejoins the lockstep and its telemetry resumes.  The run says it is degraded, and why."""
    sc = small_scenario("dead", duration_s=400.0)
    path = write_scenario(tmp_path / "dead.toml", sc)
    out = tmp_path / "out"
    p = _launch(path, out, free_port, "--realtime", "20",  # 20 s of wall time if undisturbed
                "--hosting", "one-per-process")
    try:
        _under_way(out, "dead")
        os.kill(_wait_pid(["fsw", "--spacecraft", "2", "--scenario", str(path)], 10.0),
                signal.SIGKILL)
        sc3 = _wait_pid(["fsw", "--spacecraft", "3", "--scenario", str(path)], 10.0)
        os.kill(sc3, signal.SIGSTOP)
        time.sleep(14.0)  # past the 10 s lease: the router drops it, the sim flies on
        os.kill(sc3, signal.SIGCONT)
    finally:
        stdout, stderr = p.communicate(timeout=120)
    assert p.returncode == 1 and "degraded" in stdout, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "degraded" and "sc2 killed by SIGKILL" in summary["error"]
    assert summary["t_sim_final_s"] == sc.duration_s  # the mission went on to its end
    events = summary["sim"]["participants"]
    assert [e["what"] for e in events["sc2"]] == ["lost"]
    assert [e["what"] for e in events["sc3"]] == ["lost", "rejoined"]
    t_dead = events["sc2"][0]["t_sim"]
    link = [d for d in summary["detections"] if d["spacecraft"] == 2 and d["class"] == "link"]
    assert link and link[0]["time_s"] - t_dead <= LINK_FAULT_BOUND_S
    archive = out / "run.mcap"
    assert _times(archive, topics.key("dead", "sc1", "nav", "estimate"))[-1] >= 399.0
    assert _times(archive, topics.key("dead", "sc2", "nav", "estimate"))[-1] <= t_dead
    sc3_t = _times(archive, topics.key("dead", "sc3", "nav", "estimate"))
    assert sc3_t[-1] >= 399.0 and np.diff(sc3_t).max() > 20.0  # a gap, then back
    outages = {e["spacecraft"]: e["outages"] for e in summary["telemetry"]}
    lost_at, back_at = (e["t_sim"] for e in events["sc3"])
    assert any(a <= lost_at and back_at <= b + 30.0 for a, b in outages[3])  # the report shows it
    assert not load_run(archive).truncated


def test_restart_on_crash_rejoins_the_lockstep(tmp_path: Path, free_port: int) -> None:
    """The process of sc2 killed (the default hosting: sc2 and those packed with it, stepping
    together; one process per node: test_dead_and_stalled_processes_are_faults_not_the_end):
    every spacecraft it hosts is lost, restarted from its critical-data store and back in the
    lockstep while the sim holds the clock."""
    sc = small_scenario("again", duration_s=200.0)
    path = write_scenario(tmp_path / "again.toml", sc)
    out = tmp_path / "out"
    p = _launch(path, out, free_port, "--realtime", "10", "--restart-on-crash",
                "--processes", "2")
    try:
        _under_way(out, "again")
        pid, hosted = _fsw_pid(path, 2, 10.0)
        os.kill(pid, signal.SIGKILL)
    finally:
        stdout, stderr = p.communicate(timeout=120)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "degraded" and "(restarted: restored after tick" in \
        summary["error"], stderr
    assert hosted == [1, 2]  # 3 observers in 2 processes: sc1 and sc2, then sc3
    participants = summary["sim"]["participants"]
    assert sorted(participants) == [f"sc{i}" for i in hosted]
    for i in hosted:
        assert [e["what"] for e in participants[f"sc{i}"]] == ["lost", "rejoined"]
        t_lost, t_back = (e["t_sim"] for e in participants[f"sc{i}"])
        assert t_back - t_lost <= sc.rates.dt_s  # the sim held the clock while it restarted
        t = _times(out / "run.mcap", topics.key("again", f"sc{i}", "nav", "estimate"))
        assert t[-1] >= 199.0 and (t < t_lost).any()  # before the crash, and to the end
    host = "+".join(f"sc{i}" for i in hosted)
    assert (out / "logs" / f"{host}.restart1.log").is_file()


def _killed_mid_run(tmp_path: Path, port: int, name: str,
                    victim: Callable[[Path, Path], list[str]], *extra: str,
                    duration_s: float = 400.0, status: str = "failed",
                    ) -> tuple[dict[str, Any], float, Path]:
    """A run of ``duration_s`` (400 s) paced at 10x (40 s of wall time) with the launcher's
    ``extra`` options, whose process ``victim(scenario, out)`` names (its command line) is
    killed once the run is under way; it ends with ``status`` (a failed run keeps what was
    recorded).  The summary, the wall time from the kill to the launcher's exit, and the
    scenario's path."""
    sc = small_scenario(name, duration_s=duration_s)
    path = write_scenario(tmp_path / f"{name}.toml", sc)
    out = tmp_path / "out"
    p = _launch(path, out, port, "--realtime", "10", *extra)
    killed = time.monotonic()
    try:
        _under_way(out, name, estimates=40)  # 4 s of wall: the recorder has flushed
        os.kill(_wait_pid(victim(path, out), 10.0), signal.SIGKILL)
        killed = time.monotonic()
    finally:
        _, stderr = p.communicate(timeout=120)
    assert p.returncode == 1, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == status, summary["error"]
    if status == "failed":
        assert 0.0 < summary["t_sim_final_s"] < sc.duration_s  # what was recorded is kept
    return summary, time.monotonic() - killed, path


def _recorder(path: Path, _out: Path) -> list[str]:
    """The recorder's command line (of the run of scenario ``path``)."""
    return ["ground.archive.record", "--scenario", str(path)]


def test_recorder_death_stops_the_run_at_once(tmp_path: Path, free_port: int) -> None:
    summary, after_s, _ = _killed_mid_run(tmp_path, free_port, "norec", _recorder)
    assert after_s < 15.0  # not the 40 s of the run
    assert "recorder" in summary["error"] and "nothing after it is recorded" in summary["error"]
    assert summary["archive"]["truncated"]


def _seqs(archive: RunArchive) -> dict[str, list[int]]:
    """Each key's sequence numbers, in archive order."""
    out: dict[str, list[int]] = {}
    for r in archive.held():
        out.setdefault(r.key, []).append(json.loads(r.payload)["seq"])
    return out


def test_restarted_recorder_continues_the_archive_in_a_next_segment(tmp_path: Path,
                                                                    free_port: int) -> None:
    """With --restart-on-crash a killed recorder is an incident, not the end: started again,
    it writes run-1.mcap, which the summary reads with run.mcap as one run to the end; the
    messages lost are those sent between the first segment's last complete chunk and the
    restarted recorder's first message, counted by topic, and no other."""
    summary, _, _ = _killed_mid_run(tmp_path, free_port, "rerec", _recorder,
                                    "--restart-on-crash", duration_s=200.0, status="degraded")
    out = tmp_path / "out"
    assert "recorder killed by SIGKILL" in summary["error"] and "(restarted)" in summary["error"]
    assert (out / "logs" / "recorder.restart1.log").is_file()
    assert summary["t_sim_final_s"] == 200.0  # read to the end, in the second segment
    info = summary["archive"]
    assert info["segments"] == [{"file": "run.mcap", "truncated": True},
                                {"file": "run-1.mcap", "truncated": False}]
    with open(out / "run-1.mcap", "rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    assert meta["segment"] == {"index": "1", "first": "run.mcap"}
    assert meta["run"]["scenario"] == "rerec" and "resolved_json" in meta["scenario"]
    # lost: exactly the gap between the segments, key by key
    first_alone = tmp_path / "first" / "run.mcap"
    first_alone.parent.mkdir()
    first_alone.write_bytes((out / "run.mcap").read_bytes())
    first = load_run(first_alone)
    run = load_run(out / "run.mcap")
    assert first.lost == {} and len(run) == summary["messages"]["total"]
    before, merged = _seqs(first), _seqs(run)
    gaps = {k: s[len(before.get(k, []))] - (before[k][-1] if k in before else 0) - 1
            for k, s in merged.items() if len(s) > len(before.get(k, []))}
    assert run.lost == {k: n for k, n in gaps.items() if n}
    # by topic in the summary (how many depends on when the kill fell between two flushes of
    # the recorder, and on how long the sim flew on without it)
    assert info["lost"] == {"total": sum(run.lost.values()), "by_topic": by_topic(run.lost)}


def test_router_death_stops_the_run_at_once_naming_it(tmp_path: Path, free_port: int) -> None:
    summary, after_s, path = _killed_mid_run(
        tmp_path, free_port, "norouter",
        lambda _, out: ["deploy.router", "--config", str(out / "access" / "router.json5")])
    assert after_s < 20.0  # not the 40 s of the run
    assert summary["error"].startswith("router") and "the bus is down" in summary["error"]
    assert "at sim t≈" in summary["error"]
    deadline = time.monotonic() + 10.0
    while _pids_with(str(path)) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _pids_with(str(path)) == []  # nothing left running without its bus


def test_malformed_messages_are_dropped_and_the_app_goes_on(tmp_path: Path, free_port: int) -> None:
    sc = small_scenario("bad", duration_s=200.0)
    path = write_scenario(tmp_path / "bad.toml", sc)
    out = tmp_path / "out"
    p = _launch(path, out, free_port, "--realtime", "20")
    _fsw_pid(path, 1, timeout_s=30.0)
    # the sim's own account (a compromised sim): the router lets it publish on sc1's sensor keys
    hostile = _join(out, "sim")
    key = cat.RELNAV.key("bad", "sc1")  # what sc1's nav app subscribes to
    running = threading.Semaphore(0)
    try:
        # inject only once sc1 is demonstrably subscribed and running (not on a timer: a loaded
        # machine starts processes slowly)
        hostile.subscribe(topics.key("bad", "sc1", "nav", "estimate"), lambda *_: running.release())
        assert running.acquire(timeout=60), "the run never got going"
        for _ in range(10):
            hostile.publish(key, "RelNavMeasurement", b'{"garbage": true}')
            hostile.publish(key, "RelNavMeasurement", b"\xff\xfe")
            time.sleep(0.1)
    finally:
        hostile.close()
    stdout, stderr = p.communicate(timeout=60)
    assert p.returncode == 0, stderr
    archive = load_run(out / "run.mcap")
    stats = archive.messages(topics.key("bad", "sc1", "exec", "stats"), ExecStats)
    assert stats[-1].invalid_dropped >= 10 and stats[-1].app_errors == 0
    est = archive.messages(topics.key("bad", "sc1", "nav", "estimate"), StateEstimate)
    # nav kept running to the end (in real-time mode the sim does not wait for late answers,
    # so on a loaded machine the last tick's estimate may miss the archive)
    assert est[-1].t_sim >= sc.duration_s - 2.0


def test_range_limited_link_cuts_and_restores_with_distance() -> None:
    """Ground link of each observer over half an orbit: delivered exactly while within range."""
    sc = small_scenario("range", duration_s=2900.0, comms={"range_m": 36.0},
                        rates={"high_hz": 1.0, "mid_hz": 1.0, "low_hz": 0.1})
    truth: dict[float, np.ndarray] = {}
    links: list[LinkStats] = []

    def tap(key: str, type_name: str, payload: bytes) -> None:
        if type_name == "TruthState":
            m = TruthState.model_validate_json(payload)
            truth[m.t_sim] = np.linalg.norm(np.array(m.r_lvlh_m), axis=1)
        elif type_name == "LinkStats" and "/ground/" in key:
            links.append(LinkStats.model_validate_json(payload))

    run_inproc(sc, tap=tap)
    for sc_id in (1, 2, 3):
        prev = None
        pattern = []
        for m in links:
            c = next((c for c in m.links if c.src == f"sc{sc_id}"), None)
            if c is None:
                continue
            if prev is not None:
                d_dist = c.delivered - prev.delivered
                d_range = c.dropped_range - prev.dropped_range
                dist = truth[m.t_sim - 1.0][sc_id - 1]  # sent one tick before delivery
                if abs(dist - sc.comms.range_m) > 0.05:  # away from the boundary
                    assert (d_dist > 0) == (dist <= sc.comms.range_m), (sc_id, m.t_sim, dist)
                    assert (d_range > 0) == (dist > sc.comms.range_m), (sc_id, m.t_sim, dist)
                pattern.append("D" if d_dist > 0 else "R")
            prev = c
        runs = "".join(ch for i, ch in enumerate(pattern) if i == 0 or pattern[i - 1] != ch)
        assert "DRD" in runs or "RDR" in runs, f"sc{sc_id} link never cut and restored: {runs}"


def _pids_with(argument: str) -> list[int]:
    """PIDs of the processes with ``argument`` in their command line."""
    out = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        if argument.encode() in cmd:
            out.append(int(pid))
    return out


def test_terminated_launcher_stops_every_process(tmp_path: Path, free_port: int) -> None:
    """SIGTERM to the launcher (a scheduler, ``kill``) stops the whole constellation and still
    writes the archive and a failed summary; nothing is left holding the port."""
    sc = small_scenario("term", duration_s=400.0)
    path = write_scenario(tmp_path / "term.toml", sc)
    out = tmp_path / "out"
    p = _launch(path, out, free_port, "--realtime", "20")
    try:
        _fsw_pid(path, 1, timeout_s=30.0)
        watcher = _join(out, "tlm")
        seen = threading.Semaphore(0)
        try:
            watcher.subscribe(topics.key("term", "sc1", "nav", "estimate"),
                              lambda *_: seen.release())
            assert seen.acquire(timeout=60), "the run never got going"
        finally:
            watcher.close()
        assert len(_pids_with(str(path))) >= 5  # sim, 3 observers, ground, recorder
    finally:
        p.send_signal(signal.SIGTERM)  # also the clean-up if anything above failed
    _, stderr = p.communicate(timeout=60)
    assert p.returncode == 128 + signal.SIGTERM and "interrupted" in stderr
    deadline = time.monotonic() + 10.0
    router_config = str(out / "access" / "router.json5")
    while (_pids_with(str(path)) or _pids_with(router_config)) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _pids_with(str(path)) == [] and _pids_with(router_config) == []  # the router too
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"  # deploy/interrupts.py
    assert not load_run(out / "run.mcap").truncated


def _fsw_pid(path: Path, spacecraft: int, timeout_s: float) -> tuple[int, list[int]]:
    """PID of the flight process of a run of ``path`` hosting ``spacecraft``, and the ids of
    the spacecraft it hosts."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        for pid in filter(str.isdigit, os.listdir("/proc")):
            try:
                cmd = Path(f"/proc/{pid}/cmdline").read_bytes().decode().split("\0")
            except OSError:
                continue
            if cmd[1:3] != ["-m", "fsw"] or str(path) not in cmd or "--spacecraft" not in cmd:
                continue
            i = cmd.index("--spacecraft") + 1
            hosted = [int(a) for a in itertools.takewhile(str.isdigit, cmd[i:])]
            if spacecraft in hosted:
                return int(pid), hosted
        time.sleep(0.1)
    raise TimeoutError(f"no flight process hosting sc{spacecraft}")


def _wait_pid(argv_parts: list[str], timeout_s: float) -> int:
    """PID of the process whose command line contains ``argv_parts`` consecutively."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        for pid in os.listdir("/proc"):
            if not pid.isdigit():
                continue
            try:
                cmd = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
            except OSError:
                continue
            text = [c.decode(errors="replace") for c in cmd]
            n = len(argv_parts)
            if any(text[i:i + n] == argv_parts for i in range(len(text) - n + 1)):
                return int(pid)
        time.sleep(0.1)
    raise TimeoutError(f"no process with {argv_parts}")
