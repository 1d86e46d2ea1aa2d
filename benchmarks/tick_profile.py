"""Where a tick goes: CPU per tick by tick type, by component and per message, in one process
and over Zenoh, beside the floor of the tick's own math (issue 61).

    python benchmarks/tick_profile.py [--duration S] [--zenoh-duration S] [--skip-zenoh]
                                      [--json FILE]

* **One process, unprofiled**: the default mission run in this process with its archive (the
  recorder child, as the launcher runs it), the thread's CPU time stamped at every Tick:
  the mean CPU of a 10 Hz-only tick, and what a 1 Hz and a 0.1 Hz tick add
  (``tick_budget.by_rate``'s three-tick windows), with the messages each carries.
* **One process, by component**: the same run under cProfile, every function's own time
  bucketed by the file it lives in (``COMPONENTS``: each app, each sim unit, the Bus, the
  executive and lockstep, the archive tap, message objects, numpy's Python side, the compiled
  math, ...), given as shares of the unprofiled CPU per tick (cProfile slows Python more than
  C: the shares of Python-heavy parts are upper bounds).
* **The floor**: the compiled math alone, per tick: every numba kernel call (each kernel a
  module binds is timed around its call), OSQP's solves, and the time numpy's C functions spend
  (under the profiler) less their per-call overhead (measured on 3-element arrays in the same
  process): what the tick would cost with no Python around its arithmetic.  Today's ratio to
  it is the figure the design's target (≤ 2×) speaks of.
* **Over Zenoh**: the default run command (``deploy/run_constellation.py``, default hosting),
  each process's CPU time (user + system, read from ``/proc`` while it runs), its share, the
  CPU per tick of the whole run, and the CPU per message archived.

Every part runs at any commit since the fleet step (it reads only the launcher's command line,
``deploy.inproc.run_inproc`` and the archive), so before and after are measured by the same
script: run it from the other checkout's directory with this file's path.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import psutil

REPO = Path.cwd()
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from deploy.inproc import run_inproc  # noqa: E402
from ground.archive.metadata import run_metadata  # noqa: E402
from ground.archive.recorder_process import RecorderProcess  # noqa: E402
from interfaces.contracts import catalogue as cat  # noqa: E402
from interfaces.contracts.scenario import Scenario, load_scenario  # noqa: E402
from interfaces.runtime.transport import Sample  # noqa: E402

DEFAULT = REPO / "deploy" / "scenarios" / "default.toml"
COMPONENTS: tuple[tuple[str, str], ...] = (
    # (component, a substring of the file path or function label), first match wins
    ("compiled math (numba, OSQP)", "<compiled-call>"),
    ("compiled math (numba, OSQP)", "osqp"),
    ("numpy C functions", "of 'numpy."),
    ("numpy C functions", "<built-in method numpy"),
    ("numpy Python side", "numpy/"),
    ("message objects (pydantic)", "pydantic"),
    ("message objects (pydantic)", "interfaces/contracts/"),
    ("archive tap", "<built-in method posix.write>"),  # the pipe to the recorder child
    ("archive tap", "harness/"),
    ("archive tap", "ground/archive/"),
    ("Bus (bus, inbox, admission, link stage, recent)", "interfaces/runtime/bus.py"),
    ("Bus (bus, inbox, admission, link stage, recent)", "interfaces/runtime/inbox.py"),
    ("Bus (bus, inbox, admission, link stage, recent)", "interfaces/runtime/admission.py"),
    ("Bus (bus, inbox, admission, link stage, recent)", "interfaces/runtime/link_stage.py"),
    ("Bus (bus, inbox, admission, link stage, recent)", "interfaces/runtime/recent.py"),
    ("Bus (bus, inbox, admission, link stage, recent)", "interfaces/runtime/subscriptions.py"),
    ("Bus (bus, inbox, admission, link stage, recent)", "interfaces/runtime/transport.py"),
    ("Bus (bus, inbox, admission, link stage, recent)", "fsw/lib/channel"),
    ("executive and lockstep", "interfaces/runtime/"),
    ("executive and lockstep", "sim/lockstep.py"),
    ("executive and lockstep", "sim/node.py"),
    ("app attitude", "fsw/apps/attitude.py"),
    ("app nav", "fsw/apps/nav.py"),
    ("app guidance (MPC)", "fsw/apps/guidance.py"),
    ("app guidance (MPC)", "fsw/lib/mpc"),
    ("app camera", "fsw/apps/camera.py"),
    ("app infocost", "fsw/apps/infocost.py"),
    ("app neighbours", "fsw/apps/neighbours.py"),
    ("flight libraries (fsw/lib, gnc)", "fsw/"),
    ("ground FDIR", "ground/"),
    ("sim camera", "sim/camera.py"),
    ("sim camera", "sim/units/camera.py"),
    ("sim units (sensors, actuators, attitude, truth)", "sim/"),
    ("flight libraries (fsw/lib, gnc)", "gnc/"),
    ("scipy", "scipy/"),
    ("Python runtime (threads, logging, dataclasses, ...)", ""),
)
"""Where a function's own time goes: the first component whose pattern its label holds."""


