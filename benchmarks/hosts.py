"""Lockstep ticks per second across rehearsed hosts against the links' one-way delay
(docs/hosts.md, "Lockstep across hosts"), set beside the round-trip bound.

    python benchmarks/hosts.py [--hosts deploy/hosts/lab.toml] [--delays 0,2,5,10,20]
        [--duration 120] [--out DIR]

For each delay d (ms, every host's link), the default scenario is rehearsed on the map
(``--rehearse``, needs CAP_NET_ADMIN) for ``--duration`` s of sim time.  The tick rate is read
from the archive: the recorder's receipt times of the sim's ticks over the run's second half
(start-up and the first ticks' compilation left out).  The bound is one tick's path and its
answers' path back: with every router linked to the hub, sim -> hub -> spacecraft and back,

    period >= d_sim + 2 d_hub + d_sc  (4 d with every link at d),

so ticks/s <= 1 / (4 d); the zero-delay rate is the machine's own limit, and
``1 / (1/rate_0 + 4 d)`` is the rate a delay would leave it if the two simply added.
Prints one row per delay: ticks/s, the bound, the additive estimate, and the ratio measured
to it.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from deploy.host_map import HostMap, load_host_map  # noqa: E402
from harness.archive.reader import load_run  # noqa: E402
from interfaces.contracts import catalogue as cat  # noqa: E402


def path_delay_s(host_map: HostMap, delay_ms: float) -> float:
    """One tick's round trip through the routers with every link at ``delay_ms``, s: the sim's
    host to the hub to the farthest spacecraft host, and back (the hub's link crossed twice
    unless the sim or the spacecraft are on it)."""
    hub, sim = host_map.hub, host_map.host_of("sim")
    links = 0
    for h in host_map.hosts:
        if not any(n.startswith("sc") for n in h.nodes):
            continue
        out = (sim.name != hub.name) + (h.name != hub.name)  # sim -> hub -> h
        links = max(links, 2 * out)  # and the answers back the same way
    return links * delay_ms / 1e3


def ticks_per_s(out: Path, mission: str) -> float:
    """Ticks per wall second over the run's second half, from the recorder's receipt times."""
    ticks = load_run(out / "run.mcap").records(cat.TICK.key(mission))
    half = ticks[len(ticks) // 2:]
    span_s = (half[-1].publish_time_ns - half[0].publish_time_ns) / 1e9
    return (len(half) - 1) / span_s


def run(host_map_path: Path, delay_ms: float, duration_s: float, out: Path) -> float:
    cmd = [sys.executable, str(REPO / "deploy" / "run_constellation.py"), "--hosts",
           str(host_map_path), "--rehearse", "--link-delay-ms", str(delay_ms), "--duration",
           str(duration_s), "--no-report", "--out", str(out), "--overwrite"]
    done = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"delay {delay_ms} ms: the run failed:\n{done.stderr[-2000:]}")
    return ticks_per_s(out, "default")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--hosts", type=Path, default=REPO / "deploy" / "hosts" / "lab.toml")
    p.add_argument("--delays", default="0,2,5,10,20", help="one-way delays, ms")
    p.add_argument("--duration", type=float, default=120.0, help="sim time per run, s")
    p.add_argument("--out", type=Path, help="keep the runs here (default: a temporary folder)")
    args = p.parse_args(argv)
    host_map = load_host_map(args.hosts)
    delays = [float(d) for d in args.delays.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        base = args.out or Path(tmp)
        print(f"{'delay ms':>8} {'ticks/s':>8} {'bound':>8} {'additive':>9} {'ratio':>6}")
        rate0 = None
        for d in delays:
            rate = run(args.hosts, d, args.duration, base / f"d{d:g}")
            rate0 = rate0 or rate
            trip = path_delay_s(host_map, d)
            bound = 1.0 / trip if trip > 0 else float("inf")
            additive = 1.0 / (1.0 / rate0 + trip)
            print(f"{d:8g} {rate:8.1f} {bound:8.1f} {additive:9.1f} {rate / additive:6.2f}",
                  flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
