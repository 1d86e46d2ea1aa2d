"""The FDIR pipeline's sequential test (ground/fdir/sequential.py) on windows of images made
by the twin's own camera model: a nominal camera (the sim's multiplicative noise) never
crosses, a degraded one crosses on its first image, and the crossing declares a fault whose
class is then looked for on the images since the change the scan estimated."""

from __future__ import annotations

import logging
import math
from dataclasses import replace

import numpy as np
import pydantic
import pytest

from gnc.image_scan import Crossing
from gnc.infocost import Camera
from gnc.poi import sphere_pois
from gnc.poi_map import PoiMap
from gnc.sequential_test import ScanResult
from gnc.twin import TwinModel, centre_boresights
from ground.fdir.declaration import Declarer
from ground.fdir.identify import Evidence, Tolerances, classify, classify_part
from ground.fdir.information import IDENTIFY_IMAGES, InformationTest, Judgement, evidence_part
from ground.fdir.observer import ObserverState
from ground.fdir.sequential import SequentialTest, decided, image_false_alarm
from ground.fdir.threshold import WindowThreshold
from ground.fdir.window import SettledMap, WindowContext
from interfaces.contracts.messages import FaultReport, FdirWindow
from tests.conftest import small_scenario

NOISE = 0.05
SCENARIO = small_scenario(fdir={"detector": "sequential"}, camera={"noise_frac": NOISE})
TWIN = TwinModel(*sphere_pois(2000, 5.0), Camera(math.radians(12.0), 200.0, 1.0), 5.0)


def _arc(t: np.ndarray) -> np.ndarray:
    """The plan: an arc 20 m out, (K, 3) LVLH m at times ``t`` (s)."""
    ang = 1e-3 * t
    return np.stack([20.0 * np.cos(ang), 20.0 * np.sin(ang), 3.0 * np.ones(len(t))], axis=1)


def _score(test: SequentialTest, ctx: WindowContext) -> Crossing | None:
    """The test's score of ``ctx``, its model drawn on the plan over the whole window."""
    return test.score(ctx, _arc(test.plan_times(ctx.a, ctx.b)))


def _window(a: float, beta: list[float], rng: np.random.Generator) -> WindowContext:
    """Window [a, a + len(beta)) of one image a second on an arc 20 m out, each image seen
    by a camera of health ``beta[k]`` with the sim's noise max(0, 1 + ν ε) per POI."""
    t = a + np.arange(len(beta), dtype=float)
    planned = _arc(t)
    prec = TWIN.precision(planned, centre_boresights(planned))
    seen = []
    for p, b in zip(prec, beta, strict=True):
        poi = np.flatnonzero(p > 0.0)
        noise = np.maximum(0.0, 1.0 + NOISE * rng.standard_normal(len(poi)))
        seen.append((poi, b * p[poi] * noise))
    settled = SettledMap.of(PoiMap.uniform(len(TWIN.poi_pos), 1.0, 3))
    return WindowContext(1, a, a + len(beta), settled, [], t, planned, False, None, None, None,
                         seen, 0.0)


def test_a_nominal_camera_does_not_cross() -> None:
    test = SequentialTest(SCENARIO, TWIN, 1e-6)
    rng = np.random.default_rng(5)
    assert all(_score(test, _window(a, [1.0] * 30, rng)) is None for a in (0.0, 30.0, 60.0))
    assert test.last_scored_s(1) == 89.0
    record = test.window_fields(1, 60.0)  # what FdirWindow carries of the scan
    assert 0.0 < record["scan_z_max"] < record["scan_threshold"] == test.c
    assert 0.0 < record["image_sigma"] < NOISE  # one POI's noise, averaged over an image's
    assert "nis_scan_z_max" not in record  # no nav update came
    assert test.window_fields(1, 90.0) == {}  # nothing of it scored
    assert test.window_fields(2, 60.0) == {}