COMPILED = COMPONENTS[0][0]
TOP = 25
"""How many functions the report lists by own time."""


def component_of(label: str) -> str:
    """The component (``COMPONENTS``) of a profiled function's label (file:line(name))."""
    return next(name for name, pattern in COMPONENTS if pattern in label)


@contextmanager
def timed_kernels() -> Iterator[dict[str, float]]:
    """While inside: every call of a numba kernel from Python and every OSQP solve is timed
    (s, total, under ``"numba"`` and ``"osqp"``, with their counts).  The dispatchers' call is
    wrapped on their class, so a kernel called from a kernel runs compiled, untimed (it is
    inside its caller's time)."""
    import osqp
    from numba.core.dispatcher import Dispatcher

    spent = {"numba": 0.0, "osqp": 0.0, "numba_calls": 0.0, "osqp_calls": 0.0}
    Dispatcher.__call__ = _timer(Dispatcher.__call__, spent, "numba")  # type: ignore[method-assign]
    solve = osqp.OSQP.solve
    osqp.OSQP.solve = _timer(solve, spent, "osqp")  # type: ignore[method-assign]
    try:
        yield spent
    finally:
        del Dispatcher.__call__  # the C type's call again
        osqp.OSQP.solve = solve  # type: ignore[method-assign]


def _timer(fn: Callable[..., Any], spent: dict[str, float], kind: str) -> Callable[..., Any]:
    clock = time.perf_counter

    def compiled_call(*args: Any, **kwargs: Any) -> Any:  # its own time: the compiled math
        start = clock()
        try:
            return fn(*args, **kwargs)
        finally:
            spent[kind] += clock() - start
            spent[kind + "_calls"] += 1

    return compiled_call


def mission(scenario: Scenario, profile: cProfile.Profile | None = None,
            ) -> tuple[np.ndarray, np.ndarray, float, dict[str, float]]:
    """Run ``scenario`` in this process with its archive (the recorder child, as the
    launcher's one-process run has it): the thread's CPU time of every tick (s, by k), the
    messages of every tick, the run's CPU time in this thread (s), and the compiled math's
    time (``timed_kernels``) with the recorder child's CPU time (s, ``"recorder"``)."""
    tick_key = cat.TICK.key(scenario.name)
    stamps: list[float] = []
    counts: list[int] = [0]
    out = Path(tempfile.mkdtemp(prefix="insp-tick-profile-"))
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    with timed_kernels() as math, \
            RecorderProcess(out / "run.mcap", run_metadata(scenario, "inproc", "")) as rec:
        def tap(sample: Sample) -> None:
            if sample.key == tick_key:
                stamps.append(time.thread_time())
                counts.append(0)
            counts[-1] += 1
            rec.record_sample(sample)

        start = time.thread_time()
        if profile is not None:
            profile.enable()
        run_inproc(scenario, sample_tap=tap)
        if profile is not None:
            profile.disable()
        cpu = time.thread_time() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    math["recorder"] = (after.ru_utime + after.ru_stime) - (children.ru_utime
                                                            + children.ru_stime)
    shutil.rmtree(out, ignore_errors=True)
    return np.diff(np.array(stamps)), np.array(counts[1:-1]), cpu, math


