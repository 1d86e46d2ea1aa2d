"""A run interrupted ends as a run (issue 40): SIGINT (Ctrl-C) or SIGTERM to an in-process
run stops it at a tick boundary, writes summary.json with ``status: interrupted`` and the sim
time reached, closes an archive the reader reads whole, prints no traceback, says in its last
line how far it got (as summary.json does), and exits 128 + the signal's number; the replay
reads it, judging nothing past where it ends, and reproduces its ground."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from harness.archive.reader import load_run
from harness.replay import replay_run
from harness.summary import RunSummary
from tests.conftest import REPO

NOMINAL = REPO / "deploy" / "scenarios" / "nominal.toml"
PROGRESS = re.compile(r"(?:t=|t_sim\s+)(\d+\.\d) ")


@pytest.mark.parametrize("transport, signum", [("inproc", signal.SIGINT),
                                               ("inproc", signal.SIGTERM),
                                               ("zenoh", signal.SIGINT)])
def test_an_interrupted_run_is_written_as_one(tmp_path: Path, free_port: int, transport: str,
                                              signum: int) -> None:
    out = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    port = free_port
    endpoint = ["--endpoint", f"tcp/127.0.0.1:{port}"] if transport == "zenoh" else []
    proc = subprocess.Popen(
        [sys.executable, "-m", "deploy.cli", "run", "--scenario", str(NOMINAL), "--transport",
         transport, *endpoint, "--no-report", "--out", str(out)],
        cwd=REPO, env=env, text=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stderr is not None
    seen = []
    for line in proc.stderr:  # the sim's (or the launcher's) progress: some ticks flown
        seen.append(line)
        t = PROGRESS.search(line)
        if t and float(t.group(1)) >= 100.0:
            break
    proc.send_signal(signum)
    stdout, rest = proc.communicate(timeout=120)
    stderr = "".join(seen) + rest
    assert proc.returncode == 128 + signum, stderr
    assert "Traceback" not in stderr
    summary = RunSummary.read(out / "summary.json")
    assert summary.status == "interrupted" and summary.error
    reached = summary.t_sim_final_s
    assert reached is not None and 0.0 < reached < summary.duration_s
    last = stdout.strip().splitlines()[0]
    assert last.startswith("interrupted: ") and f"{reached:.0f} of 1200 s simulated" in last
    archive = load_run(out / "run.mcap")
    assert not archive.truncated
    replay = replay_run(out / "run.mcap", {})  # what replay and reports read of it
    assert replay.span.end_s <= reached + 1.0 and replay.faithful_until_s() <= reached + 1.0
    assert replay.matches_live()
