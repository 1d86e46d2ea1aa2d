"""Messages of the lockstep and of every node's housekeeping: the sim's ticks and status, the
nodes' answers, heartbeats, executive statistics and link counters."""

from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field

from interfaces.contracts.messages.base import MAX_TIME_S, Message


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
    rejoin: list[str] = Field(
        default_factory=list,
        description="participants the sim lost and sees again, until each answers a tick: "
                    "such a node takes this tick as its own next one, however far ahead")


class TickDone(Message):
    """A node's answer to tick k: it has run its groups; ``published`` as in Tick.expect."""

    k: int = Field(ge=0)
    published: dict[str, int] = Field(default_factory=dict)


class SimStatus(Message):
    """Lifecycle of the run, from the sim: ``running`` then ``finished`` (nodes then exit);
    ``participants``: the nodes lost from the lockstep (process died, stalled, disconnected) and
    rejoined, with their sim times; with ``--realtime``, the pacing (``sim/pacing.py``)."""

    class Event(BaseModel):
        model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)
        what: Literal["lost", "rejoined"]
        t_sim: float = Field(ge=0.0, le=MAX_TIME_S)

    state: Literal["waiting", "running", "finished", "aborted"]
    k: int = Field(default=0, ge=0)
    reason: str = ""
    rejected_commands: int = Field(
        default=0, ge=0, description="actuator commands refused (stale, future or wrong sender)")
    participants: dict[str, list[Event]] = Field(default_factory=dict, max_length=64)
    pace_ceiling: float | None = Field(
        default=None, gt=0.0, description="--realtime SPEED: the most the sim runs, × real time "
                                           "(None: lockstep alone)")
    hard_deadline: bool = Field(
        default=False, description="paced with hard deadlines: an answer later than the next "
                                   "tick's due time is a missed tick of its node")
    late_ticks: dict[str, int] = Field(
        default_factory=dict, max_length=64,
        description="per node, the ticks its answer came too late for")


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
    """Executive statistics: cycle slips per rate group, app errors, invalid messages dropped,
    messages refused at admission (``interfaces.runtime.admission``: a sender not owning its key, an
    absurd sequence number or date, a full queue, an implausible tick)."""

    node: str
    groups: dict[str, GroupStats]
    app_errors: int = 0
    invalid_dropped: int = 0
    refused: int = 0
    barrier_timeouts: int = 0
    ticks: int = 0


class OverflowRun(BaseModel):
    """Messages of one topic that an onboard store could not keep, sent no more than
    ``MERGE_GAP_S`` apart (``links/onboard_store.py``)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    MERGE_GAP_S: ClassVar[float] = 10.0
    topic: str = Field(description="app/name of the key")
    first_s: float = Field(description="send time of the first, s")
    last_s: float = Field(description="send time of the last, s")
    count: int = Field(ge=1)


class StoreCounter(BaseModel):
    """A spacecraft's onboard store of its telemetry to the ground, with ground passes
    (``[ground] contact = "passes"``): what entered it, what was dumped (each message's last
    bit received), sent again after a loss, lost to overflow (by topic and time) and what is
    still on board.  Bytes are JSON bytes without the wall-clock stamp."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    stored: int = 0
    stored_bytes: int = 0
    dumped: int = 0
    dumped_bytes: int = 0
    retransmitted: int = 0
    overflow: int = 0
    overflow_bytes: int = 0
    onboard: int = 0
    onboard_bytes: int = 0
    onboard_since_s: float | None = Field(
        default=None, description="send time of the oldest message still aboard, s (None: "
                                  "none aboard)")
    judged_since_s: float | None = Field(
        default=None, description="send time of the oldest message aboard of the topics the "
                                  "ground FDIR judges (priorities 0 and 1), s (None: none)")
    overflow_runs: list[OverflowRun] = Field(default_factory=list, max_length=100_000)
    offered_bytes_by_topic: dict[str, int] = Field(
        default_factory=dict, max_length=256,
        description="what was offered to it (stored or lost to overflow), by topic (app/name)")
    peak_bytes: int = Field(default=0, ge=0, description="the most it held at once")


class LinkCounter(BaseModel):
    """Counters of one directed link src -> dst (messages offered to the channel).  With
    ground passes a downlink has its store's counters (``store``; ``sent`` counts the
    transmissions of the dump, ``dropped_loss`` those sent again) and an uplink counts the
    messages that waited on the ground for a pass (``held``)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    src: str
    dst: str
    sent: int = 0
    delivered: int = 0
    dropped_range: int = 0
    dropped_loss: int = 0
    dropped_cut: int = 0
    held: int | None = None
    store: StoreCounter | None = None


class LinkStats(Message):
    """Per-link counters of the receiving node's channel model."""

    node: str
    links: list[LinkCounter]
