"""The threshold that comes from the hardware (the chapter's future work, Sec. III.E; docs/fdir.md
"Detection and isolation"): the distribution of the ratio x = ΔH_i / ΔH_i^pred of one observer
over one FDI window when nothing is faulty, from what its judge (the ground, or a neighbour)
knows of the observer's hardware, and τ_i as its quantile for a stated false-alarm probability.

Where the nominal ratio departs from 1:

* the camera: every measured precision is β σ⁻¹ max(0, 1 + ν ε), ε ~ N(0, 1) independent per
  POI and image (``[camera] noise_frac`` = ν).  Over the window's observations, with weights
  w = φ ψ σ⁻¹ of the predicted images, x has mean m₁ and variance v Σw² / (Σw)², with m₁ and v
  the mean and variance of the clipped factor (closed form, :func:`clipped_noise_moments`);
* the position: the observer flies its plan within its station-keeping accuracy
  (``fdir.track_sigma_m`` holding a PRO, ``fdir.transfer_sigma_m`` on a transfer, 1σ per axis),
  widened by the offset from the plan its nav reports (up to the plan test's tolerance:
  :func:`position_sigma`), and its camera aims from the nav estimate, off the truth by the
  nav's reported 1σ;
* the pointing: the attitude loop's tracking jitter (``fdir.pointing_jitter_deg``, 1σ per axis)
  and the attitude knowledge the observer reports (``sigma_att_rad``).

Position and pointing errors vary slowly against a window (orbit and loop time constants), so
each draw holds one position offset and one small rotation over the whole window (the
conservative choice: no averaging over images).  The pose part is a small Monte Carlo through the
twin; the camera part is exact given the weights.  Their sum is summarised as a Gaussian
x ~ N(μ, σ²) and τ solves P(|1 − x| > τ) = q: the tail beyond the samples is the Gaussian's.
Pure functions; the window test (``gnc/window_test.py``) feeds them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.optimize import brentq
from scipy.special import ndtr

from gnc.twin import TwinModel, sample_stride

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class RatioModel:
    """x = ΔH_i / ΔH_i^pred under no fault: mean and 1σ, with the parts of the spread that come
    from the camera's noise and from the pose; ``image_spreads``: the pose's part of one
    image's ratio for each imaged pose (:func:`imaged`; 0 where the prediction sees
    nothing; empty: not drawn)."""

    mean: float
    std: float
    camera_std: float
    pose_std: float
    image_spreads: tuple[float, ...] = ()

    @property
    def image_pose_std(self) -> float:
        """The pose's part of one image's ratio, its RMS over the imaged poses the prediction
        sees (0: none), which a window's sum can average away where a tilt helps one image
        and costs another."""
        seen = [x for x in self.image_spreads if x > 0.0]
        return math.sqrt(sum(x * x for x in seen) / len(seen)) if seen else 0.0

    def threshold(self, q: float) -> float:
        """τ with P(|1 − x| > τ) = ``q`` for x ~ N(mean, std²) (0 < q < 1)."""
        if not 0.0 < q < 1.0:
            raise ValueError(f"false-alarm probability must be in (0, 1), got {q!r}")
        offset = abs(1.0 - self.mean)
        if self.std <= 0.0:
            return offset
        return float(brentq(lambda tau: self.exceedance(tau) - q, 0.0, offset + 40.0 * self.std,
                            xtol=1e-12))

    def exceedance(self, tau: float) -> float:
        """P(|1 − x| > τ) for x ~ N(mean, std²)."""
        below = ndtr((1.0 - tau - self.mean) / self.std)
        above = ndtr((self.mean - 1.0 - tau) / self.std)
        return float(below + above)

    def z(self, x: float) -> float:
        """The standardised residual (x − mean) / std of an observed ratio."""
        return (x - self.mean) / self.std if self.std > 0.0 else math.inf


def pose_spreads_at(model: RatioModel, times: np.ndarray, at: np.ndarray) -> np.ndarray:
    """σ_b (relative) at each of the image times ``at``: the larger of the model's spreads at
    the two imaged poses (``times``) about it, so an image between a quiet pose and a
    sensitive one counts as the sensitive one."""
    spreads = np.asarray(model.image_spreads) / model.mean
    if len(spreads) == 1:
        return np.full(len(at), spreads[0])
    j = np.clip(np.searchsorted(times, at), 1, len(spreads) - 1)
    return np.maximum(spreads[j - 1], spreads[j])


def clipped_noise_moments(nu: float) -> tuple[float, float]:
    """Mean and variance of Y = max(0, 1 + ν ε), ε ~ N(0, 1) (the sim's measured-precision
    factor): with a = −1/ν, E[Y] = Φ(−a) + ν φ(a) and E[Y²] = (1 + ν²) Φ(−a) + ν φ(a)."""
    if nu <= 0.0:
        return 1.0, 0.0
    a = -1.0 / nu
    tail = float(ndtr(-a))
    dens = math.exp(-0.5 * a * a) / math.sqrt(2.0 * math.pi)
    m1 = tail + nu * dens
    m2 = (1.0 + nu * nu) * tail + nu * dens
    return m1, max(m2 - m1 * m1, 0.0)


def small_rotations(vectors: FloatArray, angles: FloatArray) -> FloatArray:
    """Rotate unit ``vectors`` (K, 3) by the rotation vector ``angles`` rad, one (3,) for all
    or one per row (K, 3) (first order, renormalised: the errors are far below a radian)."""
    out = vectors + np.cross(angles, vectors)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


POSE_IMAGES = 6
"""The pose draws image at most this many of a window's planned poses, evenly spread (the
offsets are common to the window, so a few images carry its geometry)."""


def imaged(rows: npt.NDArray[Any]) -> npt.NDArray[Any]:
    """The rows of a window's planned poses (or their times) the pose draws image: every
    k-th, at most ``POSE_IMAGES``."""
    return rows[::sample_stride(len(rows), POSE_IMAGES)]


def ratio_model(twin: TwinModel, positions: FloatArray, aims: FloatArray, psi: FloatArray,
                phi: FloatArray, position_sigma_m: float, pointing_sigma_rad: float,
                noise_frac: float, samples: int, rng: np.random.Generator,
                prec: FloatArray | None = None) -> RatioModel | None:
    """The nominal distribution of x for the window's images taken from the planned
    ``positions`` (K, 3) with the camera aimed at ``aims`` (K, 3) (LVLH, m); ψ and φ as the
    prediction holds them.  ``position_sigma_m`` is the truth's 1σ per axis about the plan,
    ``pointing_sigma_rad`` the boresight's 1σ per axis about the aim; ``prec``: the
    prediction's precision (K, M) when already computed.  Returns None when the prediction
    holds no information (no threshold, no decision)."""
    weight = phi * psi
    if prec is None:
        prec = twin.precision(positions, _aimed(aims, positions))
    w = prec * weight
    total = float(w.sum())
    if not total > 0.0:
        return None
    m1, v = clipped_noise_moments(noise_frac)
    camera_var = v * float(np.sum(w * w)) / total**2
    pos, aim, imaged_prec = imaged(positions), imaged(aims), imaged(prec)
    ref = float(np.sum(imaged_prec @ weight))
    if not ref > 0.0:
        return None
    offsets = rng.normal(0.0, position_sigma_m, (samples, 1, 3))
    tilts = rng.normal(0.0, pointing_sigma_rad, (samples, 1, 3))
    true_pos = (pos[None, :, :] + offsets).reshape(-1, 3)
    bore = small_rotations(_aimed(np.tile(aim, (samples, 1)), true_pos),
                           np.repeat(tilts, len(pos), axis=1).reshape(-1, 3))  # one per draw
    per_image = (twin.precision(true_pos, bore) @ weight).reshape(samples, len(pos))
    draws = per_image.sum(axis=1) / ref
    pose_mean = float(draws.mean())
    pose_var = float(draws.var(ddof=1)) if samples > 1 else 0.0
    mean = m1 * pose_mean
    var = m1 * m1 * pose_var + camera_var * pose_mean**2
    spreads = m1 * _image_spreads(per_image, imaged_prec @ weight, pose_mean)
    return RatioModel(mean, math.sqrt(var), math.sqrt(camera_var) * abs(pose_mean),
                      m1 * math.sqrt(pose_var), tuple(float(x) for x in spreads))


def _image_spreads(per_image: FloatArray, predicted: FloatArray, mean: float) -> FloatArray:
    """Each image's RMS ratio about the window's mean ratio ``mean`` across the pose draws
    (``per_image``: samples × images of drawn gains; ``predicted``: each image's predicted
    gain): its spread and its own offset from the window's mean, about which the sequential
    test takes its residual; 0 with one draw, and where the prediction sees nothing."""
    out = np.zeros(len(predicted))
    seen = predicted > 0.0
    if per_image.shape[0] >= 2 and seen.any():
        deviation = per_image[:, seen] / predicted[seen] - mean
        out[seen] = np.sqrt(np.mean(deviation**2, axis=0))
    return out


def _aimed(aims: FloatArray, positions: FloatArray) -> FloatArray:
    """Unit boresights from ``positions`` to ``aims``."""
    los = aims - positions
    return los / np.linalg.norm(los, axis=1, keepdims=True)


def position_sigma(track_sigma_m: float, nav_sigma_m: float,
                   nav_offsets_m: FloatArray | None, tolerance_m: float) -> float:
    """1σ per axis of the truth about the plan over a window: the station-keeping spec
    (``track_sigma_m``), the nav's reported 1σ, and the per-axis RMS of the offsets from the
    plan the nav itself reports (K, 3), counted up to ``tolerance_m`` (beyond it the detector's
    plan test speaks, ``gnc/window_test.py``) -- after a transfer the loop settles onto
    its PRO for a few minutes, off it by more than the spec, and the ground sees it."""
    rms = 0.0
    if nav_offsets_m is not None and len(nav_offsets_m):
        rms = min(math.sqrt(float(np.mean(np.sum(nav_offsets_m**2, axis=1))) / 3.0), tolerance_m)
    return math.sqrt(track_sigma_m**2 + nav_sigma_m**2 + rms**2)


def window_false_alarm(per_observer_hour: float, window_s: float, persistence: int,
                       tests: int = 1) -> float:
    """Per-test false-alarm probability q for one observer's window: a budget of
    ``per_observer_hour`` false alarms per observer-hour spread over its 3600 / ``window_s``
    windows an hour (the windows correction; the constellation's rate is the budget times the
    number of observers), split evenly between ``tests`` fused tests (Bonferroni), and with a
    fault declared on ``persistence`` exceedances in a row, q = (budget per window)^(1/N)
    (windows treated as independent)."""
    if not per_observer_hour > 0.0 or not window_s > 0.0:
        raise ValueError("the false-alarm budget and the window must be positive")
    per_window = min(per_observer_hour * window_s / 3600.0, 0.5)
    return min(per_window ** (1.0 / max(persistence, 1)) / max(tests, 1), 0.5)
