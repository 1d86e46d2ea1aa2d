"""The sequential test on per-image evidence (issue 41; docs/fdir.md, "The sequential test"): each
image's information gain against the nominal twin's prediction, x_k = ΔH_k / ΔH_k^pred (Eq. 9
image by image), judged the moment it arrives instead of once per FDI window.

The nominal model of the relative residual r_k = x_k / μ − 1 (μ: the hardware model's mean
ratio, ``gnc/hardware_threshold.py``) has two parts:

* b_k, the pose's effect (station keeping, the nav-aimed camera, pointing jitter), 1σ = σ_b
  (the hardware model's ``image_spreads`` over μ: an image's spread under the window's pose
  draws, at its own geometry), correlated from image to image in whatever way the loops make
  it;
* e_k, the camera's precision noise, independent per image, 1σ = σ_e (v Σw²/(Σw)² of the
  image's predicted weights, as the hardware model has it for the window).

A change of the mean by δ (Table 3: δ < 0 degraded, δ > 0 improved) is sought by a scan over
the most recent n images, n in ``lengths``: Z_n = m_n / √(σ_b² + σ_e²/n), m_n their mean
residual (the generalised likelihood ratio of a mean shift after an unknown change point,
restricted to those spans, with b the nuisance the spans share).  A fault is declared when
max_n |Z_n| exceeds c.  A shift of 20% against σ_b = 0.5% crosses on its first image; one
near σ_b needs the window's images, as Eq. 9 per window does.

c comes from the false-alarm budget, not from campaigns (:func:`scan_threshold`).  Whatever
the pose effect's correlation from image to image, the mean of n residuals has a variance of
at most σ_b² + σ_e²/n (the camera's noise is independent, and a mean of terms of 1σ σ_b has at
most σ_b), so every Z_n has at most unit variance under the model, and the union bound over
the spans makes the probability that the scan crosses at a given image at most 2 L Φ(−c).  The
budget per observer-hour over the images of an hour sets it; the mean time to a false alarm
(the average run length) is at least its inverse.  Were the pose effect constant over a
window, a lower c would do (the window is then nearly one test), but the pointing jitter is
not: in the paper's set-up consecutive images' ratios correlate at 0.55, at 0.03 five apart.

The delay's lower bound (Lorden 1971; ``../shared/REFERENCE.md``, "Detection statistics"):
no test with a mean time to false alarm of γ images has a smaller worst-case mean delay than
about log γ / D images, D = δ² / (2σ²) the per-image Kullback-Leibler divergence of the shift
(:func:`kl_gaussian_shift`, :func:`delay_bound`).  Pure functions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from numba import njit
from scipy.special import chdtrc, chdtri, ndtr, ndtri

FloatArray = npt.NDArray[np.float64]

SCAN_LENGTHS: tuple[int, ...] = (1, 2, 4, 8, 16, 32)
"""The spans (images) the scan tries: dyadic, so a shift sustained over n images is within a
factor of two of a span that matches it (the usual stand-in for every change point)."""

@dataclass(frozen=True)
class ScanResult:
    """The scan at one image: the largest |Z_n|, its signed value and its span n (images)."""

    z: float
    signed: float
    span: int


def scan_statistic(residuals: npt.ArrayLike, sigma_e: npt.ArrayLike, sigma_b: npt.ArrayLike,
                   lengths: Sequence[int] = SCAN_LENGTHS) -> ScanResult | None:
    """The scan at the newest of ``residuals`` (r_k, oldest first): for each span n of
    ``lengths`` the newest n hold, Z_n = m_n / S_n; the largest |Z_n|.  None with no residual.
    ``sigma_e``, ``sigma_b``: each image's camera and pose 1σ (relative; one value for all, or
    one per residual), and S_n² = (mean σ_b)² + Σ σ_e² / n² over the span, the bound on the
    variance of m_n whatever the pose's correlation (Minkowski)."""
    r = np.asarray(residuals, dtype=float)
    spans = np.array([n for n in lengths if n <= len(r)])
    if not len(spans):
        return None
    sum_r = np.cumsum(r[::-1])[spans - 1]
    sum_b = np.cumsum(np.broadcast_to(np.asarray(sigma_b, dtype=float), r.shape)[::-1])
    sum_e2 = np.cumsum(np.broadcast_to(np.asarray(sigma_e, dtype=float), r.shape)[::-1] ** 2)
    sd = np.sqrt((sum_b[spans - 1] / spans) ** 2 + sum_e2[spans - 1] / spans**2)
    z = sum_r / spans / sd
    best = int(np.argmax(np.abs(z)))
    return ScanResult(float(abs(z[best])), float(z[best]), int(spans[best]))


