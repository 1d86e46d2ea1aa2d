"""Onboard FDIR app: the agent-level FDIR of Fig. 5, in cFS's Limit Checker / Stored Command
style (watchpoints, sequences and their tables: ``fsw/lib/onboard_fdir.py``).

Rate group high (ω_high), so that a ground declaration is acted on in the tick it arrives.
Inputs, all of this spacecraft: the attitude estimate (pointing error, wheel momentum, star
tracker), the nav estimate (NIS), the guidance status (thrust, safe hold), its own observations
(blank images), the ground's fault reports, and its neighbours' declarations naming it
(``fsw/apps/neighbours.py``: an event, and ``[neighbours] action``). Outputs: stored-sequence
commands to this spacecraft's apps (``sc/N/fdir/command``) and events (``sc/N/fdir/event``).

Each step it first acts on the ground's reports that name this spacecraft, then samples the
watchpoints with what arrived.  A report starts its class's sequences (actuator: safe hold and
a plan request; camera: camera off; state sensor: nav reset) and a trip its watchpoint's
action, each announced by an event.

**It never fights the ground's re-plan** (the rules, each tested in
``tests/fsw/apps/test_fdir.py``):

1. Onboard, nothing changes an assignment: safe hold only withholds thrust and transfers, and
   ends the moment guidance holds an assignment newer than the one in force when it began
   (the ground's re-plan always ends it; ``recovered`` is announced).
2. A class is acted on once per episode: a report repeating a class already acted on starts
   nothing; once safe hold has ended, a new actuator declaration starts it again.
3. Safe hold is not started twice; a watchpoint whose action is safe hold while in it starts
   nothing.
4. The onboard FDIR declares nothing to the ground's FDIR: it reports events and asks for a
   plan; the ground's FDIR and planner decide.
"""

from __future__ import annotations

from typing import Literal

from fsw.lib.onboard_fdir import (
    SEQUENCES,
    WATCHPOINT_CLASS,
    BlankImages,
    WatchState,
    class_sequences,
    momentum_frac,
    pointing_deg,
    thrust_duty,
    watch,
)
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    AttitudeEstimate,
    FaultReport,
    GuidanceStatus,
    NeighbourDeclaration,
    OnboardCommand,
    OnboardFdirEvent,
    PoiObservations,
    StateEstimate,
)
from interfaces.runtime.app import App, AppContext, Input, Output


