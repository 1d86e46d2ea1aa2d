"""Tests of the passive-relative-orbit library (gnc.pro) against independent references.

References: the closed-form HCW STM (gnc.hcw.hcw_stm) for boundedness; a nonlinear two-body
integration in ECI (scipy solve_ivp, DOP853) for energy matching; an energy evaluated in 40-digit
decimal arithmetic; brute-force dense sampling for the distance searches; the e/i-vector formula
of D'Amico & Montenbruck (JGCD 29(3), 2006) for the radial-normal separation.
"""

from __future__ import annotations

import math
from decimal import Decimal, getcontext

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gnc.constants import MU_EARTH_M3_S2, R_EARTH_M
from gnc.hcw import drift_per_orbit, hcw_stm, mean_motion
from gnc.pro import (
    Pro,
    energy_matched_state,
    min_distance_between,
    min_distance_to_origin,
    min_radial_normal_distance,
    pro_from_state,
    pro_ring,
)
from interfaces.contracts.messages import ProElements

ALT = 500e3
A_CHIEF = R_EARTH_M + ALT
N = mean_motion(ALT)
PERIOD = 2.0 * math.pi / N


def _random_pro(rng: np.random.Generator, scale: float = 100.0) -> Pro:
    return Pro(
        float(rng.uniform(0.1, 1.0) * scale),
        float(rng.uniform(-math.pi, math.pi)),
        float(rng.uniform(-1.0, 1.0) * scale),
        float(rng.uniform(0.0, 1.0) * scale),
        float(rng.uniform(-math.pi, math.pi)),
    )


def test_the_pro_of_uplinked_elements() -> None:
    e = ProElements(rho_x_m=12.0, alpha_x_rad=0.3, rho_y_m=-1.0, rho_z_m=20.0, alpha_z_rad=1.1)
    assert Pro.of(e) == Pro(12.0, 0.3, -1.0, 20.0, 1.1)


def test_state_and_states_follow_the_pro_form() -> None:
    p = Pro(30.0, 0.4, -12.0, 20.0, -1.1)
    t = np.linspace(0.0, 2.3 * PERIOD, 17)
    batch = p.states(N, t)
    assert batch.shape == (17, 6)
    for ti, row in zip(t, batch, strict=True):
        np.testing.assert_allclose(p.state(N, float(ti)), row, rtol=0, atol=1e-12)
    # PRO form written out here, plus its derivative by central differences
    x = 30.0 * np.sin(N * t + 0.4)
    y = -12.0 + 60.0 * np.cos(N * t + 0.4)
    z = 20.0 * np.sin(N * t - 1.1)
    np.testing.assert_allclose(batch[:, :3], np.stack([x, y, z], axis=1), atol=1e-12)
    dt = 1e-3
    fd = (p.states(N, t + dt)[:, :3] - p.states(N, t - dt)[:, :3]) / (2 * dt)
    np.testing.assert_allclose(batch[:, 3:], fd, atol=1e-9)
    assert p.period_s(N) == pytest.approx(5677.0, abs=0.1)  # REFERENCE.md, 500 km
    with pytest.raises(ValueError):
        Pro(float("nan"), 0.0, 0.0, 0.0, 0.0)


def test_bounded_over_ten_orbits_under_hcw() -> None:
    rng = np.random.default_rng(1)
    for _ in range(5):
        p = _random_pro(rng)
        s0 = p.state(N, 0.0)
        scale = np.linalg.norm(np.concatenate([s0[:3], s0[3:] / N]))
        for k in range(1, 11):
            sk = hcw_stm(N, k * PERIOD) @ s0
            err = np.linalg.norm(np.concatenate([sk[:3] - s0[:3], (sk[3:] - s0[3:]) / N]))
            assert err <= 1e-9 * scale
        # and between the period multiples the STM follows the PRO form
        t = rng.uniform(0.0, 10 * PERIOD, 20)
        prop = np.einsum("tij,j->ti", hcw_stm(N, t), s0)
        np.testing.assert_allclose(prop, p.states(N, t), rtol=0, atol=1e-9 * scale)
        assert abs(drift_per_orbit(N, s0)) < 1e-12 * scale


