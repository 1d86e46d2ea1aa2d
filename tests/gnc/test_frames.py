"""Onboard LVLH model against the simulator's truth frame (two-body chief, no J2)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from gnc import quat
from gnc.frames import lvlh_rate_lvlh, lvlh_to_eci_quat, orbit_plane_axes
from gnc.hcw import mean_motion
from sim.dynamics import RelativeTruth, circular_chief_eci, lvlh_basis


def test_onboard_lvlh_matches_truth_frame_over_an_orbit() -> None:
    alt, inc = 500e3, np.radians(51.6)
    n = mean_motion(alt)
    truth = RelativeTruth(circular_chief_eci(alt, inc), np.zeros((1, 6)), energy_match=False)
    worst = 0.0
    for _ in range(12):
        t = truth.t_s
        c_true = lvlh_basis(truth.chief_eci)           # rows: LVLH axes in ECI
        c_model = quat.to_matrix(lvlh_to_eci_quat(t, n, inc)).T
        worst = max(worst, float(np.abs(c_true - c_model).max()))
        for _ in range(10):
            truth.step(47.3, substeps=8)
    assert worst < 1e-8


def test_lvlh_rate_is_the_derivative_of_the_frame() -> None:
    n, inc, t, h = 1.1e-3, 0.7, 1234.0, 1e-3
    r0, r1 = (Rotation.from_quat(lvlh_to_eci_quat(s, n, inc)) for s in (t, t + h))
    w_lvlh = (r0.inv() * r1).as_rotvec() / h   # body (LVLH) axes rate of the frame
    assert np.allclose(w_lvlh, lvlh_rate_lvlh(n), atol=1e-12)


def test_orbit_plane_axes_are_the_columns_of_the_313_rotation_over_a_drifting_node() -> None:
    """p and q are the first two columns of R3(Ω) R1(i) (scipy's rotation, independent), for an
    array of nodes and for one."""
    inc = 0.9
    nodes = np.linspace(-3.0, 3.0, 7)
    p, q = orbit_plane_axes(np.cos(nodes), np.sin(nodes), np.cos(inc), np.sin(inc))
    for k, node in enumerate(nodes):
        r = Rotation.from_euler("ZX", [node, inc]).as_matrix()
        np.testing.assert_allclose(p[k], r[:, 0], atol=1e-15)
        np.testing.assert_allclose(q[k], r[:, 1], atol=1e-15)
    p1, q1 = orbit_plane_axes(np.cos(1.0), np.sin(1.0), np.cos(inc), np.sin(inc))
    assert p1.shape == q1.shape == (3,)
    np.testing.assert_allclose(np.cross(p1, q1), Rotation.from_euler("ZX", [1.0, inc])
                               .as_matrix()[:, 2], atol=1e-15)
