"""Soak: host faults that change no result (issue 27).  Two orbits of the default mission over
Zenoh with ``--restart-on-crash``, beside a clean run of the same scenario and seed; a chaos
schedule kills, in turn, a random flight process, the ground, the recorder and the router,
every few simulated minutes.

    python benchmarks/soak.py [--duration S] [--every S] [--seed N] [--out DIR]

Prints each kill (what, when), then the soak run against the clean one:

* the detections (time, spacecraft, class) and the summary's figures, equal or not;
* every message of the clean run's archive looked for in the soak's segments, by key and
  sequence number, its content compared without wall-clock fields (the lockstep's ticks and
  answers, the sim's status and the executives' statistics set apart: the open tick is sent
  again after each kill and answered again, the status names who was lost, the statistics are
  wall-clock times);
* the messages the soak's archive counts lost, by topic (only those in flight at a kill may
  be), and its segments.

Exit status 0 when the soak run's results and messages are the clean run's and nothing was
lost; 1 otherwise.  About twice the reference mission's Zenoh wall time (two runs).
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from harness.archive.reader import Record, load_run  # noqa: E402
from interfaces.contracts import catalogue as cat  # noqa: E402
from interfaces.contracts import topics  # noqa: E402
from interfaces.contracts.messages import Heartbeat, registry  # noqa: E402
from interfaces.contracts.scenario import load_scenario  # noqa: E402
from interfaces.runtime.zenoh_transport import ZenohSettings, ZenohTransport  # noqa: E402

SCENARIO = REPO / "deploy" / "scenarios" / "default.toml"
TWO_ORBITS_S = 11354.0
SET_APART = {"Tick", "TickDone", "SimStatus", "ExecStats"}
VOLATILE = {"status", "error", "wall_s", "real_time_factor", "archive", "messages", "sim",
            "exec", "ticks"}
"""Summary fields a restart changes by nature: how the run went, its wall time, its archive's
files and message counts, the lockstep's events, the executives' wall-clock statistics."""
_T_WALL = re.compile(rb'"t_wall":[^,}]*,?')


def main(argv: list[str] | None = None) -> int:
    sys.stdout.reconfigure(line_buffering=True)  # type: ignore[union-attr]
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--duration", type=float, default=TWO_ORBITS_S, help="simulated s")
    p.add_argument("--every", type=float, default=240.0, help="simulated s between kills")
    p.add_argument("--seed", type=int, default=42, help="the chaos schedule's seed")
    p.add_argument("--out", type=Path, help="where the two runs go (default: a temp folder)")
    p.add_argument("--reuse-clean", action="store_true",
                   help="take the clean run already in --out (same duration and code)")
    args = p.parse_args(argv)
    out = args.out or Path(tempfile.mkdtemp(prefix="soak-"))
    if args.reuse_clean and (out / "clean" / "summary.json").is_file():
        clean = json.loads((out / "clean" / "summary.json").read_text())
        print(f"clean run: {clean['status']}, {clean['duration_s']:.0f} s in "
              f"{clean['wall_s']:.0f} s wall (reused)")
    else:
        clean, clean_wall = _fly(out / "clean", args.duration, 17551, [])
        print(f"clean run: {clean['status']}, {args.duration:.0f} s in {clean_wall:.0f} s wall")
    schedule = _schedule(args.duration, args.every, np.random.default_rng(args.seed))
    soak, soak_wall = _fly(out / "soak", args.duration, 17552, schedule)
    print(f"soak run: {soak['status']}, {args.duration:.0f} s in {soak_wall:.0f} s wall, "
          f"{len(schedule)} kills")
    ok = _compare(clean, soak, out)
    print(f"\nruns in {out}\n{'PASS' if ok else 'FAIL'}: the soak run's results and messages "
          f"{'are' if ok else 'are not'} the clean run's")
    return 0 if ok else 1


def _schedule(duration_s: float, every_s: float, rng: np.random.Generator
              ) -> list[tuple[float, str]]:
    """(sim time s, process) kills: a random flight process, the ground, the recorder, the
    router, in turn, every ``every_s`` until a kill's worth before the end."""
    n = load_scenario(SCENARIO).observers.count
    kinds = ["flight", "ground", "recorder", "router"]
    out = []
    for i, t in enumerate(np.arange(every_s, duration_s - every_s / 2, every_s)):
        kind = kinds[i % len(kinds)]
        out.append((float(t), f"sc{rng.integers(1, n + 1)}" if kind == "flight" else kind))
    return out