def test_pro_from_state_round_trip() -> None:
    rng = np.random.default_rng(2)
    for _ in range(20):
        p = _random_pro(rng, scale=float(rng.uniform(1.0, 500.0)))
        t = float(rng.uniform(0.0, 5e4))
        q = pro_from_state(N, p.state(N, t), t)
        for name in ("rho_x_m", "rho_y_m", "rho_z_m"):
            assert getattr(q, name) == pytest.approx(getattr(p, name), rel=1e-9, abs=1e-9)
        for name in ("alpha_x_rad", "alpha_z_rad"):
            d = getattr(q, name) - getattr(p, name)
            assert abs(math.remainder(d, 2 * math.pi)) < 1e-9
        times = rng.uniform(-1e4, 1e5, 5)
        np.testing.assert_allclose(q.states(N, times), p.states(N, times), atol=1e-8)


def test_pro_from_state_rejects_drifting_and_bad_states() -> None:
    s = Pro(50.0, 0.3, 0.0, 40.0, 0.3).state(N, 0.0)
    drifting = s.copy()
    drifting[4] += 1e-3  # 1 mm/s off the no-drift condition: 17 m per orbit
    with pytest.raises(ValueError, match="not on a passive relative orbit"):
        pro_from_state(N, drifting)
    with pytest.raises(ValueError):
        pro_from_state(N, np.full(6, np.nan))
    with pytest.raises(ValueError):
        pro_from_state(N, np.zeros(5))
    # an energy-matched state is accepted (its HCW drift equivalent is millimetres)
    matched = energy_matched_state(s, A_CHIEF)
    assert abs(drift_per_orbit(N, matched)) > 1e-3
    q = pro_from_state(N, matched)
    assert q.rho_x_m == pytest.approx(50.0, rel=1e-9)


def _energy_residual_decimal(state: np.ndarray, a: float, mu: float) -> Decimal:
    """Deputy energy minus chief energy (m^2/s^2), in 40-digit decimal arithmetic."""
    getcontext().prec = 40
    x, y, z, vx, vy, vz = (Decimal(float(v)) for v in state)
    da, dmu = Decimal(a), Decimal(mu)
    n = (dmu / da**3).sqrt()
    r = ((da + x) ** 2 + y**2 + z**2).sqrt()
    v2 = (vx - n * y) ** 2 + (vy + n * (da + x)) ** 2 + vz**2
    return v2 / 2 - dmu / r + dmu / (2 * da)


def test_energy_matching_is_exact_to_round_off() -> None:
    rng = np.random.default_rng(3)
    for scale in (10.0, 100.0, 1000.0):
        for _ in range(5):
            s = _random_pro(rng, scale).state(N, float(rng.uniform(0, PERIOD)))
            s[3:] += rng.normal(0.0, 1e-3 * scale * N, 3)  # not necessarily on a PRO
            m = energy_matched_state(s, A_CHIEF)
            np.testing.assert_array_equal(np.delete(m, 4), np.delete(s, 4))
            # one ulp of vy (<= 4.4e-16 m/s for the 1 km orbits) moves the energy by
            # n a ulp <= 3.4e-12 m^2/s^2; the uncorrected-cancellation formula is ~1e-9 off
            assert abs(float(_energy_residual_decimal(m, A_CHIEF, MU_EARTH_M3_S2))) < 1e-11
            # the HCW state itself is off by about n a |delta|, i.e. a real correction happened
            delta = m[4] - s[4]
            assert abs(delta) > 1e-10
    with pytest.raises(ValueError):
        energy_matched_state([0, 0, 0, 0, 0, 1e5], A_CHIEF)  # 100 km/s: no bound solution


