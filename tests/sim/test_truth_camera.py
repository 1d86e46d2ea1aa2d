"""The sim's truth cameras: what an image sees follows the true pose, faults act as specified."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gnc.infocost import Camera, visibility
from gnc.poi import sphere_pois
from interfaces.contracts.rng import stream
from sim.camera import TruthCameras

CAM = Camera(half_angle_rad=np.radians(20.0), max_range_m=200.0, k=1.0)


def _cameras(n: int, noise: float = 0.0) -> TruthCameras:
    pos, nrm = sphere_pois(2000, 5.0)
    return TruthCameras(pos, nrm, CAM, np.array([0.0, 0.0, 1.0]), noise,
                        [stream(1, "camera", i) for i in range(1, n + 1)])


def _pointing_at_origin(r: np.ndarray) -> np.ndarray:
    """Attitudes (body -> LVLH) whose body +z looks from r at the target centre."""
    return np.array([Rotation.align_vectors([-p], [[0.0, 0.0, 1.0]])[0].as_quat() for p in r])


def test_image_sees_exactly_the_visible_pois_with_sigma_k_d2() -> None:
    cams = _cameras(2)
    r = np.array([[30.0, 0.0, 0.0], [0.0, -20.0, 10.0]])
    q = _pointing_at_origin(r)
    imgs = cams.images(r, q)
    vis = visibility(r, cams.boresights_lvlh(q), cams.poi_pos, cams.poi_normal, CAM)
    for i, img in enumerate(imgs):
        assert np.array_equal(img.poi, np.flatnonzero(vis[i]))
        d2 = np.sum((cams.poi_pos[img.poi] - r[i]) ** 2, axis=1)
        assert np.allclose(img.precision, 1.0 / (CAM.k * d2), rtol=1e-12)
        assert 0 < len(img.poi) < len(cams.poi_pos) // 2  # a hemisphere at most


def test_camera_degradation_scales_the_information_by_beta() -> None:
    cams = _cameras(1)
    r = np.array([[25.0, 5.0, -3.0]])
    q = _pointing_at_origin(r)
    nominal = cams.images(r, q)[0]
    cams.beta[0] = 0.7
    degraded = cams.images(r, q)[0]
    assert np.array_equal(nominal.poi, degraded.poi)
    assert np.allclose(degraded.precision, 0.7 * nominal.precision, rtol=1e-12)


def test_misalignment_beyond_the_field_of_view_sees_nothing_of_the_target() -> None:
    cams = _cameras(1)
    r = np.array([[40.0, 0.0, 0.0]])
    q = _pointing_at_origin(r)
    assert len(cams.images(r, q)[0].poi) > 0
    # The target (radius 5 m at 40 m) subtends 7.2°; a 30° rotation of the boresight with a
    # 20° half-angle cone leaves it entirely outside.
    cams.misalignment[0] = Rotation.from_euler("x", 30.0, degrees=True).as_quat()
    assert len(cams.images(r, q)[0].poi) == 0


def test_measurement_noise_is_unbiased_and_reproducible() -> None:
    r = np.array([[20.0, 0.0, 0.0]])
    q = _pointing_at_origin(r)
    a, b = _cameras(1, noise=0.1), _cameras(1, noise=0.1)
    clean = _cameras(1).images(r, q)[0].precision
    ratios = np.concatenate([a.images(r, q)[0].precision / clean for _ in range(20)])
    assert ratios.mean() == pytest.approx(1.0, abs=4 * 0.1 / np.sqrt(len(ratios)))
    assert ratios.std() == pytest.approx(0.1, rel=0.1)
    assert not np.array_equal(a.images(r, q)[0].precision, a.images(r, q)[0].precision)
    # the same seed gives the same first image
    assert np.array_equal(_cameras(1, noise=0.1).images(r, q)[0].precision,
                          b.images(r, q)[0].precision)


def test_compiled_and_numpy_precision_give_the_same_images() -> None:
    """The sim's cameras on the compiled precision kernel and on the numpy reference see the same
    POIs with the same quantised precisions, noise included, over poses that cross the cone,
    range and horizon boundaries (200 seeded draws, 5 observers each)."""
    rng = np.random.default_rng(11)
    fast, ref = _cameras(5, noise=0.05), _cameras(5, noise=0.05)
    ref.compiled = False
    seen = 0
    for _ in range(200):
        r = rng.normal(size=(5, 3))
        r *= rng.uniform(6.0, 260.0, (5, 1)) / np.linalg.norm(r, axis=1, keepdims=True)
        q = Rotation.random(5, random_state=rng).as_quat()  # most look away, some graze
        q[:3] = _pointing_at_origin(r[:3])
        for a, b in zip(fast.images(r, q), ref.images(r, q), strict=True):
            assert np.array_equal(a.poi, b.poi) and np.array_equal(a.precision, b.precision)
            seen += len(a.poi)
    assert seen > 10_000  # the draws did see POIs