class OnboardFdirApp(App):
    NAME = "fdir"
    RATE = "high"
    INPUTS = (
        Input(cat.FAULT_REPORT, "on_report"),
        Input(cat.ATTITUDE_ESTIMATE, "on_attitude"),
        Input(cat.NAV_ESTIMATE, "on_estimate"),
        Input(cat.GUIDANCE_STATUS, "on_guidance"),
        Input(cat.OBSERVATIONS, "on_observations"),
        Input(cat.NEIGHBOUR_DECLARATION, "on_neighbours"),
    )
    OUTPUTS = (Output("command", cat.FDIR_COMMAND), Output("event", cat.FDIR_EVENT))
    CRITICAL = ("states", "blank", "acted", "safe", "camera_off", "track_since",
                "assignment_id", "_reports", "_samples", "_recovered", "_told")

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.sc_id = ctx.spacecraft or 0
        self.table = sc.onboard_fdir.table()
        self.h_max = sc.actuators.wheel_max_momentum_nms
        self.u_max = sc.actuators.thruster_max_force_n / (sc.observers.mass_kg * 3.0 ** 0.5)
        self.states = {name: WatchState() for name in self.table}
        self.blank = BlankImages()
        self.acted: set[str] = set()
        """the classes acted on in this episode"""
        self.safe: Literal["off", "commanded", "on"] = "off"
        """safe hold: commanded, then on once guidance reports it, off when it ends"""
        self.camera_off = False
        self.track_since: float | None = None
        """when the attitude app last began tracking, s (None: not tracking)"""
        self.settle_s = sc.attitude.settling_time_s
        self.assignment_id = 0
        self._reports: list[FaultReport] = []
        self._samples: list[tuple[str, float]] = []
        self._recovered = False
        self._told: list[NeighbourDeclaration] = []
        self.neighbours_action = sc.neighbours.action

    # --- inputs: each sample queued for the step ------------------------------------------

    def on_report(self, msg: FaultReport) -> None:
        if msg.spacecraft == self.sc_id:
            self._reports.append(msg)

    def on_attitude(self, msg: AttitudeEstimate) -> None:
        if msg.mode != "track":
            self.track_since = None
        elif self.track_since is None:
            self.track_since = msg.t_sim
        tracked = msg.t_sim - self.track_since if self.track_since is not None else 0.0
        self._sample("pointing_deg", pointing_deg(msg, tracked, self.settle_s))
        self._sample("wheel_momentum_frac", momentum_frac(msg, self.h_max))
        self._sample("star_tracker_gap_s", msg.star_tracker_age_s)

    def on_estimate(self, msg: StateEstimate) -> None:
        self._sample("nav_nis", msg.nis)

    def on_guidance(self, msg: GuidanceStatus) -> None:
        self.assignment_id = msg.assignment_id
        if self.safe == "commanded" and msg.mode == "safe":
            self.safe = "on"
        elif self.safe == "on" and msg.mode != "safe":
            self._recovered = True
        self._sample("thrust_duty_excess", thrust_duty(msg, self.u_max))

    def on_neighbours(self, msg: NeighbourDeclaration) -> None:
        if msg.subject == self.sc_id:
            self._told.append(msg)

    def on_observations(self, msg: PoiObservations) -> None:
        if self.track_since is not None and not self.camera_off:  # tracking
            self._sample("blank_image_frac", self.blank.add(len(msg.poi)))

    def _sample(self, name: str, value: float | None) -> None:
        if value is not None:
            self._samples.append((name, value))

    # --- cycle ----------------------------------------------------------------------------

    def step(self, t: float) -> None:
        reports, self._reports = self._reports, []
        for r in reports:
            self._on_declared(t, r)
        told, self._told = self._told, []
        for d in told:
            self._event(t, "report", "neighbours", detail=f"declared by neighbours {d.judges} "
                        f"(window to {d.t_end_s:.0f} s)")
            self._run(t, self.neighbours_action, None)
        samples, self._samples = self._samples, []
        for name, value in samples:
            self._check(t, name, value)
        if self._recovered:
            self._recovered, self.safe = False, "off"
            self.acted.discard("actuator")
            self._event(t, "recovered", "safe_hold",
                        detail="safe hold ended: a newer assignment received")

    def _on_declared(self, t: float, report: FaultReport) -> None:
        """A ground declaration naming this spacecraft: its class's sequences, once."""
        c = report.fault_class
        self._event(t, "report", c or "", fault_class=c,
                    detail=f"declared by the ground (window to {report.window_end_s:.0f} s)")
        if c is None or c in self.acted:
            return
        self.acted.add(c)
        for seq in class_sequences(c):
            self._run(t, seq, c)

    def _check(self, t: float, name: str, value: float) -> None:
        wp = self.table[name]
        change = watch(wp, self.states[name], value)
        if change is None:
            return
        self._event(t, change, name, value=value, limit=wp.limit,
                    detail=f"action {wp.action}" if change == "trip" else "")
        if change == "trip":
            self._run(t, wp.action, WATCHPOINT_CLASS[name])

    def _run(self, t: float, seq: str, fault_class: str | None) -> None:
        """Start stored sequence ``seq``: its commands, then its event."""
        if seq == "none" or (seq == "safe_hold" and self.safe != "off"):
            return
        if seq == "safe_hold":
            self.safe = "commanded"
        if seq == "camera_off":
            self.camera_off = True
        for command in SEQUENCES[seq]:
            self.publish("command", OnboardCommand(
                sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id, command=command,  # type: ignore[arg-type]
                sequence=seq, assignment_id=self.assignment_id))
        if seq == "request_plan":
            self._event(t, "plan_request", "safe_hold" if self.safe != "off" else seq,
                        fault_class=fault_class, detail="a new plan asked of the ground")
        self._event(t, "sequence", seq, fault_class=fault_class,
                    detail=", ".join(SEQUENCES[seq]) or "no command")

    def _event(self, t: float, event: str, name: str, value: float | None = None,
               limit: float | None = None, fault_class: str | None = None,
               detail: str = "") -> None:
        self.log.warning("sc%d onboard FDIR %s %s%s at t=%.1f s", self.sc_id, event, name,
                         f" ({detail})" if detail else "", t)
        self.publish("event", OnboardFdirEvent(
            sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id, event=event,  # type: ignore[arg-type]
            name=name[:32], value=value, limit=limit, fault_class=fault_class,  # type: ignore[arg-type]
            detail=detail[:200]))
