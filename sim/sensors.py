"""Sensor models of the sim (the hardware stand-in)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class RelNavSensor:
    """Relative navigation sensor of one observer: true LVLH position and velocity plus white
    Gaussian noise of standard deviations ``sigma_r_m`` (m) and ``sigma_v_mps`` (m/s), drawn from
    the observer's own seeded generator (so adding an observer does not change the others' noise).
    """

    sigma_r_m: float
    sigma_v_mps: float
    rng: np.random.Generator

    def measure(self, r_true_m: np.ndarray, v_true_mps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Noisy (position m, velocity m/s) of a true relative state."""
        noise = self.rng.standard_normal(6)
        return (r_true_m + self.sigma_r_m * noise[:3], v_true_mps + self.sigma_v_mps * noise[3:])

