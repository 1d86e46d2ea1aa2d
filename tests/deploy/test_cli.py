"""``insp-fdir`` (deploy/cli.py): the console script declared in pyproject.toml, its five
subcommands handing over to each tool's own ``main(argv)`` (the command as a process:
tests/missions/test_cli_process.py)."""

from __future__ import annotations

import importlib
import inspect
import re
import tomllib

import pytest

from deploy import cli
from tests.conftest import REPO

SUBCOMMANDS = ("run", "campaign", "replay", "tlm", "archive")


def test_the_console_script_resolves_to_the_dispatcher() -> None:
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    target = project["scripts"]["insp-fdir"]
    module, _, attr = target.partition(":")
    main = getattr(importlib.import_module(module), attr)
    assert callable(main) and main is cli.main
    assert "pandas" in " ".join(project["dependencies"])
    assert "pyarrow" in " ".join(project["dependencies"])


def test_every_subcommand_is_a_main_taking_argv() -> None:
    assert tuple(cli.COMMANDS) == SUBCOMMANDS
    for name in SUBCOMMANDS:
        main = cli.entry(name)
        assert callable(main)
        params = inspect.signature(main).parameters
        assert "argv" in params and params["argv"].default is None, name


def test_every_commands_help_is_plain_and_short(capsys: pytest.CaptureFixture[str]) -> None:
    """``--help`` of every tool: no reST markup (backquotes, roles), a description of a few
    paragraphs that names where the details are."""
    for name in cli.COMMANDS:
        with pytest.raises(SystemExit) as stop:
            cli.main([name, "--help"])
        assert stop.value.code == 0
        text = capsys.readouterr().out
        description = re.split(r"\n(?:positional arguments|options):",
                               text.split("\n\n", 1)[1])[0]
        assert "`" not in text and ":class:" not in text, name
        assert "Details: docs/" in description and len(description.splitlines()) <= 20, name
