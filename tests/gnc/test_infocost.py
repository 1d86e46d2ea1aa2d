"""Information-cost library (gnc/infocost.py, gnc/poi.py) against independent truth:
the paper's Sec. III.F worked example computed through the library, closed forms (REFERENCE.md
"Information cost"), finite differences, a per-pair brute-force visibility check, and invariants
on random poses drawn from seeded generators."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gnc import infocost as ic
from gnc.poi import sphere_pois

# ----------------------------------------------------------------------------- POIs


@pytest.mark.parametrize("count", [1, 2, 50, 1000])
def test_sphere_pois_on_sphere_with_outward_unit_normals(count: int) -> None:
    pos, nrm = sphere_pois(count, 2.5)
    assert pos.shape == nrm.shape == (count, 3)
    np.testing.assert_allclose(np.linalg.norm(nrm, axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(pos, axis=1), 2.5, atol=1e-13)
    np.testing.assert_allclose(pos, 2.5 * nrm, atol=1e-14)


def test_sphere_pois_near_uniform() -> None:
    """Cap counts match the area fraction; nearest-neighbour spacing lies in a narrow band."""
    m, r = 2000, 1.0
    pos, nrm = sphere_pois(m, r)
    rng = np.random.default_rng(7)
    for _ in range(20):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        h = rng.uniform(0.1, 1.0)  # cap height on the unit sphere: area fraction h/2 (Archimedes)
        inside = int(np.count_nonzero(nrm @ axis >= 1.0 - h))
        # A lattice of equal-area cells: discrepancy ~ O(sqrt(M)) points along the cap rim at most.
        assert abs(inside - m * h / 2.0) <= 2.0 * math.sqrt(m)
    d2 = np.sum((pos[:, None, :] - pos[None, :, :]) ** 2, axis=-1)
    np.fill_diagonal(d2, np.inf)
    nn = np.sqrt(d2.min(axis=1))
    cell = math.sqrt(4.0 * math.pi * r * r / m)  # side of a square cell of the same area
    assert 0.6 * cell < nn.min() and nn.max() < 1.3 * cell


def test_sphere_pois_bad_input() -> None:
    for count, radius in [(0, 1.0), (-3, 1.0), (2.5, 1.0), (10, 0.0), (10, -1.0),
                          (10, float("nan"))]:
        with pytest.raises(ValueError):
            sphere_pois(count, radius)  # type: ignore[arg-type]


# ----------------------------------------------------------------------------- visibility


def _brute_visible(p: np.ndarray, b: np.ndarray, s: np.ndarray, n: np.ndarray | None,
                   cam: ic.Camera) -> np.ndarray:
    """Per-pair loop with explicit angles (arccos), an independent formulation."""
    out = np.zeros((len(p), len(s)), dtype=bool)
    for i in range(len(p)):
        bi = b[i] / np.linalg.norm(b[i])
        for j in range(len(s)):
            v = s[j] - p[i]
            d = float(np.linalg.norm(v))
            ang = math.acos(float(np.clip(bi @ v / d, -1.0, 1.0)))
            ok = ang <= cam.half_angle_rad and d <= cam.max_range_m
            if n is not None:
                ok = ok and float(n[j] @ (p[i] - s[j])) > 0.0
            out[i, j] = ok
    return out


def _look_at_target(rng: np.random.Generator, count: int, dist: tuple[float, float],
                    jitter: float) -> tuple[np.ndarray, np.ndarray]:
    """Random camera positions at a distance in ``dist`` pointing at the origin ± jitter rad."""
    u = rng.normal(size=(count, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    p = u * rng.uniform(*dist, size=(count, 1))
    b = -u + jitter * rng.normal(size=(count, 3))
    return p, b / np.linalg.norm(b, axis=1, keepdims=True)


def test_visibility_matches_brute_force() -> None:
    rng = np.random.default_rng(11)
    s, n = sphere_pois(300, 1.0)
    p, b = _look_at_target(rng, 6, (2.0, 6.0), 0.15)
    cam = ic.Camera(half_angle_rad=math.radians(15.0), max_range_m=5.0)
    for normals in (n, None):
        got = ic.visibility(p, b, s, normals, cam)
        want = _brute_visible(p, b, s, normals, cam)
        # Pairs within rounding of a boundary could legitimately differ; require none here.
        assert np.array_equal(got, want)
        assert 0 < got.sum() < got.size  # the test exercises both outcomes


def test_visibility_cases() -> None:
    """On the boresight, in range, facing: seen; back-facing, outside the cone, beyond range:
    not."""
    cam = ic.Camera(half_angle_rad=math.radians(20.0), max_range_m=10.0)
    s, n = np.array([[1.0, 0.0, 0.0]]), np.array([[1.0, 0.0, 0.0]])
    look = np.array([[-1.0, 0.0, 0.0]])

    def seen(p: list[float], b: np.ndarray = look, normals: np.ndarray | None = n) -> bool:
        return bool(ic.visibility(np.array([p]), b, s, normals, cam)[0, 0])

    assert seen([5.0, 0.0, 0.0])                      # on the boresight, 4 m, facing
    assert not seen([-5.0, 0.0, 0.0], b=-look)        # behind the sphere: back-facing
    assert seen([-5.0, 0.0, 0.0], b=-look, normals=None)  # same pose without the facing test
    assert not seen([5.0, 0.0, 0.0], b=np.array([[0.0, 1.0, 0.0]]))  # 90° off the boresight
    assert seen([10.9, 0.0, 0.0]) and not seen([11.1, 0.0, 0.0])     # range 9.9 m / 10.1 m
    # Cone edge: POI at 19.9° seen, at 20.1° not (camera 4 m away, boresight rotated in x-y).
    for deg, expected in ((19.9, True), (20.1, False)):
        a = math.radians(deg)
        b = np.array([[-math.cos(a), math.sin(a), 0.0]])
        assert seen([5.0, 0.0, 0.0], b=b) is expected
    # Grazing (n·(p − s) = 0) counts as not seen.
    assert not seen([1.0, 4.0, 0.0], b=np.array([[0.0, -1.0, 0.0]]))


def test_visibility_normalises_boresight_and_rejects_bad_input() -> None:
    cam = ic.Camera()
    s, n = sphere_pois(20, 1.0)
    p = np.array([[5.0, 0.0, 0.0]])
    a = ic.visibility(p, np.array([[-1.0, 0.0, 0.0]]), s, n, cam)
    assert np.array_equal(a, ic.visibility(p, np.array([[-7.0, 0.0, 0.0]]), s, n, cam))
    bad_calls = [
        (np.array([[np.nan, 0.0, 0.0]]), np.array([[-1.0, 0.0, 0.0]]), s, n),
        (p, np.zeros((1, 3)), s, n),
        (p, np.array([[-1.0, 0.0]]), s, n),
        (p, np.array([[-1.0, 0.0, 0.0]]), s[:, :2], n),
        (p, np.array([[-1.0, 0.0, 0.0]]), s, n[:5]),
        (np.zeros(3), np.array([[-1.0, 0.0, 0.0]]), s, n),
    ]
    for args in bad_calls:
        with pytest.raises(ValueError):
            ic.visibility(*args, cam)
    for kw in ({"half_angle_rad": 0.0}, {"half_angle_rad": 2.0}, {"max_range_m": -1.0},
               {"k": 0.0}, {"k": float("nan")}):
        with pytest.raises(ValueError):
            ic.Camera(**kw)


# ----------------------------------------------------------------------------- closed forms


def test_identical_observers_and_single_observer_closed_form() -> None:
    """N identical observers at distance d: H = φ/(w⁻¹ + N/(k d²)) (REFERENCE.md)."""
    s, n = np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]])
    phi, w_inv, k = 0.8, 0.05, 0.3
    cam = ic.Camera(k=k)
    prev = 0.0
    for d in (0.5, 3.0, 20.0, 150.0):
        for count in (1, 4):
            p = np.tile([0.0, 0.0, 1.0 + d], (count, 1))
            b = np.tile([0.0, 0.0, -1.0], (count, 1))
            f = ic.precision(p, b, s, n, cam)
            assert ic.information_cost(phi, w_inv, f) == pytest.approx(
                phi / (w_inv + count / (k * d * d)), rel=1e-12)
        one = ic.information_cost(phi, w_inv, ic.precision(p[:1], b[:1], s, n, cam))
        assert prev < one < phi / w_inv  # one observer: grows with d toward φ·w
        prev = one


def test_unseen_poi_contributes_phi_w_and_zero_prior_is_rejected() -> None:
    rng = np.random.default_rng(5)
    f = rng.uniform(0.0, 2.0, size=(3, 4))
    f[:, 2] = 0.0
    phi = np.array([0.5, 1.0, 2.0, 0.25])
    w_inv = np.array([0.1, 0.2, 0.4, 0.3])
    h = ic.h_poi(w_inv, f)
    assert h[2] == pytest.approx(1.0 / 0.4, rel=1e-15)
    keep = [0, 1, 3]
    assert ic.information_cost(phi, w_inv, f) \
        - ic.information_cost(phi[keep], w_inv[keep], f[:, keep]) \
        == pytest.approx(phi[2] / w_inv[2], rel=1e-12)
    with pytest.raises(ValueError, match="POI 2"):
        ic.information_cost(phi, 0.0, f)
    assert math.isfinite(ic.information_cost(phi[keep], 0.0, f[:, keep]))  # w⁻¹ = 0, all seen: fine
    for args in [(phi, w_inv, -f), (phi, -w_inv, f), (phi[:3], w_inv, f), (phi, w_inv, f[0]),
                 (phi, w_inv, np.full((3, 4), np.nan)), (-phi, w_inv, f)]:
        with pytest.raises(ValueError):
            ic.information_cost(*args)


# ----------------------------------------------------------------------------- invariants


def _random_case(rng: np.random.Generator, n_obs: int = 4, m: int = 400
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, ic.Camera,
                            np.ndarray, np.ndarray, np.ndarray]:
    s, n = sphere_pois(m, 1.0)
    p, b = _look_at_target(rng, n_obs, (2.0, 8.0), 0.1)
    cam = ic.Camera(half_angle_rad=math.radians(25.0), max_range_m=50.0, k=rng.uniform(0.2, 3.0))
    phi = rng.uniform(0.0, 1.0, size=m)
    w_inv = rng.uniform(0.01, 0.5, size=m)
    f = rng.uniform(0.0, 0.2, size=(n_obs, m)) * (rng.random((n_obs, m)) < 0.3)
    return p, b, s, n, cam, phi, w_inv, f


def test_decomposition_is_exact_and_observations_never_increase_cost() -> None:
    rng = np.random.default_rng(2024)
    for _ in range(25):
        p, b, s, n, cam, phi, w_inv, f = _random_case(rng)
        total = ic.information_cost(phi, w_inv, f)
        parts = ic.prior_term(phi, w_inv, f) + ic.agent_contributions(phi, w_inv, f).sum()
        assert parts == pytest.approx(total, rel=1e-12)
        new = ic.precision(p, b, s, n, cam)
        assert np.all(new >= 0.0) and new.any()
        after = ic.information_cost(phi, w_inv, f + new)
        assert after <= total
        seen = new.sum(axis=0) > 0
        assert after < total or not np.any(phi[seen] > 0)
        # one agent at a time, too
        for i in range(len(p)):
            g = f.copy()
            g[i] += new[i]
            assert ic.information_cost(phi, w_inv, g) <= total


def test_gradient_matches_central_finite_differences() -> None:
    """∂H⁺/∂p_i against central differences of information_cost (visible set unchanged)."""
    rng = np.random.default_rng(99)
    h = 1e-4
    checked = 0
    while checked < 8:
        p, b, s, n, cam, phi, w_inv, f = _random_case(rng, n_obs=3, m=300)
        vis = ic.visibility(p, b, s, n, cam)
        grad = ic.cost_gradient(p, b, s, n, cam, phi, w_inv, f)
        fd = np.zeros_like(grad)
        edge = False
        for i in range(len(p)):
            for c in range(3):
                vals = []
                for sign in (1.0, -1.0):
                    q = p.copy()
                    q[i, c] += sign * h
                    edge |= not np.array_equal(ic.visibility(q, b, s, n, cam), vis)
                    vals.append(ic.information_cost(phi, w_inv, f + ic.precision(q, b, s, n, cam)))
                fd[i, c] = (vals[0] - vals[1]) / (2.0 * h)
        if edge:  # a POI crosses a FoV edge: H is not differentiable there; draw another case
            continue
        assert vis.any()
        assert np.linalg.norm(grad - fd) <= 1e-6 * np.linalg.norm(grad)
        checked += 1


# ----------------------------------------------------------------------------- paper Sec. III.F

S_1DOF = np.array([[1.0, 1.0, 0.0], [-1.0, -1.0, 0.0]])  # Eq. 13 with a = 1
PHI, W_INV, CAM = 0.5, 0.0, ic.Camera(k=1.0)               # Eq. 22
VIS = np.ones((2, 2), dtype=bool)                          # all POIs visible (1-DOF example)
LOOK = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])        # irrelevant when VIS is given


def _obs(x: np.ndarray) -> np.ndarray:
    """One observation per agent at (x_i, 0, 0): σ⁻¹ (2, 2) through the library (Eq. 14)."""
    return ic.precision(np.column_stack((x, np.zeros(2), np.zeros(2))), LOOK, S_1DOF, None, CAM,
                        visible=VIS)


def _grad_x(x: np.ndarray) -> np.ndarray:
    """∂H/∂x_i (Eq. 17) through the library: no prior information, observations at x."""
    p = np.column_stack((x, np.zeros(2), np.zeros(2)))
    return ic.cost_gradient(p, LOOK, S_1DOF, None, CAM, PHI, W_INV, np.zeros((2, 2)),
                            visible=VIS)[:, 0]


def _cost(x: np.ndarray) -> float:
    return ic.information_cost(PHI, W_INV, _obs(x))


def test_gradient_reduces_to_paper_eq17() -> None:
    x = np.array([-1.5, 1.5])
    dx = x[:, None] - S_1DOF[None, :, 0]
    sy2 = S_1DOF[None, :, 1] ** 2
    h = 1.0 / (W_INV + np.sum(1.0 / (CAM.k * (dx ** 2 + sy2)), axis=0))   # Eq. 15
    eq17 = np.sum(PHI * 2.0 / CAM.k * h ** 2 * dx / (dx ** 2 + sy2) ** 2, axis=1)
    np.testing.assert_allclose(_grad_x(x), eq17, rtol=1e-13)
    assert np.all(np.abs(eq17) > 0.1)  # a non-degenerate example


def test_paper_actuator_fault_example() -> None:
    """Eq. 22-25: bias δ = 0.05 on agent 1 → r_1 = 1.5, H_m,1 = 0.5; r_2 = 1, H_m,2 = 0.

    ΔH_i^pred = (∂H/∂x_i)Δx_i and ΔH_i^real = (∂H/∂x_i)Δx_i^real (Eq. 18) with the gradient from
    cost_gradient.  The exact (non-linearised) ratio, moving agent i alone and differencing H,
    differs by the curvature of H and is bounded loosely.
    """
    x = np.array([-1.5, 1.5])
    dx_cmd = np.array([0.1, -0.1])                 # Eq. 22-23: agent 2 moves by −0.1
    dx_real = dx_cmd + np.array([0.05, 0.0])       # Eq. 23
    g = _grad_x(x)
    r = (g * dx_real) / (g * dx_cmd)
    hm = np.abs(1.0 - r)
    np.testing.assert_allclose(r, [1.5, 1.0], atol=1e-12)
    np.testing.assert_allclose(hm, [0.5, 0.0], atol=1e-12)
    h0 = _cost(x)
    exact = []
    for i in range(2):
        e = np.eye(2)[i]
        exact.append((_cost(x + e * dx_real[i]) - h0) / (_cost(x + e * dx_cmd[i]) - h0))
    print(f"actuator fault: linearised r = {r}, exact finite-change r = {exact}")
    assert exact[0] == pytest.approx(1.5, rel=0.10)
    assert exact[1] == pytest.approx(1.0, abs=1e-12)


def test_paper_sensor_fault_example() -> None:
    """Eq. 21, 26-27: β = 0.7 on agent 2 → r_2 = 0.7, H_m,2 = 0.3; r_1 = 1, H_m,1 = 0.

    State at t − Δt: one observation per agent at x (F0).  Over the step both agents move as
    commanded (Eq. 23 without bias) and observe again; agent 2's faulty camera delivers β σ⁻¹
    (Eq. 21).  ΔH_i is the change of agent i's contribution H_i (Eq. 8) computed with
    ``agent_contributions(..., psi=ψ_nom)``, ψ_nom = H_POI(F0)² from the nominal state at t − Δt:
    the paper's linearisation holds H_POI (i.e. ψ) fixed, so ΔH_i = Σ_s φ ψ_nom ΔF_is, linear in
    the new precision, and the ratio is exactly β.  Recomputing ψ from the faulty state instead
    (non-linearised) shifts both agents' ratios; that figure is printed and bounded loosely.
    """
    beta = 0.7
    x = np.array([-1.5, 1.5])
    x_next = x + np.array([0.1, -0.1])
    f0 = _obs(x)
    step_pred = _obs(x_next)
    step_real = step_pred * np.array([[1.0], [beta]])
    psi_nom = ic.h_poi(W_INV, f0) ** 2
    pred = ic.agent_contributions(PHI, W_INV, step_pred, psi=psi_nom)
    real = ic.agent_contributions(PHI, W_INV, step_real, psi=psi_nom)
    # consistency with the state form: H_i(F0 + step) − H_i(F0) with ψ held at ψ_nom
    np.testing.assert_allclose(
        ic.agent_contributions(PHI, W_INV, f0 + step_pred, psi=psi_nom)
        - ic.agent_contributions(PHI, W_INV, f0, psi=psi_nom), pred, rtol=1e-12)
    r = real / pred
    np.testing.assert_allclose(r, [1.0, beta], atol=1e-12)
    np.testing.assert_allclose(np.abs(1.0 - r), [0.0, 0.3], atol=1e-12)
    base = ic.agent_contributions(PHI, W_INV, f0)
    exact = (ic.agent_contributions(PHI, W_INV, f0 + step_real) - base) \
        / (ic.agent_contributions(PHI, W_INV, f0 + step_pred) - base)
    print(f"sensor fault: linearised r = {r}, psi recomputed r = {exact}")
    # With ψ recomputed the loss of agent 2's information also rescales agent 1's past
    # contribution (ψ is shared): both ratios fall below 1 (≈ 0.918 each here), so isolation
    # needs ψ held at the state of t − Δt, as above.
    assert beta < exact[1] < 1.0 and beta < exact[0] < 1.0