def _two_body_lvlh(state: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Nonlinear two-body truth: map the LVLH state to ECI about a circular equatorial chief
    (r_c = a (cos nt, sin nt, 0)), integrate the deputy with DOP853, map back to LVLH."""
    x, y, z, vx, vy, vz = state
    r0 = np.array([A_CHIEF + x, y, z])  # chief at (a, 0, 0) at t = 0: LVLH axes = ECI axes
    v0 = np.array([vx - N * y, vy + N * (A_CHIEF + x), vz])  # v_rel + omega x r

    def rhs(_t: float, s: np.ndarray) -> np.ndarray:
        r = s[:3]
        return np.concatenate([s[3:], -MU_EARTH_M3_S2 * r / np.linalg.norm(r) ** 3])

    sol = solve_ivp(rhs, (0.0, float(times[-1])), np.concatenate([r0, v0]), method="DOP853",
                    rtol=1e-12, atol=1e-9, t_eval=times)
    assert sol.success
    out = np.empty((times.size, 3))
    for i, (t, s) in enumerate(zip(sol.t, sol.y.T, strict=True)):
        c, sn = math.cos(N * t), math.sin(N * t)
        eci_to_lvlh = np.array([[c, sn, 0.0], [-sn, c, 0.0], [0.0, 0.0, 1.0]])
        out[i] = eci_to_lvlh @ s[:3] - np.array([A_CHIEF, 0.0, 0.0])
    return out


def test_energy_matched_pro_does_not_drift_under_two_body_truth() -> None:
    """50 m PRO at 500 km, three orbits of nonlinear two-body motion.

    The HCW-only state has a semi-major axis a_dep != a (second-order energy error), so it
    drifts along-track by -3 pi (a_dep - a) per orbit (Kepler: dn/n = -1.5 da/a).  The matched
    state has exactly the chief's energy, hence its period: the relative motion is periodic and
    the drift is zero up to the integrator's error (rtol 1e-12 on |r| = 6.9e6 m: ~1e-5 m per
    orbit), so the bound is 1e-4 m per orbit.  Measured: HCW-only -18.8 mm/orbit (prediction
    -18.76 mm), matched -1.4e-5 m/orbit.
    """
    p = Pro(50.0, 0.3, 0.0, 50.0, 0.3)
    s_hcw = p.state(N, 0.0)
    s_matched = energy_matched_state(s_hcw, A_CHIEF)
    times = PERIOD * np.arange(4.0)
    drift_hcw = (_two_body_lvlh(s_hcw, times)[-1, 1] - s_hcw[1]) / 3.0
    drift_matched = (_two_body_lvlh(s_matched, times)[-1, 1] - s_matched[1]) / 3.0

    # independent prediction of the HCW-only drift from its two-body energy
    x, y, z, vx, vy, vz = s_hcw
    v = np.array([vx - N * y, vy + N * (A_CHIEF + x), vz])
    energy = 0.5 * v @ v - MU_EARTH_M3_S2 / math.dist((A_CHIEF + x, y, z), (0, 0, 0))
    a_dep = -MU_EARTH_M3_S2 / (2.0 * energy)
    predicted = -3.0 * math.pi * (a_dep - A_CHIEF)

    assert abs(drift_hcw) > 0.01  # ~19 mm per orbit
    assert drift_hcw == pytest.approx(predicted, rel=0.02)
    assert abs(drift_matched) < 1e-4
    assert abs(drift_matched) < 0.01 * abs(drift_hcw)


def _brute_min(positions: np.ndarray) -> tuple[float, int]:
    d = np.linalg.norm(positions, axis=1)
    i = int(np.argmin(d))
    return float(d[i]), i


def test_min_distance_to_origin_against_dense_sampling() -> None:
    rng = np.random.default_rng(4)
    t = np.linspace(0.0, PERIOD, 200_001)
    pros = [_random_pro(rng) for _ in range(15)] + [
        Pro(20.0, 0.0, 0.0, 0.0, 0.0),     # in-plane ellipse about the target: min = rho_x
        Pro(10.0, 1.0, 50.0, 10.0, 1.0),   # ellipse offset along-track
        Pro(0.0, 0.0, 35.0, 0.0, 0.0),     # stationary point: constant distance
    ]
    for p in pros:
        d, t_min = min_distance_to_origin(p, N)
        brute, i = _brute_min(p.states(N, t)[:, :3])
        assert 0.0 <= t_min < PERIOD
        assert d <= brute + 1e-9
        assert d == pytest.approx(brute, abs=1e-6 * (1.0 + brute))
        assert np.linalg.norm(p.state(N, t_min)[:3]) == pytest.approx(d, abs=1e-9)
    assert min_distance_to_origin(Pro(20.0, 0.0, 0.0, 0.0, 0.0), N)[0] == pytest.approx(20.0)
    assert min_distance_to_origin(Pro(0.0, 0.0, 35.0, 0.0, 0.0), N)[0] == pytest.approx(35.0)


def test_min_distance_between_against_dense_sampling() -> None:
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, PERIOD, 200_001)
    for _ in range(10):
        a, b = _random_pro(rng), _random_pro(rng)
        d, t_min = min_distance_between(a, b, N)
        brute, _ = _brute_min(a.states(N, t)[:, :3] - b.states(N, t)[:, :3])
        assert d <= brute + 1e-9
        assert d == pytest.approx(brute, abs=1e-6 * (1.0 + brute))
        sep = np.linalg.norm(a.state(N, t_min)[:3] - b.state(N, t_min)[:3])
        assert sep == pytest.approx(d, abs=1e-9)
    ring = pro_ring(2, 30.0, 0.0, 30.0)  # opposite phases: r_b = -r_a at every instant
    d, _ = min_distance_between(ring[0], ring[1], N)
    # separation 2 |r_a|, |r_a|^2 = 1800 sin^2 + 3600 cos^2 >= 1800
    assert d == pytest.approx(2.0 * math.sqrt(1800.0))
    assert d == pytest.approx(2.0 * min_distance_to_origin(ring[0], N)[0])


def _damico_min(de: np.ndarray, di: np.ndarray) -> float:
    """D'Amico & Montenbruck (2006) minimum radial-normal distance for a*de, a*di in m."""
    num = math.sqrt(2.0) * abs(float(de @ di))
    den = math.sqrt(de @ de + di @ di + np.linalg.norm(de + di) * np.linalg.norm(de - di))
    return num / den if den > 0 else 0.0


