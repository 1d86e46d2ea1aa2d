"""The topic catalogue: every kind of message on the bus, its key and its type, named once
(docs/architecture.md, "Key expressions").

A ``Topic`` is one ``(space, app, name, type)``.  Its *space* says whose key space it lives in
and so who may publish it:

- ``SPACECRAFT``: ``insp/<mission>/sc/<id>/<app>/<name>``, published by spacecraft ``<id>``;
- ``SIM`` / ``GROUND``: ``insp/<mission>/sim|ground/<app>/<name>``, one publisher;
- ``SIM_HARDWARE``: ``insp/<mission>/sim/<app>/sc<id>/<name>``, the sim standing in for the
  hardware of spacecraft ``<id>`` (its sensors);
- ``EVERY_NODE``: ``<node prefix>/<app>/<name>``, published by every lockstep node (the
  executive's lockstep answer and housekeeping).

Apps declare their inputs and outputs from these topics (``interfaces.runtime.app``), the sim and
the executive declare theirs (``PUBLISHES``), the bus refuses to publish a message of the wrong type
on a catalogued key, and ``tests/interfaces/contracts/test_catalogue.py`` checks that every input
has exactly one producer of its type.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Generic, TypeVar

from interfaces.contracts import messages as m
from interfaces.contracts import topics


class Space(enum.Enum):
    """Whose key space a topic lives in (see the module docstring)."""

    SPACECRAFT = "sc"
    SIM = "sim"
    GROUND = "ground"
    SIM_HARDWARE = "sim hardware"
    EVERY_NODE = "every node"


M = TypeVar("M", bound=m.Message)


@dataclass(frozen=True)
class Topic(Generic[M]):
    """One kind of message: ``type`` on the key ``app/name`` of the key space ``space``.
    ``bundled``: hardware traffic, which never passes the link stage and travels over Zenoh in
    its process's bundle of the tick (``interfaces.contracts.bundle``)."""

    space: Space
    app: str
    name: str
    type: type[M]
    doc: str = ""
    bundled: bool = False

    def key(self, mission: str, node: str | None = None) -> str:
        """The concrete key.  ``node`` is the publisher for SPACECRAFT and EVERY_NODE topics,
        the spacecraft (``"sc<id>"``) whose hardware it is for SIM_HARDWARE, and ignored for
        SIM and GROUND topics (one publisher, whoever asks)."""
        if self.space in (Space.SIM, Space.GROUND):
            return topics.key(mission, self.space.value, self.app, self.name)
        if node is None:
            raise ValueError(f"{self} needs a node")
        by_spacecraft = self.space in (Space.SPACECRAFT, Space.SIM_HARDWARE)
        if by_spacecraft and topics.spacecraft_of(node) is None:
            raise ValueError(f"{self} belongs to a spacecraft node ('sc<N>'), not {node!r}")
        if self.space is Space.SIM_HARDWARE:
            return topics.key(mission, topics.SIM, self.app, node, self.name)
        return topics.key(mission, node, self.app, self.name)

    def every(self, mission: str) -> str:
        """Key expression of this topic from every publisher (every spacecraft, every node)."""
        if self.space is Space.EVERY_NODE:
            return f"{topics.ROOT}/{mission}/**/{self.app}/{self.name}"
        if self.space in (Space.SIM, Space.GROUND):
            return self.key(mission)
        return self.every_spacecraft(mission)

    def any_mission(self) -> str:
        """Key expression of this topic from every publisher of any mission (tools reading an
        archive before they know its mission)."""
        return self.every("m").replace(f"{topics.ROOT}/m/", f"{topics.ROOT}/*/", 1)

    def every_spacecraft(self, mission: str) -> str:
        """Key expression of this topic for every spacecraft (for SIM_HARDWARE: every
        spacecraft's hardware)."""
        if self.space is Space.SIM_HARDWARE:
            return f"{topics.node_prefix(mission, topics.SIM)}/{self.app}/*/{self.name}"
        if self.space in (Space.SIM, Space.GROUND):
            raise ValueError(f"{self} is not per spacecraft")
        return topics.all_spacecraft(mission, self.app, self.name)

    @property
    def path(self) -> str:
        """``app/name``: the topic as the onboard stores and their accounting name it."""
        return f"{self.app}/{self.name}"

    def __str__(self) -> str:
        return f"{self.path} ({self.type.__name__})"


# --- the sim: time master, truth and hardware -------------------------------------------------
TICK = Topic(Space.SIM, "clock", "tick", m.Tick, "lockstep tick k (the sim is the time master)",
             bundled=True)
SIM_STATUS = Topic(Space.SIM, "clock", "status", m.SimStatus, "run state, progress, counters")
TRUTH = Topic(Space.SIM, "truth", "state", m.TruthState, "true states (channel model, evaluation)",
              bundled=True)
