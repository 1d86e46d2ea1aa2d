"""Ground passes: when a ground station sees the target, from the target's orbit over a
rotating Earth.

The ground reaches the constellation through the target (the relay at the LVLH origin), so
contact is a property of the target's orbit and the stations.  The target flies a circular
orbit of radius ``a``, inclination ``i``, right ascension of the ascending node ``Ω`` and
argument of latitude ``u`` (from the node, in the direction of motion) at t = 0.  With J2 the
node and the argument of latitude drift at their secular J2 rates for e = 0 (the node's, and
the perigee's plus the mean anomaly's):

    Ω' = -3/2 n J2 (R/a)^2 cos i
    u' = n + 3/4 n J2 (R/a)^2 (5 cos^2 i - 1) + 3/4 n J2 (R/a)^2 (3 cos^2 i - 1)

(the short-period terms, a few km, move a pass by about a second and are left out).

ECI z is the Earth's spin axis (as in :mod:`sim.dynamics`); the Earth turns at
``OMEGA_EARTH_RAD_S`` from the Greenwich sidereal angle θ0 at t = 0, which
:func:`greenwich_sidereal_angle` gives for a UTC epoch (IAU 1982 GMST, UT1 = UTC).  Stations
are geodetic (WGS-84 ellipsoid); a station sees the target while the target's elevation above
its local horizon (the plane normal to the geodetic up) exceeds the station's mask.

Units: SI (m, s, rad) in every function; degrees only in the names that say so.
"""

from __future__ import annotations

import bisect
import functools
import math
from dataclasses import dataclass
from datetime import UTC, datetime

import numpy as np
import numpy.typing as npt
from scipy.optimize import brentq, minimize_scalar

from gnc.constants import J2_EARTH, MU_EARTH_M3_S2, R_EARTH_M
from gnc.frames import orbit_plane_axes
from interfaces.contracts.scenario import Scenario
from interfaces.contracts.timing import TIME_TOL_S

FloatArray = npt.NDArray[np.float64]

OMEGA_EARTH_RAD_S = 7.292115146706979e-5
"""Earth's sidereal rotation rate, rad/s (WGS-84)."""
WGS84_FLATTENING = 1.0 / 298.257223563
"""WGS-84 flattening of the reference ellipsoid."""
_J2000 = datetime(2000, 1, 1, 12, 0, 0, tzinfo=UTC)


@dataclass(frozen=True)
class CircularOrbit:
    """The target's orbit: a circle of radius ``radius_m`` at ``inclination_rad``, node
    ``raan_rad`` and argument of latitude ``arg_lat_rad`` at t = 0, with ``j2`` the secular
    drift of the node and the argument of latitude."""

    radius_m: float
    inclination_rad: float
    raan_rad: float = 0.0
    arg_lat_rad: float = 0.0
    j2: bool = False

    @property
    def mean_motion_rad_s(self) -> float:
        return math.sqrt(MU_EARTH_M3_S2 / self.radius_m ** 3)

    def rates_rad_s(self) -> tuple[float, float]:
        """(Ω', u'): the node's and the argument of latitude's rates, rad/s."""
        n = self.mean_motion_rad_s
        if not self.j2:
            return 0.0, n
        k = 0.75 * n * J2_EARTH * (R_EARTH_M / self.radius_m) ** 2
        c2 = math.cos(self.inclination_rad) ** 2
        return -2.0 * k * math.cos(self.inclination_rad), n + k * (5.0 * c2 - 1.0) + k * (
            3.0 * c2 - 1.0)

    def positions_eci(self, t_s: FloatArray) -> FloatArray:
        """ECI positions at the times ``t_s`` (s from t = 0), m, shape (len(t_s), 3)."""
        raan_rate, u_rate = self.rates_rad_s()
        node = self.raan_rad + raan_rate * t_s
        u = self.arg_lat_rad + u_rate * t_s
        p, q = orbit_plane_axes(np.cos(node), np.sin(node), math.cos(self.inclination_rad),
                                math.sin(self.inclination_rad))
        return self.radius_m * (np.cos(u)[:, None] * p + np.sin(u)[:, None] * q)


