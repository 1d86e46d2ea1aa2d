"""The Foxglove layout of a run, ``run.foxglove.json`` beside ``run.mcap``: import it in Foxglove
(Layouts, Import from file) with the archive open, and the run reads at once.

Built from the scenario alone (the observers, the mission's key prefix, ground passes or
not), it reads the archive's topics as they are, by Foxglove message paths
(``<key>{spacecraft==1}.metric``, ``<key>.links[:]{src=='sc1'}.delivered``); the archive is not
changed.  Three tabs:

- **FDIR**: H, the ground's information cost at each FDI window's start
  (``ground/fdir/constellation.cost``), and each H_i (``sc/<i>/infocost/telemetry.h_i``);
  per observer the metric H_m against its threshold τ (``ground/fdir/window``), and with
  ``fdir.detector = "sequential"`` the scan statistic against its threshold c; the faults
  injected (``sim/truth/faults``, when the scenario has any) and declared
  (``ground/fdir/report``), as state transitions and the latest of each in full.
- **LVLH**: the truth poses in the 3D panel (``harness.foxglove_scene``: a user script of the
  layout draws ``sim/truth/state``), the truth in full, and per observer its estimated track
  in the orbit plane (``sc/<i>/nav/estimate.x``: radial and cross-track against
  along-track, m).  Foxglove paths index no array of arrays, so the truth's positions
  (``r_lvlh_m``, one row per observer) plot nowhere but in the 3D panel.
- **Ground contact**: the telemetry the ground received from each observer
  (``ground/bus/link_stats``) and whether it is stale (``ground/tlm/status``); with ground
  passes, what waits aboard for the next pass, and the pass table (``gnc.passes``) in the
  panel's title, since no topic carries it (summary.json's ``ground_contact`` has it too).

The layout format is the one Foxglove exports (``configById``, ``layout``, ``globalVariables``,
``userNodes``, ``playbackConfig``).  ``ground/fdir/report`` is in an archive only once the
ground declared something: a run without a declaration leaves its panels empty.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, Final, Literal

from gnc.passes import scenario_pass_table
from harness import foxglove_scene as scene
from harness.destination import write_whole
from interfaces.contracts import catalogue as cat
from interfaces.contracts.scenario import Fault, Scenario
from interfaces.contracts.topics import GROUND, sc_node

LAYOUT_FILE: Final = "run.foxglove.json"
"""The layout's file name, beside ``run.mcap``."""

TITLE: Final = "foxglovePanelTitle"
"""Key of a panel's title in its configuration."""

ROOT: Final = "Tab!run"
"""The root panel: the tabs."""

PANEL_TYPES: Final = frozenset({"Tab", "Plot", "StateTransitions", "RawMessages", "3D"})
"""The Foxglove panel types the layout uses (a panel's id is ``<type>!<name>``)."""

METRIC_COLOUR, THRESHOLD_COLOUR = "#4e98e2", "#f5774d"
PASSES_IN_TITLE: Final = 6
"""At most this many passes are listed in a panel title (summary.json lists them all)."""

Mosaic = str | dict[str, Any]
"""A layout tree: a panel id, or a split ``{direction, first, second, splitPercentage}``."""
Panels = dict[str, dict[str, Any]]
"""Panel configurations by panel id."""


def layout(scenario: Scenario, mission: str) -> dict[str, Any]:
    """The Foxglove layout of a run of ``scenario`` whose keys start ``insp/<mission>/``."""
    tabs = [_fdir_tab(scenario, mission), _lvlh_tab(scenario, mission),
            _contact_tab(scenario, mission)]
    panels: Panels = {ROOT: {"activeTabIdx": 0,
                             "tabs": [{"title": title, "layout": tree}
                                      for title, tree, _ in tabs]}}
    for _, _, configs in tabs:
        panels.update(configs)
    return {"configById": panels, "globalVariables": {},
            "userNodes": {scene.SCRIPT_ID: scene.user_script(scenario, mission)},
            "playbackConfig": {"speed": 1.0}, "layout": ROOT}


