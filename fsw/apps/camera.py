"""Camera app: where to look, and what was seen (paper Sec. II.C-D).

Rate group mid (ω_mid).  Inputs: the camera's images (from the sim), the observations of every
observer (its own come back through the bus; a neighbour's arrive only within range) to keep
the fused POI map, and the nav estimate.  Outputs: the observations of each image, shared with
the other observers and the ground, and the pointing target for the attitude app.

Pointing (``camera.pointing``): the target's centre (default), or, with ``"max_variance"``,
every ``RETARGET_S`` the POI of maximum current variance (φ·H_POI) that is reachable:
front-facing and in camera range from the estimated position, and within ``RETARGET_MAX_DEG``
of the current line of sight.  The aim point does not jump to it: it glides there over the
next ``RETARGET_S`` on a smoothstep (rate zero at both ends, at most 1.2°/s of line-of-sight
turn, below the attitude app's rate limit), and its rate is published with the target so the
attitude app tracks it with feed-forward instead of chasing steps.  It retargets only while
the attitude app is tracking (a target moving during a slew would end it off target).  Until
it has a position estimate it points at the target's centre.
"""

from __future__ import annotations

import math

import numpy as np

from fsw.lib.neighbour_judge import Exclusions
from gnc.poi_map import PoiMap
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import (
    AttitudeEstimate,
    CameraImage,
    NeighbourDeclaration,
    NeighbourRuling,
    OnboardCommand,
    PointingTarget,
    PoiObservations,
    ReportedPose,
    StateEstimate,
)
from interfaces.contracts.timing import TIME_TOL_S
from interfaces.runtime.app import App, AppContext, Input, Output

RETARGET_S = 10.0
"""Period of the pointing-target choice, s."""
RETARGET_MAX_DEG = 8.0
"""Largest change of line of sight allowed at a retarget, deg."""


