"""The hardware threshold (gnc/hardware_threshold.py) against independent truth: the
sim's own cameras imaging the same poses (sim/camera.py), brute-force Monte Carlo of the clipped
noise, and the normal distribution's quantiles."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import norm

from gnc.hardware_threshold import (
    RatioModel,
    clipped_noise_moments,
    pose_spreads_at,
    position_sigma,
    ratio_model,
    small_rotations,
    window_false_alarm,
)
from gnc.infocost import Camera
from gnc.poi import sphere_pois
from gnc.twin import TwinModel, centre_boresights, delta_h
from interfaces.contracts.rng import stream
from sim.camera import TruthCameras

CAM = Camera(math.radians(12.0), 200.0, 1.0)


def _twin() -> TwinModel:
    return TwinModel(*sphere_pois(2000, 5.0), CAM, 5.0)


def _window(k: int = 30) -> np.ndarray:
    """Planned positions of a window: an arc at 20 m from the target centre."""
    ang = np.linspace(0.0, 0.4, k)
    return np.stack([20.0 * np.cos(ang), 20.0 * np.sin(ang), 3.0 * np.ones(k)], axis=1)


def _map(twin: TwinModel) -> tuple[np.ndarray, np.ndarray]:
    """ψ and φ of a partly inspected map: uneven, so the weights are not all alike."""
    rng = np.random.default_rng(3)
    psi = rng.uniform(0.05, 1.0, len(twin.poi_pos)) ** 2
    return psi, np.ones(len(twin.poi_pos))


@pytest.mark.parametrize("nu", [0.05, 0.2, 0.5, 0.9])
def test_clipped_noise_moments_match_monte_carlo(nu: float) -> None:
    y = np.maximum(0.0, 1.0 + nu * np.random.default_rng(0).standard_normal(2_000_000))
    m1, v = clipped_noise_moments(nu)
    assert m1 == pytest.approx(y.mean(), abs=3e-3 * max(nu, 0.1))
    assert v == pytest.approx(y.var(), rel=1e-2)
    assert clipped_noise_moments(0.0) == (1.0, 0.0)


def test_threshold_is_the_two_sided_normal_quantile() -> None:
    model = RatioModel(mean=1.0, std=0.01, camera_std=0.01, pose_std=0.0)
    for q in (1e-2, 1e-4, 1e-6):
        tau = model.threshold(q)
        assert tau == pytest.approx(0.01 * norm.ppf(1.0 - q / 2.0), rel=1e-6)
        assert model.exceedance(tau) == pytest.approx(q, rel=1e-6)
    shifted = RatioModel(mean=0.97, std=0.01, camera_std=0.01, pose_std=0.0)
    tau = shifted.threshold(1e-4)  # one tail dominates: 0.03 + z(1e-4) σ
    assert tau == pytest.approx(0.03 + 0.01 * norm.ppf(1.0 - 1e-4), rel=1e-4)
    assert RatioModel(0.98, 0.0, 0.0, 0.0).threshold(1e-3) == pytest.approx(0.02)
    with pytest.raises(ValueError):
        model.threshold(0.0)


def _sim_ratios(twin: TwinModel, pos: np.ndarray, psi: np.ndarray, phi: np.ndarray,
                nu: float, trials: int) -> np.ndarray:
    """ΔH/ΔH_pred of ``trials`` windows imaged by the sim's cameras at the planned poses."""
    bore = centre_boresights(pos)
    q = np.array([Rotation.align_vectors([b], [[0.0, 0.0, 1.0]])[0].as_quat() for b in bore])
    cams = TruthCameras(twin.poi_pos, twin.poi_normal, CAM, np.array([0.0, 0.0, 1.0]), nu,
                        [stream(7, "camera", i) for i in range(len(pos))])
    pred = twin.predicted(pos, bore, psi, phi)
    out = []
    for _ in range(trials):
        images = cams.images(pos, q)
        out.append(sum(delta_h(psi[im.poi], phi[im.poi], im.precision) for im in images) / pred)
    return np.array(out)


@pytest.mark.parametrize("nu", [0.05, 0.5])
def test_camera_part_matches_the_sims_cameras(nu: float) -> None:
    """With the pose exact, the model's mean and spread are those of the sim's noisy cameras."""
    twin = _twin()
    pos = _window(12)
    psi, phi = _map(twin)
    model = ratio_model(twin, pos, np.zeros_like(pos), psi, phi, 1e-9, 1e-12, nu, 4,
                        np.random.default_rng(0))
    assert model is not None
    x = _sim_ratios(twin, pos, psi, phi, nu, 300)
    assert model.pose_std < 1e-6
    assert model.mean == pytest.approx(x.mean(), abs=4.0 * x.std() / math.sqrt(len(x)))
    assert model.std == pytest.approx(x.std(ddof=1), rel=0.15)


POSE_ERRORS = (0.3, math.radians(0.5))
"""Position (m) and pointing (rad) 1σ per axis of the pose tests below."""


