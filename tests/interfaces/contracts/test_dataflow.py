"""The dataflow (interfaces/contracts/dataflow.py) and the declarations it is drawn from
(interfaces/runtime/assembly.py): every declared input and output is an edge, every catalogued
topic that anything reads appears with its readers, the sim's and the executives' topics come
from the catalogue's publisher field, and the picture in docs/architecture.md is current."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from fsw.apps.guidance import GuidanceApp
from fsw.apps.nav import NavApp
from interfaces.contracts import catalogue as cat
from interfaces.contracts import dataflow
from interfaces.contracts.catalogue import Space, Topic
from interfaces.contracts.dataflow import Declared, End, Flow, Read, pattern
from interfaces.contracts.topology import main
from interfaces.runtime.assembly import app_class, declarations
from interfaces.runtime.executive import TickClient
from sim.node import SimNode
from tests.conftest import REPO

DOC = REPO / "docs" / "architecture.md"
REGENERATE = "python -m interfaces.contracts.topology --write-doc"


def _flows() -> tuple[Flow, ...]:
    return dataflow.graph(declarations())


def _flow(topic: Topic, flows: tuple[Flow, ...]) -> Flow:
    return next(f for f in flows if f.topic == topic)


def test_the_nav_estimate_goes_from_nav_to_guidance_as_they_declare() -> None:
    assert cat.NAV_ESTIMATE in {o.topic for o in NavApp.OUTPUTS}
    assert cat.NAV_ESTIMATE in {i.topic for i in GuidanceApp.INPUTS}
    flow = _flow(cat.NAV_ESTIMATE, _flows())
    assert flow.producers == (End("sc", "nav", "mid"),)
    assert End("sc", "guidance", "low") in flow.consumers
    assert "sc/{i}/nav/estimate: sc{i}.nav [mid] → " in str(flow)
    assert "sc{i}.guidance [low]" in str(flow)


def test_every_declared_input_and_output_is_an_edge() -> None:
    flows = _flows()
    for slot in dataflow.roster():
        app = app_class(slot.name)
        for o in app.OUTPUTS:
            assert End(slot.place, app.NAME, app.RATE, slot.when) in _flow(o.topic, flows).producers
        for i in app.INPUTS:
            readers = [(c.place, c.who, c.rate, c.when, c.every)
                       for c in _flow(i.topic, flows).consumers]
            assert (slot.place, app.NAME, app.RATE, slot.when, i.every_spacecraft) in readers


def _read_somewhere() -> set[Topic]:
    """Every topic something reads, gathered from the declarations here, not by the graph."""
    apps = [app_class(s.name) for s in dataflow.roster()]
    return ({i.topic for a in apps for i in a.INPUTS} | set(SimNode.SUBSCRIBES)
            | set(TickClient.SUBSCRIBES) | {cat.TRUTH})


def test_every_catalogued_topic_that_anything_reads_appears_with_its_readers() -> None:
    flows = _flows()
    text, picture = dataflow.edges(flows), dataflow.mermaid(flows)
    assert [f.topic for f in flows] == list(cat.ALL)
    for topic in _read_somewhere():
        flow = _flow(topic, flows)
        assert flow.producers and flow.consumers, topic
        assert str(flow) in text.splitlines()
        assert f"{topic.app}/{topic.name}" in picture
    unread = [f for f in flows if not f.consumers]
    assert {f.topic for f in unread}.isdisjoint(_read_somewhere())
    assert all(f"{pattern(f.topic)}: " in text and "(the recorder only)" in str(f) for f in unread)


def test_what_no_app_publishes_is_the_catalogues_and_the_sim_reads_its_declaration() -> None:
    flows = _flows()
    for f in flows:
        if f.topic.space in (Space.SIM, Space.SIM_HARDWARE):
            assert f.producers == (End("sim", "sim"),)
        elif f.topic.space is Space.EVERY_NODE:
            assert f.producers == (End("node", "executive"),)
    for topic in SimNode.SUBSCRIBES:
        assert End("sim", "sim", every=True) in _flow(topic, flows).consumers
    assert str(_flow(cat.THRUST, flows)) == "sc/{i}/act/thrust: sc{i}.guidance [low] → sim"


def test_optional_apps_are_drawn_and_marked() -> None:
    flows = _flows()
    picture = dataflow.mermaid(flows)
    for slot in dataflow.roster():
        if slot.when:
            name = app_class(slot.name).NAME
            assert f'sc_{name}["{name}<br/>' in picture and f"if {slot.when}" in picture
    assert '    sc_fdir -.->|"fdir/command"| sc_nav' in picture.splitlines()


def test_the_recorder_is_said_once_and_given_no_edge() -> None:
    flows = _flows()
    assert sum("recorder (" in line for line in dataflow.edges(flows).splitlines()) == 1
    arrows = [line for line in dataflow.mermaid(flows).splitlines() if "->" in line]
    assert arrows and not any(line.endswith("recorder") for line in arrows)


def test_keys_collapse_over_spacecraft_and_nodes() -> None:
    assert pattern(cat.NAV_ESTIMATE) == "sc/{i}/nav/estimate"
    assert pattern(cat.RELNAV) == "sim/sensors/sc{i}/relnav"
    assert pattern(cat.HEARTBEAT) == "{node}/exec/heartbeat"
    assert pattern(cat.TICK) == "sim/clock/tick"
    assert pattern(cat.ASSIGNMENTS) == "ground/planner/assignments"


def test_a_made_up_wiring_gives_its_edges() -> None:
    """The graph on declarations of its own: own key, every spacecraft's, optional, unread."""
    declared = (
        Declared("nav", "sc", "mid", writes=(cat.NAV_ESTIMATE,)),
        Declared("watch", "ground", "low", reads=(Read(cat.NAV_ESTIMATE, True),)),
        Declared("fdir", "sc", "high", reads=(Read(cat.NAV_ESTIMATE), Read(cat.HEARTBEAT)),
                 when="onboard_fdir"),
        Declared("executive", "node", writes=(cat.HEARTBEAT,)),
    )
    flows = dataflow.graph(declared)
    assert str(_flow(cat.NAV_ESTIMATE, flows)) == (
        "sc/{i}/nav/estimate: sc{i}.nav [mid] → ground.watch [low], sc{i}.fdir [high, if "
        "onboard_fdir]")
    assert str(_flow(cat.HEARTBEAT, flows)) == (
        "{node}/exec/heartbeat: {node}.executive → sc{i}.fdir [high, if onboard_fdir] "
        "(sc{i}'s own)")
    assert str(_flow(cat.TICK, flows)) == "sim/clock/tick: (no publisher) → (the recorder only)"
    arrows = dataflow.mermaid(flows).splitlines()
    assert '    sc_nav -->|"nav/estimate"| ground_watch' in arrows
    assert '    sc_nav -.->|"nav/estimate"| sc_fdir' in arrows


