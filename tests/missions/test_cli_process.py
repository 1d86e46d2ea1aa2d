"""``insp-fdir`` (deploy/cli.py) as a process of its own: its help lists the five subcommands,
a subcommand's help is its tool's own, a missing or unknown subcommand is a usage error, and
``archive list`` of a recorded run prints what the tool prints."""

from __future__ import annotations

import importlib
import io
import os
import subprocess
import sys
from contextlib import redirect_stdout
from pathlib import Path

import pytest

from deploy import cli
from harness.archive.cli import list_topics
from harness.archive.reader import load_run
from interfaces.runtime.arguments import command_help
from tests.conftest import REPO, recorded_run, small_scenario
from tests.deploy.test_cli import SUBCOMMANDS


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    """``python -m deploy.cli ARGS`` in a subprocess importing this checkout."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-m", "deploy.cli", *args], capture_output=True,
                          text=True, env=env, cwd=REPO, timeout=120)


def test_help_lists_the_subcommands_one_line_each() -> None:
    done = _cli("--help")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    for name in SUBCOMMANDS:
        line = next(ln for ln in lines if ln.split()[:1] == [name])
        assert cli.COMMANDS[name].help in line


@pytest.mark.parametrize("name", SUBCOMMANDS)
def test_a_subcommands_help_is_the_tools_own_under_its_insp_fdir_name(name: str) -> None:
    done = _cli(name, "--help")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"usage: insp-fdir {name}")
    doc = importlib.import_module(cli.COMMANDS[name].module).__doc__
    assert command_help(doc, "").splitlines()[0] in done.stdout  # its own docstring's


def test_no_or_unknown_subcommand_is_a_usage_error() -> None:
    for args in ((), ("bogus",)):
        done = _cli(*args)
        assert done.returncode == 2 and "usage: insp-fdir" in done.stderr, args
    with pytest.raises(SystemExit) as ended:
        cli.main(["nope"])
    assert ended.value.code == 2


def test_archive_list_through_the_dispatcher(tmp_path: Path) -> None:
    recorded_run(small_scenario("cli", duration_s=3.0, observers={"count": 1}), tmp_path)
    path = tmp_path / "run.mcap"
    expected = io.StringIO()
    list_topics(load_run(path), expected)
    done = _cli("archive", "list", str(path))
    assert done.returncode == 0, done.stderr
    assert done.stdout == expected.getvalue()
    assert "insp/cli/sc/1/nav/estimate" in done.stdout
    captured = io.StringIO()
    with redirect_stdout(captured):
        assert cli.main(["archive", "list", str(path)]) == 0
    assert captured.getvalue() == expected.getvalue()
    assert _cli("archive", "summary", str(tmp_path / "none.mcap")).returncode == 2