def numpy_call_overhead() -> float:
    """The time (s) the profiler records for one call of a numpy C method on 3-element arrays
    (``ndarray.dot``): a call's cost with no arithmetic to speak of."""
    a, b = np.ones(3), np.ones(3)
    probe = cProfile.Profile()
    probe.enable()
    for _ in range(20000):
        a.dot(b)
    probe.disable()
    stats = pstats.Stats(probe).stats  # type: ignore[attr-defined]
    return next(tt / nc for (f, _, name), (_, nc, tt, _, _) in stats.items()
                if f == "~" and "'dot'" in name)


def components(profile: cProfile.Profile
               ) -> tuple[dict[str, float], dict[str, float], float, int]:
    """Own time by component (s) and by function (s, labelled with its component), the numpy
    C functions' time less their per-call overhead (s: the arithmetic), and the number of
    numpy C calls."""
    stats = pstats.Stats(profile).stats  # type: ignore[attr-defined]
    out: Counter[str] = Counter()
    functions: dict[str, float] = {}
    numpy_c, numpy_calls = 0.0, 0
    for (path, line, name), (_, ncalls, tottime, _, _) in stats.items():
        label = f"{path}:{line}({name})" if path != "~" else name
        if name == "compiled_call":
            label = "<compiled-call>"
        comp = component_of(label)
        out[comp] += tottime
        short = label.split("site-packages/")[-1].replace(str(REPO) + "/", "")
        functions[f"{short}  [{comp.split(' (')[0]}]"] = tottime
        if comp == "numpy C functions":
            numpy_c += tottime
            numpy_calls += ncalls
    overhead = numpy_call_overhead()
    return dict(out), functions, max(0.0, numpy_c - numpy_calls * overhead), numpy_calls


def by_tick_type(cpu_s: np.ndarray, counts: np.ndarray, scenario: Scenario
                 ) -> dict[str, dict[str, float]]:
    """CPU per tick (ms) of the 10 Hz-only ticks and what a 1 Hz and a 0.1 Hz tick add, with
    their messages (``tick_budget.by_rate``'s windows)."""
    from benchmarks.tick_budget import by_rate

    table = by_rate(cpu_s, scenario)
    msgs = by_rate(counts.astype(float) * 1e-3, scenario)  # the same windows, in messages
    for kind in table:
        table[kind]["messages"] = msgs[kind]["mean"]
    return table


def one_process(scenario: Scenario) -> dict[str, Any]:
    """The one-process figures (module docstring).  The compiled math's time is measured
    around its calls in the unprofiled run; the rest of the CPU is shared out among the
    other components as the profiled run's own times say."""
    run_inproc(scenario.with_overrides(None, 5.0))  # imports and compiled kernels loaded
    cpu_s, counts, cpu, math = mission(scenario)
    n_ticks = scenario.n_ticks
    profile = cProfile.Profile()
    _, _, cpu_prof, _ = mission(scenario, profile)
    own, functions, numpy_math, numpy_calls = components(profile)
    compiled = math["numba"] + math["osqp"]
    rest = {c: s for c, s in own.items() if c != COMPILED}
    scale = (cpu - compiled) / sum(rest.values())
    per_tick_ms = 1e3 * cpu / n_ticks
    comps = {c: 1e3 * s * scale / n_ticks for c, s in rest.items()}
    comps[COMPILED] = 1e3 * compiled / n_ticks
    numpy_ms = 1e3 * numpy_math * scale / n_ticks
    floor_ms = comps[COMPILED] + numpy_ms
    return {
        "duration_s": scenario.duration_s, "cpu_s": cpu, "ticks": n_ticks,
        "cpu_per_tick_ms": per_tick_ms, "messages_per_tick": float(counts.mean()),
        "by_tick_type_ms": by_tick_type(cpu_s, counts, scenario),
        "components_ms_per_tick": comps, "profiled_cpu_s": cpu_prof,
        "top_functions_ms_per_tick": {
            f: 1e3 * s * scale / n_ticks
            for f, s in sorted(functions.items(), key=lambda kv: -kv[1])[:TOP]},
        "floor_ms_per_tick": floor_ms,
        "floor_parts_ms_per_tick": {
            "numba kernels": 1e3 * math["numba"] / n_ticks,
            "OSQP solves": 1e3 * math["osqp"] / n_ticks,
            "numpy C arithmetic (less per-call overhead)": numpy_ms},
        "recorder_child_ms_per_tick": 1e3 * math["recorder"] / n_ticks,
        "numba_calls_per_tick": math["numba_calls"] / n_ticks,
        "numpy_c_calls_per_tick": numpy_calls / n_ticks,
        "ratio_to_floor": per_tick_ms / max(floor_ms, 1e-9),
    }


