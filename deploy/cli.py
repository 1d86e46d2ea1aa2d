"""``insp-fdir``: one command for the project's tools, each a subcommand handing the rest of the
command line to the tool's own ``main(argv)`` (``insp-fdir run --help`` is the run's help).

    insp-fdir run --scenario deploy/scenarios/default.toml --out runs/x
    insp-fdir archive list runs/x/run.mcap

The tools keep their own commands too (``python deploy/run_constellation.py``,
``python -m harness.archive``...).  The console script is declared in pyproject.toml
(``[project.scripts]``); ``python -m deploy.cli`` is the same without installing.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Callable, Sequence
from typing import Final, NamedTuple


class Command(NamedTuple):
    """A subcommand: the module whose ``main(argv) -> int`` runs it, and one line of help."""

    module: str
    help: str


COMMANDS: Final = {
    "run": Command("deploy.run_constellation", "run one scenario (sim, flight software, ground)"),
    "campaign": Command("deploy.run_campaign", "run, replay or sweep a fault campaign"),
    "replay": Command("harness.replay", "re-run the ground FDIR on a run's archive"),
    "tlm": Command("ground.tools.tlm", "watch a running constellation's telemetry live"),
    "archive": Command("harness.archive.cli", "list, summarize or export a run archive"),
}
"""Subcommand -> the module that runs it (imported only when that subcommand is run)."""


def entry(name: str) -> Callable[[list[str] | None], int]:
    """The ``main`` of subcommand ``name`` (its module imported now)."""
    main: Callable[[list[str] | None], int] = importlib.import_module(COMMANDS[name].module).main
    return main


def _parser() -> argparse.ArgumentParser:
    """The top-level parser: it only shows help and rejects unknown subcommands (a known one
    is dispatched before parsing, so its options are all its own)."""
    p = argparse.ArgumentParser(prog="insp-fdir", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True,
                           title="commands (`insp-fdir COMMAND --help` for each)")
    for name, command in COMMANDS.items():
        sub.add_parser(name, help=command.help, add_help=False)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``insp-fdir`` with ``argv`` (default: the process's arguments); the exit status."""
    args = list(sys.argv[1:] if argv is None else argv)
    if args and args[0] in COMMANDS:
        if argv is None:  # a tool's parser without a prog of its own names it by sys.argv[0]
            sys.argv[0] = f"insp-fdir {args[0]}"
        return entry(args[0])(args[1:])
    _parser().parse_args(args)  # help, or an error for a missing or unknown command: exits
    return 2  # pragma: no cover - parse_args exits for every argument list reaching it


if __name__ == "__main__":
    raise SystemExit(main())
