"""The Foxglove layout written by real runs (harness/foxglove_layout.py): a campaign's run and a
launcher run with ground passes each leave ``run.foxglove.json`` beside ``run.mcap``, every
topic it reads is one the archive holds, and every series it plots finds values there."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from deploy.campaign import RunSpec, execute_run
from deploy.run_constellation import main
from harness import foxglove_layout as fl
from harness.archive.reader import load_run
from interfaces.contracts import catalogue as cat
from interfaces.contracts.scenario import Scenario, load_scenario
from tests.conftest import REPO, write_scenario

_TOKEN = re.compile(r"\.(\w+)|\[(-?\d+|:)\]|\{(\w+)==('[^']*'|-?\d+)\}")


def _scenario(base: str, name: str) -> Scenario:
    """Three observers of ``base`` for 200 s, observer 2 reporting twice its H_i from the
    start: the ground declares it within the run (at 140 s)."""
    data = load_scenario(REPO / "deploy" / "scenarios" / f"{base}.toml").model_dump()
    data.update(name=name, duration_s=200.0, observers={**data["observers"], "count": 3},
                rates={**data["rates"], "fdi_period_s": 20.0},
                target={**data["target"], "pois": 1000}, neighbours={"enabled": False},
                faults=[{"spacecraft": 2, "kind": "faulty_data", "start_s": 0.0,
                         "magnitude": 2.0}])
    return Scenario.model_validate(data)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, str]]:
    """{kind: (run directory, mission)}: a campaign run heard continuously, and a launcher
    run (in-process) with ground passes under a mission name of its own."""
    out = tmp_path_factory.mktemp("foxglove")
    spec = RunSpec("fox", "fox", _scenario("nominal", "fox"))
    assert execute_run(spec, str(out))["status"] == "completed"
    passes = write_scenario(out / "passes.toml", _scenario("passes", "foxpass"))
    assert main(["--scenario", str(passes), "--out", str(out / "passes"), "--transport",
                 "inproc", "--mission", "fox-7", "--no-report"]) == 0
    return {"campaign": (out / "runs" / "fox", "fox"), "passes": (out / "passes", "fox-7")}


@pytest.mark.parametrize("kind", ["campaign", "passes"])
def test_every_topic_the_layout_reads_is_in_the_archive(
        runs: dict[str, tuple[Path, str]], kind: str) -> None:
    run, mission = runs[kind]
    doc = json.loads((run / fl.LAYOUT_FILE).read_text(encoding="utf-8"))
    archive = set(load_run(run / "run.mcap").topics())
    assert fl.layout_topics(doc) and fl.missing_topics(doc, archive) == set()
    assert cat.FAULT_REPORT.key(mission) in fl.layout_topics(doc)  # declared in the run
    assert ("Plot!aboard" in doc["configById"]) == (kind == "passes")
    wrong = f"insp/{mission}/sc/4/nav/estimate"  # three observers: no sc4
    doc["configById"]["Plot!track-sc1"]["xAxisPath"]["value"] = f"{wrong}.x[1]"
    assert fl.missing_topics(doc, archive) == {wrong}


@pytest.mark.parametrize("kind", ["campaign", "passes"])
def test_every_series_finds_values_in_the_archive(
        runs: dict[str, tuple[Path, str]], kind: str) -> None:
    run, mission = runs[kind]
    doc = json.loads((run / fl.LAYOUT_FILE).read_text(encoding="utf-8"))
    archive = load_run(run / "run.mcap")
    declared = {"constellation declared", "sc1 declared", "sc3 declared"}  # nothing to show
    for pid, config in doc["configById"].items():
        if fl.panel_type(pid) not in ("Plot", "StateTransitions"):
            continue
        series = [(p["value"], p["label"]) for p in config["paths"]]
        if "xAxisPath" in config:
            series.append((config["xAxisPath"]["value"], "x"))
        for path, label in series:
            messages = archive.messages(fl.topic_of(path))
            values = [v for m in messages for v in _values(path, m.model_dump(mode="json"))]
            kinds = {type(v) for v in values if v is not None}
            if label in declared:
                assert not values, (path, values)
            elif fl.panel_type(pid) == "Plot":
                assert kinds and kinds <= {int, float}, (path, kinds)
            else:
                assert kinds and kinds <= {bool, str}, (path, kinds)
    report = archive.messages(cat.FAULT_REPORT.key(mission))
    assert [r.spacecraft for r in report] and {r.spacecraft for r in report} == {2}


def _values(path: str, message: dict[str, Any]) -> list[Any]:
    """What a message path reads from one message (Foxglove's names, slices and equality
    filters, enough for the layout's paths)."""
    found: list[Any] = [message]
    rest = path[len(fl.topic_of(path)):]
    for name, index, field, value in (m.groups() for m in _TOKEN.finditer(rest)):
        if name is not None:
            found = [f[name] for f in found if isinstance(f, dict) and name in f]
        elif index == ":":
            found = [x for f in found for x in f]
        elif index is not None:
            found = [f[int(index)] for f in found]
        else:
            want = value.strip("'") if value.startswith("'") else int(value)
            found = [f for f in found if f.get(field) == want]
    return found
