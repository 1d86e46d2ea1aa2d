"""The raw lockstep limit over Zenoh: ticks per second between a ticker and N answering nodes
that do no work, each in its own process, on the real Bus and Zenoh transport.

    python benchmarks/lockstep_limit.py [--nodes 6] [--ticks 3000]

The ticker publishes Tick k and waits for TickDone(k) from every node (the sim's handshake);
each node answers from its transport thread.  This is the ceiling of any multi-process run:
the reference mission's 113,540 ticks at this rate take ``113540 / rate`` seconds before any
flight software runs.
"""

from __future__ import annotations

import argparse
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from interfaces.contracts import catalogue as cat  # noqa: E402
from interfaces.contracts import topics  # noqa: E402
from interfaces.contracts.messages import Tick, TickDone  # noqa: E402
from interfaces.runtime.bus import Bus  # noqa: E402
from interfaces.runtime.zenoh_transport import ZenohSettings, ZenohTransport  # noqa: E402

MISSION = "lockbench"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def echo(node: str, endpoint: str) -> None:
    """A node that answers every tick at once, until the final tick."""
    bus = Bus(node, MISSION, ZenohTransport(ZenohSettings(connect=(endpoint,))))
    done = threading.Event()
    key = cat.TICK_DONE.key(MISSION, node)

    def on_tick(t: Tick) -> None:
        bus.publish(key, TickDone(sender=node, t_sim=t.t_sim, k=t.k), announce=False)
        if t.final:
            done.set()

    bus.subscribe(cat.TICK.key(MISSION), Tick, on_tick, immediate=True)
    bus.declare_alive()
    done.wait(600.0)
    time.sleep(0.2)
    bus.close()


def ticker(nodes: list[str], ticks: int, endpoint: str) -> float:
    """Run ``ticks`` lockstep ticks against ``nodes``; return ticks per second."""
    bus = Bus(topics.SIM, MISSION, ZenohTransport(ZenohSettings.hub(endpoint)))
    cond = threading.Condition()
    answered: set[str] = set()
    alive: set[str] = set()
    state = {"k": -1}

    def on_done(m: TickDone) -> None:
        with cond:
            if m.k == state["k"]:
                answered.add(m.sender)
                cond.notify_all()

    def on_alive(node: str, up: bool) -> None:
        with cond:
            (alive.add if up else alive.discard)(node)
            cond.notify_all()

    for n in nodes:
        bus.subscribe(cat.TICK_DONE.key(MISSION, n), TickDone, on_done, immediate=True)
    bus.watch_alive(on_alive)
    with cond:
        if not cond.wait_for(lambda: set(nodes) <= alive, timeout=60.0):
            raise TimeoutError("echo nodes did not join")
    time.sleep(0.5)  # let the peer mesh settle
    start = time.perf_counter()
    for k in range(ticks):
        with cond:
            answered.clear()
            state["k"] = k
        bus.publish(cat.TICK.key(MISSION), Tick(sender=topics.SIM, t_sim=0.1 * k, k=k, dt_s=0.1,
                                               final=k == ticks - 1), announce=False)
        with cond:
            if not cond.wait_for(lambda: len(answered) == len(nodes), timeout=10.0):
                raise TimeoutError(f"tick {k}: answers from {sorted(answered)} only")
    rate = ticks / (time.perf_counter() - start)
    bus.close()
    return rate


def measure(n_nodes: int = 6, ticks: int = 3000) -> float:
    """Ticks per second of the lockstep with ``n_nodes`` idle node processes."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    nodes = [f"sc{i}" for i in range(1, n_nodes + 1)]
    procs = [subprocess.Popen([sys.executable, __file__, "--echo", n, "--endpoint", endpoint],
                              cwd=REPO) for n in nodes]
    try:
        return ticker(nodes, ticks, endpoint)
    finally:
        for p in procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--nodes", type=int, default=6)
    p.add_argument("--ticks", type=int, default=3000)
    p.add_argument("--echo", help=argparse.SUPPRESS)
    p.add_argument("--endpoint", help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.echo:
        echo(args.echo, args.endpoint)
        return
    rate = measure(args.nodes, args.ticks)
    print(f"lockstep over Zenoh, {args.nodes} idle nodes: {rate:.0f} ticks/s "
          f"({1e6 / rate:.0f} µs per tick)")


if __name__ == "__main__":
    main()