@dataclass(frozen=True)
class GroundStation:
    """A ground station: geodetic latitude and longitude (rad), altitude above the WGS-84
    ellipsoid (m), and the elevation mask (rad) above which it sees the target."""

    name: str
    latitude_rad: float
    longitude_rad: float
    altitude_m: float = 0.0
    mask_rad: float = math.radians(10.0)

    def ecef(self) -> tuple[FloatArray, FloatArray]:
        """The station's Earth-fixed position (m) and its geodetic up (unit), each shape (3,)."""
        e2 = WGS84_FLATTENING * (2.0 - WGS84_FLATTENING)
        sl, cl = math.sin(self.latitude_rad), math.cos(self.latitude_rad)
        so, co = math.sin(self.longitude_rad), math.cos(self.longitude_rad)
        n = R_EARTH_M / math.sqrt(1.0 - e2 * sl * sl)
        up = np.array([cl * co, cl * so, sl])
        pos = np.array([(n + self.altitude_m) * cl * co, (n + self.altitude_m) * cl * so,
                        (n * (1.0 - e2) + self.altitude_m) * sl])
        return pos, up


@dataclass(frozen=True)
class ContactWindow:
    """One pass: the station sees the target over [aos_s, los_s) (clipped to the run), with
    its highest elevation at ``tca_s``."""

    station: str
    aos_s: float
    los_s: float
    tca_s: float
    max_elevation_deg: float

    @property
    def duration_s(self) -> float:
        return self.los_s - self.aos_s


def greenwich_sidereal_angle(epoch: datetime) -> float:
    """The Greenwich mean sidereal angle at a UTC ``epoch`` (taken as UT1), rad in [0, 2π)
    (IAU 1982 GMST; 280.46061837° at J2000.0)."""
    if epoch.tzinfo is None:
        raise ValueError("epoch must be timezone-aware (UTC)")
    days = (epoch - _J2000).total_seconds() / 86400.0
    centuries = days / 36525.0
    deg = (280.46061837 + 360.98564736629 * days + 0.000387933 * centuries ** 2
           - centuries ** 3 / 38710000.0)
    return math.radians(deg % 360.0)


def elevation_rad(orbit: CircularOrbit, station: GroundStation, theta0_rad: float,
                  t_s: FloatArray) -> FloatArray:
    """The target's elevation above the station's horizon at the times ``t_s``, rad."""
    pos, up = station.ecef()
    theta = theta0_rad + OMEGA_EARTH_RAD_S * t_s
    c, s = np.cos(theta), np.sin(theta)
    # The station's position and up in ECI: ECEF turned about z by the sidereal angle.
    st = np.stack([c * pos[0] - s * pos[1], s * pos[0] + c * pos[1],
                   np.full_like(theta, pos[2])], axis=-1)
    st_up = np.stack([c * up[0] - s * up[1], s * up[0] + c * up[1],
                      np.full_like(theta, up[2])], axis=-1)
    rho = orbit.positions_eci(t_s) - st
    sin_el = np.einsum("ij,ij->i", rho, st_up) / np.linalg.norm(rho, axis=1)
    return np.arcsin(np.clip(sin_el, -1.0, 1.0))


def contact_windows(orbit: CircularOrbit, station: GroundStation, theta0_rad: float,
                    duration_s: float, step_s: float = 5.0) -> list[ContactWindow]:
    """The station's passes over [0, duration_s], in time order.

    The elevation is sampled every ``step_s`` and each crossing of the mask is refined by
    Brent's method to 1 ms; a pass shorter than about ``step_s`` (a graze of the mask) can be
    missed.  A pass open at t = 0 or at the end is clipped there.
    """
    if duration_s <= 0.0 or step_s <= 0.0:
        raise ValueError(f"duration_s and step_s must be positive, got {duration_s}, {step_s}")

    def above(t: float) -> float:
        return float(elevation_rad(orbit, station, theta0_rad, np.array([t]))[0]
                     - station.mask_rad)

    t = np.append(np.arange(0.0, duration_s, step_s), duration_s)
    up = elevation_rad(orbit, station, theta0_rad, t) > station.mask_rad
    edges = np.flatnonzero(np.diff(up.astype(np.int8)))
    crossings = [brentq(above, t[k], t[k + 1], xtol=1e-3) for k in edges]
    bounds = ([0.0] if up[0] else []) + crossings + ([duration_s] if up[-1] else [])
    return [_window(orbit, station, theta0_rad, a, b)
            for a, b in zip(bounds[0::2], bounds[1::2], strict=False)]