def _fly(out: Path, duration_s: float, port: int, schedule: list[tuple[float, str]]
         ) -> tuple[dict[str, Any], float]:
    """One run of the default scenario, killing the processes of ``schedule`` at its times;
    its summary and wall time."""
    argv = [sys.executable, str(REPO / "deploy" / "run_constellation.py"), "--scenario",
            str(SCENARIO), "--out", str(out), "--duration", str(duration_s), "--no-report",
            "--restart-on-crash", "--endpoint", f"tcp/127.0.0.1:{port}"]
    wall0 = time.monotonic()
    launcher = subprocess.Popen(argv, cwd=REPO, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
    clock = _SimClock(out) if schedule else None
    try:
        for t_kill, victim in schedule:
            assert clock is not None
            if not clock.wait_for(t_kill, launcher):
                break
            pid = _pid_of(victim, out)
            print(f"  t≈{clock.t:7.1f} s: killing {victim} (pid {pid})", flush=True)
            if pid:
                os.kill(pid, signal.SIGKILL)
        launcher.wait()
    finally:
        if clock is not None:
            clock.close()
        if launcher.poll() is None:
            launcher.terminate()
            launcher.wait(timeout=60)
    return json.loads((out / "summary.json").read_text()), time.monotonic() - wall0


class _SimClock:
    """The run's sim time, from the ground's heartbeat (read-only telemetry account)."""

    def __init__(self, out: Path) -> None:
        self.t = 0.0
        self._tick = threading.Condition()
        self._session = _join(out)
        self._session.subscribe(cat.HEARTBEAT.key(_mission(), topics.GROUND), self._on)

    def _on(self, _key: str, _type: str, payload: bytes) -> None:
        with self._tick:
            self.t = Heartbeat.model_validate_json(payload).t_sim
            self._tick.notify_all()

    def close(self) -> None:
        self._session.close()

    def wait_for(self, t_sim: float, launcher: subprocess.Popen[bytes]) -> bool:
        """Block until the run reaches ``t_sim`` (False if the launcher ended first)."""
        with self._tick:
            while self.t < t_sim:
                if launcher.poll() is not None:
                    return False
                self._tick.wait(0.5)
        return True


def _mission() -> str:
    return load_scenario(SCENARIO).name


def _join(out: Path) -> ZenohTransport:
    deadline = time.monotonic() + 60.0
    while True:
        try:
            return ZenohTransport(ZenohSettings(config_file=str(out / "access" / "tlm.json5")))
        except Exception:  # noqa: BLE001 - the launcher is still writing the accounts
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def _pid_of(victim: str, out: Path) -> int | None:
    """The pid of this run's process ``victim`` (sc<N>: the flight process hosting it, ground,
    recorder, router)."""
    parts = {"ground": ["-m", "ground", "--scenario"],
             "recorder": ["-m", "ground.archive.record"],
             "router": ["-m", "deploy.router", "--config", str(out / "access" / "router.json5")]}
    want = parts.get(victim, ["-m", "fsw", "--spacecraft"])
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            cmd = [c.decode() for c in Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")]
        except OSError:
            continue
        ours = victim == "router" or str(out / "access") in " ".join(cmd)
        at = [i for i in range(len(cmd)) if cmd[i:i + len(want)] == want]
        if not ours or not at:
            continue
        hosted = itertools.takewhile(str.isdigit, cmd[at[0] + len(want):])
        if victim in parts or victim[2:] in hosted:
            return int(pid)
    return None


def _compare(clean: dict[str, Any], soak: dict[str, Any], out: Path) -> bool:
    """Print the comparison (module docstring); whether everything matched."""
    figures = {k for k in clean if k not in VOLATILE}
    differing = sorted(k for k in figures if clean.get(k) != soak.get(k))
    same_detections = clean.get("detections") == soak.get("detections")
    print(f"\ndetections: {len(clean.get('detections') or [])} in the clean run, "
          f"{'the same' if same_detections else 'DIFFERENT'} in the soak run")
    print(f"summary figures differing: {differing or 'none'}")
    archive = soak.get("archive") or {}
    lost = (archive.get("lost") or {}).get("by_topic", {})
    print(f"segments: {[s['file'] for s in archive.get('segments') or [{'file': 'run.mcap'}]]}")
    print(f"lost (in flight at a kill): {sum(lost.values())} {lost or ''}")
    expected = _digests(out / "clean")
    total = len(expected)
    missing, changed, extra = _match(expected, out / "soak")
    print(f"messages of the clean run: {total:,} compared; missing in the soak's segments: "
          f"{missing:,}; different: {changed:,}; only in the soak: {extra:,}")
    return not differing and same_detections and not missing and not changed and not lost


def _digest(rec: Record) -> int:
    """A hash of the message without its wall-clock fields."""
    wall = registry()[rec.type_name].WALL_CLOCK_FIELDS
    if wall == {"t_wall"}:
        return hash(_T_WALL.sub(b"", rec.payload))
    d = json.loads(rec.payload)
    for f in wall:
        d.pop(f, None)
    return hash(json.dumps(d, sort_keys=True))


def _records(run: Path, sink: Any) -> None:
    """Stream every compared record of ``run``'s archive to ``sink`` (none kept in memory)."""
    def take(rec: Record) -> None:
        if rec.type_name not in SET_APART:
            sink(rec)
    load_run(run / "run.mcap", stream={"**": take})


def _digests(run: Path) -> dict[tuple[str, int], int]:
    got: dict[tuple[str, int], int] = {}
    _records(run, lambda r: got.__setitem__((r.key, _seq(r)), _digest(r)))
    return got


def _match(expected: dict[tuple[str, int], int], run: Path) -> tuple[int, int, int]:
    """(missing, different, extra) messages of ``run`` against ``expected`` (consumed)."""
    counts = {"changed": 0, "extra": 0}

    def check(rec: Record) -> None:
        want = expected.pop((rec.key, _seq(rec)), None)
        if want is None:
            counts["extra"] += 1
        elif want != _digest(rec):
            counts["changed"] += 1
    _records(run, check)
    return len(expected), counts["changed"], counts["extra"]


def _seq(rec: Record) -> int:
    m = re.search(rb'"seq":(\d+)', rec.payload)
    return int(m.group(1)) if m else 0


if __name__ == "__main__":
    raise SystemExit(main())