def over_zenoh(duration_s: float, short_s: float = 10.0) -> dict[str, Any]:
    """The default run over Zenoh for ``duration_s`` and for ``short_s``: each one's figures
    (:func:`zenoh_run`), and the CPU per tick by process that the longer adds (start-up and
    wrap-up cancel out), ms."""
    long, short = zenoh_run(duration_s), zenoh_run(short_s)
    scenario = load_scenario(DEFAULT)
    ticks = (scenario.with_overrides(None, duration_s).n_ticks
             - scenario.with_overrides(None, short_s).n_ticks)
    long["short_run"] = short
    long["marginal_ms_per_tick"] = {
        label: 1e3 * (s - short["cpu_s_by_process"].get(label, 0.0)) / ticks
        for label, s in long["cpu_s_by_process"].items()}
    long["marginal_us_per_message"] = 1e6 * (long["cpu_s"] - short["cpu_s"]) / max(
        1, long["messages"] - short["messages"])
    return long


def zenoh_run(duration_s: float, poll_s: float = 0.2) -> dict[str, Any]:
    """The default run over Zenoh: CPU per process (s, from ``/proc``), wall time, messages
    archived."""
    from mcap.reader import make_reader

    out = Path(tempfile.mkdtemp(prefix="insp-tick-profile-"))
    cmd = [sys.executable, "deploy/run_constellation.py", "--duration", str(duration_s),
           "--out", str(out / "run"), "--no-report"]
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    cpu: dict[int, tuple[str, float]] = {}
    root = psutil.Process(proc.pid)
    while proc.poll() is None:
        for p in [root, *_children(root)]:
            try:
                t = p.cpu_times()
                cpu[p.pid] = (_label(p.cmdline()), t.user + t.system)
            except psutil.Error:
                continue
        time.sleep(poll_s)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise RuntimeError(f"the Zenoh run failed ({proc.returncode}): {proc.stderr}")
    with open(out / "run" / "run.mcap", "rb") as f:
        messages = sum(1 for _ in make_reader(f).iter_messages())
    shutil.rmtree(out, ignore_errors=True)
    by_process: Counter[str] = Counter()
    for label, seconds in cpu.values():
        by_process[label] += seconds
    total = sum(by_process.values())
    return {"duration_s": duration_s, "wall_s": wall, "rtf": duration_s / wall,
            "cpu_s_by_process": dict(by_process), "cpu_s": total, "messages": messages}


def _children(p: psutil.Process) -> list[psutil.Process]:
    try:
        return p.children(recursive=True)
    except psutil.Error:
        return []


def _label(cmdline: list[str]) -> str:
    """A process's name for the table: the node it runs or its script."""
    text = " ".join(cmdline)
    for opt in ("--spacecraft", "--node"):
        if opt in cmdline:
            i = cmdline.index(opt)
            return f"fsw {cmdline[i + 1]}" if opt == "--spacecraft" else cmdline[i + 1]
    for name in ("run_constellation", "router", "recorder", "sim", "ground", "fsw"):
        if name in text:
            return name
    return cmdline[0] if cmdline else "?"