class CameraApp(App):
    NAME = "camera"
    RATE = "mid"
    INPUTS = (
        Input(cat.CAMERA_IMAGE, "on_image"),
        Input(cat.OBSERVATIONS, "on_observations", every_spacecraft=True),
        Input(cat.NAV_ESTIMATE, "on_estimate"),
        Input(cat.ATTITUDE_ESTIMATE, "on_attitude"),
        Input(cat.FDIR_COMMAND, "on_command"),
        Input(cat.NEIGHBOUR_DECLARATION, "on_declaration"),
        Input(cat.NEIGHBOUR_RULING, "on_ruling"),
    )
    OUTPUTS = (Output("observations", cat.OBSERVATIONS), Output("pointing", cat.POINTING))
    CRITICAL = ("map", "aim_start", "aim_goal", "aim_t", "next_retarget", "_images", "_est",
                "_tracking", "off", "max_variance", "_to_centre", "_att", "_track_since",
                "exclusions")

    def __init__(self, ctx: AppContext) -> None:
        super().__init__(ctx)
        sc = ctx.scenario
        self.sc_id = ctx.spacecraft or 0
        self.poi_pos, self.poi_normal = ctx.constants.poi_pos, ctx.constants.poi_normal
        self.map = PoiMap.uniform(sc.target.pois, sc.target.prior_variance, sc.observers.count)
        self.max_range = sc.camera.max_range_m
        self.max_variance = sc.camera.pointing == "max_variance"
        self.aim_start = np.zeros(3)  # glide of the aim point (LVLH, m) from here at aim_t...
        self.aim_goal = np.zeros(3)   # ...to here at aim_t + RETARGET_S
        self.aim_t = 0.0
        self.next_retarget = 0.0
        self._images: list[CameraImage] = []
        self._est: StateEstimate | None = None
        self._tracking = False  # the attitude app tracks the aim (not slewing, initialised)
        self.off = False  # the onboard FDIR turned the camera off: no observations shared
        self._to_centre = False  # the onboard FDIR asked for the target's centre
        self.with_pose = sc.neighbours.enabled  # each image's observations carry the pose
        self._att: AttitudeEstimate | None = None
        self._track_since: float | None = None  # when the attitude app began tracking, s
        self.exclusions = Exclusions()  # observers the neighbours declared: not fused

    def on_image(self, msg: CameraImage) -> None:
        self._images.append(msg)

    def on_observations(self, msg: PoiObservations) -> None:
        if self.max_variance and (msg.spacecraft == self.sc_id or self.exclusions.admits(msg)):
            self.map.add(msg.spacecraft, *msg.arrays())  # the map serves max-variance only

    def on_declaration(self, msg: NeighbourDeclaration) -> None:
        self.exclusions.declared(msg, self.sc_id)

    def on_ruling(self, msg: NeighbourRuling) -> None:
        for m in self.exclusions.ruled(msg):
            self.on_observations(m)

    def on_estimate(self, msg: StateEstimate) -> None:
        self._est = msg

    def on_attitude(self, msg: AttitudeEstimate) -> None:
        self._tracking = msg.mode == "track"
        self._att = msg
        if not self._tracking:
            self._track_since = None
        elif self._track_since is None:
            self._track_since = msg.t_sim

    def on_command(self, msg: OnboardCommand) -> None:
        """The onboard FDIR: ``camera_off`` stops the observations for good; ``point_target``
        glides the aim back to the target's centre and keeps it there."""
        if msg.command == "camera_off" and not self.off:
            self.off = True
            self.log.warning("camera off (onboard FDIR): no more observations")
        elif msg.command == "point_target":
            self._to_centre = True

    def step(self, t: float) -> None:
        images, self._images = self._images, []
        pose = self._pose(t) if self.with_pose else None
        for img in images if not self.off else ():
            self.publish("observations", PoiObservations.of_image(img, self.ctx.node, t, pose))
        if self._to_centre:
            self._to_centre, self.max_variance = False, False
            self.aim_start, self.aim_t, self.aim_goal = self._aim_at(t)[0], t, np.zeros(3)
        if self.max_variance and t >= self.next_retarget - TIME_TOL_S and self._est is not None \
                and self._tracking:
            self.next_retarget = t + RETARGET_S
            self.aim_start, self.aim_t = self._aim_at(t)[0], t
            self.aim_goal = self._choose(np.array(self._est.x[:3]), self.aim_start)
        aim, rate, accel = self._aim_at(t)
        self.publish("pointing", PointingTarget(
            sender=self.ctx.node, t_sim=t, spacecraft=self.sc_id, target_lvlh_m=aim.tolist(),
            target_rate_lvlh_mps=rate.tolist(), target_accel_lvlh_mps2=accel.tolist()))

    def _pose(self, t: float) -> ReportedPose | None:
        """The pose this observer reports with its observations (its latest nav and attitude
        estimates): what its neighbours judge it by (``fsw/apps/neighbours.py``)."""
        est, att = self._est, self._att
        if est is None or att is None:
            return None
        return ReportedPose(
            nav_m=list(est.x[:3]), nav_sigma_m=est.position_sigma_m(),
            aim_m=list(att.target_lvlh_m), knowledge_rad=att.sigma_att_rad,
            tracking_rad=att.pointing_error_rad,
            tracking_s=0.0 if self._track_since is None else max(t - self._track_since, 0.0))

    def _aim_at(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Aim point (m), rate (m/s) and acceleration (m/s²) at time t on the glide from
        ``aim_start`` to ``aim_goal``: a smoothstep 3τ² − 2τ³ over ``RETARGET_S``
        (τ = elapsed/RETARGET_S), so the rate starts and ends at zero; the peak rate is 1.5× the
        mean."""
        tau = (t - self.aim_t) / RETARGET_S
        if tau >= 1.0 - 1e-12:
            return self.aim_goal.copy(), np.zeros(3), np.zeros(3)
        tau = max(0.0, tau)
        delta = self.aim_goal - self.aim_start
        return (self.aim_start + delta * (tau * tau * (3.0 - 2.0 * tau)),
                delta * (6.0 * tau * (1.0 - tau) / RETARGET_S),
                delta * (6.0 * (1.0 - 2.0 * tau) / RETARGET_S**2))

    def _choose(self, r: np.ndarray, aim: np.ndarray) -> np.ndarray:
        """The reachable POI of maximum φ·H_POI (``aim`` if none is reachable)."""
        to_cam = r - self.poi_pos
        dist = np.linalg.norm(to_cam, axis=1)
        los_now = aim - r
        los = self.poi_pos - r
        cos_turn = (los @ los_now) / (dist * max(1e-9, float(np.linalg.norm(los_now))))
        ok = ((np.einsum("ij,ij->i", self.poi_normal, to_cam) > 0.0) & (dist <= self.max_range)
              & (cos_turn >= math.cos(math.radians(RETARGET_MAX_DEG))))
        if not ok.any():
            return aim
        score = np.where(ok, self.map.phi * self.map.variance(), -np.inf)
        return np.array(self.poi_pos[int(np.argmax(score))])
