"""The Foxglove layout of a run (harness/foxglove_layout.py): Foxglove's layout JSON, every
panel placed once, every message path a catalogued key of the mission with fields its message
has, the panels following the scenario, and the checker that names what an archive lacks.
Against a real archive: tests/missions/test_foxglove_layout_run.py."""

from __future__ import annotations

import copy
import json
import re
from pathlib import Path
from typing import Any

import pytest

from harness import foxglove_layout as fl
from harness import foxglove_scene as scene
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import json_schema
from interfaces.contracts.scenario import Scenario, load_scenario
from tests.conftest import REPO, small_scenario

M = "fox"
PASSES = load_scenario(REPO / "deploy" / "scenarios" / "passes.toml")
"""Five observers, ground passes, a thruster fault on observer 2."""
PLAIN = small_scenario(M, observers={"count": 3}, fdir={"detector": "window"})
"""Three observers heard continuously, no fault, judged by the window test alone."""
SEQUENTIAL = small_scenario(M, observers={"count": 3})
"""The same, judged by the sequential test (the default)."""

_TOKEN = re.compile(r"\.(\w+)|\[(-?\d+|:)\]|\{(\w+)==('[^']*'|-?\d+|true|false)\}")


def _resolve(schema: dict[str, Any], node: dict[str, Any]) -> dict[str, Any]:
    """A schema node with its reference followed and ``X | None`` taken as ``X``."""
    if "$ref" in node:
        return _resolve(schema, schema["$defs"][node["$ref"].rsplit("/", 1)[1]])
    if "anyOf" in node:
        return _resolve(schema, next(n for n in node["anyOf"] if n.get("type") != "null"))
    return node


def leaf_type(path: str, mission: str) -> str:
    """Walk a message path through its topic's JSON schema (catalogued type of the key); the
    JSON type it ends on.  A field the message lacks, a slice of a non-array or a filter on a
    field that is not there fails."""
    topic = fl.topic_of(path)
    kind = cat.topic_of(topic)
    assert kind is not None and topic.startswith(f"insp/{mission}/"), path
    schema = json_schema(kind.type)
    node, rest = _resolve(schema, schema), path[len(topic):]
    for m in _TOKEN.finditer(rest):
        name, index, field, value = m.groups()
        if name is not None:
            node = _resolve(schema, node["properties"][name])
        elif index is not None:
            assert node["type"] == "array", path
            node = _resolve(schema, node["items"])
        else:
            wanted = "string" if value.startswith("'") else ("boolean" if value in (
                "true", "false") else "integer")
            assert _resolve(schema, node["properties"][field])["type"] == wanted, path
    assert "".join(m.group(0) for m in _TOKEN.finditer(rest)) == rest, path
    return str(node.get("type", "object"))


def test_a_layout_is_foxglove_layout_json_with_each_panel_placed_once() -> None:
    doc = fl.layout(PASSES, M)
    assert json.loads(json.dumps(doc)) == doc
    assert set(doc) == {"configById", "globalVariables", "userNodes", "playbackConfig", "layout"}
    assert doc["layout"] == fl.ROOT and doc["playbackConfig"] == {"speed": 1.0}
    tabs = doc["configById"][fl.ROOT]["tabs"]
    assert [t["title"] for t in tabs] == ["FDIR", "LVLH", "Ground contact"]
    placed = [pid for t in tabs for pid in fl.leaves(t["layout"])]
    assert sorted(placed) == sorted(set(doc["configById"]) - {fl.ROOT})  # each once, no stray
    assert all(fl.panel_type(pid) in fl.PANEL_TYPES and "!" in pid for pid in doc["configById"])
    for t in tabs:
        _splits_add_up(t["layout"])
    (script,) = doc["userNodes"].values()
    assert set(script) == {"name", "sourceCode"}


def _splits_add_up(tree: fl.Mosaic) -> None:
    if isinstance(tree, dict):
        assert tree["direction"] in ("row", "column") and 0 < tree["splitPercentage"] < 100
        _splits_add_up(tree["first"])
        _splits_add_up(tree["second"])


@pytest.mark.parametrize("scenario", [PASSES, PLAIN, SEQUENTIAL],
                         ids=["passes", "plain", "sequential"])
