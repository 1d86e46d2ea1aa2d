"""The import rules of the house: the contracts import nothing else of the project; the runtime
imports only the contracts (and the link faults and contact windows its channel stage applies,
and the mission's constants it hands the apps); the shared GNC library (``gnc``) only the
contracts; fault injection (``faults``) the contracts and the library; none of them imports
flight, sim or ground code, and flight, sim and ground never import each other (imports inside
functions included: they are read from the source, not from what a run happens to load)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.conftest import REPO

PROJECT = ("interfaces", "gnc", "faults", "links", "fsw", "sim", "ground", "harness", "deploy",
           "benchmarks", "tests")


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


def _violations(room: str, allowed: tuple[str, ...], root: Path = REPO) -> list[str]:
    """Imports from the files of ``room`` (a package or module, dotted, under ``root``) outside
    the ``allowed`` prefixes."""
    bad = []
    base = root / room.replace(".", "/")
    module = base.with_suffix(".py")
    paths = [module] if module.is_file() else sorted(base.rglob("*.py"))
    assert paths, f"no source in {room}"
    for path in paths:
        for module in sorted(_imports(path)):
            if not any(module == a or module.startswith(a + ".") for a in allowed):
                bad.append(f"{path.relative_to(root)} imports {module}")
    return bad


RUNTIME_MAY = ("interfaces.contracts", "interfaces.runtime", "links", "faults.schedule",
               "gnc.mission", "gnc.passes")
"""The runtime's channel stage applies the link faults (``links/faults.py``) and the ground's
contact windows (``gnc/passes.py``), and an app's context carries the mission's constants
(``gnc/mission.py``)."""


def test_the_contracts_import_only_the_contracts() -> None:
    assert _violations("interfaces.contracts", ("interfaces.contracts",)) == []


def test_the_runtime_imports_only_the_contracts_itself_and_what_it_hands_on() -> None:
    assert _violations("interfaces.runtime", RUNTIME_MAY) == []


def test_the_gnc_library_imports_only_the_contracts_and_itself() -> None:
    assert _violations("gnc", ("interfaces.contracts", "gnc")) == []


def test_fault_injection_imports_only_the_contracts_the_library_and_itself() -> None:
    assert _violations("faults", ("interfaces.contracts", "gnc", "faults")) == []


def test_the_link_faults_import_no_library() -> None:
    """The channel stage of every process loads them: the contracts are all they need."""
    for room in ("links.faults", "faults.schedule"):
        assert _violations(room, ("interfaces.contracts", "faults", "links")) == []


@pytest.mark.parametrize("room", ["fsw", "sim", "ground"])
def test_flight_sim_and_ground_import_none_of_each_other(room: str) -> None:
    assert _violations(room, ("interfaces", "gnc", "faults", room)) == []


def test_the_rule_reader_sees_a_violation(tmp_path: Path) -> None:
    """The checker itself: an import of flight code inside a runtime function is reported."""
    room = tmp_path / "interfaces" / "runtime"
    room.mkdir(parents=True)
    probe = room / "probe.py"
    probe.write_text("def f() -> None:\n    from fsw.lib import mpc\n")
    where = probe.relative_to(tmp_path)
    assert _violations("interfaces.runtime", RUNTIME_MAY, root=tmp_path) == [
        f"{where} imports fsw.lib", f"{where} imports fsw.lib.mpc"]
