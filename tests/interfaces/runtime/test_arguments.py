"""The command-line value types every tool shares (interfaces/runtime/arguments.py)."""

from __future__ import annotations

import argparse
import sys

import pytest

from interfaces.runtime.arguments import (
    endpoint,
    log_level,
    mission_name,
    positive_int,
    prog_name,
)


def test_values_are_taken_or_refused_with_a_reason() -> None:
    assert log_level("info") == "INFO" and positive_int("3") == 3
    assert mission_name("space-1_a") == "space-1_a"
    for check, text, says in ((log_level, "loud", "one of DEBUG"), (positive_int, "0", "at least"),
                              (positive_int, "x", "a whole number"),
                              (mission_name, "a/b", "letters, digits")):
        with pytest.raises(argparse.ArgumentTypeError, match=says):
            check(text)


@pytest.mark.parametrize("text", ["tcp/127.0.0.1:7447", "tls/host.example:443",
                                  "tcp/[::1]:7447", "udp/10.0.0.2:1?iface=eth0",
                                  "unixsock-stream//tmp/zenoh.sock"])
def test_a_zenoh_endpoint_is_taken_as_given(text: str) -> None:
    assert endpoint(text) == text


@pytest.mark.parametrize("text, says", [
    ("garbage", "not a Zenoh endpoint"), ("http/x:80", "not a Zenoh endpoint"),
    ("tcp/", "not a Zenoh endpoint"), ("tcp/localhost", "tcp/HOST:PORT"),
    ("tcp/:7447", "tcp/HOST:PORT"), ("tls/h:0", "1-65535"), ("tcp/h:99999", "1-65535"),
    ("tcp/h:port", "tcp/HOST:PORT")])
def test_a_malformed_endpoint_is_refused_with_its_form(text: str, says: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match=says):
        endpoint(text)


def test_a_tool_speaks_under_its_insp_fdir_name_when_run_as_one(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "argv", ["insp-fdir replay", "--help"])
    assert prog_name("python -m harness.replay") == "insp-fdir replay"
    monkeypatch.setattr(sys, "argv", ["/usr/bin/pytest"])
    assert prog_name("python -m harness.replay") == "python -m harness.replay"