def test_every_path_is_a_key_of_the_mission_with_fields_its_message_has(
        scenario: Scenario) -> None:
    doc = fl.layout(scenario, M)
    for pid, config in doc["configById"].items():
        for path in fl.panel_paths(pid, config):
            if path == scene.SCENE_TOPIC:
                continue
            leaf = leaf_type(path, M)
            if fl.panel_type(pid) == "Plot":
                assert leaf in ("number", "integer"), path
            elif fl.panel_type(pid) == "StateTransitions":
                assert leaf in ("boolean", "string"), path
            else:
                assert leaf == "object" and path == fl.topic_of(path), path


def test_the_walk_refuses_a_field_the_message_lacks() -> None:
    with pytest.raises(KeyError):
        leaf_type(f"{cat.FDIR_WINDOW.key(M)}{{spacecraft==1}}.metrik", M)
    with pytest.raises(AssertionError):
        leaf_type(f"{cat.FDIR_WINDOW.key(M)}{{spacecraft=='1'}}.metric", M)


def test_the_panels_follow_the_scenario() -> None:
    passes, plain = fl.layout(PASSES, M)["configById"], fl.layout(PLAIN, M)["configById"]
    assert sum(pid.startswith("Plot!metric-sc") for pid in passes) == 5
    assert sum(pid.startswith("Plot!track-sc") for pid in plain) == 3
    sequential = fl.layout(SEQUENTIAL, M)["configById"]  # the scan against c, per observer
    assert sum(pid.startswith("Plot!scan-sc") for pid in sequential) == 3
    assert not any(pid.startswith("Plot!scan-sc") for pid in plain)
    # passes: what waits aboard, and the pass table in the title (no topic carries it)
    assert "passes (AOS–LOS, s): mid 29–498, mid 5963–6367" in passes["Plot!aboard"][fl.TITLE]
    assert "Plot!aboard" not in plain
    # faults: injected rows only for the observers a fault acts on; none without faults
    labels = [p["label"] for p in passes["StateTransitions!faults"]["paths"]]
    assert [label for label in labels if "injected" in label] == ["sc2 injected (thruster_bias)"]
    assert [label for label in labels if "declared" in label] == [
        "constellation declared", *(f"sc{i} declared" for i in range(1, 6))]
    assert "RawMessages!fault-event" not in plain
    assert cat.FAULT_EVENTS.key(M) not in fl.layout_topics(fl.layout(PLAIN, M))
    late = PASSES.model_copy(update={"duration_s": 500.0})  # the fault starts at 520 s
    assert cat.FAULT_EVENTS.key(M) not in fl.layout_topics(fl.layout(late, M))


def test_missing_topics_names_what_an_archive_lacks() -> None:
    doc = fl.layout(PLAIN, M)
    held = fl.layout_topics(doc) | {cat.TICK.key(M)}  # an archive holds more than is shown
    assert fl.missing_topics(doc, held) == set()
    assert scene.SCENE_TOPIC not in fl.layout_topics(doc)  # the script's own, not the archive's
    assert cat.TRUTH.key(M) in fl.layout_topics(doc)  # the script's input is the archive's
    wrong = copy.deepcopy(doc)
    wrong["configById"]["Plot!H_i"]["paths"][0]["value"] = "insp/fox/sc/9/infocost/telemetry.h_i"
    assert fl.missing_topics(wrong, held) == {"insp/fox/sc/9/infocost/telemetry"}
    assert fl.missing_topics(fl.layout(PLAIN, "other"), held) == {
        t.replace("insp/fox/", "insp/other/") for t in fl.layout_topics(doc)}
    with pytest.raises(ValueError, match="unknown panel type"):
        fl.panel_paths("Map!x", {})


def test_topic_of_reads_bare_filtered_and_quoted_topics() -> None:
    assert fl.topic_of("insp/m/sc/1/nav/estimate.x[1]") == "insp/m/sc/1/nav/estimate"
    assert fl.topic_of("insp/m/ground/fdir/window{spacecraft==1}.metric") == \
        "insp/m/ground/fdir/window"
    assert fl.topic_of('"a b/\\"c\\"".x') == 'a b/"c"'
    assert fl.topic_of("/studio_script/insp/lvlh_scene") == "/studio_script/insp/lvlh_scene"


def test_write_layout_writes_it_beside_the_archive(tmp_path: Path) -> None:
    path = fl.write_layout(tmp_path, PLAIN)
    assert path == tmp_path / fl.LAYOUT_FILE == tmp_path / "run.foxglove.json"
    assert json.loads(path.read_text(encoding="utf-8")) == json.loads(json.dumps(
        fl.layout(PLAIN, PLAIN.name)))
