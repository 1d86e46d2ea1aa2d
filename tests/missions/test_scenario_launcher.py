"""The launcher (deploy/run_constellation.py), as a process, refuses a bad scenario file clearly
and before anything starts."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO


@pytest.mark.parametrize("section, key", [
    ("[comms]\nrange = 5\n", "comms.range"),
    ("[rates]\nfdi_period_s = 2.5\n", "rates.fdi_period_s = 2.5 s must be a whole number"),
])
def test_launcher_rejects_a_bad_scenario_clearly(tmp_path: Path, section: str, key: str) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\nduration_s = 10\n' + section)
    p = subprocess.run([sys.executable, str(REPO / "deploy" / "run_constellation.py"),
                        "--scenario", str(bad), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and key in p.stderr
    assert not (tmp_path / "o").exists(), "refused before anything started"
