"""Message models exchanged on the bus (pydantic v2, JSON on the wire).

Every message carries the sender node (``"sim"``, ``"ground"``, ``"sc<N>"``), a sequence
number that the Bus assigns per key expression on publish (like a CCSDS packet sequence
count per APID), and the simulation time ``t_sim`` in seconds.  ``t_wall`` is the publisher's
wall-clock time (UNIX seconds) and is the only field that differs between two runs of the same
scenario and seed.

Non-finite floats (NaN, inf) are rejected on construction and on receipt: a message carrying
one is invalid, is dropped and counted.  Unknown fields are rejected too.
"""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field

Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]
Vec6 = Annotated[list[float], Field(min_length=6, max_length=6)]
Mat6 = Annotated[list[Vec6], Field(min_length=6, max_length=6)]
RateGroupName = Literal["high", "mid", "low"]


class Message(BaseModel):
    """Base of every bus message."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    WALL_CLOCK_FIELDS: ClassVar[frozenset[str]] = frozenset({"t_wall"})

    sender: str = Field(max_length=64, description="node that published the message")
    seq: int = Field(default=0, ge=0, description="per-key sequence count, set by the Bus")
    t_sim: float = Field(ge=0.0, description="simulation time of the message, s")
    t_wall: float = Field(default=0.0, description="publisher wall clock, UNIX s (not reproducible)")


# --- time and lockstep -----------------------------------------------------------------------


class Tick(Message):
    """Tick k from the sim (the time master): nodes run their rate groups for t_sim = k*dt.

    ``expect`` maps each key published since the previous tick to its last sequence number; a
    receiver waits until it holds those of its subscriptions before it runs the tick, so message
    arrival order never changes the result (determinism across transports).
    """

    k: int = Field(ge=0)
    dt_s: float = Field(gt=0.0)
    expect: dict[str, int] = Field(default_factory=dict)
    final: bool = Field(default=False, description="last tick of the run")


class TickDone(Message):
    """A node's answer to tick k: it has run its groups; ``published`` as in Tick.expect."""

    k: int = Field(ge=0)
    published: dict[str, int] = Field(default_factory=dict)


class SimStatus(Message):
    """Lifecycle of the run, from the sim: ``running`` then ``finished`` (nodes then exit)."""

    state: Literal["waiting", "running", "finished", "aborted"]
    k: int = Field(default=0, ge=0)
    reason: str = ""


# --- sim truth and sensors -------------------------------------------------------------------


class TruthState(Message):
    """True relative states of all observers in the target's LVLH frame (x radial, y along-track,
    z cross-track).  Used by the channel model (range) and archived as truth for evaluation.
    """

    spacecraft: list[int]
    r_lvlh_m: list[Vec3]
    v_lvlh_mps: list[Vec3]


class RelNavMeasurement(Message):
    """Relative position/velocity sensor of one observer (LVLH, noisy, seeded)."""

    spacecraft: int = Field(ge=1)
    r_m: Vec3
    v_mps: Vec3
    sigma_r_m: float = Field(gt=0.0)
    sigma_v_mps: float = Field(gt=0.0)


# --- flight software -------------------------------------------------------------------------


class StateEstimate(Message):
    """Navigation filter output: relative state [x, y, z, vx, vy, vz] (m, m/s, LVLH) and its 6x6
    covariance; ``nis`` is the normalized innovation squared of the last update (chi-square, 6 dof).
    """

    spacecraft: int = Field(ge=1)
    x: Vec6
    P: Mat6
    nis: float | None = None


class Heartbeat(Message):
    """Node liveness and identity, at ω_mid."""

    node: str
    apps: list[str]
    k: int = Field(ge=0)


class GroupStats(BaseModel):
    """Execution statistics of one rate group."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    runs: int = 0
    cycle_slips: int = Field(default=0, description="runs longer than the group's budget")
    max_exec_ms: float = 0.0
    budget_ms: float = 0.0


class ExecStats(Message):
    """Executive statistics: cycle slips per rate group, app errors, invalid messages dropped."""

    node: str
    groups: dict[str, GroupStats]
    app_errors: int = 0
    invalid_dropped: int = 0
    barrier_timeouts: int = 0
    ticks: int = 0


class LinkCounter(BaseModel):
    """Counters of one directed link src -> dst (messages offered to the channel)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    src: str
    dst: str
    sent: int = 0
    delivered: int = 0
    dropped_range: int = 0
    dropped_loss: int = 0
    dropped_cut: int = 0


class LinkStats(Message):
    """Per-link counters of the receiving node's channel model."""

    node: str
    links: list[LinkCounter]


class TelemetryStatus(Message):
    """Ground view of each spacecraft's telemetry: received, sequence gaps, last time seen."""

    class Entry(BaseModel):
        model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
        spacecraft: int
        received: int = 0
        seq_gaps: int = Field(default=0, description="messages missing by sequence count")
        last_t_sim: float | None = None
        stale: bool = False

    entries: list[Entry]


ALL_MESSAGES: tuple[type[Message], ...] = (
    Tick,
    TickDone,
    SimStatus,
    TruthState,
    RelNavMeasurement,
    StateEstimate,
    Heartbeat,
    ExecStats,
    LinkStats,
    TelemetryStatus,
)


def registry() -> dict[str, type[Message]]:
    """Message type name -> model, for decoding by name (recorder, telemetry, schema server)."""
    return {m.__name__: m for m in ALL_MESSAGES}


def json_schema(msg_type: type[Message]) -> dict[str, object]:
    """JSON schema of a message type (the form written to MCAP and served on the bus)."""
    return msg_type.model_json_schema()
