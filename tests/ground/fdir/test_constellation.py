"""The global check (ground/fdir/constellation.py): the constellation ratio's nominal model
against Monte Carlo, and the verdicts -- nominal, one faulty observer (explained by it), a
common-mode fault (no single observer explains it), two independent faults."""

from __future__ import annotations

import numpy as np
import pytest

from gnc.hardware_threshold import RatioModel
from ground.fdir.constellation import ObserverGain, constellation_check, constellation_ratio

PRED = [0.004, 0.002, 0.003, 0.005, 0.001]
MODELS = [RatioModel(1.0 + 0.002 * i, 0.01 + 0.003 * i, 0.005, 0.01) for i in range(5)]
Q = 1e-4


def _gains(ratios: list[float]) -> list[ObserverGain]:
    return [ObserverGain(i + 1, r * p, p, m)
            for i, (r, p, m) in enumerate(zip(ratios, PRED, MODELS, strict=False))]  # a few


def test_constellation_model_matches_monte_carlo() -> None:
    rng = np.random.default_rng(0)
    draws = np.array([[rng.normal(m.mean, m.std) for m in MODELS] for _ in range(40_000)])
    x = (draws * PRED).sum(axis=1) / sum(PRED)
    _, model = constellation_ratio(_gains([1.0] * 5))
    assert model.mean == pytest.approx(x.mean(), abs=3e-4)
    assert model.std == pytest.approx(x.std(), rel=0.02)


def test_nominal_window_is_not_exceeded() -> None:
    verdict = constellation_check(_gains([m.mean for m in MODELS]), Q)
    assert verdict is not None and not verdict.exceeded and not verdict.common_mode


def test_one_faulty_observer_explains_the_excess() -> None:
    ratios = [m.mean for m in MODELS]
    ratios[3] = 0.5  # the largest predicted gain: it moves the constellation ratio
    verdict = constellation_check(_gains(ratios), Q)
    assert verdict is not None and verdict.exceeded
    assert verdict.explained_by == 4 and not verdict.common_mode


def test_common_mode_fault_is_explained_by_no_observer() -> None:
    verdict = constellation_check(_gains([0.8] * 5), Q)
    assert verdict is not None and verdict.exceeded and verdict.common_mode
    assert verdict.explained_by is None
    assert verdict.ratio == pytest.approx(0.8)


def test_two_independent_faults_are_not_common_mode() -> None:
    ratios = [m.mean for m in MODELS]
    ratios[0], ratios[3] = 0.5, 0.6  # two observers off, the other three on their means + ε
    ratios[1] += 1e-3
    verdict = constellation_check(_gains(ratios), Q)
    assert verdict is not None and verdict.exceeded and not verdict.common_mode


def test_too_few_observers_give_no_verdict() -> None:
    assert constellation_check(_gains([0.8, 0.8]), Q) is None

