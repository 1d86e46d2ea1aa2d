"""The per-tick budget in one process (issue 25): what a tick of the lockstep costs, bare and
with the default mission's work, by rate group.

    python benchmarks/tick_budget.py [--duration S] [--bare-ticks N] [--json FILE]

* **bare lockstep**: a ticker and 6 nodes (5 observers and the ground) on the in-process
  transport, each a real :class:`~interfaces.runtime.executive.Executive` with no apps, answering
  every tick and publishing its housekeeping at ω_mid: the message pattern of a run with no
  work in it.  Wall time per tick.
* **the default mission's ticks**: the default scenario in one process with its archive (the
  recorder child, as ``run_constellation.py --transport inproc`` runs it), the wall time of
  every tick measured between two Tick messages.  A tick k runs its 10 Hz group, its 1 Hz group
  when k is a multiple of ω_high/ω_mid, its 0.1 Hz group when a multiple of ω_high/ω_low, then
  the sim's step and the next tick's sensors.  The table gives the mean of the ticks with only
  10 Hz work, and what a 1 Hz and a 0.1 Hz tick add to it on average (means, since a run's
  wall time is their sum; medians beside them).

* **the slower work per call**, in the same run: the sim's camera images (one call images
  every observer), the nav step, the infocost fusion of one observations message, the ground
  FDIR's work per observer-window (hardware threshold and identification evidence included;
  with the sequential test, each part of a window judged for its class too), the sequential
  test's image scan and NIS scan per call (an observer's images or nav updates come since the
  last, the window's ratio model drawn on the first) and an MPC solve.  Each is timed around
  the real call (the method wrapped for the run, restored after).

Targets (issue 42; issue 25's before it): bare ≤ 40 µs, 10 Hz-only ≤ 0.5 ms, a 1 Hz tick
adds ≤ 3 ms, a 0.1 Hz tick adds ≤ 10 ms; per call: camera image ≤ 0.3 ms, fusion ≤ 0.3 ms,
nav ≤ 0.1 ms, FDIR ≤ 3 ms per observer-window, image scan ≤ 0.3 ms and NIS scan ≤ 0.1 ms a
call, MPC solve ≤ 0.8 ms.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import multiprocessing
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from deploy.inproc import run_inproc  # noqa: E402
from ground.archive.metadata import run_metadata  # noqa: E402
from ground.archive.recorder_process import RecorderProcess  # noqa: E402
from interfaces.contracts import catalogue as cat  # noqa: E402
from interfaces.contracts import topics  # noqa: E402
from interfaces.contracts.messages import Tick, TickDone  # noqa: E402
from interfaces.contracts.scenario import Scenario, load_scenario  # noqa: E402
from interfaces.runtime.bus import Bus  # noqa: E402
from interfaces.runtime.executive import Executive, TickClient  # noqa: E402
from interfaces.runtime.transport import InprocNetwork, Sample  # noqa: E402

DEFAULT = REPO / "deploy" / "scenarios" / "default.toml"
TARGETS_MS = {"bare": 0.04, "high": 0.5, "mid": 3.0, "low": 10.0}
CALLS: tuple[tuple[str, str, str, float], ...] = (
    # (module, attribute path, what, target ms per call)
    ("sim.camera", "TruthCameras.images", "sim camera, one image", 0.3),
    ("fsw.apps.nav", "NavApp.step", "nav step", 0.1),
    ("fsw.apps.infocost", "InfoCostApp.on_observations", "infocost fusion, one image", 0.3),
    ("ground.fdir.information", "InformationTest.judge", "ground FDIR, one observer-window",
     3.0),
    ("ground.fdir.sequential", "SequentialTest.score",
     "ground image scan, per call", 0.3),
    ("ground.fdir.sequential", "SequentialTest.score_nis",
     "ground NIS scan, per call", 0.1),
    ("fsw.lib.mpc", "MpcTracker.solve", "MPC solve", 0.8),
)
"""The slower work timed per call, with its target per call (ms)."""


def bare_lockstep(scenario: Scenario, ticks: int) -> float:
    """Wall time per tick (s) of the bare in-process lockstep: 6 app-less executives."""
    mission = "bare"
    scenario = scenario.with_overrides(None, ticks * scenario.rates.dt_s)
    net = InprocNetwork()
    nodes = [topics.sc_node(i) for i in range(1, 6)] + [topics.GROUND]
    for node in nodes:
        TickClient(Executive(Bus(node, mission, net.endpoint()), scenario, []), synchronous=True)
    bus = Bus(topics.SIM, mission, net.endpoint())
    answered: set[str] = set()
    lock = threading.Lock()

    def on_done(m: TickDone) -> None:
        with lock:
            answered.add(m.sender)

    for node in nodes:
        bus.subscribe(cat.TICK_DONE.key(mission, node), TickDone, on_done, immediate=True)
    dt, expect = scenario.rates.dt_s, {}
    start = time.perf_counter()
    for k in range(ticks):
        answered.clear()
        bus.publish(cat.TICK.key(mission), Tick(sender=topics.SIM, t_sim=k * dt, k=k, dt_s=dt,
                                                expect=expect, final=k == ticks - 1),
                    announce=False)
        if len(answered) != len(nodes):
            raise RuntimeError(f"tick {k}: answers from {sorted(answered)} only")
        bus.wait_for(expect, 1.0)
        bus.dispatch(k * dt, include_now=True)
    return (time.perf_counter() - start) / ticks


@contextlib.contextmanager
def timed_calls(calls: tuple[tuple[str, str, str, float], ...]
                ) -> Iterator[dict[str, list[float]]]:
    """Time every call of the named methods while inside (wall s per call, by method)."""
    times: dict[str, list[float]] = {name: [] for _, name, _, _ in calls}
    saved = []
    for module, name, _, _ in calls:
        cls_name, method = name.split(".")
        cls = getattr(importlib.import_module(module), cls_name)
        original = getattr(cls, method)
        saved.append((cls, method, original))
        setattr(cls, method, _timer(original, times[name]))
    try:
        yield times
    finally:
        for cls, method, original in saved:
            setattr(cls, method, original)


def _timer(fn: Callable[..., object], sink: list[float]) -> Callable[..., object]:
    def wrapped(*args: object, **kwargs: object) -> object:
        start = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            sink.append(time.perf_counter() - start)

    return wrapped


def mission_ticks(scenario: Scenario, out: Path) -> tuple[np.ndarray, float]:
    """Wall time of every tick of ``scenario`` run in one process with its archive (s, by k),
    and the wall time of the whole run (s)."""
    stamps: list[float] = []
    tick_key = cat.TICK.key(scenario.name)
    out.mkdir(parents=True, exist_ok=True)
    with RecorderProcess(out / "run.mcap", run_metadata(scenario, "inproc", "")) as rec:
        def tap(sample: Sample) -> None:
            if sample.key == tick_key:
                stamps.append(time.perf_counter())
            rec.record_sample(sample)

        start = time.perf_counter()
        run_inproc(scenario, sample_tap=tap)
        wall = time.perf_counter() - start
    return np.diff(np.array(stamps)), wall


def by_rate(tick_s: np.ndarray, scenario: Scenario) -> dict[str, dict[str, float]]:
    """Tick time (ms, mean and median) of the ticks with only 10 Hz work, and what a 1 Hz and
    a 0.1 Hz tick add to it.

    A slower group's work spans three measured ticks: the sim makes its sensors (camera, nav)
    in the interval of the tick before, the group runs in its own, and what it published is
    delivered (fused, judged) in the next.  So a group's cost is the sum of the ticks k-1, k,
    k+1 around its tick k, less three 10 Hz-only ticks (and, for 0.1 Hz, less a 1 Hz tick's
    addition); the 10 Hz-only ticks are those two or more ticks from a 1 Hz tick."""
    ms = 1e3 * tick_s
    k = np.arange(ms.size)
    p_mid, p_low = scenario.rates.ticks_per("mid"), scenario.rates.ticks_per("low")
    from_mid = np.minimum(k % p_mid, p_mid - k % p_mid)
    high = from_mid >= 2
    base_mean, base_med = ms[high].mean(), float(np.median(ms[high]))
    out = {"high": {"mean": base_mean, "median": base_med, "n": int(high.sum())}}
    centres = k[(k % p_mid == 0) & (k >= 1) & (k + 1 < ms.size)]
    windows = ms[centres - 1] + ms[centres] + ms[centres + 1] - 3.0 * base_mean
    is_low = centres % p_low == 0
    mid_mean, mid_med = windows[~is_low].mean(), float(np.median(windows[~is_low]))
    out["mid"] = {"mean": mid_mean, "median": mid_med, "n": int((~is_low).sum())}
    out["low"] = {"mean": windows[is_low].mean() - mid_mean,
                  "median": float(np.median(windows[is_low])) - mid_med,
                  "n": int(is_low.sum())}
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--duration", type=float, default=600.0,
                   help="simulated seconds of the default mission (default %(default)s)")
    p.add_argument("--bare-ticks", type=int, default=20000)
    p.add_argument("--out", type=Path, default=Path("/tmp/insp-tick-budget"))
    p.add_argument("--json", type=Path, help="also write the figures as JSON here")
    args = p.parse_args()
    scenario = load_scenario(DEFAULT).with_overrides(None, args.duration)
    bare_lockstep(scenario, 500)  # warm-up
    bare = bare_lockstep(scenario, args.bare_ticks)
    run_inproc(scenario.with_overrides(None, 5.0))  # imports and compiled kernels loaded
    tick_s, wall = mission_ticks(scenario, args.out)
    table = by_rate(tick_s, scenario)
    with timed_calls(CALLS) as calls:
        mission_ticks(scenario, args.out)
    rows = [("bare lockstep, 6 nodes", 1e3 * bare, None, "bare"),
            ("10 Hz-only tick", table["high"]["mean"], table["high"]["median"], "high"),
            ("a 1 Hz tick adds", table["mid"]["mean"], table["mid"]["median"], "mid"),
            ("a 0.1 Hz tick adds", table["low"]["mean"], table["low"]["median"], "low")]
    print(f"default mission, {args.duration:.0f} s in one process with its archive: "
          f"{wall:.1f} s wall, {args.duration / wall:.1f}x real time")
    print(f"{'per tick':<24} {'mean ms':>9} {'median ms':>10} {'target ms':>10}  ratio")
    for name, mean, med, key in rows:
        target = TARGETS_MS[key]
        r = target / max(mean, 1e-9)
        print(f"{name:<24} {mean:>9.3f} {'' if med is None else f'{med:.3f}':>10} "
              f"{target:>10.2f}  {r:5.2f} {'✓' if r >= 1 else '✗'}")
    print(f"\n{'per call (a second run, timed)':<36} {'calls':>7} {'mean ms':>9} "
          f"{'median ms':>10} {'target ms':>10}  ratio")
    per_call = {}
    for _, name, what, target in CALLS:
        ms = 1e3 * np.array(calls[name] or [np.nan])
        if name == "TruthCameras.images":  # one call images every observer
            ms = ms / scenario.observers.count
        per_call[name] = {"calls": len(calls[name]), "mean": float(ms.mean()),
                          "median": float(np.median(ms))}
        r = target / max(float(ms.mean()), 1e-9)
        print(f"{what:<36} {len(calls[name]):>7} {ms.mean():>9.3f} {np.median(ms):>10.3f} "
              f"{target:>10.2f}  {r:5.2f} {'✓' if r >= 1 else '✗'}")
    if args.json:
        args.json.write_text(json.dumps({"bare_ms": 1e3 * bare, "rtf": args.duration / wall,
                                         "by_rate_ms": table, "per_call_ms": per_call},
                                        indent=1))


if __name__ == "__main__":
    multiprocessing.freeze_support()
    main()
