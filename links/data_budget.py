"""A spacecraft's telemetry data budget with ground passes (``[ground] contact = "passes"``;
docs/architecture.md, "Data budget"): what each observer stores for the ground per second, by
topic, and whether its onboard store (``links.onboard_store``) holds what accumulates between
two dumps.

* **Bytes per second, a priori** (:func:`estimate_Bps`).  The observations dominate (over 95%
  on the default mission): one message per image at ω_mid, with one entry per POI the image
  sees.  The entries are estimated from the design, not from a run: the share of the target's
  surface a camera at distance d sees, pointed at the centre (front-facing, inside the cone,
  within range: :func:`visible_fraction`), averaged over the PROs the scenario names (the
  observers', its phases', or the candidate library of ``[assignment]``), the largest of
  those.  A message of that many entries is built and its JSON bytes counted
  (``onboard_store.message_bytes``, as the store counts them).  The other topics are of fixed
  size (``FIXED_BYTES``, their JSON bytes on the default mission) at their rate groups.
  It over-estimates: the camera's cone and the incidence of the POIs on the limb cut more than
  the model does (the default mission measured about 0.7 of it).
* **The store's peak** (:func:`store_peak`): a fluid model of the store over the run's passes:
  it fills at the production rate out of contact and drains at ``downlink_bps`` minus the
  production in contact.  Its peak is what the store must hold; what is aboard after the last
  pass's end shows whether the passes keep up.

``budget`` gathers both; the launcher warns at load when the store is smaller than the peak,
naming the figures, and summary.json's ``ground_contact.data_budget`` holds the estimate beside
each store's measured bytes per second by topic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gnc.passes import ContactPlan
from interfaces.contracts import catalogue as cat
from interfaces.contracts.messages import PoiObservations
from interfaces.contracts.messages.poi_packing import quantise
from interfaces.contracts.scenario import Scenario
from links.onboard_store import message_bytes

OBSERVATIONS = cat.OBSERVATIONS.path

FIXED_BYTES: dict[str, tuple[str, float]] = {
    cat.NAV_ESTIMATE.path: ("mid", 770.0),
    cat.ATTITUDE_ESTIMATE.path: ("mid", 725.0),
    cat.HEARTBEAT.path: ("mid", 165.0),
    cat.GUIDANCE_STATUS.path: ("low", 500.0),
    cat.INFO_COST.path: ("fdi", 400.0),
}
"""Fixed-size topics each observer stores for the ground: (rate group, JSON bytes per message,
as ``message_bytes`` counts them on the default mission).  Rare ones (transfer plans, FDIR
events, neighbours' declarations) are left out."""

SAMPLES = 24
"""Phase samples of a PRO (in-plane and cross-track, each) for its mean visible share."""


def visible_fraction(distance_m: float, radius_m: float, half_angle_rad: float,
                     max_range_m: float) -> float:
    """Share of a sphere's surface (radius ``radius_m``) a camera at ``distance_m`` from its
    centre, pointed at it, sees: the POIs facing the camera (angle from the sub-camera point
    below arccos(R/d)) inside the cone (R sin(θ+α) ≤ d sin α) and within ``max_range_m``."""
    d, r = distance_m, radius_m
    if d <= r or d - r > max_range_m:
        return 0.0
    theta = math.acos(r / d)
    if d * math.sin(half_angle_rad) < r:
        theta = min(theta, math.asin(d * math.sin(half_angle_rad) / r) - half_angle_rad)
    return 0.5 * (1.0 - math.cos(max(theta, 0.0)))


def _pro_sizes(scenario: Scenario) -> list[tuple[float, float, float]]:
    """(ρx, ρy, ρz) of every PRO the scenario names, m."""
    sizes = []
    n = scenario.observers.count
    if scenario.observers.start == "pro":
        sizes += [(p[0], p[2], p[3]) for p in map(scenario.observers.pro, range(1, n + 1))]
    for phase in scenario.phases:
        if phase.assign == "information":
            a = scenario.assignment
            sizes += [(x, 0.0, z) for x in a.rho_x_m for z in a.rho_z_m]
        else:
            sizes += [(p[0], p[2], p[3]) for p in (phase.pro_of(i, n) for i in range(1, n + 1))]
    return sizes


def mean_visible_fraction(scenario: Scenario, rho: tuple[float, float, float]) -> float:
    """The visible share (:func:`visible_fraction`) averaged over a PRO of size ``rho``."""
    u = np.linspace(0.0, 2.0 * np.pi, SAMPLES, endpoint=False)
    ax, az = np.meshgrid(u, u)
    x, y, z = rho[0] * np.sin(ax), rho[1] + 2.0 * rho[0] * np.cos(ax), rho[2] * np.sin(az)
    cam = scenario.camera
    return float(np.mean([visible_fraction(d, scenario.target.radius_m,
                                           math.radians(cam.half_angle_deg), cam.max_range_m)
                          for d in np.sqrt(x * x + y * y + z * z).ravel()]))


def observation_bytes(entries: int, pois: int) -> int:
    """JSON bytes of an image's observations with ``entries`` POIs of ``pois`` (indices spread
    over the target, precisions of a 20-30 m image with the camera's digits, packed), as the
    store counts them."""
    idx = np.linspace(0, pois - 1, max(entries, 0)).astype(int)
    prec = quantise(1.0 / (np.linspace(20.0, 30.0, len(idx)) ** 2 * np.pi))
    msg = PoiObservations(sender="sc1", t_sim=1234.5, spacecraft=1, image_t_s=1234.5,
                          poi=idx, precision=prec)
    return message_bytes(msg)


def estimate_Bps(scenario: Scenario) -> dict[str, float]:
    """Bytes per second one observer stores for the ground, by topic (module docstring)."""
    rates = {"mid": scenario.rates.mid_hz, "low": scenario.rates.low_hz,
             "fdi": 1.0 / scenario.rates.fdi_period_s}
    share = max((mean_visible_fraction(scenario, rho) for rho in _pro_sizes(scenario)),
                default=0.5)
    entries = round(share * scenario.target.pois)
    out = {OBSERVATIONS: rates["mid"] * observation_bytes(entries, scenario.target.pois)}
    out |= {topic: rates[group] * size for topic, (group, size) in FIXED_BYTES.items()}
    return out


def store_peak(rate_Bps: float, windows: tuple[tuple[float, float], ...], duration_s: float,
               downlink_bps: float) -> tuple[float, float]:
    """(peak bytes, bytes aboard after the last contact in the run) of a store filled at
    ``rate_Bps`` from t = 0 and dumped at ``downlink_bps`` in the contact ``windows``
    ((start, end) s, in time order) of [0, ``duration_s``]."""
    fill = peak = 0.0
    t = 0.0
    drain = downlink_bps / 8.0 - rate_Bps
    for start, end in windows:
        start, end = min(max(start, t), duration_s), min(end, duration_s)
        fill += rate_Bps * (start - t)
        peak = max(peak, fill)
        fill = max(fill - drain * (end - start), 0.0)
        peak = max(peak, fill)
        t = end
    after_last = fill
    peak = max(peak, fill + rate_Bps * max(duration_s - t, 0.0))
    return peak, after_last


@dataclass(frozen=True)
class DataBudget:
    """One observer's budget with ground passes (module docstring)."""

    rates_Bps: dict[str, float]
    """estimated bytes per second stored for the ground, by topic"""
    peak_bytes: float
    """the store's estimated peak over the run"""
    aboard_after_last_pass_bytes: float
    store_bytes: int
    downlink_bps: float

    @property
    def total_Bps(self) -> float:
        return sum(self.rates_Bps.values())

    @property
    def holds(self) -> bool:
        return self.peak_bytes <= self.store_bytes

    def warnings(self) -> list[str]:
        """What the launcher warns about at load: a store that cannot hold the peak, and
        passes too short to dump what accumulates."""
        out = []
        if not self.holds:
            out.append(
                f"[ground] store_bytes = {self.store_bytes:,} cannot hold what accumulates "
                f"between dumps: about {self.total_Bps:,.0f} B/s per observer "
                f"({self.rates_Bps[OBSERVATIONS]:,.0f} of them observations) peaks at "
                f"{self.peak_bytes:,.0f} bytes aboard at {self.downlink_bps:,.0f} bit/s; the "
                "store will overflow (housekeeping first, the FDIR's data last)")
        if self.aboard_after_last_pass_bytes > 0.0:
            out.append(
                f"[ground] downlink_bps = {self.downlink_bps:,.0f}: the passes cannot dump "
                f"what accumulates (about {self.total_Bps:,.0f} B/s per observer); "
                f"{self.aboard_after_last_pass_bytes:,.0f} bytes stay aboard after the last "
                "pass, and the ground's judgement falls behind")
        return out


def budget(scenario: Scenario) -> DataBudget | None:
    """The data budget of a scenario with ground passes (None: the ground hears always)."""
    plan = ContactPlan.of(scenario)
    if plan is None:
        return None
    rates = estimate_Bps(scenario)
    g = scenario.ground
    peak, after = store_peak(sum(rates.values()), plan.windows, scenario.duration_s,
                             g.downlink_bps)
    return DataBudget(rates, peak, after, g.store_bytes, g.downlink_bps)
