"""Telemetry monitor: the ground's view of what each spacecraft has sent.

Rate group low.  Inputs: every spacecraft's state estimate and heartbeat.  Output: per
spacecraft the messages received, the messages missing by sequence count (lost on the link or
out of range), whether it has gone silent and when it was silent before (outages longer than
``STALE_AFTER_S``: a stalled, crashed or unreachable spacecraft), and how often its navigation
filter has diverged and restarted (``StateEstimate.resets``, logged as it happens).  Missing
telemetry is a fact to report (a link problem), never a zero.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from interfaces.contracts import catalogue as cat
from interfaces.contracts import topics
from interfaces.contracts.messages import Message, StateEstimate, TelemetryStatus
from interfaces.runtime.app import App, AppContext, Input, Output


@dataclass
class _Track:
    received: int = 0
    gaps: int = 0
    last_t: float | None = None
    nav_resets: int = 0
    outages: list[tuple[float, float]] = field(default_factory=list)
    last_seq: dict[str, int] = field(default_factory=dict)


class TelemetryMonitor(App):
    NAME = "tlm_monitor"
    RATE = "low"
    INPUTS = (
        Input(cat.NAV_ESTIMATE, "on_tlm", every_spacecraft=True),
        Input(cat.HEARTBEAT, "on_tlm", every_spacecraft=True),
    )
    OUTPUTS = (Output("status", cat.TLM_STATUS),)
    CRITICAL = ("tracks",)
    STALE_AFTER_S = 10.0
    """A spacecraft silent for longer than this (sim seconds) is reported stale."""

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        self.tracks = {i: _Track() for i in range(1, ctx.scenario.observers.count + 1)}

    def on_tlm(self, msg: Message) -> None:
        sc = topics.spacecraft_of(msg.sender)
        track = self.tracks.get(sc) if sc is not None else None
        if track is None:
            return
        kind = type(msg).__name__
        last = track.last_seq.get(kind, 0)
        if msg.seq > last + 1:
            track.gaps += msg.seq - last - 1
        track.last_seq[kind] = max(last, msg.seq)
        track.received += 1
        if track.last_t is not None and msg.t_sim - track.last_t > self.STALE_AFTER_S:
            track.outages.append((track.last_t, msg.t_sim))
            self.log.warning("sc%d heard again at t=%.1f s after %.1f s of silence", sc,
                             msg.t_sim, msg.t_sim - track.last_t)
        track.last_t = msg.t_sim if track.last_t is None else max(track.last_t, msg.t_sim)
        if isinstance(msg, StateEstimate) and msg.resets > track.nav_resets:
            self.log.warning("sc%d reports its navigation filter restarted (%d so far, t=%.1f s)",
                             sc, msg.resets, msg.t_sim)
            track.nav_resets = msg.resets

    def step(self, t: float) -> None:
        entries = [
            TelemetryStatus.Entry(
                spacecraft=sc, received=tr.received, seq_gaps=tr.gaps, last_t_sim=tr.last_t,
                nav_resets=tr.nav_resets, outages=[list(o) for o in tr.outages[-100:]],
                stale=tr.last_t is None or t - tr.last_t > self.STALE_AFTER_S)
            for sc, tr in self.tracks.items()
        ]
        self.publish("status", TelemetryStatus(sender=self.ctx.node, t_sim=t, entries=entries))
