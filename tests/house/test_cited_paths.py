"""Every repository path the code and the docs cite exists (docstrings, comments, README,
docs/): a move or a rename that leaves a stale citation fails here."""

from __future__ import annotations

import re
from pathlib import Path

from tests.conftest import REPO

CITED = re.compile(
    r"(?<![\w./-])((?:interfaces|gnc|faults|links|fsw|sim|ground|harness|deploy|docs|benchmarks|tests)"
    r"/[\w./-]*\w\.(?:py|md|toml))")
SOURCES = ("interfaces", "gnc", "faults", "links", "fsw", "sim", "ground", "harness", "deploy",
           "benchmarks", "tests", "docs")


def _citing_files() -> list[Path]:
    files = [REPO / "README.md"]
    for top in SOURCES:
        files += [p for p in (REPO / top).rglob("*") if p.suffix in (".py", ".md", ".toml")
                  and "__pycache__" not in p.parts]
    return files


def cited_paths(text: str) -> set[str]:
    """The repository paths ``text`` cites (``gnc/twin.py``, ``docs/fdir.md``)."""
    return {m.rstrip(".") for m in CITED.findall(text)}


def test_the_pattern_finds_citations() -> None:
    assert cited_paths("see ``gnc/twin.py`` and docs/fdir.md, not x/ground/y.py") == {
        "gnc/twin.py", "docs/fdir.md"}


def test_every_cited_path_exists() -> None:
    missing = sorted(f"{p.relative_to(REPO)} cites {c}" for p in _citing_files()
                     for c in cited_paths(p.read_text()) if not (REPO / c).exists())
    assert missing == []
