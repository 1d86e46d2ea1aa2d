"""A SIGKILLed writer of the MCAP run archive (ground.archive.recorder.McapRecorder), a real
process, leaves a file harness.archive.reader.load_run reads back: truncated, its metadata
whole, and at least every record flushed before the kill, in order."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from harness.archive.reader import Record, load_run
from tests.conftest import REPO

_KILLED_WRITER = """
import sys, time
sys.path.insert(0, sys.argv[2])
from ground.archive.recorder import McapRecorder
from interfaces.contracts.messages import RelNavMeasurement

rec = McapRecorder(sys.argv[1], metadata={"run": {"seed": "1"}}, chunk_size=4096)
i = 0
def record():
    global i
    m = RelNavMeasurement(sender="sim", seq=i, t_sim=i * 0.1, spacecraft=1,
                          r_m=[float(i), 0.0, 0.0], v_mps=[0.0, 0.0, 0.0], sigma_r_m=1.0,
                          sigma_v_mps=1.0)
    rec.record("insp/m1/sim/sensors/sc1/relnav", "RelNavMeasurement", m.model_dump_json().encode())
    i += 1
for _ in range(1000):
    record()
rec.flush()
print(i, flush=True)
while True:  # keep recording until killed
    record()
    if i % 100 == 0:
        time.sleep(0.001)
"""


def test_sigkilled_writer_leaves_a_readable_file(tmp_path: Path) -> None:
    path = tmp_path / "killed.mcap"
    proc = subprocess.Popen(
        [sys.executable, "-c", _KILLED_WRITER, str(path), str(REPO)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line.strip(), proc.stderr.read() if proc.stderr else ""
        flushed = int(line)
        time.sleep(0.2)  # let it write more chunks, and probably be mid-chunk when killed
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait(timeout=10)
    assert proc.returncode == -signal.SIGKILL

    run = load_run(path)
    assert run.truncated
    assert run.metadata == {"run": {"seed": "1"}}
    records = run.records("insp/m1/**")
    seqs = [r.message().seq for r in records]
    assert len(seqs) >= flushed
    assert seqs == list(range(len(seqs)))
    assert all(isinstance(r, Record) for r in records)
    assert [r.log_time_ns for r in records] == [round(s * 0.1 * 1e9) for s in seqs]