def test_a_degraded_camera_crosses_on_its_first_image() -> None:
    test = SequentialTest(SCENARIO, TWIN, 1e-6)
    rng = np.random.default_rng(6)
    assert _score(test, _window(0.0, [1.0] * 30, rng)) is None
    crossing = _score(test, _window(30.0, [1.0] * 10 + [0.8] * 20, rng))
    assert crossing is not None and crossing.image_t_s == 40.0
    assert crossing.direction == "degraded" and crossing.scan.span == 1
    assert crossing.change_s == 40.0  # the span that crossed: this image alone
    assert crossing.shift == pytest.approx(-0.2, abs=0.02)
    assert crossing.scan.z > test.c and crossing.limit < abs(crossing.shift)
    assert test.window_fields(1, 30.0)["scan_z_max"] == crossing.scan.z


def _pointing(ctx: WindowContext, error_deg: list[float]) -> WindowContext:
    """``ctx`` with the attitude reports of a loop aimed at the target's centre whose reported
    pointing error is ``error_deg`` at each image."""
    k = len(ctx.times)
    bore = centre_boresights(ctx.planned)
    att = np.column_stack([bore, np.radians(error_deg), np.zeros((k, 3)), np.full(k, 1e-4)])
    return replace(ctx, attitude=att)


def test_five_images_in_a_row_pointing_beyond_the_tolerance_declare_at_once() -> None:
    """The window test's pointing test image by image (``gnc.image_scan.POINTING_RUN``): a
    loop reporting 0.1° never crosses, nor four images at 3° then one back within 1°; from
    the image where 3° begins, the fifth crosses, its change at the first.  The pipeline
    declares it at once (the observer's own attitude), named for the pointing run."""
    test = SequentialTest(SCENARIO, TWIN, 1e-6)
    rng = np.random.default_rng(9)
    assert _score(test, _pointing(_window(0.0, [1.0] * 30, rng), [0.1] * 30)) is None
    broken = [0.1] * 10 + [3.0] * 4 + [0.5] + [3.0] * 4 + [0.1] * 11
    assert _score(test, _pointing(_window(30.0, [1.0] * 30, rng), broken)) is None
    crossing = _score(test, _pointing(_window(60.0, [1.0] * 30, rng), [0.1] * 12 + [3.0] * 18))
    assert crossing is not None and crossing.test == "pointing"
    assert crossing.image_t_s == 76.0 and crossing.change_s == 72.0
    assert crossing.direction is None and crossing.scan.span == 5
    assert crossing.shift == pytest.approx(3.0) and crossing.limit == pytest.approx(1.0)
    declarer = Declarer(SCENARIO.fdir, "ground", logging.getLogger("test"))
    report = declarer.declare_crossing(1, crossing, 90.0)
    assert report.evidence["pointing_scan"] == 1.0 and declarer.change_s(1) == 72.0
    split = SequentialTest(SCENARIO, TWIN, 1e-6)  # a run across two windows' scoring
    assert _score(split, _pointing(_window(0.0, [1.0] * 30, rng), [0.1] * 27 + [3.0] * 3)) \
        is None
    across = _score(split, _pointing(_window(30.0, [1.0] * 30, rng), [3.0] * 30))
    assert across is not None and (across.image_t_s, across.change_s) == (31.0, 27.0)
    assert across.shift == pytest.approx(3.0)


def test_a_crossing_declares_a_fault_the_windows_then_name() -> None:
    declarer = Declarer(SCENARIO.fdir, "ground", logging.getLogger("test"))
    test = SequentialTest(SCENARIO, TWIN, 1e-6)
    crossing = _score(test, _window(0.0, [0.5] * 30, np.random.default_rng(7)))
    assert crossing is not None and crossing.image_t_s == 0.0
    report = declarer.declare_crossing(1, crossing, 30.0)
    assert report.detector == "sequential" and report.fault_class is None
    assert report.t_sim == 0.0 and report.window_end_s == 30.0
    assert declarer.declared(1) and declarer.identifying(1)


