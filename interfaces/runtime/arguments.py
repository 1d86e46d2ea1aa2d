"""Command-line values every tool checks the same way (issue 40): a log level among the
logging module's, a count of at least one.  Each is an ``argparse`` type, so a bad value is
refused by the parser with exit 2 and a line naming the option, never a traceback."""

from __future__ import annotations

import argparse
import sys

from interfaces.contracts.topics import is_segment

LOG_LEVELS = ("DEBUG", "INFO", "WARNING", "ERROR")


def log_level(text: str) -> str:
    """A logging level name, any case (``info`` is ``INFO``)."""
    level = text.upper()
    if level not in LOG_LEVELS:
        raise argparse.ArgumentTypeError(f"{text!r}: one of {', '.join(LOG_LEVELS)}")
    return level


def positive_int(text: str) -> int:
    """A whole number of at least 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value}: at least 1")
    return value


def mission_name(text: str) -> str:
    """A key-space name (one key segment: letters, digits, '_' or '-')."""
    if not is_segment(text):
        raise argparse.ArgumentTypeError(f"{text!r}: letters, digits, '_' or '-' only (one "
                                         "segment of the bus's keys)")
    return text


def prog_name(own: str) -> str:
    """The name a tool's help and errors go under: ``insp-fdir <subcommand>`` when run as one
    (``deploy/cli.py`` names it in ``sys.argv[0]``), else its own (``python -m ...``)."""
    return sys.argv[0] if sys.argv[0].startswith("insp-fdir ") else own


def add_log_level(parser: argparse.ArgumentParser) -> None:
    """``--log-level LEVEL``, default INFO."""
    parser.add_argument("--log-level", type=log_level, default="INFO", metavar="LEVEL",
                        help=f"console log level: {', '.join(LOG_LEVELS)} (default %(default)s)")