FAULT_EVENTS = Topic(Space.SIM, "truth", "faults", m.FaultEvent, "injected faults switching")
RELNAV = Topic(Space.SIM_HARDWARE, "sensors", "relnav", m.RelNavMeasurement,
               "relative navigation sensor", bundled=True)
ATTITUDE_SENSORS = Topic(Space.SIM_HARDWARE, "sensors", "attitude", m.AttitudeMeasurement,
                         "gyro and star tracker", bundled=True)
CAMERA_IMAGE = Topic(Space.SIM_HARDWARE, "sensors", "camera", m.CameraImage,
                     "the POIs in the camera's view, with their precisions", bundled=True)

# --- a spacecraft's flight software ---------------------------------------------------------
THRUST = Topic(Space.SPACECRAFT, "act", "thrust", m.ThrustCommand, "thruster command",
               bundled=True)
WHEELS = Topic(Space.SPACECRAFT, "act", "wheels", m.WheelCommand, "reaction-wheel torque",
               bundled=True)
NAV_ESTIMATE = Topic(Space.SPACECRAFT, "nav", "estimate", m.StateEstimate,
                     "relative state estimate")
ATTITUDE_ESTIMATE = Topic(Space.SPACECRAFT, "attitude", "estimate", m.AttitudeEstimate,
                          "attitude estimate and pointing status")
OBSERVATIONS = Topic(Space.SPACECRAFT, "camera", "observations", m.PoiObservations,
                     "the camera's POI observations, shared with the constellation")
POINTING = Topic(Space.SPACECRAFT, "camera", "pointing", m.PointingTarget,
                 "where the camera wants to look")
TRANSFER_PLAN = Topic(Space.SPACECRAFT, "guidance", "plan", m.TransferPlanMsg,
                      "planned transfer to the assigned PRO")
GUIDANCE_STATUS = Topic(Space.SPACECRAFT, "guidance", "status", m.GuidanceStatus,
                        "guidance mode, Δv spent, distance from plan")
INFO_COST = Topic(Space.SPACECRAFT, "infocost", "telemetry", m.InfoCostTelemetry,
                  "local information cost H_i (Eq. 8)")
FDIR_COMMAND = Topic(Space.SPACECRAFT, "fdir", "command", m.OnboardCommand,
                     "onboard FDIR stored-sequence command to its own apps")
FDIR_EVENT = Topic(Space.SPACECRAFT, "fdir", "event", m.OnboardFdirEvent,
                   "onboard FDIR events: trips, reports, sequences, recovery")
NEIGHBOUR_JUDGEMENT = Topic(Space.SPACECRAFT, "neighbours", "judgement", m.NeighbourJudgement,
                            "verdicts on the neighbours heard over an FDI window (Eq. 9)")
NEIGHBOUR_DECLARATION = Topic(Space.SPACECRAFT, "neighbours", "declaration",
                              m.NeighbourDeclaration, "a fault declared by neighbours' agreement")

# --- every lockstep node's executive --------------------------------------------------------
TICK_DONE = Topic(Space.EVERY_NODE, "exec", "tick_done", m.TickDone, "lockstep answer to a tick",
                  bundled=True)
HEARTBEAT = Topic(Space.EVERY_NODE, "exec", "heartbeat", m.Heartbeat, "node alive, its apps")
EXEC_STATS = Topic(Space.EVERY_NODE, "exec", "stats", m.ExecStats, "rate-group timing, errors")
LINK_STATS = Topic(Space.EVERY_NODE, "bus", "link_stats", m.LinkStats, "channel model counters")

# --- the ground -----------------------------------------------------------------------------
ASSIGNMENTS = Topic(Space.GROUND, "planner", "assignments", m.ProAssignments,
                    "PRO assignments (the uplink)")
DECISIONS = Topic(Space.GROUND, "planner", "decisions", m.AssignmentDecision,
                  "information-driven orbit decisions with their gains")
FDIR_WINDOW = Topic(Space.GROUND, "fdir", "window", m.FdirWindow, "one FDI window's evidence")
FAULT_REPORT = Topic(Space.GROUND, "fdir", "report", m.FaultReport, "declared faults")
CONSTELLATION_WINDOW = Topic(Space.GROUND, "fdir", "constellation", m.ConstellationWindow,
                             "the global check (Eq. 6) of one FDI window")
SCAN_STATUS = Topic(Space.GROUND, "fdir", "scan", m.ScanStatus,
                    "the sequential test's statistics per observer, as scored")
