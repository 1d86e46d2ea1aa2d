"""The import rules of the house (docs/architecture.md, "Import rules"): every room stands on a
floor, and a room imports only rooms on the floors below its own, never one beside it or above
it; the runtime takes from the shared library only the mission's constants; and no module
imports itself round a cycle.  Imports inside functions included: they are read from the
source, not from what a run happens to load."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.conftest import REPO

PROJECT = ("interfaces", "gnc", "faults", "links", "fsw", "sim", "ground", "harness", "deploy",
           "benchmarks", "tests")

FLOORS: tuple[tuple[str, ...], ...] = (
    ("interfaces.contracts",),
    ("gnc",),
    ("interfaces.runtime", "links", "faults"),
    ("fsw", "sim", "ground"),
    ("harness",),
    ("deploy",),
    ("benchmarks", "tests"),
)
"""The rooms, ground floor first: the contracts every process agrees on; the shared GNC
library; the runtime every node runs on, the simulated radio and fault injection, which know
nothing of each other (the Bus calls the radio through the link stage the runtime declares);
flight, sim and ground, which never import each other; the experiment harness; the launcher;
then benchmarks and tests, which may import anything."""

NARROW = {("interfaces.runtime", "gnc"): ("gnc.mission",)}
"""Where a room takes only part of a room below: the runtime hands every app the mission's
constants (``gnc/mission.py``) and nothing else of the library."""


def _imports(path: Path) -> set[str]:
    """The project modules ``path`` imports, dotted (``from a.b import c`` gives ``a.b`` and
    ``a.b.c``: ``c`` may be a module)."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module)
            out.update(f"{node.module}.{a.name}" for a in node.names)
    return {m for m in out if m.split(".")[0] in PROJECT}


def _room(module: str) -> str | None:
    """The room a dotted module belongs to (the longest room name it starts with)."""
    rooms = sorted((r for floor in FLOORS for r in floor), key=len, reverse=True)
    return next((r for r in rooms if module == r or module.startswith(r + ".")), None)


def _floor(room: str) -> int:
    return next(i for i, floor in enumerate(FLOORS) if room in floor)


def _sources(room: str, root: Path) -> list[Path]:
    """The source files of ``room`` (dotted) under ``root``."""
    base = root / room.replace(".", "/")
    module = base.with_suffix(".py")
    return [module] if module.is_file() else sorted(base.rglob("*.py"))


def _allowed(room: str, module: str) -> bool:
    """Whether a file of ``room`` may import ``module``."""
    target = _room(module)
    if target is None or target == room:
        return True
    narrow = NARROW.get((room, target))
    if narrow is not None:
        return any(module == n or module.startswith(n + ".") for n in narrow)
    return _floor(target) < _floor(room)


def _violations(room: str, root: Path = REPO) -> list[str]:
    """The imports of ``room``'s files that break the floors."""
    paths = _sources(room, root)
    assert paths, f"no source in {room}"
    return [f"{path.relative_to(root)} imports {module}"
            for path in paths for module in sorted(_imports(path))
            if not _allowed(room, module)]


def _module_graph(root: Path) -> dict[str, set[str]]:
    """Every project module (dotted, packages by their own name) and the project modules it
    imports, under ``root``."""
    files = {}
    for top in PROJECT:
        for path in (root / top).rglob("*.py") if (root / top).is_dir() else ():
            name = ".".join(path.relative_to(root).with_suffix("").parts)
            files[name.removesuffix(".__init__")] = path
    return {m: {i for i in _imports(p) if i in files and i != m} for m, p in files.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected parts of ``graph`` with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            part = stack[stack.index(v):]
            del stack[stack.index(v):]
            if len(part) > 1:
                out.append(sorted(part))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


@pytest.mark.parametrize("room", [r for floor in FLOORS[:-1] for r in floor])
def test_a_room_imports_only_the_floors_below_it(room: str) -> None:
    assert _violations(room) == []


def test_no_module_imports_itself_round_a_cycle() -> None:
    assert _cycles(_module_graph(REPO)) == []


def test_the_rule_reader_sees_a_violation(tmp_path: Path) -> None:
    """The checker itself: an import of flight code inside a runtime function, the runtime
    reaching into the library past the mission's constants, and the radio importing the
    runtime beside it are reported."""
    room = tmp_path / "interfaces" / "runtime"
    room.mkdir(parents=True)
    probe = room / "probe.py"
    probe.write_text("def f() -> None:\n    from fsw.lib import mpc\n\nimport gnc.twin\n")
    radio = tmp_path / "links"
    radio.mkdir()
    sideways = radio / "probe.py"
    sideways.write_text("import interfaces.runtime.bus\n")
    where = probe.relative_to(tmp_path)
    assert _violations("interfaces.runtime", root=tmp_path) == [
        f"{where} imports fsw.lib", f"{where} imports fsw.lib.mpc", f"{where} imports gnc.twin"]
    assert _violations("links", root=tmp_path) == [
        f"{sideways.relative_to(tmp_path)} imports interfaces.runtime.bus"]


def test_the_cycle_reader_sees_a_cycle(tmp_path: Path) -> None:
    """The checker itself: two modules that import each other, one of them only for its
    types, are a cycle."""
    radio = tmp_path / "links"
    radio.mkdir()
    (radio / "a.py").write_text("from links.b import B\n")
    (radio / "b.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                                "    from links.a import A\n")
    assert _cycles(_module_graph(tmp_path)) == [["links.a", "links.b"]]