def test_the_budget_is_shared_image_by_image() -> None:
    """0.01 false alarms per observer-hour, one image a second, shared by the window test,
    the window's NIS test and the two scans; without the NIS, by the window test and the
    image scan."""
    tests = InformationTest(SCENARIO, TWIN).tests
    assert tests == 4 and image_false_alarm(SCENARIO, tests) == pytest.approx(0.01 / 4 / 3600)
    assert InformationTest(small_scenario(fdir={"detector": "sequential", "fuse_nis": False},
                                          camera={"noise_frac": NOISE}), TWIN).tests == 2
    assert InformationTest(small_scenario(), TWIN).tests == 4  # the default: sequential
    window = small_scenario(fdir={"detector": "window"})
    assert InformationTest(window, TWIN).tests == 2  # the window and NIS tests


def test_an_unknown_detector_is_refused_naming_the_key() -> None:
    with pytest.raises(pydantic.ValidationError, match="detector"):
        small_scenario(fdir={"detector": "cusum"})


@pytest.mark.parametrize("budget", [0.0, -0.01, 101.0, math.nan])
def test_a_false_alarm_budget_out_of_range_is_refused_naming_the_key(budget: float) -> None:
    """The budget is per observer-hour, in (0, 100]: at 100 an image's share of it is still a
    probability (``image_false_alarm``), below 0 or at 0 no threshold exists."""
    with pytest.raises(pydantic.ValidationError, match="false_alarms_per_observer_hour"):
        small_scenario(fdir={"false_alarms_per_observer_hour": budget})


def _crossing(t: float, signed: float) -> Crossing:
    return Crossing(t, ScanResult(abs(signed), signed, 1), signed / 100.0, 0.05)


def test_a_crossing_waits_for_the_other_observers_images() -> None:
    """sc1 crossed at 12 s: declared once sc2 and sc3 are looked at up to 12 s, or at the
    window's end; an observer not scored in the window is not waited for."""
    crossings = {1: _crossing(12.0, -8.0)}
    assert decided(crossings, [1, 2, 3], {1: 12.0, 2: 14.0, 3: 11.0}, False) == []
    assert decided(crossings, [1, 2, 3], {1: 12.0, 2: 14.0, 3: 11.0}, True) == [1]
    assert decided(crossings, [1, 2, 3], {1: 12.0, 2: 14.0, 3: 12.0}, False) == [1]
    assert decided(crossings, [1, 2], {1: 12.0, 2: 14.0, 3: 0.0}, False) == [1]


def test_a_change_every_observer_sees_alike_is_left_to_the_global_check() -> None:
    both_down = {1: _crossing(12.0, -8.0), 2: _crossing(13.0, -9.0)}
    assert decided(both_down, [1, 2], {1: 12.0, 2: 13.0}, True) is None
    opposite = {1: _crossing(12.0, -8.0), 2: _crossing(13.0, 9.0)}
    assert decided(opposite, [1, 2], {1: 12.0, 2: 13.0}, True) == [1, 2]
    # sc3 saw nothing: sc1's is decided; sc2's waits for sc1's images after 12 s, which are
    # scored once sc1's crossing is decided
    assert decided(both_down, [1, 2, 3], {1: 12.0, 2: 13.0, 3: 13.0}, False) == [1]
    alone = {1: _crossing(12.0, -8.0)}
    assert decided(alone, [1], {1: 12.0}, False) == [1]  # one observer: its own fault


def test_the_nis_scan_declares_a_growing_nis_and_nothing_nominal() -> None:
    """Nominal NIS (χ²(6) draws, one a second for an hour) never crosses at 1e-6 per update;
    an unmodelled force's innovations (NIS ×30) cross within two updates, named the NIS
    scan's, with the span's mean NIS per degree above the mean it had to exceed; the window
    records its largest statistic."""
    test = SequentialTest(SCENARIO, TWIN, 1e-6)
    rng = np.random.default_rng(8)
    nominal = [(float(t), float(v)) for t, v in enumerate(rng.chisquare(6, 3600))]
    assert test.score_nis(1, nominal, True, 3570.0) is None
    record = test.window_fields(1, 3570.0)
    assert 0.0 < record["nis_scan_z_max"] < record["nis_scan_threshold"] == test.c_nis
    faulty = nominal + [(3600.0 + k, 30.0 * float(v)) for k, v in
                        enumerate(rng.chisquare(6, 5))]
    crossing = test.score_nis(1, faulty, True, 3600.0)
    assert crossing is not None and crossing.test == "nis" and crossing.direction is None
    assert 3600.0 <= crossing.image_t_s <= 3601.0 and crossing.scan.z > test.c_nis
    assert crossing.shift > crossing.limit > 1.0
    assert test.window_fields(1, 3600.0)["nis_scan_z_max"] == crossing.scan.z


