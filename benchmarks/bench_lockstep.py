"""Lockstep speed: ticks per second for 5 observers on both transports, and the real-time factor
of the default scenario.

    python benchmarks/bench_lockstep.py [--duration S]

Runs deploy/run_constellation.py (the real multi-process set-up for Zenoh) and reads the figures
back from summary.json and the sim's log.  Prints a table and the Zenoh/inproc ratio.
"""

from __future__ import annotations

import argparse
import re
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from harness.summary import RunSummary  # noqa: E402


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def run(transport: str, duration: float, out: Path) -> dict[str, float]:
    cmd = [sys.executable, str(REPO / "deploy" / "run_constellation.py"), "--transport", transport,
           "--duration", str(duration), "--out", str(out), "--no-report"]
    if transport == "zenoh":  # an in-process run refuses Zenoh-only options
        cmd += ["--endpoint", f"tcp/127.0.0.1:{_free_port()}"]
    subprocess.run(cmd, cwd=REPO, check=True, capture_output=True)
    s = RunSummary.read(out / "summary.json")
    # the sim logs its own tick rate (excludes process start-up and shutdown)
    log = (out / "logs" / "sim.log").read_text() if (out / "logs" / "sim.log").exists() else ""
    rates = [float(x) for x in re.findall(r"([0-9.]+) ticks/s", log)]
    ticks, wall_s = s.ticks or 0, s.wall_s or 0.0
    return {"ticks": ticks, "wall_s": wall_s, "ticks_per_s_wall": ticks / wall_s,
            "ticks_per_s_sim_loop": rates[-1] if rates else ticks / wall_s,
            "real_time_factor": s.real_time_factor}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--duration", type=float, default=300.0, help="simulated seconds per run")
    args = p.parse_args()
    res = {}
    with tempfile.TemporaryDirectory() as tmp:
        for transport in ("inproc", "zenoh"):
            res[transport] = run(transport, args.duration, Path(tmp) / transport)
    print(f"default scenario (5 observers + ground, 10/1/0.1 Hz), {args.duration:.0f} s simulated")
    print(f"{'transport':<10} {'ticks':>7} {'wall s':>8} {'ticks/s (wall)':>15} "
          f"{'ticks/s (sim loop)':>19} {'x real time':>12}")
    for t, r in res.items():
        print(f"{t:<10} {r['ticks']:>7} {r['wall_s']:>8.1f} {r['ticks_per_s_wall']:>15.0f} "
              f"{r['ticks_per_s_sim_loop']:>19.0f} {r['real_time_factor']:>12.1f}")
    ratio = res["zenoh"]["ticks_per_s_sim_loop"] / res["inproc"]["ticks_per_s_sim_loop"]
    print(f"zenoh / inproc tick rate (sim loop): {ratio:.2f}")


if __name__ == "__main__":
    main()
