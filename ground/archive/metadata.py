"""Run metadata the recorder writes into an archive: what ran, with which seed, scenario and
software (MCAP metadata records ``run`` and ``scenario``; read back by
``harness.archive.run_scenario``)."""

from __future__ import annotations

import functools
import importlib.metadata
import subprocess
import time
from pathlib import Path

from interfaces.contracts.scenario import Scenario


@functools.cache
def software_version() -> str:
    """The package version, with the git commit of the checkout it runs from when there is
    one (``0.1.0+g46a41bc``, ``-dirty`` with uncommitted changes)."""
    try:
        version = importlib.metadata.version("insp-fdir")
    except importlib.metadata.PackageNotFoundError:
        version = "unknown (not installed)"
    repo = Path(__file__).resolve().parents[2]
    try:
        commit = subprocess.run(["git", "-C", str(repo), "describe", "--always", "--dirty",
                                 "--exclude", "*"], capture_output=True, text=True, timeout=10,
                                check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return version
    return f"{version}+g{commit}" if commit else version


def run_metadata(scenario: Scenario, transport: str,
                 scenario_toml: str) -> dict[str, dict[str, str]]:
    """MCAP metadata records of a run: what ran, with which seed and software."""
    return {
        "run": {"scenario": scenario.name, "seed": str(scenario.seed), "transport": transport,
                "duration_s": str(scenario.duration_s), "software_version": software_version(),
                "started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())},
        "scenario": {"toml": scenario_toml, "resolved_json": scenario.model_dump_json()},
    }