@dataclass(frozen=True)
class ImageEvidence:
    """The images' residuals r_k and camera 1σ σ_e,k (relative), for the images ``kept``
    (a mask over those given: the twin predicts something of them)."""

    residuals: FloatArray
    sigma_e: FloatArray
    kept: npt.NDArray[np.bool_]


@dataclass
class ScanBuffer:
    """One observer's newest residuals and their 1σ parts (oldest first, at most the longest
    span, :func:`scan_statistic`'s inputs), the time of the last image looked at (scored or
    passed over) and of the last one scored."""

    r: list[float] = field(default_factory=list)
    sigma_e: list[float] = field(default_factory=list)
    sigma_b: list[float] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    """the images' times (s)"""
    last_t: float = -math.inf
    scored_t: float = -math.inf
    beyond_run: int = 0
    """how many of the newest images in a row reported a pose beyond its tolerance"""

    def push(self, r: float, sigma_e: float, sigma_b: float, t: float,
             beyond: bool = False) -> None:
        """An image of time ``t`` (s) scored: its residual and 1σ parts, and whether it
        reported a pose beyond its tolerance (``beyond``)."""
        self.beyond_run = self.beyond_run + 1 if beyond else 0
        keep = max(SCAN_LENGTHS) - 1
        self.r = [*self.r[-keep:], r]
        self.sigma_e = [*self.sigma_e[-keep:], sigma_e]
        self.sigma_b = [*self.sigma_b[-keep:], sigma_b]
        self.times = [*self.times[-keep:], t]
        self.last_t = self.scored_t = t

    def scan(self) -> ScanResult | None:
        """The scan at the newest residual (:func:`scan_statistic`, compiled:
        :func:`scan_compiled`)."""
        z, signed, span = scan_compiled(np.array(self.r), np.array(self.sigma_e),
                                        np.array(self.sigma_b), _LENGTHS)
        return ScanResult(z, signed, span) if span else None


_LENGTHS = np.array(SCAN_LENGTHS, dtype=np.int64)


@njit(cache=True, error_model="numpy")  # x/0: inf or NaN, as numpy
def scan_compiled(residuals: FloatArray, sigma_e: FloatArray, sigma_b: FloatArray,
                  lengths: npt.NDArray[np.int64]) -> tuple[float, float, int]:
    """:func:`scan_statistic` of one value per residual, compiled (the same bits: the same
    sums in the same order): (max |Z_n|, its signed value, its span n), span 0 with no
    residual."""
    k = len(residuals)
    best, signed, span, nan = -1.0, 0.0, 0, False
    sum_r = sum_b = sum_e2 = 0.0
    done = 0
    for n in lengths:
        if n > k:
            continue
        while done < n:  # the newest first, as the reference's cumulative sums
            i = k - 1 - done
            sum_r += residuals[i]
            sum_b += sigma_b[i]
            sum_e2 += sigma_e[i] ** 2
            done += 1
        sd = math.sqrt((sum_b / n) ** 2 + sum_e2 / n**2)
        z = sum_r / n / sd
        if math.isnan(z) and not nan:  # numpy's argmax: the first NaN
            best, signed, span, nan = abs(z), z, n, True
        elif not nan and abs(z) > best:
            best, signed, span = abs(z), z, n
    return (best if span else 0.0), signed, span


def image_evidence(gains: FloatArray, weights: FloatArray, mean: float,
                   noise_var: float) -> ImageEvidence:
    """Each image's residual r_k = (ΔH_k / ΔH_k^pred) / μ − 1 and its camera 1σ σ_e,k =
    √(v Σ w²) / Σ w (``gnc.hardware_threshold``'s camera part, image by image); ``gains``:
    ΔH_k (K,); ``weights``: the predicted images' w = φψσ⁻¹ (K, M), whose sum is ΔH_k^pred;
    ``mean``: μ; ``noise_var``: v, the clipped noise factor's variance.  Images the twin
    predicts nothing of are dropped (no evidence)."""
    predicted = weights.sum(axis=1)
    kept = predicted > 0.0
    w = weights[kept]
    sigma_e = np.sqrt(noise_var * np.sum(w * w, axis=1)) / predicted[kept]
    return ImageEvidence(gains[kept] / predicted[kept] / mean - 1.0, sigma_e, kept)