def test_min_radial_normal_distance_against_damico_and_sampling() -> None:
    rng = np.random.default_rng(6)
    phase = np.linspace(0.0, 2.0 * math.pi, 100_001)
    cases = [_random_pro(rng) for _ in range(20)]
    cases += [Pro(30.0, 0.2, 0.0, 20.0, 0.2 + math.pi / 2),  # parallel e/i: min(rho_x, rho_z)
              Pro(30.0, 0.2, 0.0, 20.0, 0.2),                # perpendicular e/i: 0
              Pro(30.0, 0.2, 0.0, 30.0, 0.2 + 1e-6)]         # nearly perpendicular, no cancellation
    for p in cases:
        got = min_radial_normal_distance(p)
        # mapping derived in the docstring: a de = rho_x (cos phi, sin phi), phi = -alpha_x - pi/2,
        # a di = rho_z (cos theta, sin theta), theta = -alpha_z
        phi, theta = -p.alpha_x_rad - math.pi / 2, -p.alpha_z_rad
        de = p.rho_x_m * np.array([math.cos(phi), math.sin(phi)])
        di = p.rho_z_m * np.array([math.cos(theta), math.sin(theta)])
        assert got == pytest.approx(_damico_min(de, di), rel=1e-9, abs=1e-9)
        pos = p.positions_at_phase(phase)
        # compare squares: f = x^2 + z^2 is smooth (|f''| <= 2 (rho_x^2 + rho_z^2) per rad^2),
        # so the sampled minimum exceeds the true one by at most (rho_x^2 + rho_z^2) step^2 / 4
        brute2 = float(np.min(pos[:, 0] ** 2 + pos[:, 2] ** 2))
        step = phase[1] - phase[0]
        assert got**2 <= brute2 + 1e-12
        assert got**2 >= brute2 - (p.rho_x_m**2 + p.rho_z_m**2) * step**2 / 4 - 1e-12
    assert min_radial_normal_distance(cases[-3]) == pytest.approx(20.0)
    assert min_radial_normal_distance(cases[-2]) == pytest.approx(0.0, abs=1e-12)
    # sin(1e-6) * 30 m: the cancellation-free form keeps this exactly
    expected = 30.0 * 1e-6 / math.sqrt(2)
    assert min_radial_normal_distance(cases[-1]) == pytest.approx(expected, rel=1e-6)


def test_pro_ring_is_one_orbit_shifted_in_time() -> None:
    ring = pro_ring(5, 25.0, 3.0, 40.0, phase0_rad=0.7)
    assert len(ring) == 5
    t = np.linspace(0.0, PERIOD, 7)
    for i, p in enumerate(ring):
        assert p.alpha_x_rad == pytest.approx(0.7 + 2 * math.pi * i / 5)
        assert p.alpha_x_rad == p.alpha_z_rad
        # member i is member 0 seen i/5 of a period later
        np.testing.assert_allclose(p.states(N, t), ring[0].states(N, t + i * PERIOD / 5), atol=1e-9)
    with pytest.raises(ValueError):
        pro_ring(0, 1.0, 0.0, 1.0)