def test_the_nis_scan_of_a_declared_observer_starts_afresh() -> None:
    """Updates looked at while declared are not scored, and what was held before is
    dropped: four NIS of 22 in a row cross (their mean per degree, 3.7, is beyond span 4's
    3.2 at 1e-6), not when the first two came before a declaration and the third during."""
    updates = [(float(t), 22.0) for t in range(4)]
    test = SequentialTest(SCENARIO, TWIN, 1e-6)
    assert test.score_nis(2, updates[:2], True, 0.0) is None
    assert test.score_nis(2, updates[:3], False, 0.0) is None  # declared: looked at
    assert test.score_nis(2, updates, True, 0.0) is None  # one value held: no crossing
    crossing = SequentialTest(SCENARIO, TWIN, 1e-6).score_nis(2, updates, True, 0.0)
    assert crossing is not None and crossing.image_t_s == 3.0 and crossing.scan.span == 4
    assert crossing.change_s == 0.0  # the growth began with the span's first update


def test_a_change_late_in_a_window_is_identified_on_its_images_alone() -> None:
    """A camera degraded to β = 0.75 for the last 12 images of a window: over the whole
    window the 18 nominal images before it hold the median β̂ near 1, within its margin of
    standard errors, and name nothing; the images since the change the scan estimated name
    the camera (looked at first, the whole window's still judged), and the window records
    where that evidence starts.  Fewer than ``IDENTIFY_IMAGES`` since the change: the whole
    window alone, as before."""
    ctx = _window(0.0, [1.0] * 18 + [0.75] * 12, np.random.default_rng(9))
    test, tol = InformationTest(SCENARIO, TWIN), Tolerances.of(SCENARIO.fdir)
    window = FdirWindow(sender="ground", t_sim=30.0, spacecraft=1, t_start_s=0.0, t_end_s=30.0,
                        images=30)
    whole = test.judge(ctx, ObserverState(), window, True, True)
    assert whole.window.failed == ["information"] and whole.window.evidence_since_s is None
    assert whole.part is None and classify(whole.evidence, tol, whole.window.failed) is None
    j = test.judge(ctx, ObserverState(), window, True, True, since_s=18.0)
    assert j.window.evidence_since_s == 18.0 and j.window.failed == ["information"]
    assert j.evidence == whole.evidence and j.part is not None
    assert j.part.beta_hat == pytest.approx(0.75, abs=0.05)
    assert classify_part(j.part, tol, j.window.failed) == "camera"
    declarer = Declarer(SCENARIO.fdir, "ground", logging.getLogger("test"))
    declarer.declare_crossing(1, _crossing(18.0, -8.0), 30.0)
    (verdict, report) = declarer.declare(1, j, None)
    assert isinstance(report, FaultReport) and report.fault_class == "camera"
    assert report.evidence["beta_hat"] == j.part.beta_hat  # the part's evidence named it
    assert evidence_part(ctx, 30.0 - IDENTIFY_IMAGES + 1.0) is None
    assert evidence_part(ctx, 0.0) is None  # no change within the window
    assert len(evidence_part(ctx, 18.0).times) == 12  # type: ignore[union-attr]


