"""The launcher's watch over the recorder with --restart-on-crash (deploy/run_constellation.py,
``_Watch``), on real child processes standing in for the sim and the recorder: a recorder that
cannot come back -- dead again after every restart, or silent after one -- stops the run,
named.  The recorder killed in a whole run and restarted: test_constellation.py."""

from __future__ import annotations

from pathlib import Path

import pytest

import deploy.run_constellation as launcher
from interfaces.contracts.topology import RECORDER, ROUTER, SIM
from tests.conftest import REPO, small_scenario


def _watch(tmp_path: Path, recorder_code: str, recorder_up: int = 0) -> launcher._Watch:
    """A watch with --restart-on-crash over a recorder running ``recorder_code`` and a sim
    that waits, whose recorder token has appeared ``recorder_up`` times (never again)."""
    sup = launcher.Supervisor(REPO)
    sup.start(launcher.Child(RECORDER.name, ["-c", recorder_code], tmp_path / "recorder.log"))
    sup.start(launcher.Child(SIM.name, ["-c", "import time; time.sleep(60)"], tmp_path / "sim.log"))
    return launcher._Watch(sup, launcher._Progress(small_scenario("sup")), flight={},
                           restart=True, recorder_up=lambda: recorder_up)


def test_a_recorder_dead_after_every_restart_stops_the_run(tmp_path: Path) -> None:
    watch = _watch(tmp_path, "raise SystemExit(3)")
    try:
        error = watch.run()
    finally:
        watch.sup.stop_all()
    assert error is not None and error.startswith("recorder (pid ")
    assert (f"exited with code 3 at sim t≈0.0 s: nothing after it is recorded; stopping the "
            f"run (restarted {launcher.MAX_RESTARTS} times)") in error
    assert [str(i) for i in watch.incidents] == (
        ["recorder exited with code 3 at t≈0.0 s (restarted)"] * launcher.MAX_RESTARTS)
    assert (tmp_path / f"recorder.restart{launcher.MAX_RESTARTS}.log").is_file()


def test_a_restarted_recorder_that_never_announces_itself_stops_the_run(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The first recorder dies; its successor runs but declares no token in time."""
    monkeypatch.setattr(launcher, "SERVICE_READY_S", 1.0)
    first_dies = ("import pathlib, sys, time\n"
                  f"if not pathlib.Path({str(tmp_path / 'recorder.restart1.log')!r}).exists():\n"
                  "    sys.exit(1)\n"
                  "time.sleep(60)\n")
    watch = _watch(tmp_path, first_dies, recorder_up=1)
    try:
        error = watch.run()
    finally:
        watch.sup.stop_all()
    assert error is not None and "it was not back within 1 s" in error
    assert "nothing after it is recorded" in error and "still running" in error
    assert len(watch.incidents) == 1 and watch.restarts == {RECORDER.name: 1}



def test_a_router_dead_after_every_restart_stops_the_run_naming_it(tmp_path: Path) -> None:
    watch = _watch(tmp_path, "import time; time.sleep(60)")
    watch.sup.start(launcher.Child(ROUTER.name, ["-c", "raise SystemExit(4)"],
                                   tmp_path / "router.log"))
    try:
        error = watch.run()
    finally:
        watch.sup.stop_all()
    assert error is not None and error.startswith("router (pid ")
    assert "the bus is down" in error and f"(restarted {launcher.MAX_RESTARTS} times)" in error
    assert [i.node for i in watch.incidents] == [ROUTER.name] * launcher.MAX_RESTARTS


def test_a_stop_ends_the_watch_interrupted_unless_the_sim_had_finished(tmp_path: Path) -> None:
    """SIGINT or SIGTERM set the watch's stop: with the sim still flying the run is
    interrupted; with the sim finished it is complete (nothing raised into the shutdown)."""
    for finished, expected in ((False, launcher.INTERRUPTED), (True, None)):
        watch = _watch(tmp_path, "import time; time.sleep(60)", recorder_up=1)
        if finished:
            watch.progress.finished.set()
        watch.stop.set()
        try:
            assert watch.run() == expected
        finally:
            watch.sup.stop_all()
