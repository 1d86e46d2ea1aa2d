"""Mission runs sit apart: a test that flies a mission or starts processes lives in
tests/missions/, whose conftest marks every test there ``mission``, so that
``python -m pytest -m "not mission"`` runs the unit tests alone.

Read from the source (inside functions too): outside tests/missions/ no test module imports
what starts processes (``subprocess``, ``multiprocessing``, the launcher and its supervisor, a
Dask cluster) nor calls what flies a run (``run_inproc``, the shared ``recorded_run``) or
starts a process (``dask_cluster``, ``RecorderProcess``).  A monkeypatched ``run_inproc`` is
not a call, and a campaign refused before it runs is not a run: what a file cannot show, the
unit-only time does."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.conftest import REPO

MISSIONS = REPO / "tests" / "missions"

STARTS_PROCESSES = ("subprocess", "multiprocessing", "concurrent.futures.process", "distributed",
                    "deploy.run_constellation", "deploy.processes")
"""Modules whose import means processes (or a launcher that starts them)."""

FLIES = frozenset({"run_inproc", "recorded_run", "dask_cluster", "RecorderProcess",
                   "ProcessPoolExecutor", "Popen"})
"""Callables that fly a run or start a process, by name (a call of ``x.name`` counts too)."""

def mission_code(path: Path) -> list[str]:
    """What in ``path`` flies a run or starts processes: ``line: what``, in line order."""
    found: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        modules: list[str] = []
        if isinstance(node, ast.Import):
            modules = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            modules = [node.module, *(f"{node.module}.{a.name}" for a in node.names)]
        for m in modules:
            if any(m == s or m.startswith(s + ".") for s in STARTS_PROCESSES):
                found.append((node.lineno, f"imports {m}"))
        if isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(
                f, ast.Attribute) else None
            if name in FLIES:
                found.append((node.lineno, f"calls {name}"))
    return [f"{line}: {what}" for line, what in sorted(found)]


def _unit_test_files() -> list[Path]:
    return sorted(p for p in (REPO / "tests").rglob("test_*.py")
                  if MISSIONS not in p.parents and "__pycache__" not in p.parts)


def test_no_unit_test_flies_a_mission_or_starts_a_process() -> None:
    files = _unit_test_files()
    assert len(files) > 50
    found = [f"{p.relative_to(REPO)}:{what}" for p in files for what in mission_code(p)]
    assert found == [], "move these tests to tests/missions/"


def test_the_reader_sees_runs_and_processes(tmp_path: Path) -> None:
    """The checker itself: a run in a fixture, a subprocess inside a function and a Dask
    cluster are found; a monkeypatched runner is not a run."""
    probe = tmp_path / "test_probe.py"
    probe.write_text(
        "import deploy.inproc\n"
        "from tests.conftest import dask_cluster\n\n"
        "def live():\n    return deploy.inproc.run_inproc(None)\n\n"
        "def test_x(monkeypatch):\n"
        "    import subprocess\n"
        "    monkeypatch.setattr(deploy.inproc, 'run_inproc', None)\n"
        "    with dask_cluster():\n        pass\n")
    assert mission_code(probe) == ["5: calls run_inproc", "8: imports subprocess",
                                   "10: calls dask_cluster"]


def test_every_mission_is_marked(request: pytest.FixtureRequest) -> None:
    """The folder's conftest marks what it collects: of the tests this session runs, those of
    tests/missions/ are missions and no other is (in a whole run, every test is checked)."""
    items = request.session.items
    for item in items:
        inside = MISSIONS in Path(item.path).parents
        assert (item.get_closest_marker("mission") is not None) == inside, item.nodeid