def write_layout(out: Path, scenario: Scenario, mission: str | None = None) -> Path:
    """Write ``<out>/run.foxglove.json`` (``mission``: the key prefix, the scenario's name by
    default); returns its path."""
    path = out / LAYOUT_FILE
    doc = layout(scenario, mission or scenario.name)
    write_whole(path, json.dumps(doc, indent=1, ensure_ascii=False) + "\n")
    return path


# --- the tabs: (title, tree, panels) ---------------------------------------------------------

Tab = tuple[str, Mosaic, Panels]


def _observers(scenario: Scenario) -> range:
    return range(1, scenario.observers.count + 1)


def _faults_in_run(scenario: Scenario) -> list[Fault]:
    """The scenario's faults that start before the run ends (``sim/truth/faults`` has an
    event of each)."""
    return [f for f in scenario.faults if f.start_s < scenario.duration_s]


def _fdir_tab(scenario: Scenario, mission: str) -> Tab:
    info: Panels = {"Plot!H": _plot("H, the ground's information cost at each window start",
                                    [_series(f"{cat.CONSTELLATION_WINDOW.key(mission)}.cost",
                                             "H")]),
                    "Plot!H_i": _plot("H_i per observer (Eq. 8)", [
                        _series(f"{cat.INFO_COST.key(mission, sc_node(i))}.h_i", f"H_{i}",
                                _colour(i)) for i in _observers(scenario)])}
    metric = {f"Plot!metric-sc{i}": _metric_plot(mission, i) for i in _observers(scenario)}
    scan = ({f"Plot!scan-sc{i}": _scan_plot(mission, i) for i in _observers(scenario)}
            if scenario.fdir.detector == "sequential" else {})
    faults = _fault_panels(scenario, mission)
    tree = _split([_split(list(info), "column"),
                   *(_split(list(panels), "column") for panels in (metric, scan) if panels),
                   _split(list(faults), "column")], "row")
    return "FDIR", tree, {**info, **metric, **scan, **faults}


def _metric_plot(mission: str, i: int) -> dict[str, Any]:
    window = f"{cat.FDIR_WINDOW.key(mission)}{{spacecraft=={i}}}"
    return _plot(f"sc{i}: metric H_m against its threshold τ (Eq. 9)",
                 [_series(f"{window}.metric", "H_m", METRIC_COLOUR),
                  _series(f"{window}.threshold", "τ", THRESHOLD_COLOUR)])


def _scan_plot(mission: str, i: int) -> dict[str, Any]:
    scan = f"{cat.SCAN_STATUS.key(mission)}{{spacecraft=={i}}}"
    return _plot(f"sc{i}: the sequential test's scan statistics as they are scored "
                 f"(images, NIS) against their thresholds",
                 [_series(f"{scan}.image_z", "images: max_n |Z_n|", METRIC_COLOUR),
                  _series(f"{scan}.image_threshold", "c", THRESHOLD_COLOUR),
                  _series(f"{scan}.nis_z", "NIS: max_n z_n"),
                  _series(f"{scan}.nis_threshold", "c NIS")])


def _fault_panels(scenario: Scenario, mission: str) -> Panels:
    report = cat.FAULT_REPORT.key(mission)
    panels: Panels = {"StateTransitions!faults": _fault_states(scenario, mission)}
    if _faults_in_run(scenario):
        panels["RawMessages!fault-event"] = _raw("The latest fault event (injected)",
                                                  cat.FAULT_EVENTS.key(mission))
    panels["RawMessages!fault-report"] = _raw("The latest fault report (declared)", report)
    return panels


def _fault_states(scenario: Scenario, mission: str) -> dict[str, Any]:
    """Per observer (0: the constellation): its injected faults on or off, and the class of
    each declaration (its value changes at each report)."""
    faults = _faults_in_run(scenario)
    report, events = cat.FAULT_REPORT.key(mission), cat.FAULT_EVENTS.key(mission)
    paths = []
    for i in [0, *_observers(scenario)]:
        name = f"sc{i}" if i else "constellation"
        kinds = ", ".join(sorted({f.kind for f in faults if f.spacecraft == i}))
        if kinds:
            paths.append(_series(f"{events}{{spacecraft=={i}}}.active",
                                 f"{name} injected ({kinds})"))
        paths.append(_series(f"{report}{{spacecraft=={i}}}.fault_class", f"{name} declared"))
    return {TITLE: "Faults injected (sim truth) and declared (ground FDIR)", "paths": paths,
            "isSynced": True, "showPoints": True}


