"""Nothing lost when the environment fails: a run whose disk fills, whose disk is too small,
whose folder is read-only or whose whole process group is signalled ends with a summary (or,
refused before any work, with nothing written) and a one-line cause, with the exit code a
script can act on; what was archived stays readable.  Each case makes its own small filesystem
(a tmpfs) or read-only mount, or signals the group, and removes it at the end."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from dataclasses import dataclass
from pathlib import Path

import pytest

from harness.archive.reader import load_run
from harness.summary import RunSummary
from tests.conftest import REPO, small_scenario, write_scenario
from tests.mounts import read_only, tmpfs

SC = small_scenario("envfail", duration_s=300.0, target={"pois": 1000},
                    rates={"high_hz": 5.0, "fdi_period_s": 50.0})
"""3 observers, 1,000 POIs: an archive of about 4 MB, estimated at 4.7 MB."""


@dataclass(frozen=True)
class Case:
    """One environment failure: where the run goes (``place``: a context making the folder
    that holds ``--out``), the launcher's options, what the user must get: the exit code, a
    fragment of the one-line cause on stderr, and the summary's status (None: refused before
    any work, nothing written)."""

    name: str
    place: Callable[[Path], AbstractContextManager[Path]]
    options: tuple[str, ...]
    exit_code: int
    cause: str
    status: str | None


def _disk(size_mb: float) -> Callable[[Path], AbstractContextManager[Path]]:
    return lambda where: tmpfs(where / "disk", size_mb)


def _read_only(where: Path) -> AbstractContextManager[Path]:
    (where / "ro" / "empty").mkdir(parents=True)
    return read_only(where / "ro")


CASES = [
    Case("disk too small for the estimate", _disk(10.0), ("--transport", "inproc"), 2,
         "free; the run needs about", None),
    Case("disk full mid-run, in process", _disk(10.0),
         ("--transport", "inproc", "--skip-disk-check"), 1, "disk full at t =", "failed"),
    Case("disk full mid-run, over Zenoh", _disk(10.0), ("--skip-disk-check",), 1,
         "disk full at t ≈", "failed"),
    Case("read-only folder, new --out", _read_only, ("--transport", "inproc"), 2,
         "cannot make the folder: Read-only file system", None),
]


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_the_environment_failing_loses_nothing(tmp_path: Path, free_port: int,
                                               case: Case) -> None:
    scenario = write_scenario(tmp_path / "envfail.toml", SC)
    with case.place(tmp_path) as folder:
        out = folder / "run"
        proc = subprocess.run(
            [sys.executable, str(REPO / "deploy" / "run_constellation.py"), "--scenario",
             str(scenario), "--out", str(out), "--no-report", *case.options,
             *([] if "inproc" in case.options else
               ["--endpoint", f"tcp/127.0.0.1:{free_port}"])],
            cwd=REPO, capture_output=True, text=True, timeout=300, check=False)
        errors = [line for line in proc.stderr.splitlines() if line.startswith("error: ")]
        assert proc.returncode == case.exit_code, proc.stderr
        assert "Traceback" not in proc.stderr
        assert len(errors) == 1 and case.cause in errors[0], proc.stderr
        if case.status is None:
            assert not (out / "summary.json").exists() and not (out / "run.mcap").exists()
            return
        _written_whole(out, case.status, case.cause)


def _written_whole(out: Path, status: str, cause: str) -> None:
    """The summary is whole, names the cause and how far the run got, and the archive
    replays to that point."""
    summary = RunSummary.read(out / "summary.json")
    assert summary.status == status and summary.error and cause in summary.error
    reached = summary.t_sim_final_s
    assert reached is not None and 0.0 < reached < SC.duration_s
    archive = load_run(out / "run.mcap")
    assert len(archive) > 0 and archive.end_s == pytest.approx(reached, abs=1.0)
    assert not (out / ".disk-reserve").exists()


def test_a_signal_to_the_whole_group_ends_the_run_as_one(tmp_path: Path) -> None:
    """SIGTERM to the run's process group (``timeout``, ``scancel``, systemd): the recorder
    is shielded, the archive closed with its footer, the summary written; exit 143."""
    scenario = write_scenario(tmp_path / "envfail.toml",
                              SC.model_copy(update={"duration_s": 3000.0}))
    out = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, str(REPO / "deploy" / "run_constellation.py"), "--scenario",
         str(scenario), "--out", str(out), "--no-report", "--transport", "inproc"],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True)
    deadline = time.monotonic() + 120.0
    while not (out / "run.mcap").exists() or (out / "run.mcap").stat().st_size < 100_000:
        assert proc.poll() is None and time.monotonic() < deadline, proc.stderr
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGTERM)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGTERM, stderr
    assert "Traceback" not in stderr
    assert [ln for ln in stderr.splitlines() if ln.startswith("error: ")] == \
        ["error: interrupted by SIGTERM"]
    summary = RunSummary.read(out / "summary.json")
    assert summary.status == "interrupted" and summary.t_sim_final_s
    archive = load_run(out / "run.mcap")
    assert not archive.truncated
    assert archive.end_s == pytest.approx(summary.t_sim_final_s, abs=1.0)