def test_a_part_names_nothing_while_the_nav_walks_off_a_plan_the_camera_holds() -> None:
    """A nav sensor's step being absorbed: the nav 0.46 m off the plan, the camera located
    0.09 m off it with a standard error of 0.22 m, and a seen set not the reported pose's.
    The whole window's rules would name the camera; a part names nothing until the nav is
    beyond the tolerance (the nav sensor, as the rules say) or the camera off the plan
    beyond half the tolerance and three standard errors (then the spacecraft moved: a state
    disturbance's jump, named ``actuator``)."""
    tol = Tolerances.of(SCENARIO.fdir)
    walking = Evidence(beta_hat=0.99, beta_se=0.03, camera_vs_nav_m=0.46, nav_vs_plan_m=0.46,
                       camera_vs_plan_m=0.09, camera_se_m=0.22, seen_overlap=0.77)
    assert classify(walking, tol) == "camera" and classify_part(walking, tol) is None
    walked = replace(walking, nav_vs_plan_m=0.6, camera_vs_nav_m=0.6)  # beyond the tolerance
    assert classify_part(walked, tol) == classify(walked, tol) == "state_sensor"
    jumped = replace(walking, camera_vs_plan_m=1.6, camera_vs_nav_m=1.2, camera_se_m=0.09,
                     offset_alignment=0.99)
    assert classify_part(jumped, tol) == classify(jumped, tol) == "actuator"


def test_after_a_nis_step_a_nav_walking_off_a_plan_the_camera_holds_is_the_sensor() -> None:
    """Declared on a NIS step (one update): with the NIS still failing, the nav 0.16 m off
    the plan and the camera 0.12 m off it (identify campaign, paper-late-nav-bias-0004, 10 s
    after its change) is the nav sensor; the truth's jump (the camera off by the step) or a
    drift leading the nav (the camera the farther off) is not, and neither is a NIS passed,
    a nav on its plan, or a crossing that was not a step."""
    tol = Tolerances.of(SCENARIO.fdir)
    early = Evidence(beta_hat=1.01, beta_se=0.03, camera_vs_nav_m=0.21, nav_vs_plan_m=0.16,
                     camera_vs_plan_m=0.12, camera_se_m=0.21, seen_overlap=0.9)
    assert classify_part(early, tol, ["nis"]) is None
    assert classify_part(early, tol, ["nis"], nis_span=1) == "state_sensor"
    assert classify_part(early, tol, [], nis_span=1) is None  # the NIS passes
    on_plan = replace(early, nav_vs_plan_m=0.05)
    assert classify_part(on_plan, tol, ["nis"], nis_span=1) is None
    leading = replace(early, camera_vs_plan_m=0.3)  # the truth ahead of the nav: a drift
    assert classify_part(leading, tol, ["nis"], nis_span=1) != "state_sensor"
    jumped = replace(early, camera_vs_plan_m=2.4, camera_vs_nav_m=2.3, camera_se_m=0.1,
                     offset_alignment=0.99)
    assert classify_part(jumped, tol, ["nis"], nis_span=1) == "actuator"
    declarer = Declarer(SCENARIO.fdir, "ground", logging.getLogger("test"))
    step = Crossing(12.0, ScanResult(20.0, 20.0, 1), 80.0, 7.0, test="nis")
    declarer.declare_crossing(1, step, 30.0)
    part = _part_judgement(1, early)
    report = declarer.identify_part(1, part, 22.0, 30.0)
    assert report is not None and report.fault_class == "state_sensor"
    drift = Crossing(12.0, ScanResult(7.0, 7.0, 8), 3.0, 2.0, test="nis")
    declarer.declare_crossing(2, drift, 30.0)  # not a step: the part waits
    assert declarer.identify_part(2, _part_judgement(2, early), 22.0, 30.0) is None


