"""The window test (gnc/window_test.py) against independent truth -- the threshold's exceedance
is the false-alarm share it was asked for, the floor guard raises it, each pose test flips at
its tolerance, a window imaged as predicted has H_m = 0 and one at β = 0.5 has H_m = 0.5 (Eq.
9), the spreads are the root sum of their parts -- and, as a regression check, against the
numbers the two copies it replaced gave at 24321f4 for the same inputs: the neighbours' judge's
threshold (``fsw/lib/neighbour_judge._threshold``), the ground's
(``ground/fdir/information.InformationTest.threshold``), and their pose tests
(``neighbour_judge.pose_tests``; ``consistency.failed_tests`` of ``identify.pose_evidence``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gnc.hardware_threshold import window_false_alarm
from gnc.infocost import Camera
from gnc.poi import sphere_pois
from gnc.pro import Pro
from gnc.twin import TwinModel, aimed_boresights, centre_boresights
from gnc.window_test import (
    WindowPose,
    WindowTestSettings,
    exceeded,
    failed_tests,
    floor_guard,
    hardware_threshold,
    information,
    pose_tests,
)
from tests.conftest import small_scenario

N = 0.0011  # rad/s
PRO = Pro(10.0, 0.3, 0.0, 15.0, 1.1)
TWIN = TwinModel(*sphere_pois(2000, 5.0), Camera(math.radians(12.0), 200.0, 1.0), 5.0, 0.1)
CFG = WindowTestSettings.of(small_scenario())
TIMES = np.arange(300.0, 330.0)
PLANNED = PRO.states(N, TIMES)[:, :3]
K = len(TIMES)


def _map() -> tuple[np.ndarray, np.ndarray]:
    psi = np.random.default_rng(3).uniform(0.05, 1.0, len(TWIN.poi_pos)) ** 2
    return psi, np.ones(len(TWIN.poi_pos))


def _reported(moving: bool = False, nav_sigma_column: bool = False) -> WindowPose:
    """The pose of the captured windows: the nav 0.37 m off the plan, its 1σ 5-6 cm, the aim
    point off the target centre, attitude knowledge 1-2e-4 rad, pointing error 0.15-0.45°."""
    sigma = 0.05 + 0.01 * np.arange(K) / K
    tracking = math.radians(0.3) * (1 + 0.5 * np.sin(np.arange(K)))
    return WindowPose(PLANNED, np.tile([0.5, -0.2, 0.1], (K, 1)),
                      PLANNED + np.array([0.3, -0.1, 0.2]),
                      sigma[:, None] if nav_sigma_column else sigma, tracking,
                      1e-4 * (1 + np.arange(K) / K), moving)


def _still(nav_off_m: float = 0.0, pointing_rad: float = 0.0) -> WindowPose:
    """A pose whose statistics are exact: the plan at the origin, the nav off it along x."""
    return WindowPose(np.zeros((K, 3)), None, np.tile([nav_off_m, 0.0, 0.0], (K, 1)), None,
                      np.full(K, pointing_rad), None)


def test_the_settings_are_the_scenarios() -> None:
    scenario = small_scenario(fdir={"pointing_jitter_deg": 0.05, "fuse_guidance": False})
    cfg = WindowTestSettings.of(scenario)
    assert cfg.pointing_jitter_rad == math.radians(0.05) and not cfg.fuse_pose
    assert cfg.noise_frac == scenario.camera.noise_frac
    assert cfg.window_s == scenario.rates.fdi_period_s == 30.0
    assert cfg.false_alarm() == pytest.approx(0.01 * 30.0 / 3600.0)  # 120 windows an hour
    assert cfg.false_alarm(2) == window_false_alarm(0.01, 30.0, 1, 2)  # split between two


def test_the_threshold_exceeds_with_the_asked_probability_and_the_floor_guards_it() -> None:
    psi, phi = _map()
    pose = _reported()
    prec = TWIN.precision(PLANNED, pose.boresights())
    for q in (1e-2, 1e-4):
        hw = hardware_threshold(pose, TWIN, psi, phi, prec, CFG, q, np.random.default_rng(0))
        assert hw is not None and not hw.floored and hw.tau == hw.quantile
        assert hw.model.exceedance(hw.tau) == pytest.approx(q, rel=1e-6)
    high = WindowTestSettings.of(small_scenario(fdir={"floor": 0.5}))
    hw = hardware_threshold(pose, TWIN, psi, phi, prec, high, 1e-4, np.random.default_rng(0))
    assert hw is not None and hw.floored and hw.tau == 0.5 and hw.quantile < 0.5
    assert floor_guard(0.1, 0.2) == (0.2, True) and floor_guard(0.2, 0.2) == (0.2, False)
    far = WindowPose(PLANNED * 50.0, None, None, None, None, None)  # 1 km: nothing seen
    assert hardware_threshold(far, TWIN, psi, phi, TWIN.precision(far.planned,
                              far.boresights()), CFG, 1e-3, np.random.default_rng(0)) is None


def test_the_spreads_add_their_parts() -> None:
    pose = WindowPose(PLANNED, None, PLANNED + [0.3, 0.0, 0.4], np.full(K, 0.02),
                      np.full(K, math.radians(3.0)), np.full(K, 1e-4))
    assert pose.position_sigma(CFG) == pytest.approx(math.sqrt(
        CFG.track_sigma_m**2 + 0.02**2 + 0.25 / 3.0))  # 0.5 m off: 0.5/√3 per axis
    moving = WindowPose(PLANNED, None, None, None, None, None, moving=True)
    assert moving.position_sigma(CFG) == CFG.transfer_sigma_m
    assert pose.pointing_sigma(CFG) == pytest.approx(math.hypot(  # the error up to 1°
        CFG.pointing_jitter_rad, 1e-4, math.radians(1.0)))
    assert _still().pointing_sigma(CFG) == CFG.pointing_jitter_rad


def test_each_pose_test_flips_at_its_tolerance() -> None:
    tol = CFG.position_tol_m
    assert pose_tests(_still(nav_off_m=tol), None, CFG) == []
    assert pose_tests(_still(nav_off_m=math.nextafter(tol, 1.0)), None, CFG) == ["plan"]
    point = math.radians(CFG.pointing_tol_deg)
    assert pose_tests(_still(pointing_rad=point * (1 - 1e-12)), None, CFG) == []
    assert pose_tests(_still(pointing_rad=point * (1 + 1e-12)), None, CFG) == ["pointing"]
    dv = CFG.dv_rate_tol_mps2
    assert pose_tests(_still(), dv, CFG) == []
    assert pose_tests(_still(), math.nextafter(dv, 1.0), CFG) == ["dv_rate"]
    unreported = WindowPose(PLANNED, None, None, None, None, None)
    assert pose_tests(unreported, None, CFG) == []  # what is not reported does not fail
    off = WindowTestSettings.of(small_scenario(fdir={"fuse_guidance": False}))
    assert pose_tests(_still(nav_off_m=1.0), 1.0, off) == []


def test_a_window_imaged_as_predicted_passes_and_a_dimmed_camera_fails() -> None:
    psi, phi = _map()
    pose = WindowPose(PLANNED, None, None, None, None, None)
    rows = TWIN.precision(PLANNED, centre_boresights(PLANNED))
    for beta, h_m, failed in ((1.0, 0.0, []), (0.5, 0.5, ["information"])):
        seen = [(np.flatnonzero(r > 0), beta * r[r > 0]) for r in rows]
        info = information(seen, pose, psi, phi, TWIN)
        assert info.metric == pytest.approx(h_m, abs=1e-12)
        assert info.dh == pytest.approx(beta * info.dh_pred, rel=1e-12)
        assert failed_tests(info, 0.1, pose, None, CFG) == failed
        assert failed_tests(info, None, pose, None, CFG) == []  # no threshold: no verdict
    assert info.direction == "degraded"


@pytest.mark.parametrize(("failed", "decided", "verdict"), [
    ([], True, False), (["information"], True, True), (["pointing"], False, True),
    ([], False, None)])
def test_the_verdict(failed: list[str], decided: bool, verdict: bool | None) -> None:
    assert exceeded(failed, decided) is verdict


# --- the numbers the two copies gave at 24321f4 (regression) ---------------------------------

JUDGE_TAU = 0.06401894171272644
"""``neighbour_judge._threshold`` on ``_reported()``, the small scenario's settings, rng [7, 1]"""
GROUND = {  # InformationTest.threshold, q = 1e-3, seed 3, spacecraft 1, window at 300 s
    "hold": (0.0610039660779226, 0.9848388099258931, 0.014834532690421074),
    "transfer": (0.06398489914641832, 0.9843007602987768, 0.015624996966559732),
    "no pose": (0.011036659758249452, 1.0040375460433797, 0.0022649150652544973),
}
"""(model τ, ratio mean, ratio 1σ)"""


