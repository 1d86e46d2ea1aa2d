"""The one-process run's guarded recorder tap (deploy/recorder_guard.py): the recorder's first
failure stops the run and drops what follows, never raises into the publishing app, and is
said in one line, a full disk as "disk full at t = ... s"."""

from __future__ import annotations

import errno
import threading

import pytest

from deploy.recorder_guard import RecorderGuard, disk_full_cause
from ground.archive.recorder_process import RecorderDied
from interfaces.contracts.messages import Heartbeat
from interfaces.runtime.transport import Sample


def _sample(t_sim: float) -> Sample:
    msg = Heartbeat(sender="sc1", t_sim=t_sim, node="sc1", apps=["nav"], k=int(t_sim * 10))
    return Sample("insp/m/sc/1/exec/heartbeat", "Heartbeat", message=msg)


@pytest.mark.parametrize("error, cause", [
    (OSError(errno.ENOSPC, "No space left on device"), "disk full at t = 0.3 s: "),
    (RecorderDied("the recorder process ended", disk_full=True, t_sim_s=0.25),
     "disk full at t = 0.2 s: "),
    (RecorderDied("the recorder process ended (killed by SIGKILL)", t_sim_s=0.25),
     "the recorder failed at t = 0.2 s: the recorder process ended (killed by SIGKILL)"),
    (OSError(errno.EIO, "Input/output error"), "the recorder failed at t = 0.3 s: "),
])
def test_the_first_failure_stops_the_run_and_names_the_cause(error: Exception,
                                                             cause: str) -> None:
    stop, kept = threading.Event(), []

    def record(sample: Sample) -> None:
        if sample.message is not None and sample.message.t_sim >= 0.3:
            raise error
        kept.append(sample.message.t_sim if sample.message else None)

    guard = RecorderGuard(record, stop)
    for k in range(6):
        guard(_sample(0.1 * k))  # never raises
    assert stop.is_set() and guard.error is error
    assert kept == pytest.approx([0.0, 0.1, 0.2])  # what follows the failure is dropped
    assert guard.cause is not None and guard.cause.startswith(cause)
    assert "\n" not in guard.cause
    assert disk_full_cause(guard.cause) == cause.startswith("disk full")


def test_a_recorder_that_never_fails_says_nothing() -> None:
    stop = threading.Event()
    guard = RecorderGuard(lambda _sample: None, stop)
    guard(_sample(1.0))
    assert guard.cause is None and not stop.is_set()
