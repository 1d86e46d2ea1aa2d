"""Message models exchanged on the bus (pydantic v2, JSON on the wire).

Every message carries the sender node (``"sim"``, ``"ground"``, ``"sc<N>"``), a sequence
number that the Bus assigns per key expression on publish (like a CCSDS packet sequence
count per APID), and the simulation time ``t_sim`` in seconds.  ``t_wall`` is the publisher's
wall-clock time (UNIX seconds) and is the only field that differs between two runs of the same
scenario and seed.

Non-finite floats (NaN, inf) are rejected on construction and on receipt: a message carrying
one is invalid, is dropped and counted.  Unknown fields are rejected too.


The models are grouped by producer: ``base`` (the base class and ranges), ``lockstep``
(ticks, answers, housekeeping of every node), ``sim``, ``fsw`` and ``ground``; every name is
imported here, so ``interfaces.contracts.messages`` stays the one place to import them from.
"""

from __future__ import annotations

from interfaces.contracts.messages.base import (
    MAX_ACCEL_MPS2,
    MAX_ANGLE_RAD,
    MAX_FORCE_N,
    MAX_PRECISION,
    MAX_RANGE_M,
    MAX_RATE_RADPS,
    MAX_SPEED_MPS,
    MAX_TIME_S,
    MAX_TORQUE_NM,
    Accel,
    Angle,
    Force,
    Mat6,
    Message,
    Position,
    Quat,
    Rate,
    RateGroupName,
    State6,
    Time,
    Torque,
    Unjudged,
    Velocity,
    stamp,
)
from interfaces.contracts.messages.fsw import (
    AttitudeEstimate,
    GuidanceStatus,
    InfoCostTelemetry,
    NeighbourCrossing,
    NeighbourDeclaration,
    NeighbourJudgement,
    NeighbourVerdict,
    OnboardCommand,
    OnboardFdirEvent,
    PointingTarget,
    PoiObservations,
    ReportedPose,
    StateEstimate,
    ThrustCommand,
    TransferPlanMsg,
    WheelCommand,
)
from interfaces.contracts.messages.ground import (
    MAX_PRO_SIZE_M,
    MAX_TRANSFER_S,
    WINDOW_TESTS,
    AssignmentDecision,
    BaselineVerdict,
    ConstellationWindow,
    FaultReport,
    FdirWindow,
    NeighbourRuling,
    ProAssignment,
    ProAssignments,
    ProElements,
    ScanStatus,
    TelemetryStatus,
    WindowTest,
)
from interfaces.contracts.messages.lockstep import (
    ExecStats,
    GroupStats,
    Heartbeat,
    LinkCounter,
    LinkStats,
    OverflowRun,
    SimStatus,
    StoreCounter,
    Tick,
    TickDone,
)
from interfaces.contracts.messages.sim import (
    AttitudeMeasurement,
    CameraImage,
    FaultEvent,
    RelNavMeasurement,
    TruthState,
)

__all__ = [
    "MAX_RANGE_M",
    "MAX_SPEED_MPS",
    "MAX_ACCEL_MPS2",
    "MAX_RATE_RADPS",
    "MAX_FORCE_N",
    "MAX_TORQUE_NM",
    "MAX_TIME_S",
    "MAX_PRECISION",
    "MAX_ANGLE_RAD",
    "Position",
    "Velocity",
    "Accel",
    "Rate",
    "Force",
    "Torque",
    "State6",
    "Quat",
    "Mat6",
    "Time",
    "Angle",
    "RateGroupName",
    "Message",
    "stamp",
    "Tick",
    "TickDone",
    "SimStatus",
    "Heartbeat",
    "GroupStats",
    "ExecStats",
    "LinkCounter",
    "LinkStats",
    "OverflowRun",
    "StoreCounter",
    "TruthState",
    "RelNavMeasurement",
    "AttitudeMeasurement",
    "CameraImage",
    "FaultEvent",
    "ThrustCommand",
    "WheelCommand",
    "StateEstimate",
    "TransferPlanMsg",
    "GuidanceStatus",
    "PoiObservations",
    "ReportedPose",
    "NeighbourCrossing",
    "NeighbourVerdict",
    "NeighbourJudgement",
    "NeighbourDeclaration",
    "NeighbourRuling",
    "InfoCostTelemetry",
    "PointingTarget",
    "AttitudeEstimate",
    "OnboardCommand",
    "OnboardFdirEvent",
    "MAX_PRO_SIZE_M",
    "MAX_TRANSFER_S",
    "Unjudged",
    "WindowTest",
    "WINDOW_TESTS",
    "ProElements",
    "ProAssignment",
    "ProAssignments",
    "FdirWindow",
    "ConstellationWindow",
    "ScanStatus",
    "FaultReport",
    "BaselineVerdict",
    "AssignmentDecision",
    "TelemetryStatus",
    "ALL_MESSAGES",
    "registry",
    "json_schema",
]

ALL_MESSAGES: tuple[type[Message], ...] = (
    Tick,
    TickDone,
    SimStatus,
    TruthState,
    RelNavMeasurement,
    AttitudeMeasurement,
    ThrustCommand,
    WheelCommand,
    StateEstimate,
    ProAssignments,
    AssignmentDecision,
    FaultEvent,
    FdirWindow,
    FaultReport,
    ConstellationWindow,
    ScanStatus,
    BaselineVerdict,
    TransferPlanMsg,
    GuidanceStatus,
    PointingTarget,
    AttitudeEstimate,
    CameraImage,
    PoiObservations,
    InfoCostTelemetry,
    Heartbeat,
    ExecStats,
    LinkStats,
    TelemetryStatus,
    OnboardCommand,
    OnboardFdirEvent,
    NeighbourJudgement,
    NeighbourDeclaration,
    NeighbourRuling,
)


def registry() -> dict[str, type[Message]]:
    """Message type name -> model, for decoding by name (recorder, telemetry, schema server)."""
    return {m.__name__: m for m in ALL_MESSAGES}


def json_schema(msg_type: type[Message]) -> dict[str, object]:
    """JSON schema of a message type (the form written to MCAP and served on the bus)."""
    return msg_type.model_json_schema()