def test_the_pictures_block_in_the_architecture_doc_is_current() -> None:
    current = dataflow.doc_block(_flows())
    assert dataflow.block_of(DOC.read_text()) == current, f"stale: run {REGENERATE}"


def test_the_docs_sample_lines_are_lines_of_the_graph() -> None:
    lines = set(dataflow.edges(_flows()).splitlines())
    samples = [line for line in DOC.read_text().splitlines()
               if any(line.startswith(f"{pattern(t)}: ") for t in cat.ALL)]
    assert samples and [s for s in samples if s not in lines] == []


def test_a_changed_declaration_makes_the_doc_stale() -> None:
    """What the doc test compares can differ: guidance no longer reading the nav estimate."""
    def without_nav(d: Declared) -> Declared:
        kept = (r for r in d.reads if d.who != "guidance" or r.topic != cat.NAV_ESTIMATE)
        return replace(d, reads=tuple(kept))

    changed = dataflow.doc_block(dataflow.graph(map(without_nav, declarations())))
    assert changed != dataflow.block_of(DOC.read_text())
    assert 'sc_nav -->|"nav/estimate"| sc_guidance' not in changed


def test_the_block_is_spliced_between_its_markers() -> None:
    doc = f"# A\n\n{dataflow.BEGIN}\nold\n{dataflow.END}\n\ntail\n"
    new = dataflow.spliced(doc, "\nnew\n")
    assert dataflow.block_of(new) == "\nnew\n"
    assert new.startswith("# A\n\n") and new.endswith(f"{dataflow.END}\n\ntail\n")
    for broken in ("# no markers\n", doc + dataflow.BEGIN, f"{dataflow.END}\n{dataflow.BEGIN}"):
        with pytest.raises(ValueError, match="dataflow:begin"):
            dataflow.block_of(broken)


def test_the_command_prints_the_graph_and_rewrites_a_doc(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    main(["--graph"])
    assert "sc/{i}/nav/estimate: sc{i}.nav [mid] → " in capsys.readouterr().out
    main(["--mermaid"])
    assert capsys.readouterr().out == dataflow.doc_block(_flows())
    doc = tmp_path / "doc.md"
    doc.write_text(f"# Doc\n{dataflow.BEGIN}\n{dataflow.END}\n")
    main(["--write-doc"], doc=doc)
    assert "rewritten" in capsys.readouterr().out
    assert dataflow.block_of(doc.read_text()) == dataflow.doc_block(_flows())
    main(["--write-doc"], doc=doc)
    assert "already current" in capsys.readouterr().out