def _window(orbit: CircularOrbit, station: GroundStation, theta0_rad: float, aos: float,
            los: float) -> ContactWindow:
    def down(t: float) -> float:
        return -float(elevation_rad(orbit, station, theta0_rad, np.array([t]))[0])

    best = minimize_scalar(down, bounds=(aos, los), method="bounded",
                           options={"xatol": 1e-2})
    return ContactWindow(station.name, float(aos), float(los), float(best.x),
                         math.degrees(-float(best.fun)))


def pass_table(orbit: CircularOrbit, stations: list[GroundStation], theta0_rad: float,
               duration_s: float, step_s: float = 5.0) -> list[ContactWindow]:
    """Every station's passes over [0, duration_s], by acquisition time."""
    windows = [w for s in stations
               for w in contact_windows(orbit, s, theta0_rad, duration_s, step_s)]
    return sorted(windows, key=lambda w: (w.aos_s, w.station))


def scenario_pass_table(scenario: Scenario) -> list[ContactWindow]:
    """The passes of a scenario's stations over its run (``[orbit]``, ``[ground]``), by
    acquisition time; none without stations."""
    o, g = scenario.orbit, scenario.ground
    orbit = CircularOrbit(R_EARTH_M + o.altitude_km * 1e3, math.radians(o.inclination_deg),
                          math.radians(o.raan_deg), math.radians(o.arg_latitude_deg), o.j2)
    stations = [GroundStation(s.name, math.radians(s.latitude_deg),
                              math.radians(s.longitude_deg), s.altitude_m,
                              math.radians(s.elevation_mask_deg)) for s in g.stations]
    return pass_table(orbit, stations, greenwich_sidereal_angle(g.epoch), scenario.duration_s)


@dataclass(frozen=True)
class ContactPlan:
    """When the ground hears the constellation: the union of every station's passes, as
    disjoint intervals [aos, los) in time order (s).  The channel stage, the ground FDIR and
    the summary read the same plan, made by :meth:`of` from the scenario."""

    windows: tuple[tuple[float, float], ...]

    @classmethod
    def of(cls, scenario: Scenario) -> ContactPlan | None:
        """The plan of a scenario with ``[ground] contact = "passes"``; None for a ground that
        hears continuously."""
        if scenario.ground.contact != "passes":
            return None
        return cls.merged(scenario_pass_table(scenario))

    @classmethod
    def merged(cls, table: list[ContactWindow]) -> ContactPlan:
        """The union of the passes of ``table`` (overlapping passes of two stations merge)."""
        out: list[tuple[float, float]] = []
        for w in sorted(table, key=lambda w: w.aos_s):
            if out and w.aos_s <= out[-1][1]:
                out[-1] = (out[-1][0], max(out[-1][1], w.los_s))
            elif w.los_s > w.aos_s:
                out.append((w.aos_s, w.los_s))
        return cls(tuple(out))

    @functools.cached_property
    def _aos(self) -> list[float]:
        return [w[0] for w in self.windows]

    def pass_index(self, t_s: float) -> int:
        """Index of the latest contact acquired at or before ``t_s`` (s), or -1 before the
        first (the contact in progress, or the last one ended)."""
        return bisect.bisect_right(self._aos, t_s) - 1

    def in_contact(self, t_s: float) -> bool:
        i = self.pass_index(t_s)
        return i >= 0 and t_s < self.windows[i][1]

    def next_contact(self, t_s: float) -> float:
        """``t_s`` if in contact then, else the next acquisition (s); inf if none follows."""
        if self.in_contact(t_s):
            return t_s
        i = self.pass_index(t_s) + 1
        return self.windows[i][0] if i < len(self.windows) else math.inf

    def uplinked_s(self, t_send_s: float) -> float:
        """When the ground's message sent at ``t_send_s`` (s) leaves for the spacecraft: at
        once in contact, and at the run's start (t = 0: loaded aboard in a pass before the
        run); else at the next acquisition (inf if none follows)."""
        return t_send_s if t_send_s <= TIME_TOL_S else self.next_contact(t_send_s)

    def contact_end(self, t_s: float) -> float:
        """The loss of signal that ends the contact at or after ``t_s`` (s); inf if none."""
        t = self.next_contact(t_s)
        if math.isinf(t):
            return t
        return self.windows[self.pass_index(t)][1]
