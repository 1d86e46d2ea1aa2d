"""The ground's nominal twin (gnc/twin.py) against independent truth: the SCP plan's own
propagation, the PRO closed form, the Eq. 8 decomposition with ψ held, uniform cone sampling."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsw.lib.scp import plan_transfer
from gnc import infocost as ic
from gnc import twin as twin_module
from gnc.hcw import mean_motion
from gnc.poi import sphere_pois
from gnc.pro import Pro
from gnc.twin import (
    FlightPlan,
    Transfer,
    TwinModel,
    centre_boresights,
    delta_h,
    held_over,
    perturbed_boresights,
    plans_in_force,
    predicted_delta_h,
)
from interfaces.contracts.messages import ProAssignment, ProElements

N = mean_motion(500e3)


def test_planned_positions_follow_the_transfer_then_the_pro() -> None:
    old, new = Pro(20.0, 0.0, 0.0, 25.0, 0.0), Pro(12.0, 1.0, 0.0, 15.0, 2.0)
    t0, duration = 300.0, 600.0
    x0 = old.state(N, t0)
    xf = new.state(N, t0 + duration)
    plan = plan_transfer(N, x0, xf, duration, 30, 1e-3, 8.0)
    assert plan.converged
    tr = Transfer(plan.t_s + t0, plan.x, plan.u)
    fp = FlightPlan(t0, new, tr)
    t = np.array([t0, t0 + 7.3, t0 + 299.9, t0 + 599.0])
    np.testing.assert_allclose(fp.positions(N, t), plan.states_at(t - t0)[:, :3], atol=1e-9)
    after = np.array([t0 + duration, t0 + 1000.0])
    np.testing.assert_allclose(fp.positions(N, after), new.states(N, after)[:, :3], atol=1e-12)
    before = np.array([t0 - 50.0])
    np.testing.assert_allclose(FlightPlan(0.0, new).positions(N, before),
                               new.states(N, before)[:, :3], atol=1e-12)


def test_delta_h_is_the_change_of_the_contribution_with_psi_held() -> None:
    rng = np.random.default_rng(2)
    pos, nor = sphere_pois(300, 5.0)
    phi, w_inv = np.full(300, 1 / 300), np.full(300, 1.0)
    f0 = rng.uniform(0.0, 0.5, (3, 300))
    cams = np.array([[0.0, 0.0, -20.0], [15.0, 0.0, 5.0], [0.0, -18.0, 0.0]])
    prec = ic.precision(cams, centre_boresights(cams), pos, nor, ic.Camera())
    psi = ic.h_poi(w_inv, f0) ** 2
    f1 = f0.copy()
    f1[1] += prec[1]
    direct = (ic.agent_contributions(phi, w_inv, f1, psi=psi)
              - ic.agent_contributions(phi, w_inv, f0, psi=psi))
    assert delta_h(psi, phi, prec[1]) == pytest.approx(direct[1], rel=1e-12)
    assert np.allclose(np.delete(direct, 1), 0.0)  # isolation: nobody else moves
    assert predicted_delta_h(cams[1:2], centre_boresights(cams[1:2]), pos, nor, ic.Camera(),
                             psi, phi) == pytest.approx(direct[1], rel=1e-12)
    assert predicted_delta_h(np.zeros((0, 3)), np.zeros((0, 3)), pos, nor, ic.Camera(), psi,
                             phi) == 0.0


def test_the_twin_images_many_pointings_in_one_call_as_one_by_one() -> None:
    """``TwinModel.predicted_each`` (the threshold's draws imaged together) gives, bit for bit,
    what ``predicted`` gives each draw alone, and that is ``predicted_delta_h`` with the POIs
    validated at every call."""
    rng = np.random.default_rng(5)
    pos, nor = sphere_pois(400, 5.0)
    twin = TwinModel(pos, nor, ic.Camera(), 5.0)
    psi, phi = rng.uniform(0.1, 1.0, 400), np.full(400, 1 / 400)
    cams = np.array([[0.0, 0.0, -20.0], [15.0, 0.0, 5.0], [0.0, -18.0, 3.0]])
    tilted = [perturbed_boresights(centre_boresights(cams), 0.1, 3, rng) for _ in range(4)]
    each = twin.predicted_each(cams, tilted, psi, phi)
    assert each == [twin.predicted(cams, b, psi, phi) for b in tilted]
    assert each[0] == predicted_delta_h(cams, tilted[0], pos, nor, ic.Camera(), psi, phi)
    assert len(set(each)) == 4 and min(each) > 0.0  # four pointings, four gains
    assert twin.predicted_each(np.zeros((0, 3)), [np.zeros((0, 3))] * 2, psi, phi) == [0.0, 0.0]
    assert twin.predicted_each(cams, [], psi, phi) == []


def test_many_draws_are_imaged_a_few_at_a_time_with_the_same_gains(
        monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(8)
    pos, nor = sphere_pois(300, 5.0)
    twin = TwinModel(pos, nor, ic.Camera(), 5.0)
    psi, phi = rng.uniform(0.1, 1.0, 300), np.full(300, 1 / 300)
    cams = np.array([[0.0, 0.0, -20.0], [15.0, 0.0, 5.0]])
    tilted = list(np.split(perturbed_boresights(centre_boresights(cams), 0.1, 2, rng, draws=7),
                           7))
    together = twin.predicted_each(cams, tilted, psi, phi)
    monkeypatch.setattr(twin_module, "IMAGED_BYTES", 3 * 8 * 2 * 300)  # 3 draws a call
    assert twin.predicted_each(cams, tilted, psi, phi) == together
    with pytest.raises(ValueError, match="draws must be at least 1"):
        perturbed_boresights(centre_boresights(cams), 0.1, 2, rng, draws=0)


def test_stacked_draws_are_the_draws_one_after_the_other() -> None:
    rows = centre_boresights(np.array([[0.0, 0.0, -20.0], [15.0, 0.0, 5.0], [1.0, -18.0, 0.0]]))
    stacked = perturbed_boresights(rows, 0.05, 3, np.random.default_rng(9), draws=4)
    rng = np.random.default_rng(9)
    one_by_one = [perturbed_boresights(rows, 0.05, 3, rng) for _ in range(4)]
    assert np.array_equal(stacked, np.concatenate(one_by_one))
    single = perturbed_boresights(rows[0], 0.05, 5, np.random.default_rng(2), draws=2)
    assert single.shape == (10, 3) and np.allclose(np.linalg.norm(single, axis=1), 1.0)


def test_the_twin_refuses_pois_it_cannot_image_when_built() -> None:
    pos, nor = sphere_pois(10, 5.0)
    nor[3] = 0.0
    with pytest.raises(ValueError, match="poi_normal has a zero-length row"):
        TwinModel(pos, nor, ic.Camera(), 5.0)
    pos[2, 1] = np.nan
    with pytest.raises(ValueError, match="poi_pos contains NaN"):
        TwinModel(pos, nor, ic.Camera(), 5.0)


def test_perturbed_boresights_are_uniform_in_the_cone() -> None:
    b = np.array([0.3, -0.2, 0.9])
    b /= np.linalg.norm(b)
    eps = math.radians(5.0)
    d = perturbed_boresights(b, eps, 20000, np.random.default_rng(0))
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    ang = np.arccos(np.clip(d @ b, -1.0, 1.0))
    assert ang.max() <= eps + 1e-12
    # uniform in solid angle: P(angle ≤ eps/2) = (1 − cos(eps/2)) / (1 − cos eps) ≈ 0.25
    expect = (1 - math.cos(eps / 2)) / (1 - math.cos(eps))
    assert np.mean(ang <= eps / 2) == pytest.approx(expect, abs=0.015)
    with pytest.raises(ValueError):
        perturbed_boresights(b, 0.0, 3, np.random.default_rng(0))


def test_perturbed_boresights_one_per_row() -> None:
    rows = centre_boresights(np.array([[0.0, 0.0, -20.0], [10.0, 5.0, 0.0], [0.0, -7.0, 1.0]]))
    d = perturbed_boresights(rows, math.radians(2.0), 3, np.random.default_rng(1))
    assert np.all(np.arccos(np.clip(np.sum(d * rows, axis=1), -1, 1)) <= math.radians(2.0) + 1e-12)
    with pytest.raises(ValueError):
        perturbed_boresights(rows, 0.1, 2, np.random.default_rng(1))


def _assignment(aid: int, depart: float, arrive: float, rho_x: float) -> ProAssignment:
    return ProAssignment(spacecraft=1, assignment_id=aid, phase="science", t_depart_s=depart,
                         t_arrive_s=arrive,
                         pro=ProElements(rho_x_m=rho_x, alpha_x_rad=0.1, rho_y_m=0.0,
                                         rho_z_m=15.0, alpha_z_rad=0.2))


def test_a_plan_of_an_assignment_flies_its_pro_from_its_departure() -> None:
    a = _assignment(3, 100.0, 400.0, 12.0)
    plan = FlightPlan.of(a)
    assert (plan.t_from_s, plan.t_arrive_s, plan.transfer) == (100.0, 400.0, None)
    assert plan.pro == Pro(12.0, 0.1, 0.0, 15.0, 0.2)
    assert FlightPlan.of(a, 250.0).t_from_s == 250.0  # in force from a later contact
    hold = FlightPlan.of(_assignment(4, 100.0, 100.0, 12.0))
    assert hold.t_arrive_s is None and hold.holds_from_s == 100.0  # no transfer asked


def test_the_plan_in_force_is_the_last_to_have_started() -> None:
    first = FlightPlan.of(_assignment(1, 0.0, 0.0, 10.0))
    second = FlightPlan.of(_assignment(2, 100.0, 300.0, 12.0))
    ordered, which = plans_in_force([second, first], np.array([-1.0, 0.0, 99.0, 100.0, 500.0]))
    assert ordered == [first, second]
    assert list(which) == [-1, 0, 0, 1, 1]
    assert held_over([first, second], 0.0, 100.0) is first  # the change at b is outside
    assert held_over([first, second], 50.0, 150.0) is None  # a change of plan inside
    assert held_over([first, second], 150.0, 200.0) is None  # on the transfer to 300 s
    assert held_over([first, second], 300.0, 330.0) is second
    assert held_over([], 0.0, 30.0) is None and held_over([second], 0.0, 30.0) is None