def test_after_a_nis_ramp_a_nav_holding_its_plan_with_the_nis_failing_is_a_force() -> None:
    """Declared by the NIS scan over 32 updates (hard campaign, late-thruster-0000: a leak of
    14% of the maximum thrust, crossing 29 s after its onset): 4 s later the nav is 0.02 m off
    the plan and the camera located 0.14 m off it, too little for the window's rules.  The
    ramp names the actuator; a step, a NIS passed, or a nav walked off its plan does not."""
    tol = Tolerances.of(SCENARIO.fdir)
    leak = Evidence(beta_hat=0.99, beta_se=0.004, camera_vs_nav_m=0.13, nav_vs_plan_m=0.02,
                    camera_vs_plan_m=0.14, camera_se_m=0.03, seen_overlap=0.99)
    assert classify(leak, tol, ["nis"]) is None
    assert classify_part(leak, tol, ["nis"], nis_span=32) == "actuator"
    assert classify_part(leak, tol, ["nis"], nis_span=1) is None  # a step
    assert classify_part(leak, tol, [], nis_span=32) is None  # the NIS passes
    walked = replace(leak, nav_vs_plan_m=0.3)
    assert classify_part(walked, tol, ["nis"], nis_span=32) is None
    declarer = Declarer(SCENARIO.fdir, "ground", logging.getLogger("test"))
    declarer.declare_crossing(1, Crossing(12.0, ScanResult(7.0, 7.0, 32), 3.0, 2.0,
                                          test="nis"), 30.0)
    report = declarer.identify_part(1, _part_judgement(1, leak), 22.0, 30.0)
    assert report is not None and report.fault_class == "actuator"


def _part_judgement(sc: int, evidence: Evidence) -> Judgement:
    """A part of a window, judged: its NIS test failed, the evidence given."""
    window = FdirWindow(sender="ground", t_sim=22.0, spacecraft=sc, t_start_s=12.0,
                        t_end_s=22.0, images=10, failed=["nis"])
    return Judgement(window, evidence, WindowThreshold(None, None, None, 0.1, "model"))


def test_a_part_of_a_window_names_the_class_at_its_last_image() -> None:
    """A fault a scan declared at 27 s, judged on its images of 28-37 s in the next window
    (``Declarer.identify_part``): evidence naming nothing keeps it unidentified; β̂ = 0.7 off
    1 by many standard errors names the camera at 37 s, in the window ending at 60 s, with
    where its evidence starts, and ends the identification (the windows look no further)."""
    declarer = Declarer(SCENARIO.fdir, "ground", logging.getLogger("test"))
    declarer.declare_crossing(1, _crossing(27.0, -8.0), 30.0)
    assert declarer.change_s(1) == 27.0
    part = FdirWindow(sender="ground", t_sim=37.0, spacecraft=1, t_start_s=28.0, t_end_s=37.0,
                      images=10, failed=["information"])
    nothing = Judgement(part, Evidence(beta_hat=0.99, beta_se=0.01), None)  # type: ignore[arg-type]
    assert declarer.identify_part(1, nothing, 37.0, 60.0) is None and declarer.identifying(1)
    camera = Judgement(part, Evidence(beta_hat=0.7, beta_se=0.01), None)  # type: ignore[arg-type]
    report = declarer.identify_part(1, camera, 37.0, 60.0)
    assert report is not None and report.fault_class == "camera" and report.t_sim == 37.0
    assert report.window_end_s == 60.0 and report.evidence["since_s"] == 28.0
    assert not declarer.identifying(1) and declarer.change_s(1) is None
    assert declarer.declared(1)  # the episode goes on


def test_a_model_drawn_before_the_plan_was_known_is_drawn_again_on_it() -> None:
    """A window whose plan is not known over its whole span when its first images are scored
    (a transfer planned after the window began): its ratio model is drawn on those images
    alone and held only until the plan is known; then drawn on the plan, once."""
    test = SequentialTest(SCENARIO, TWIN, 1e-6)
    window = _window(0.0, [1.0] * 30, np.random.default_rng(10))
    first = WindowContext(1, 0.0, 30.0, window.settled, [], window.times[:10],
                          window.planned[:10], False, None, None, None, window.seen[:10], 0.0)
    assert test.score(first, None) is None
    assert not test.modelled(1, 0.0)  # drawn on ten images: held, but not the window's
    later = WindowContext(1, 0.0, 30.0, window.settled, [], window.times[10:],
                          window.planned[10:], False, None, None, None, window.seen[10:], 0.0)
    assert test.score(later, _arc(test.plan_times(0.0, 30.0))) is None
    assert test.modelled(1, 0.0)
    assert test.window_fields(1, 0.0)["scan_z_max"] < test.c