BASELINE = Topic(Space.GROUND, "fdir", "baseline", m.BaselineVerdict, "baseline detectors")
NEIGHBOUR_RULING = Topic(Space.GROUND, "fdir", "ruling", m.NeighbourRuling,
                         "the ground's ruling on a fault the neighbours declared")
TLM_STATUS = Topic(Space.GROUND, "tlm", "status", m.TelemetryStatus, "telemetry freshness")

ALL: tuple[Topic[m.Message], ...] = (
    TICK, SIM_STATUS, TRUTH, FAULT_EVENTS, RELNAV, ATTITUDE_SENSORS, CAMERA_IMAGE,
    THRUST, WHEELS, NAV_ESTIMATE, ATTITUDE_ESTIMATE, OBSERVATIONS, POINTING, TRANSFER_PLAN,
    GUIDANCE_STATUS, INFO_COST, FDIR_COMMAND, FDIR_EVENT, NEIGHBOUR_JUDGEMENT,
    NEIGHBOUR_DECLARATION,
    TICK_DONE, HEARTBEAT, EXEC_STATS, LINK_STATS,
    ASSIGNMENTS, DECISIONS, FDIR_WINDOW, FAULT_REPORT, CONSTELLATION_WINDOW, SCAN_STATUS,
    BASELINE, NEIGHBOUR_RULING, TLM_STATUS,
)


DOWNLINK_FIRST = (FDIR_EVENT, NEIGHBOUR_DECLARATION, INFO_COST, GUIDANCE_STATUS, TRANSFER_PLAN)
"""Dumped first in a pass, and kept longest in a full store: the onboard FDIR's events, the
neighbours' declarations, and the small telemetry the ground FDIR decides on (H_i, guidance,
plans)."""
DOWNLINK_FDIR = (NAV_ESTIMATE, ATTITUDE_ESTIMATE, OBSERVATIONS)
"""Dumped next: the rest of what the ground FDIR judges (the poses and the images)."""


FDIR_DOWNLINK_TOPICS = frozenset(t.path for t in (*DOWNLINK_FIRST, *DOWNLINK_FDIR))
"""``app/name`` of every topic the ground FDIR judges from the dump."""


def downlink_priority(key: str) -> int:
    """A spacecraft topic's priority in its onboard store and dump (0 first): 0 for
    ``DOWNLINK_FIRST``, 1 for ``DOWNLINK_FDIR``, 2 for the rest (housekeeping)."""
    topic = topic_of(key)
    if topic in DOWNLINK_FIRST:
        return 0
    return 1 if topic in DOWNLINK_FDIR else 2


def topic_of(key: str) -> Topic | None:
    """The catalogued topic of a concrete key, or of the ``every`` expression of a topic; None
    for a key outside the catalogue."""
    parts = key.split("/")
    if len(parts) < 5 or parts[0] != topics.ROOT:
        return None
    space, rest = parts[2], parts[3:]
    if space == "sc" and len(rest) == 3 and (rest[0].isdigit() or rest[0] == "*"):
        return _find((Space.SPACECRAFT, Space.EVERY_NODE), rest[1], rest[2])
    if space == topics.SIM and len(rest) == 3 and (rest[1] == "*" or topics.spacecraft_of(rest[1])):
        return _find((Space.SIM_HARDWARE,), rest[0], rest[2])
    if space in (topics.SIM, topics.GROUND, "**") and len(rest) == 2:
        spaces = (Space.EVERY_NODE,) if space == "**" else (Space(space), Space.EVERY_NODE)
        return _find(spaces, rest[0], rest[1])
    return None


def _find(spaces: tuple[Space, ...], app: str, name: str) -> Topic | None:
    return next((t for s in spaces if (t := _BY_PLACE.get((s, app, name))) is not None), None)


_BY_PLACE: Mapping[tuple[Space, str, str], Topic] = MappingProxyType(
    {(t.space, t.app, t.name): t for t in ALL})
"""Every topic by its place: (space, app, name)."""


def table() -> str:
    """The catalogue as a text table: key expression, message type, publisher, meaning."""
    who = {Space.SPACECRAFT: "each spacecraft", Space.SIM: "sim", Space.GROUND: "ground",
           Space.SIM_HARDWARE: "sim (per spacecraft)", Space.EVERY_NODE: "every node"}
    one = {Space.SIM_HARDWARE: "/sc<id>/", Space.SPACECRAFT: "/<id>/"}
    rows = [(t.every("M").replace("insp/M/", "insp/<m>/").replace("/*/", one.get(t.space, "")),
             t.type.__name__, who[t.space], t.doc) for t in ALL]
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    return "\n".join(f"{k:<{widths[0]}}  {ty:<{widths[1]}}  {w:<{widths[2]}}  {d}"
                     for k, ty, w, d in rows)


if __name__ == "__main__":
    print(table())
