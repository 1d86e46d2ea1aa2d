"""The attitude apps of a fleet stepped together over rows of arrays (fsw/lib/attitude_rows.py,
``AttitudeApp.step_all``): the same bits as each app stepping alone, and a row that fails is
its own spacecraft's failure."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fsw.apps.attitude import AttitudeApp
from fsw.lib import attitude_kernels as kern
from fsw.lib import attitude_rows
from fsw.lib.attitude import scp_slew, slerp_plan
from interfaces.contracts.messages import AttitudeMeasurement, PointingTarget, StateEstimate
from interfaces.runtime.rows import Row, joined
from tests.conftest import app_alone, small_scenario


@pytest.mark.parametrize("plan", [
    scp_slew(Rotation.random(random_state=1), Rotation.random(random_state=2), 60.0, 12, 0.05),
    slerp_plan(Rotation.random(random_state=3), Rotation.random(random_state=4), 0.0, 30.0)])
def test_the_compiled_slew_sample_is_the_plans_own_to_the_bit(plan: object) -> None:
    t_s, q, phi, w = plan.nodes()  # type: ignore[attr-defined]
    for t in np.linspace(-1.0, 62.0, 251):  # before, through and after the plan
        want = plan.at_quat(t)  # type: ignore[attr-defined]
        got = attitude_rows.slew_sample(t_s, q, np.ascontiguousarray(phi), w, len(t_s),
                                        len(w), t)
        assert all(np.array_equal(a, b) for a, b in zip(want, got, strict=True)), t


def _apps(n: int) -> tuple[list[AttitudeApp], list[list[object]]]:
    sc = small_scenario("rows")
    made = [app_alone(AttitudeApp, sc, f"sc{i + 1}", i + 1) for i in range(n)]
    return [a for a, _ in made], [s for _, s in made]


def _feed(apps: list[AttitudeApp], t: float, rng: np.random.Generator, star: bool,
          target_on_self: int | None = None, aim_at: float = 0.0, seen_at: float = 0.0) -> None:
    """The same inputs to ``apps`` as to their twins: a gyro sample (a star-tracker fix with
    ``star``: the attitude pointing the boresight, to a few arcseconds, at the target
    ``seen_at`` m along x from the LVLH origin), a nav estimate and a pointing target
    ``aim_at`` m along x (on spacecraft ``target_on_self``'s own position: no line of
    sight)."""
    for i, app in enumerate(apps):
        x = [20.0 + i, 5.0, -3.0, 0.01, 0.0, 0.002]
        los = kern.los_eci(t, app.n, *app.orbit, np.array(x), t, np.array([seen_at, 0, 0.0]),
                           np.zeros(3), np.zeros(3), t)
        q = kern.repoint(np.array([0, 0, 0, 1.0]), los, app.boresight)
        app.on_sensors(AttitudeMeasurement(
            sender="sim", t_sim=t, spacecraft=i + 1, gyro_radps=rng.normal(0, 1e-5, 3).tolist(),
            star_tracker=(q + rng.normal(0, 1e-5, 4)).tolist() if star else None,
            st_sigma_cross_rad=5e-5, st_sigma_roll_rad=3e-4))
        app.on_estimate(StateEstimate(sender=f"sc{i + 1}", t_sim=t, spacecraft=i + 1, x=x,
                                      P=np.eye(6).tolist()))
        aim = x[:3] if target_on_self == i else [aim_at, 0.0, 0.0]
        app.on_target(PointingTarget(sender=f"sc{i + 1}", t_sim=t, spacecraft=i + 1,
                                     target_lvlh_m=aim))


def test_apps_stepped_together_hold_and_publish_the_bits_each_would_alone(
        monkeypatch: pytest.MonkeyPatch) -> None:
    together, sent_together = _apps(3)
    alone, sent_alone = _apps(3)
    streams = np.random.default_rng(5), np.random.default_rng(5)
    statuses: list[int] = []
    step_rows = attitude_rows.step_rows

    def counted(*args: object) -> np.ndarray:
        out = step_rows(*args)  # type: ignore[arg-type]
        statuses.extend(out.tolist())
        return out

    monkeypatch.setattr(attitude_rows, "step_rows", counted)
    for k in range(160):  # tracking; a new target from 10 s: a slew, seen done at 40 s
        t = 0.5 * k
        for apps, rng in zip((together, alone), streams, strict=True):
            _feed(apps, t, rng, star=k % 4 == 0, aim_at=0.0 if t < 10.0 else 15.0,
                  seen_at=0.0 if t < 40.0 else 15.0)
        for app in AttitudeApp.step_all(together, t):
            app.step(t)
        for app in alone:
            app.step(t)
    _assert_same(together, alone, sent_together, sent_alone)
    assert {attitude_rows.TRACKED, attitude_rows.FOLLOWED, attitude_rows.SLEW} <= set(statuses)


def _assert_same(together: list[AttitudeApp], alone: list[AttitudeApp],
                 sent_together: list[list[object]], sent_alone: list[list[object]]) -> None:
    """Each app of ``together`` holds and has published what its twin in ``alone`` has."""
    for a, b in zip(together, alone, strict=True):
        for name in AttitudeApp.CRITICAL:
            va, vb = getattr(a, name), getattr(b, name)
            if name == "slew" and va is not None:
                va, vb = va.nodes(), vb.nodes()
                assert all(np.array_equal(x, y) for x, y in zip(va, vb, strict=True)), name
            else:
                assert (np.array_equal(va, vb) if isinstance(va, np.ndarray) else va == vb), name
    for st, sa in zip(sent_together, sent_alone, strict=True):
        assert [m.model_dump(exclude={"t_wall"}) for m in st] == \
               [m.model_dump(exclude={"t_wall"}) for m in sa]  # type: ignore[attr-defined]


@pytest.mark.parametrize("ticks", [20, 80])  # while slewing, and tracking
def test_a_row_without_a_line_of_sight_fails_alone_as_it_would_and_its_mates_fly_on(
        ticks: int) -> None:
    together, sent_together = _apps(3)
    alone, sent_alone = _apps(3)
    streams = np.random.default_rng(2), np.random.default_rng(2)
    for k in range(ticks + 1):
        t, last = 0.5 * k, k == ticks  # the last at ω_mid: the estimate is reported
        for apps, rng in zip((together, alone), streams, strict=True):
            _feed(apps, t, rng, star=k % 4 == 0, target_on_self=1 if last else None)
        left = AttitudeApp.step_all(together, t)
        if last:
            assert left == [together[1]]  # its own row's failure, untouched
            assert not together[0]._meas and not together[2]._meas
        for app in left:
            if last:
                with pytest.raises(ValueError, match="no line of sight"):
                    app.step(t)
            else:
                app.step(t)
        for i, app in enumerate(alone):
            if last and i == 1:
                with pytest.raises(ValueError, match="no line of sight"):
                    app.step(t)
            else:
                app.step(t)
    _assert_same(together, alone, sent_together, sent_alone)


def test_every_learnt_field_of_the_block_is_a_critical_attribute_of_the_app() -> None:
    """The block holds the app's learnt state only in ``attitude_rows.STATE``, each field an
    attribute the app declares ``CRITICAL`` (so it is checkpointed and restored through it);
    the rest of the block is rebuilt (the plan's nodes, each cycle's inputs, constants)."""
    rows = {name: d.name for name, d in vars(AttitudeApp).items() if isinstance(d, Row)}
    assert set(rows.values()) == set(attitude_rows.STATE)
    assert set(rows) <= set(AttitudeApp.CRITICAL)
    parts = (attitude_rows.STATE, attitude_rows.NODES, attitude_rows.INPUTS,
             attitude_rows.CONSTANT)
    assert sum(len(p) for p in parts) == len(attitude_rows.SPEC)  # a partition
    apps, _ = _apps(2)
    apps[0].slew = scp_slew(Rotation.random(random_state=5), Rotation.random(random_state=6),
                            40.0, 10, 0.05)
    saved = pickle.loads(pickle.dumps(apps[0].checkpoint()))
    joined(apps)  # into the fleet's block, then restored: the nodes come back with the plan
    apps[1].restore(saved)
    for name in attitude_rows.NODES:
        assert np.array_equal(apps[1].rows.data[name][1], apps[0].rows.data[name][0]), name
