"""Command-line values every tool checks the same way (issue 40): a log level among the
logging module's, a count of at least one, a Zenoh endpoint's form.  Each is an ``argparse``
type, so a bad value is refused by the parser with exit 2 and a line naming the option, never
a traceback."""

from __future__ import annotations

import argparse
import re
import sys
import textwrap

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


ENDPOINT_PROTOCOLS = ("tcp", "tls", "udp", "quic", "ws", "unixsock-stream")
"""The link protocols a Zenoh endpoint may name."""


def endpoint(text: str) -> str:
    """A Zenoh endpoint ``<protocol>/<address>``: tcp, tls, udp, quic and ws with
    ``host:port`` (a port of 1-65535), unixsock-stream with a path; anything after ``?`` or
    ``#`` (metadata, configuration) is left to Zenoh."""
    proto, sep, rest = text.partition("/")
    address = rest.split("?", 1)[0].split("#", 1)[0]
    if not sep or proto not in ENDPOINT_PROTOCOLS or not address:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a Zenoh endpoint: <protocol>/<address> with a protocol among "
            f"{', '.join(ENDPOINT_PROTOCOLS)} (e.g. tcp/127.0.0.1:7447)")
    if proto != "unixsock-stream":
        host, colon, port = address.rpartition(":")
        if not colon or not host or not port.isdigit() or not 1 <= int(port) <= 65535:
            raise argparse.ArgumentTypeError(
                f"{text!r}: a {proto} endpoint is {proto}/HOST:PORT with a port of 1-65535")
    return text


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


ROLES = re.compile(r":[a-z]+:`~?([^`]+)`|``([^`]+)``|`([^`]+)`")
"""reST markup in a docstring: a role (``:class:`x```), a literal (````x````), a reference."""


HELP_WIDTH = 79
"""Columns of a command's description (``argparse.RawDescriptionHelpFormatter`` keeps its
paragraphs)."""


def command_help(doc: str | None, details: str, paragraphs: int = 1) -> str:
    """A command's ``--help`` text from its module docstring: the first ``paragraphs``
    (indented usage blocks left out: argparse prints its own), without reST markup, then
    where the details are (``details``: a document of docs/)."""
    blocks = [b for b in (doc or "").strip().split("\n\n") if not b.startswith("    ")]
    plain = [ROLES.sub(lambda m: next(g for g in m.groups() if g is not None), " ".join(
        b.split())) for b in blocks[:paragraphs]]
    return "\n\n".join(textwrap.fill(b, HELP_WIDTH) for b in [*plain, f"Details: {details}"])