def print_report(one: dict[str, Any] | None, zen: dict[str, Any] | None) -> None:
    """The figures as tables."""
    if one is not None:
        print(f"one process, {one['duration_s']:.0f} s of the default mission: "
              f"{one['cpu_s']:.1f} s CPU, {one['cpu_per_tick_ms']:.3f} ms per tick, "
              f"{one['messages_per_tick']:.1f} messages per tick; the recorder child "
              f"{one['recorder_child_ms_per_tick']:.3f} ms per tick beside it")
        print(f"\n{'CPU per tick, by tick type':<34} {'ms':>8} {'messages':>9}")
        for kind, what in (("high", "10 Hz-only tick"), ("mid", "a 1 Hz tick adds"),
                           ("low", "a 0.1 Hz tick adds")):
            row = one["by_tick_type_ms"][kind]
            print(f"{what:<34} {row['mean']:>8.3f} {row['messages']:>9.1f}")
        print(f"\n{'by component (ms per tick, share)':<52} {'ms':>7} {'share':>6}")
        comps = one["components_ms_per_tick"]
        for c, ms in sorted(comps.items(), key=lambda kv: -kv[1]):
            print(f"{c:<52} {ms:>7.3f} {100 * ms / one['cpu_per_tick_ms']:>5.1f}%")
        print(f"\n{'the functions with the most own time':<72} {'ms/tick':>8}")
        for f, ms in one["top_functions_ms_per_tick"].items():
            print(f"{f[:72]:<72} {ms:>8.4f}")
        per_msg = sum(ms for c, ms in comps.items() if c.startswith(("Bus", "message",
                                                                     "archive")))
        print(f"\nper message (Bus + message objects + archive tap): "
              f"{1e3 * per_msg / max(one['messages_per_tick'], 1e-9):.1f} µs")
        print(f"\nfloor (the compiled math alone): {one['floor_ms_per_tick']:.3f} ms per tick")
        for part, ms in one["floor_parts_ms_per_tick"].items():
            print(f"  {part:<48} {ms:>7.3f}")
        print(f"ratio to the floor: {one['ratio_to_floor']:.1f}x (target <= 2x)")
    if zen is not None:
        print(f"\nover Zenoh, {zen['duration_s']:.0f} s: {zen['wall_s']:.1f} s wall "
              f"({zen['rtf']:.1f}x real time), {zen['cpu_s']:.1f} s CPU in all processes; "
              f"what a tick adds (this run less a {zen['short_run']['duration_s']:.0f} s one): "
              f"{sum(zen['marginal_ms_per_tick'].values()):.2f} ms CPU, "
              f"{zen['marginal_us_per_message']:.0f} µs CPU per message archived")
        print(f"  {'process':<20} {'CPU s':>7} {'ms/tick':>8}")
        for label, ms in sorted(zen["marginal_ms_per_tick"].items(), key=lambda kv: -kv[1]):
            print(f"  {label:<20} {zen['cpu_s_by_process'][label]:>7.1f} {ms:>8.2f}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--duration", type=float, default=300.0,
                   help="simulated s of the default mission in one process (%(default)s)")
    p.add_argument("--zenoh-duration", type=float, default=300.0,
                   help="simulated s over Zenoh (%(default)s)")
    p.add_argument("--skip-zenoh", action="store_true", help="the one-process part only")
    p.add_argument("--json", type=Path, help="also write the figures as JSON here")
    args = p.parse_args()
    scenario = load_scenario(DEFAULT).with_overrides(None, args.duration)
    one = one_process(scenario)
    zen = None if args.skip_zenoh else over_zenoh(args.zenoh_duration)
    print_report(one, zen)
    if args.json:
        args.json.write_text(json.dumps({"one_process": one, "zenoh": zen}, indent=1))


if __name__ == "__main__":
    main()
