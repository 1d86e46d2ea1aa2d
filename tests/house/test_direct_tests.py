"""Every module of the project has a test that imports it directly, or a stated reason why not.

Read from the source (imports inside functions included): the modules of interfaces, gnc,
faults, fsw, sim, ground and deploy that no test module imports by name.  Each is in
``INDIRECT`` with the reason -- most often the public module or the process through which
another test exercises it.  A module that gains a direct test, or leaves the project, leaves
the table; a new module without a test must come with one or with its reason here
(``python -m tests.house.test_direct_tests`` prints the table as it stands)."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.conftest import REPO
from tests.house.test_import_rules import _imports

PACKAGES = ("interfaces", "gnc", "faults", "links", "fsw", "sim", "ground", "harness", "deploy")

_PART = "a part of a package that re-exports every name it holds; tests import them from {}"
_MESSAGES = _PART.format(
    "interfaces.contracts.messages (tests/interfaces/contracts/test_messages.py, "
    "tests/interfaces/runtime/test_encoding.py)")
_SCENARIO = _PART.format(
    "interfaces.contracts.scenario (tests/interfaces/contracts/test_scenario.py)")
_SUMMARY = _PART.format("harness.summary, the type of summary.json")
_NODE_MAIN = ("a node process's entry point (``python -m``): the launcher starts it in "
              "tests/missions/test_constellation.py")
_APP = ("a ground app, built by name from the topology: fuzzed with every other app in "
        "tests/interfaces/runtime/test_fuzz_apps.py and flown in tests/missions/; its logic is "
        "tested where it lives ({})")
_EVALUATION = ("a section of summary.json, its record type (re-exported by harness.summary) "
               "beside its evaluation from the archive (assembled by "
               "harness/summary/build.py): checked on real runs in {}")

INDIRECT: dict[str, str] = {
    "interfaces.contracts.messages.base": _MESSAGES,
    "interfaces.contracts.messages.fsw": _MESSAGES,
    "interfaces.contracts.messages.ground": _MESSAGES,
    "interfaces.contracts.messages.lockstep": _MESSAGES,
    "interfaces.contracts.messages.sim": _MESSAGES,
    **{f"interfaces.contracts.scenario.{m}": _SCENARIO
       for m in ("base", "comms", "faults", "fdir", "flight", "ground", "mission",
                 "neighbours", "observers", "onboard", "planning", "rates", "sim")},
    "interfaces.contracts.timing": (
        "one constant, TIME_TOL_S: a fault switching on the tick at its time whatever the "
        "rounding tests it (tests/faults/test_schedule.py, tests/faults/test_software.py)"),
    "gnc.attitude_gains": (
        "the gain design the flight tracking law re-exports (fsw/lib/attitude_control.py): "
        "tests/fsw/lib/test_attitude.py checks it against the closed loop's response"),
    "fsw.spacecraft": (
        "a spacecraft's executive, built by name from the topology: "
        "tests/interfaces/contracts/test_topology.py runs its apps and its software-fault hook"),
    "sim.__main__": _NODE_MAIN,
    "sim.kernels": (
        "the compiled integrators behind sim/actuators.py, sim/attitude.py, sim/dynamics.py and "
        "sim/hardware.py: tests/sim/test_kernels.py compares them with those classes' numpy "
        "references"),
    "ground.__main__": _NODE_MAIN,
    "harness.summary.coverage": _EVALUATION.format(
        "tests/missions/test_digest_run.py and tests/missions/test_campaign_run.py"),
    "harness.summary.control": _EVALUATION.format("tests/missions/test_gnc_run.py"),
    "harness.summary.onboard": _EVALUATION.format("tests/missions/test_onboard_fdir_run.py"),
    **{f"harness.summary.{m}": _SUMMARY
       for m in ("access", "document", "fault_events", "recovery", "records",
                 "series")},
    "harness.archive.__main__": (
        "``python -m harness.archive``, two lines handing over to harness/archive/cli.py's main "
        "(tests/harness/archive/test_cli.py, tests/missions/test_archive_cli_run.py)"),
    "ground.archive.record": (
        "the recorder process (``python -m ground.archive.record``): the launcher starts it, "
        "tests/missions/test_constellation.py kills it mid-run"),
    "ground.fdir.pipeline": (
        "the FDIR's stages in their order, driven by the FDIR app: "
        "tests/ground/apps/test_fdir.py feeds it message by message, "
        "tests/ground/fdir/test_stages.py tests each stage"),
    "harness.report_head": (
        "the opening of report.md (verdict, settings, status), written by "
        "harness/report.py's write_report: tests/harness/test_report.py reads it in a real "
        "report"),
    "harness.summary.declaring": (
        "which test declared each report, filled into summary.json's detections by "
        "harness/summary/fdir.py: tests/harness/summary/test_verdict.py and "
        "tests/harness/test_report.py read it from summaries"),
}
"""Module -> why no test imports it directly (and which test exercises it)."""


def project_modules(root: Path = REPO) -> list[str]:
    """The dotted modules of the packages under ``root``; a package's ``__init__`` only when it
    holds more than a docstring."""
    out = []
    for top in PACKAGES:
        for path in sorted((root / top).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                body = ast.parse(path.read_text()).body
                if all(isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant)
                       for n in body):
                    continue
                parts.pop()
            out.append(".".join(parts))
    return out


def imported_by_tests(root: Path = REPO) -> set[str]:
    """Every project module a test file imports by name (``from a.b import c`` gives ``a.b``
    and ``a.b.c``)."""
    return {m for p in (root / "tests").rglob("*.py") if "__pycache__" not in p.parts
            for m in _imports(p)}


def without_direct_test(root: Path = REPO) -> list[str]:
    tested = imported_by_tests(root)
    return [m for m in project_modules(root) if m not in tested]


def test_every_module_has_a_direct_test_or_a_reason() -> None:
    untested = without_direct_test()
    assert [m for m in untested if m not in INDIRECT] == [], "add a test or a reason"
    assert [m for m in INDIRECT if m not in untested] == [], "tested directly now, or gone"


def test_the_reader_finds_a_module_without_test(tmp_path: Path) -> None:
    """The checker itself: a module imported only inside a test function counts; a module no
    test names, or an empty package ``__init__``, does not."""
    for where, text in ((("gnc", "__init__.py"), '"""The library."""\n'), (("gnc", "a.py"), ""),
                        (("gnc", "b.py"), ""), (("sim", "__init__.py"), "X = 1\n"),
                        (("tests", "test_a.py"), "def test_a() -> None:\n    from gnc import a\n")):
        path = tmp_path.joinpath(*where)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    for top in PACKAGES:
        (tmp_path / top).mkdir(exist_ok=True)
    assert without_direct_test(tmp_path) == ["gnc.b", "sim"]


if __name__ == "__main__":  # python -m tests.house.test_direct_tests: the table as it stands
    for module in without_direct_test():
        print(f"{module:42} {INDIRECT.get(module, 'NO TEST AND NO REASON')}")
