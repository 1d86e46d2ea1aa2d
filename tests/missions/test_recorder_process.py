"""The recorder in a process of its own: same archive as in-process, and nothing already sent is
lost when either side dies."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from ground.archive.recorder import McapRecorder
from ground.archive.recorder_process import BATCH, RecorderDied, RecorderProcess
from harness.archive.reader import load_run
from interfaces.contracts.messages import Heartbeat
from interfaces.runtime.transport import Sample
from tests.conftest import REPO


def _samples(n: int) -> list[Sample]:
    out = []
    for i in range(n):
        msg = Heartbeat(sender="sc1", t_sim=0.1 * i, node="sc1", apps=["nav"], k=i)
        out.append(Sample("insp/m/sc/1/exec/heartbeat", "Heartbeat", message=msg))
    out.append(Sample("insp/m/sc/1/exec/heartbeat", "Heartbeat", payload=b'{"not": "valid"}'))
    return out


def test_same_archive_as_the_in_process_recorder(tmp_path: Path) -> None:
    samples = _samples(2 * BATCH + 17)
    with RecorderProcess(tmp_path / "child.mcap", {"run": {"seed": "1"}}) as rec:
        for s in samples:
            rec.record_sample(s)
    with McapRecorder(tmp_path / "here.mcap", {"run": {"seed": "1"}}) as rec2:
        for s in samples:
            rec2.record_sample(s)
    child, here = load_run(tmp_path / "child.mcap"), load_run(tmp_path / "here.mcap")
    assert not child.truncated and child.metadata == here.metadata
    assert [(r.key, r.log_time_ns, r.payload) for r in child.records()] == \
        [(r.key, r.log_time_ns, r.payload) for r in here.records()]
    assert len(child) == len(samples)


def test_a_killed_run_leaves_a_complete_archive_of_what_it_sent(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    script = textwrap.dedent(f"""
        import os, signal, sys
        sys.path.insert(0, {str(REPO)!r})
        from tests.missions.test_recorder_process import _samples
        from ground.archive.recorder_process import BATCH, RecorderProcess
        rec = RecorderProcess({str(path)!r})
        for s in _samples(3 * BATCH)[:3 * BATCH]:
            rec.record_sample(s)
        os.kill(os.getpid(), signal.SIGKILL)
    """)
    proc = subprocess.run([sys.executable, "-c", script], cwd=REPO, timeout=60)
    assert proc.returncode == -signal.SIGKILL
    closed = False
    for _ in range(100):  # the child notices the end of the pipe and closes the file
        if path.exists() and not load_run(path).truncated:
            closed = True
            break
        time.sleep(0.1)
    assert closed, "the recorder process did not close the archive"
    assert len(load_run(path)) == 3 * BATCH  # every full batch sent before the kill


def test_a_dead_recorder_is_reported(tmp_path: Path) -> None:
    rec = RecorderProcess(tmp_path / "run.mcap")
    assert rec._proc.pid is not None
    os.kill(rec._proc.pid, signal.SIGKILL)
    rec._proc.join()
    with pytest.raises(RecorderDied):
        for s in _samples(4 * BATCH):
            rec.record_sample(s)
        rec.close()