def _pose_model(k: int) -> tuple[TwinModel, np.ndarray, np.ndarray, np.ndarray, RatioModel]:
    """The ratio model of a k-image window under ``POSE_ERRORS`` alone (400 draws), with the
    twin, positions and map it was drawn on."""
    twin = _twin()
    pos = _window(k)
    psi, phi = _map(twin)
    model = ratio_model(twin, pos, np.zeros_like(pos), psi, phi, *POSE_ERRORS, 0.0, 400,
                        np.random.default_rng(1))
    assert model is not None
    return twin, pos, psi, phi, model


def test_pose_part_matches_brute_force_offsets() -> None:
    """The pose spread equals the spread of the exact ratio under the same position and
    pointing errors, drawn by hand with the sim's geometry (no camera noise)."""
    twin, pos, psi, phi, model = _pose_model(10)
    sigma_p, sigma_b = POSE_ERRORS
    assert model.camera_std == 0.0
    rng = np.random.default_rng(2)
    pred = twin.predicted(pos, centre_boresights(pos), psi, phi)
    x = []
    for _ in range(400):
        p = pos + rng.normal(0.0, sigma_p, 3)
        b = small_rotations(centre_boresights(p), rng.normal(0.0, sigma_b, 3))
        x.append(twin.predicted(p, b, psi, phi) / pred)
    assert model.pose_std == pytest.approx(np.std(x, ddof=1), rel=0.2)
    assert model.mean == pytest.approx(np.mean(x), abs=3.0 * np.std(x) / 20.0)
    assert model.pose_std > 0.005  # the errors matter at this geometry


def test_an_images_pose_part_matches_brute_force_offsets() -> None:
    """Each image's spread about the window's mean ratio under the window's pose errors (what
    the sequential test takes for one image), RMS over the window's images, against the same
    errors drawn by hand."""
    twin, pos, psi, phi, model = _pose_model(6)
    sigma_p, sigma_b = POSE_ERRORS
    rng = np.random.default_rng(2)
    pred = np.array([twin.predicted(pos[k:k + 1], centre_boresights(pos[k:k + 1]), psi, phi)
                     for k in range(len(pos))])
    x = []
    for _ in range(400):
        p = pos + rng.normal(0.0, sigma_p, 3)
        b = small_rotations(centre_boresights(p), rng.normal(0.0, sigma_b, 3))
        x.append([twin.predicted(p[k:k + 1], b[k:k + 1], psi, phi) / pred[k]
                  for k in range(len(pos))])
    ratios = np.array(x)
    window = ratios @ pred / pred.sum()  # each draw's window ratio
    rms = math.sqrt(float(np.mean((ratios - window.mean()) ** 2)))
    assert model.image_pose_std == pytest.approx(rms, rel=0.2)
    assert model.image_spreads and len(model.image_spreads) == len(pos)
    assert model.image_pose_std >= model.pose_std * 0.9  # a sum averages, an image does not


def test_no_information_gives_no_model() -> None:
    twin = _twin()
    pos = _window(5) * 50.0  # 1 km away: out of range
    psi, phi = _map(twin)
    assert ratio_model(twin, pos, np.zeros_like(pos), psi, phi, 0.1, 1e-3, 0.05, 4,
                       np.random.default_rng(0)) is None


def test_window_false_alarm_budget() -> None:
    # 0.01 per observer-hour over 36 windows an hour: 2.78e-4 per window
    assert window_false_alarm(0.01, 100.0, 1) == pytest.approx(0.01 / 36.0)
    # two windows in a row: the square root
    assert window_false_alarm(0.01, 100.0, 2) == pytest.approx(math.sqrt(0.01 / 36.0))
    assert window_false_alarm(0.01, 100.0, 1, tests=2) == pytest.approx(0.01 / 72.0)
    with pytest.raises(ValueError):
        window_false_alarm(0.0, 100.0, 1)


def test_position_sigma_adds_the_reported_offsets_up_to_the_tolerance() -> None:
    assert position_sigma(0.05, 0.0, None, 0.5) == pytest.approx(0.05)
    assert position_sigma(0.03, 0.04, None, 0.5) == pytest.approx(0.05)
    offsets = np.tile([0.3, 0.0, 0.4], (10, 1))  # 0.5 m off: 0.5/√3 per axis
    assert position_sigma(0.0, 0.0, offsets, 0.5) == pytest.approx(0.5 / math.sqrt(3.0))
    assert position_sigma(0.0, 0.0, 10.0 * offsets, 0.5) == pytest.approx(0.5)  # capped


def test_an_image_takes_the_larger_pose_spread_of_the_poses_about_it() -> None:
    model = RatioModel(1.0, 0.02, 0.001, 0.02, (0.01, 0.03, 0.02))
    times = np.array([0.0, 10.0, 20.0])
    at = np.array([0.0, 5.0, 15.0, 25.0])
    assert np.allclose(pose_spreads_at(model, times, at), [0.03, 0.03, 0.03, 0.03])
    quiet = RatioModel(2.0, 0.02, 0.001, 0.02, (0.01, 0.01, 0.04))
    assert np.allclose(pose_spreads_at(quiet, times, at), [0.005, 0.005, 0.02, 0.02])
    assert np.allclose(pose_spreads_at(RatioModel(1.0, 0.0, 0.0, 0.0, (0.02,)),
                                       times[:1], at), 0.02)
