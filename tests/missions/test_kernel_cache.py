"""The run's compiled kernels (interfaces/runtime/kernels.py): compiled into an empty cache,
then found there by a fresh process; a run calls them with no argument types but those listed,
so none is compiled inside a tick."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from deploy.inproc import run_inproc
from ground.fdir import identify
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.scenario.model import parse_scenario
from interfaces.runtime.kernels import unlisted_signatures

REPO = Path(__file__).resolve().parents[2]

_COLD = """
import json
from numba import types
from interfaces.runtime.kernels import Kernel, compile_kernels, kernels_cached, unlisted_signatures
small = (Kernel("sim.kernels", "lvlh_attitudes", ((types.float64[::1], types.float64[:, ::1]),)),)
before = kernels_cached(small)
told = []
spent = compile_kernels(told.append, small)
extra = small[0].dispatcher().compile((types.float64[::1], types.float64[:, :]))
print(json.dumps({"before": before, "after": kernels_cached(small), "told": told,
                  "spent": spent, "unlisted": unlisted_signatures(small)}))
"""

_WARM = """
from interfaces.runtime.kernels import Kernel, compile_kernels, kernels_cached
from numba import types
small = (Kernel("sim.kernels", "lvlh_attitudes", ((types.float64[::1], types.float64[:, ::1]),)),)
told = []
compile_kernels(told.append, small)
print(kernels_cached(small), len(told))
"""


def _python(code: str, cache: Path) -> str:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env, check=True,
                          capture_output=True, text=True)
    return done.stdout.strip().splitlines()[-1]


def test_kernels_compile_into_an_empty_cache_and_a_fresh_process_finds_them(
        tmp_path: Path) -> None:
    cold = json.loads(_python(_COLD, tmp_path))
    assert cold["before"] is False and cold["after"] is True
    assert cold["told"][0].startswith("compiling 1 of the 1 numba kernels into the cache")
    assert cold["told"][-1].startswith("kernels compiled in")
    assert cold["spent"] > 0
    assert any(tmp_path.rglob("*lvlh_attitudes*.nbi"))
    # a signature not listed is named (a caller that changed its types)
    assert list(cold["unlisted"]) == ["sim.kernels.lvlh_attitudes"]
    assert "Array(float64, 2, 'A'" in cold["unlisted"]["sim.kernels.lvlh_attitudes"][0]
    # a fresh process finds them cached, and compiles nothing: it says nothing
    assert _python(_WARM, tmp_path) == "True 0"


def test_a_run_calls_the_kernels_with_the_listed_types_only(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The default scenario's first 200 s with two observers, in one process: truth, sensors,
    attitude, guidance and the ground's identification (which locates cameras by
    trilateration at its first windows) compile no kernel beyond the list (``run_inproc``
    loads the listed ones first)."""
    base = parse_scenario((REPO / "deploy" / "scenarios" / "default.toml").read_text())
    scenario = Scenario.model_validate({**base.model_dump(), "duration_s": 200.0,
                                        "observers": {**base.observers.model_dump(), "count": 2}})
    located: list[int] = []
    fit = identify.least_squares_each

    def spy(*args: Any) -> Any:  # passes through: only shows the identification ran
        located.append(1)
        return fit(*args)

    monkeypatch.setattr(identify, "least_squares_each", spy)
    before = unlisted_signatures()  # what other tests of this process compiled, on purpose
    run_inproc(scenario)
    assert located, "the run never located a camera: the test would miss its kernel"
    added = {k: [s for s in sigs if s not in before.get(k, [])]
             for k, sigs in unlisted_signatures().items()}
    assert {k: sigs for k, sigs in added.items() if sigs} == {}
