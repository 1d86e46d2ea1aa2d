"""Shared fixtures: small scenarios, free loopback ports."""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from harness.summary import RunSummary
from interfaces.contracts.messages import Message
from interfaces.contracts.scenario import Scenario, parse_scenario

REPO = Path(__file__).resolve().parent.parent


def small_scenario(name: str = "t", **sections: object) -> Scenario:
    """A fast scenario (2 Hz high rate) with section overrides as dicts."""
    base: dict[str, object] = {
        "name": name, "seed": 3, "duration_s": 20.0,
        "rates": {"high_hz": 2.0, "mid_hz": 1.0, "low_hz": 0.1},
        "observers": {"count": 3, "rho_x_m": 20.0, "rho_z_m": 25.0},
    }
    for k, v in sections.items():
        base[k] = {**base[k], **v} if isinstance(v, dict) and isinstance(base.get(k), dict) else v
    return Scenario.model_validate(base)


def app_alone(cls: type[Any], scenario: Scenario, node: str = "sc1",
              spacecraft: int | None = 1) -> tuple[Any, list[Message]]:
    """An app of class ``cls`` on node ``node`` outside any executive, its publications kept in
    the returned list instead of sent (to test an app's handlers and step directly)."""
    import logging

    from interfaces.runtime.app import AppContext
    from interfaces.runtime.bus import Bus
    from interfaces.runtime.transport import InprocNetwork

    ctx = AppContext(bus=Bus(node, scenario.name, InprocNetwork().endpoint()), scenario=scenario,
                     node=node, spacecraft=spacecraft, rng=np.random.default_rng(0),
                     log=logging.getLogger("t"))
    app = cls(ctx)
    sent: list[Message] = []
    app.publish = lambda name, msg: sent.append(msg)
    return app, sent


def write_scenario(path: Path, scenario: Scenario) -> Path:
    """Write a scenario as TOML (tables for the sections, inline tables/arrays inside)."""
    lines: list[str] = []
    data = scenario.model_dump(exclude_none=True)
    for k, v in data.items():
        if not isinstance(v, dict):
            lines.append(f"{k} = {_toml(v)}")
    for k, v in data.items():
        if isinstance(v, dict):
            lines.append(f"[{k}]")
            lines += [f"{kk} = {_toml(vv)}" for kk, vv in v.items()]
    path.write_text("\n".join(lines) + "\n")
    assert parse_scenario(path.read_text()) == scenario
    return path


def _toml(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, datetime):
        return v.isoformat()
    if isinstance(v, float) and v == float("inf"):
        return "inf"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{a} = {_toml(b)}" for a, b in v.items()) + " }"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return repr(v)


def settle(pred: Callable[[], bool], timeout_s: float = 5.0) -> None:
    """Poll ``pred`` until it holds or ``timeout_s`` (wall) passes (messages in flight)."""
    deadline = time.monotonic() + timeout_s
    while not pred() and time.monotonic() < deadline:
        time.sleep(0.02)


def a_free_port() -> int:
    """A TCP port free on loopback now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture
def free_port() -> int:
    return a_free_port()


def collector(*types: type[Message], key_prefix: dict[str, str] | None = None,
              ) -> tuple[Callable[[str, str, bytes], None], dict[str, list[Any]]]:
    """A raw tap (for ``run_inproc``) that validates the messages of ``types`` into lists by
    type name; ``key_prefix`` restricts a type to keys starting with the given prefix."""
    by_name = {t.__name__: t for t in types}
    out: dict[str, list[Any]] = {name: [] for name in by_name}

    def tap(key: str, type_name: str, payload: bytes) -> None:
        t = by_name.get(type_name)
        if t is not None and key.startswith((key_prefix or {}).get(type_name, "")):
            out[type_name].append(t.model_validate_json(payload))

    return tap, out


def recorded_run(scenario: Scenario, out: Path, *types: type[Message]
                 ) -> tuple[dict[str, list[Any]], RunSummary]:
    """Run ``scenario`` in-process, archiving every message to ``out/run.mcap`` and collecting
    those of ``types`` (as :func:`collector`); returns (collected by type name, the run's
    summary as written to summary.json)."""
    from deploy.inproc import run_inproc
    from ground.archive.recorder import McapRecorder
    from harness.summary.build import write_summary

    tap, got = collector(*types)
    with McapRecorder(out / "run.mcap", {}) as rec:
        def both(key: str, type_name: str, payload: bytes) -> None:
            tap(key, type_name, payload)
            rec.record(key, type_name, payload)

        run_inproc(scenario, tap=both)
    return got, write_summary(out, scenario, "inproc", 1.0, "completed")


@contextlib.contextmanager
def dask_cluster() -> Iterator[str]:
    """A real Dask scheduler and one single-threaded worker, separate processes on loopback
    (importing this repository); yields the scheduler's address and stops both."""
    port = a_free_port()
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    quiet = {"env": env, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler",
                               "--host", "127.0.0.1", "--port", str(port),
                               "--dashboard-address", ":0"], **quiet)]
    try:
        procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker",
                                       f"tcp://127.0.0.1:{port}", "--nworkers", "1",
                                       "--nthreads", "1", "--host", "127.0.0.1",
                                       "--dashboard-address", ":0"], **quiet))
        yield f"tcp://127.0.0.1:{port}"
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            p.wait(timeout=30)


def canonical(obj: object, inside: frozenset[int] = frozenset()) -> object:
    """A node's state as plain values to compare (sets sorted, arrays as bytes, objects as
    their pickled state): a pickle's bytes follow a set's history and the objects' sharing,
    not only their values."""
    if isinstance(obj, np.ndarray):
        return ("array", obj.dtype.str, obj.shape, obj.tobytes())
    if obj is None or isinstance(obj, (str, int, float, bytes)):
        return obj
    if id(obj) in inside:  # a cycle (a part pointing back at its owner)
        return ("cycle", type(obj).__qualname__)
    inside = inside | {id(obj)}
    if isinstance(obj, (set, frozenset)):
        return ("set", sorted((canonical(x, inside) for x in obj), key=repr))
    if isinstance(obj, dict):
        return {k: canonical(v, inside) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return type(obj)(canonical(x, inside) for x in obj)
    state = obj.__getstate__() if hasattr(obj, "__getstate__") else vars(obj)
    return (type(obj).__qualname__, canonical(state, inside))