def _lvlh_tab(scenario: Scenario, mission: str) -> Tab:
    view: Panels = {"3D!lvlh": scene.panel(scenario),
                    "RawMessages!truth": _raw("Truth (sim): positions in LVLH, m",
                                              cat.TRUTH.key(mission))}
    tracks = {f"Plot!track-sc{i}": _track_plot(mission, i) for i in _observers(scenario)}
    tree = _split([{"direction": "column", "first": "3D!lvlh", "second": "RawMessages!truth",
                    "splitPercentage": 70.0}, _split(list(tracks), "column")], "row")
    return "LVLH", tree, {**view, **tracks}


def _track_plot(mission: str, i: int) -> dict[str, Any]:
    nav = cat.NAV_ESTIMATE.key(mission, sc_node(i))
    return _plot(f"sc{i}: estimated track, radial and cross-track against along-track, m",
                 [_series(f"{nav}.x[0]", "x radial (R-bar)", _colour(i)),
                  _series(f"{nav}.x[2]", "z cross-track", THRESHOLD_COLOUR)],
                 x_path=f"{nav}.x[1]")


def _contact_tab(scenario: Scenario, mission: str) -> Tab:
    links, tlm = cat.LINK_STATS.key(mission, GROUND), cat.TLM_STATUS.key(mission)
    passes = scenario.ground.contact == "passes"
    panels: Panels = {"Plot!delivered": _plot(
        "Telemetry delivered to the ground, per observer (messages)",
        [_series(f"{links}.links[:]{{src=='{sc_node(i)}'}}.delivered", sc_node(i), _colour(i))
         for i in _observers(scenario)])}
    if passes:
        panels["Plot!aboard"] = _plot(
            "Stored aboard for the next pass, per observer (messages)" + _pass_table(scenario),
            [_series(f"{links}.links[:]{{src=='{sc_node(i)}'}}.store.onboard", sc_node(i),
                     _colour(i)) for i in _observers(scenario)])
    panels["StateTransitions!stale"] = {
        TITLE: "Telemetry stale on the ground (out of contact, or lost)", "isSynced": True,
        "showPoints": False,
        "paths": [_series(f"{tlm}.entries[:]{{spacecraft=={i}}}.stale", sc_node(i))
                  for i in _observers(scenario)]}
    return "Ground contact", _split(list(panels), "column"), panels


def _pass_table(scenario: Scenario) -> str:
    """`` — passes (AOS–LOS, s): mid 29–498, ...`` for a scenario with ground passes."""
    if scenario.ground.contact != "passes":
        return ""
    table = scenario_pass_table(scenario)
    shown = [f"{w.station} {w.aos_s:.0f}–{w.los_s:.0f}" for w in table[:PASSES_IN_TITLE]]
    more = f", … ({len(table)} passes)" if len(table) > PASSES_IN_TITLE else ""
    return f" — passes (AOS–LOS, s): {', '.join(shown) or 'none'}{more}"


# --- panels ----------------------------------------------------------------------------------

def _colour(i: int) -> str:
    return scene.OBSERVER_COLOURS[(i - 1) % len(scene.OBSERVER_COLOURS)]


def _series(path: str, label: str, colour: str | None = None) -> dict[str, Any]:
    s: dict[str, Any] = {"value": path, "enabled": True, "timestampMethod": "receiveTime",
                         "label": label}
    if colour is not None:
        s["color"] = colour
    return s


def _plot(title: str, series: list[dict[str, Any]], x_path: str | None = None
          ) -> dict[str, Any]:
    """A Plot panel: the series against time (log time = sim time, s), or against the values of
    ``x_path`` (paired message by message)."""
    config: dict[str, Any] = {
        TITLE: title, "paths": series, "showLegend": True, "legendDisplay": "top",
        "showPlotValuesInLegend": False, "showXAxisLabels": True, "showYAxisLabels": True,
        "isSynced": x_path is None, "xAxisVal": "timestamp", "sidebarDimension": 240}
    if x_path is not None:
        config.update(xAxisVal="custom", xAxisPath={"value": x_path, "enabled": True})
    return config


