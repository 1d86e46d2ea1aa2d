"""The command-line value types every tool shares (interfaces/runtime/arguments.py)."""

from __future__ import annotations

import argparse
import sys

import pytest

from interfaces.runtime.arguments import log_level, mission_name, positive_int, prog_name


def test_values_are_taken_or_refused_with_a_reason() -> None:
    assert log_level("info") == "INFO" and positive_int("3") == 3
    assert mission_name("space-1_a") == "space-1_a"
    for check, text, says in ((log_level, "loud", "one of DEBUG"), (positive_int, "0", "at least"),
                              (positive_int, "x", "a whole number"),
                              (mission_name, "a/b", "letters, digits")):
        with pytest.raises(argparse.ArgumentTypeError, match=says):
            check(text)


def test_a_tool_speaks_under_its_insp_fdir_name_when_run_as_one(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "argv", ["insp-fdir replay", "--help"])
    assert prog_name("python -m harness.replay") == "insp-fdir replay"
    monkeypatch.setattr(sys, "argv", ["/usr/bin/pytest"])
    assert prog_name("python -m harness.replay") == "python -m harness.replay"