def scan_threshold(q_image: float, lengths: Sequence[int] = SCAN_LENGTHS,
                   sides: int = 2) -> float:
    """c with ``sides`` L Φ(−c) = ``q_image``, the per-image share of the false-alarm budget,
    over the L = len(``lengths``) spans: the union bound on the probability that the scan at
    one image crosses, whatever the dependence between its spans and between images (each
    Z_n has at most unit variance under the model; ``sides`` 1 for a scan that looks one way,
    :func:`chi2_scan`).  The mean time to a false alarm is then at least 1 / ``q_image``
    images."""
    if not 0.0 < q_image < 1.0:
        raise ValueError(f"false-alarm probability must be in (0, 1), got {q_image!r}")
    return float(-ndtri(q_image / (sides * len(lengths))))


def scan_false_alarm(c: float, lengths: Sequence[int] = SCAN_LENGTHS, sides: int = 2) -> float:
    """``sides`` L Φ(−c): the bound on the probability that the scan at one image crosses
    ``c`` (:func:`scan_threshold`'s inverse)."""
    return float(sides * len(lengths) * ndtr(-c))


MIN_TAIL = 1e-300
"""The smallest upper-tail probability :func:`chi2_scan` scores (z ≈ 37): beyond, the same."""


def chi2_scan(values: npt.ArrayLike, dof: int, lengths: Sequence[int] = SCAN_LENGTHS
              ) -> ScanResult | None:
    """The scan for a growth of a statistic that is χ²(``dof``) under no fault, independent
    from value to value (the nav's NIS, one per measurement update; docs/fdir.md, "The nav's
    NIS, scanned too"): for each span n the
    newest n of ``values`` (oldest first) hold, their sum S_n is χ²(n dof), and z_n =
    Φ⁻¹(P(χ²(n dof) ≤ S_n)) is standard normal; the largest z_n, at least 0 (one-sided: only
    a growth is a fault, ``scan_threshold(q, sides=1)``; a sum below its median scores 0).
    None with no value."""
    v = np.asarray(values, dtype=float)
    spans = np.array([n for n in lengths if n <= len(v)])
    if not len(spans):
        return None
    sums = np.cumsum(v[::-1])[spans - 1]
    z = -ndtri(np.clip(chdtrc(dof * spans, sums), MIN_TAIL, 0.5))
    best = int(np.argmax(z))
    return ScanResult(float(z[best]), float(z[best]), int(spans[best]))


def chi2_span_limit(c: float, dof: int, span: int) -> float:
    """The sum of ``span`` values of a :func:`chi2_scan` at which its z_n reaches ``c``."""
    return float(chdtri(dof * span, ndtr(-c)))


def kl_gaussian_shift(delta: float, sigma: float) -> float:
    """D = δ² / (2σ²), nats per image: the Kullback-Leibler divergence of N(δ, σ²) from
    N(0, σ²)."""
    if not sigma > 0.0:
        raise ValueError(f"sigma must be positive, got {sigma!r}")
    return delta * delta / (2.0 * sigma * sigma)


def kl_nis_growth(mean_nis: float, dof: int) -> float:
    """(dof / 2)(λ − 1), nats per update, λ = ``mean_nis`` / ``dof``: the Kullback-Leibler
    divergence of a ``dof``-dimensional Gaussian innovation whose mean moved by μ, with
    μᵀS⁻¹μ = dof (λ − 1), from the zero-mean one of covariance S its filter predicts (an
    unmodelled force biases the innovations).  Of all Gaussian innovations whose NIS has that
    mean and whose covariance is no smaller than S, the largest (a covariance grown by λ
    instead gives (dof / 2)(λ − 1 − ln λ)): the bound it sets is the lowest.  0 for λ ≤ 1 (the
    NIS scan looks for a growth only)."""
    return 0.5 * max(mean_nis - dof, 0.0)


def delay_bound(gamma: float, divergence: float) -> float:
    """log γ / D (images): the smallest worst-case mean delay of any test whose mean time to a
    false alarm is γ images, for a change of per-image divergence D (Lorden 1971); inf for
    D = 0."""
    if not gamma > 1.0:
        raise ValueError(f"gamma must exceed 1, got {gamma!r}")
    return math.log(gamma) / divergence if divergence > 0.0 else math.inf