def _raw(title: str, topic: str) -> dict[str, Any]:
    return {TITLE: title, "topicPath": topic, "diffEnabled": False, "diffMethod": "custom",
            "diffTopicPath": "", "showFullMessageForDiff": False, "expansion": "all"}


def _split(nodes: Sequence[Mosaic], direction: Literal["row", "column"]) -> Mosaic:
    """``nodes`` side by side (``row``) or stacked (``column``), in equal shares."""
    if len(nodes) == 1:
        return nodes[0]
    half = len(nodes) // 2
    return {"direction": direction, "first": _split(nodes[:half], direction),
            "second": _split(nodes[half:], direction),
            "splitPercentage": round(100.0 * half / len(nodes), 3)}


# --- reading a layout back: its panels, message paths and topics ----------------------------

_TOPIC = re.compile(r'"((?:[^"\\]|\\.)*)"|([A-Za-z0-9_\-/]+)')
_INPUTS = re.compile(r"^export const inputs = (\[.*\]);$", re.MULTILINE)
_OUTPUT = re.compile(r"^export const output = (\".*\");$", re.MULTILINE)


def panel_type(panel_id: str) -> str:
    """The panel type of a panel id ``<type>!<name>``."""
    return panel_id.split("!", 1)[0]


def leaves(tree: Mosaic) -> list[str]:
    """The panel ids of a layout tree, first to last."""
    if isinstance(tree, str):
        return [tree]
    return [*leaves(tree["first"]), *leaves(tree["second"])]


def panel_paths(panel_id: str, config: dict[str, Any]) -> list[str]:
    """The message paths (or bare topics) a panel reads; a numeric Plot series is a reference
    line, no path.  An unknown panel type is an error."""
    kind = panel_type(panel_id)
    if kind not in PANEL_TYPES:
        raise ValueError(f"unknown panel type {kind!r} ({panel_id})")
    if kind in ("Plot", "StateTransitions"):
        values = [p["value"] for p in config["paths"]]
        if config.get("xAxisVal") in ("custom", "currentCustom"):
            values.append(config["xAxisPath"]["value"])
        return [v for v in values if not _is_number(v)]
    if kind == "RawMessages":
        return [p for p in (config["topicPath"], config.get("diffTopicPath", "")) if p]
    if kind == "3D":
        return list(config.get("topics", {}))
    return []


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def topic_of(path: str) -> str:
    """The topic a message path reads: ``insp/m/ground/fdir/window{spacecraft==1}.metric`` →
    ``insp/m/ground/fdir/window`` (a quoted topic name unquoted)."""
    m = _TOPIC.match(path)
    if m is None or not m.group(0):
        raise ValueError(f"no topic in message path {path!r}")
    quoted = m.group(1)
    return re.sub(r"\\(.)", r"\1", quoted) if quoted is not None else m.group(2)


def script_topics(doc: dict[str, Any]) -> tuple[set[str], set[str]]:
    """The topics the layout's user scripts read, and those they write."""
    inputs: set[str] = set()
    outputs: set[str] = set()
    for script in doc.get("userNodes", {}).values():
        source = script["sourceCode"]
        found_in, found_out = _INPUTS.search(source), _OUTPUT.search(source)
        if found_in is None or found_out is None:
            raise ValueError(f"user script {script.get('name')!r} has no inputs or output")
        inputs.update(json.loads(found_in.group(1)))
        outputs.add(json.loads(found_out.group(1)))
    return inputs, outputs


def message_paths(doc: dict[str, Any]) -> list[str]:
    """Every message path of every panel, in panel order."""
    return [p for pid, config in doc["configById"].items() for p in panel_paths(pid, config)]


def layout_topics(doc: dict[str, Any]) -> set[str]:
    """The archive topics the layout reads: its panels' topics and its user scripts' inputs,
    less the topics the scripts write."""
    inputs, outputs = script_topics(doc)
    return ({topic_of(p) for p in message_paths(doc)} - outputs) | inputs


def missing_topics(doc: dict[str, Any], topics: Iterable[str]) -> set[str]:
    """The topics the layout reads that are not among ``topics`` (an archive's)."""
    return layout_topics(doc) - set(topics)
