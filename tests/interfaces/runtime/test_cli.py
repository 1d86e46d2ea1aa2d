"""The command line every node process shares (interfaces/runtime/cli.py): its options, the
scenario with the seed and duration overridden, the mission's key space, a bad scenario file
ending the process with a readable message, and SIGINT or SIGTERM setting the event a node
stops on."""

from __future__ import annotations

import argparse
import os
import signal
from pathlib import Path

import pytest

from interfaces.runtime.cli import (
    add_node_args,
    load_node_scenario,
    mission_of,
    stop_on_signals,
)
from interfaces.runtime.zenoh_transport import DEFAULT_ENDPOINT
from tests.conftest import small_scenario, write_scenario


def _args(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_node_args(parser)
    return parser.parse_args(list(argv))


def test_the_scenario_with_its_overrides_and_the_key_space(tmp_path: Path) -> None:
    path = write_scenario(tmp_path / "s.toml", small_scenario("cliname", duration_s=20.0))
    args = _args("--scenario", str(path))
    assert args.connect == DEFAULT_ENDPOINT and args.zenoh_config is None
    sc = load_node_scenario(args)
    assert (sc.name, sc.seed, sc.duration_s) == ("cliname", 3, 20.0)
    assert mission_of(args, sc) == "cliname"
    args = _args("--scenario", str(path), "--seed", "9", "--duration", "7.5", "--mission", "m2")
    sc = load_node_scenario(args)
    assert (sc.seed, sc.duration_s) == (9, 7.5)
    assert mission_of(args, sc) == "m2"


def test_a_scenario_is_required_and_a_bad_one_ends_the_process_readably(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        _args()
    assert "--scenario" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\nduration_s = 10\n[comms]\nrange = 5\n')
    with pytest.raises(SystemExit) as ended:
        load_node_scenario(_args("--scenario", str(bad)))
    assert "comms.range" in str(ended.value.code) and "bad.toml" in str(ended.value.code)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_sets_the_stop_event(signum: signal.Signals) -> None:
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        stop = stop_on_signals()
        assert not stop.is_set()
        os.kill(os.getpid(), signum)  # handled in this (the main) thread, not fatal
        assert stop.wait(2.0)
    finally:
        for s, handler in saved.items():
            signal.signal(s, handler)