def test_the_neighbours_threshold_is_the_one_their_judge_gave() -> None:
    psi, phi = _map()
    pose = _reported()
    prec = TWIN.precision(PLANNED, aimed_boresights(pose.aims, PLANNED))
    hw = hardware_threshold(pose, TWIN, psi, phi, prec, CFG, CFG.false_alarm(),
                            np.random.default_rng([7, 1]))
    assert CFG.false_alarm() == 8.333333333333333e-05
    assert hw is not None and hw.tau == JUDGE_TAU


@pytest.mark.parametrize("case", sorted(GROUND))
def test_the_grounds_threshold_is_the_one_it_gave(case: str) -> None:
    psi, phi = _map()
    pose = _reported(moving=case == "transfer", nav_sigma_column=True)
    if case == "no pose":  # no attitude and no nav reports at the image times, the 1σ in
        pose = WindowPose(PLANNED, None, None, pose.nav_sigma_m, None, None)
    prec = TWIN.precision(PLANNED, pose.boresights())
    hw = hardware_threshold(pose, TWIN, psi, phi, prec, CFG, 1e-3,
                            np.random.default_rng([3, 1, 300, 1]))
    assert hw is not None and (hw.quantile, hw.model.mean, hw.model.std) == GROUND[case]


@pytest.mark.parametrize(("nav_off_m", "pointing_deg", "dv_rate", "ground"), [
    (0.3, 0.5, None, []),
    (0.6, 0.5, 1e-5, ["plan"]),
    (0.3, 1.2, None, ["pointing"]),
    (0.7, 1.5, 1.0, ["plan", "pointing", "dv_rate"]),  # the judge: the first two
])
def test_the_pose_tests_are_the_ones_both_gave(nav_off_m: float, pointing_deg: float,
                                               dv_rate: float | None, ground: list[str]) -> None:
    pose = WindowPose(PLANNED, None, PLANNED + [nav_off_m, 0.0, 0.0], None,
                      np.full(K, math.radians(pointing_deg)), None)
    assert pose_tests(pose, dv_rate, CFG) == ground
    assert pose_tests(pose, None, CFG) == [t for t in ground if t != "dv_rate"]
