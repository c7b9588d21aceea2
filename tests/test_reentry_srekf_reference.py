"""The reentry-srekf reference (solutions.reentry_srekf.reference) and its framework (course.starship),
checked against independent oracles: physics tables, the handout's closed forms, finite and
complex-step differences, the dense-covariance Gaussian formulas and a dense EKF."""

from __future__ import annotations

import ast
import contextlib
import io
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

from course import starship  # noqa: E402
from random_draws import random_draws  # noqa: E402
from course.starship import G, L, M, P0, R, RADAR_R1, RADAR_R2, SIGMA_RANGE, T0  # noqa: E402
from solutions.reentry_srekf.hidden_tests import BLANKS  # noqa: E402
from solutions.reentry_srekf import reference as ref  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


# ---------------------------------------------------------------------------------------------
# Independent oracles
# ---------------------------------------------------------------------------------------------
def f_oracle(x: np.ndarray) -> np.ndarray:
    """Equations (3) and (10) in the exp-log form of (9); works on complex x (complex step)."""
    h, v, c = x
    exponent = G * M / (R * L)
    p = P0 * np.exp(exponent * np.log(1 - L * h / T0))
    d = 0.5 * (M * P0 / R) * (1 / (T0 - L * h)) * (p / P0) * v * v * c
    return np.array([v, d - G, 0 * h])


def complex_step_jacobian(fun, x: np.ndarray, step: float = 1e-30) -> np.ndarray:
    """Jacobian of fun at x to machine precision: J[:, j] = Im f(x + i h e_j) / h."""
    x = np.asarray(x, dtype=float)
    columns = []
    for j in range(x.size):
        xc = x.astype(complex)
        xc[j] += 1j * step
        columns.append(np.imag(fun(xc)) / step)
    return np.column_stack(columns)


def central_difference_jacobian(fun, x: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """Central differences (f(x + s e_j) - f(x - s e_j)) / (2 s) with the absolute steps s_j."""
    x = np.asarray(x, dtype=float)
    columns = []
    for j in range(x.size):
        step = steps[j]
        e = np.zeros_like(x)
        e[j] = step
        columns.append((np.asarray(fun(x + e)) - np.asarray(fun(x - e))) / (2 * step))
    return np.column_stack(columns)


def rk4_oracle(z: np.ndarray, dt: float) -> np.ndarray:
    """One RK4 step of dx = f(x) dt + dw with the increment in every stage (the issue's text)."""
    x, w = z[:3], z[3:]
    k1 = f_oracle(x)
    k2 = f_oracle(x + (k1 * dt + w) / 2)
    k3 = f_oracle(x + (k2 * dt + w) / 2)
    k4 = f_oracle(x + k3 * dt + w)
    return x + dt * (k1 + 2 * k2 + 2 * k3 + k4) / 6 + w


# Steps for central differences of f and the range in (h [m], v [m/s], c [m^2/kg]). f is quadratic in v
# and linear in c, and the range does not depend on them, so central differences are exact there up to
# rounding, which a large step keeps small: at most u |f| / s = 1.1e-16 x 1200 / 1e-4 ~ 1e-9 in c's column.
# In h the functions vary on scales of (T0 - L h) / (L 5.26) > 4 km (pressure) and 5 km (range): the
# truncation (s / 4 km)^2 / 6 < 1e-8 relative for s = 1 m, and the rounding u |f| / s < 1e-12. (Steps
# relative to x, 1e-6 |x|, gave rounding errors above rtol 1e-6 for states near v = 0, c = 0 or h = 0.)
FD_STEPS = np.array([1.0, 1.0, 1e-4])


def random_upper_sqrt(rng: np.random.Generator, n: int, scales: np.ndarray | None = None) -> np.ndarray:
    """A random upper-triangular square root of a well-conditioned SPD matrix."""
    A = rng.standard_normal((n, n)) + n * np.eye(n)
    S = np.linalg.qr(A, mode="r")
    if scales is not None:
        S = S * scales[None, :]
    return S


def assert_upper_triangular(S: np.ndarray) -> None:
    assert np.array_equal(S, np.triu(S)), f"not upper triangular:\n{S}"


def assert_cov_close(P: np.ndarray, P_expected: np.ndarray, rtol: float) -> None:
    """|P - P_expected|_ij <= rtol sqrt(P_ii P_jj): relative error on the correlation scale."""
    scale = np.sqrt(np.outer(np.diag(P_expected), np.diag(P_expected)))
    err = np.abs(P - P_expected)
    assert np.all(err <= rtol * scale + 1e-300), f"max relative error {np.max(err / (scale + 1e-300)):.3g}"


def index_sets(rng: np.random.Generator, n: int) -> list[tuple[str, np.ndarray]]:
    k = int(rng.integers(1, n))  # 1 <= k < n
    perm = rng.permutation(n)
    start = int(rng.integers(0, n - k + 1))
    return [
        ("head", np.arange(k)),
        ("tail", np.arange(k, n)),
        ("segment", np.arange(start, start + k)),
        ("non-contiguous, shuffled", perm[:k]),
        ("non-ascending", np.sort(perm[:k])[::-1]),
    ]


@pytest.fixture(scope="module")
def data() -> starship.ReentryData:
    return starship.load()


@pytest.fixture(scope="module")
def result(data: starship.ReentryData) -> starship.FilterResult:
    return ref.run_reference(data)


# ---------------------------------------------------------------------------------------------
# Blank 1: ballistic process model
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("h", "rho_isa"),
    # International Standard Atmosphere densities [kg/m^3] (ISO 2533 tables)
    [(0.0, 1.2250), (5000.0, 0.73643), (11000.0, 0.36392)],
)
def test_dynamics_density_matches_standard_atmosphere(h: float, rho_isa: float) -> None:
    v, c = -200.0, 1e-3
    d = ref.ballistic_dynamics([h, v, c])[1] + G
    rho = d / (0.5 * v**2 * c)
    assert rho == pytest.approx(rho_isa, rel=1e-3)


@random_draws(false_fail=0.0, why="an identity with the closed form to rtol 1e-12, and drag > 0 for every falling state; the draw only picks the states")
def test_dynamics_matches_closed_form_and_drag_opposes_fall(seed: int) -> None:
    rng = np.random.default_rng([seed, 1])
    for _ in range(50):
        x = np.array([rng.uniform(0, 20000), rng.uniform(-800, -50), rng.uniform(1e-4, 3e-3)])
        f = ref.ballistic_dynamics(x)
        assert f.shape == (3,)
        np.testing.assert_allclose(f, f_oracle(x), rtol=1e-12, atol=1e-12)
        assert f[0] == x[1] and f[2] == 0.0
        assert f[1] > -G, "drag must decelerate a falling vehicle (d > 0)"


@random_draws(false_fail=0.0, why="deterministic differences: complex step to machine precision, central differences to truncation and rounding far below rtol 1e-6; the draw only picks the states")
def test_jacobian_matches_finite_and_complex_step_differences(seed: int) -> None:
    rng = np.random.default_rng([seed, 1])
    for _ in range(30):
        x = np.array([rng.uniform(0, 20000), rng.uniform(-800, 800), rng.uniform(-1e-3, 3e-3)])
        J = ref.ballistic_jacobian(x)
        assert J.shape == (3, 3)
        np.testing.assert_allclose(J, complex_step_jacobian(f_oracle, x), rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(
            J, central_difference_jacobian(ref.ballistic_dynamics, x, FD_STEPS), rtol=1e-6, atol=1e-9
        )


# ---------------------------------------------------------------------------------------------
# Blank 2: radar
# ---------------------------------------------------------------------------------------------
def test_radar_hand_cases() -> None:
    # radar level with the vehicle: range = r1, and the range is stationary in h
    assert RADAR_R1 == 5000.0 and RADAR_R2 == 5000.0 and SIGMA_RANGE == 50.0
    np.testing.assert_allclose(ref.radar_predict([5000.0, -300.0, 1e-3]), [5000.0], rtol=1e-15)
    np.testing.assert_allclose(ref.radar_jacobian([5000.0, -300.0, 1e-3]), [[0.0, 0.0, 0.0]], atol=1e-15)
    # 3-4-5 triangle: h - r2 = 3750 m -> range 6250 m, dr/dh = 3750/6250 = 0.6 (and -0.6 below)
    np.testing.assert_allclose(ref.radar_predict([8750.0, -300.0, 1e-3]), [6250.0], rtol=1e-15)
    np.testing.assert_allclose(ref.radar_jacobian([8750.0, -300.0, 1e-3]), [[0.6, 0.0, 0.0]], rtol=1e-14)
    np.testing.assert_allclose(ref.radar_jacobian([1250.0, -300.0, 1e-3]), [[-0.6, 0.0, 0.0]], rtol=1e-14)


@random_draws(false_fail=0.0, why="deterministic central differences, accurate far below rtol 1e-6 on the smooth range; the draw only picks the states")
def test_radar_jacobian_matches_finite_differences(seed: int) -> None:
    rng = np.random.default_rng([seed, 1])
    for _ in range(30):
        x = np.array([rng.uniform(0, 20000), rng.uniform(-800, -50), rng.uniform(1e-4, 3e-3)])
        assert ref.radar_predict(x).shape == (1,)
        J = ref.radar_jacobian(x)
        assert J.shape == (1, 3)
        np.testing.assert_allclose(J, central_difference_jacobian(ref.radar_predict, x, FD_STEPS), rtol=1e-6, atol=1e-9)


# ---------------------------------------------------------------------------------------------
# Blank 3: marginal
# ---------------------------------------------------------------------------------------------
@random_draws(false_fail=0.0, why="an identity (equation 19) on a well-conditioned square root; the draw only picks the case")
def test_marginal_of_head_is_top_left_block(seed: int) -> None:
    rng = np.random.default_rng([seed, 1])
    S = random_upper_sqrt(rng, 5)
    mu = rng.standard_normal(5)
    mu_a, S_a = ref.marginal(mu, S, [0, 1])
    np.testing.assert_array_equal(mu_a, mu[:2])
    # (19): S_a = S1 up to the signs of its rows
    np.testing.assert_allclose(np.abs(S_a), np.abs(S[:2, :2]), rtol=1e-12)


@random_draws(false_fail=0.0, why="an identity on a well-conditioned square root; the draw only picks the case")
def test_marginal_handout_example_index_order(seed: int) -> None:
    # the handout's example I = [3 5 1] (1-based) -> [2, 4, 0]
    rng = np.random.default_rng([seed, 1])
    S = random_upper_sqrt(rng, 5)
    mu = np.arange(1.0, 6.0)
    P = S.T @ S
    mu_I, S_I = ref.marginal(mu, S, [2, 4, 0])
    np.testing.assert_array_equal(mu_I, [3.0, 5.0, 1.0])
    assert_upper_triangular(S_I)
    np.testing.assert_allclose(S_I.T @ S_I, P[np.ix_([2, 4, 0], [2, 4, 0])], rtol=1e-12)


@pytest.mark.parametrize("n", range(2, 8))
@random_draws(false_fail=0.0, why="an identity to rtol 1e-12 on the correlation scale, whatever the scales; the draw only picks the case")
def test_marginal_random_index_sets(n: int, seed: int) -> None:
    rng = np.random.default_rng([seed, n])
    S = random_upper_sqrt(rng, n, scales=10.0 ** rng.uniform(-3, 3, n))
    mu = rng.standard_normal(n)
    P = S.T @ S
    for name, idx in index_sets(rng, n) + [("all, permuted", rng.permutation(n))]:
        mu_I, S_I = ref.marginal(mu, S, idx)
        assert S_I.shape == (idx.size, idx.size), name
        assert_upper_triangular(S_I)
        np.testing.assert_array_equal(mu_I, mu[idx], err_msg=name)
        assert_cov_close(S_I.T @ S_I, P[np.ix_(idx, idx)], rtol=1e-12)


# ---------------------------------------------------------------------------------------------
# Blank 4: conditional
# ---------------------------------------------------------------------------------------------
def textbook_conditional(mu, P, a, b, x_b):
    """Equation (23): mu_a + P_ab P_bb^-1 (x_b - mu_b), P_aa - P_ab P_bb^-1 P_ba (dense solves)."""
    P_ab, P_bb = P[np.ix_(a, b)], P[np.ix_(b, b)]
    gain_t = np.linalg.solve(P_bb, P_ab.T)  # (P_ab P_bb^-1)^T
    return mu[a] + gain_t.T @ (x_b - mu[b]), P[np.ix_(a, a)] - gain_t.T @ P_ab.T


def test_conditional_small_case_by_hand() -> None:
    # P = [[4, 2], [2, 3]], mu = [1, 2]; x_0 | x_1 = 5: mean 1 + 2/3 (5 - 2) = 3, var 4 - 4/3 = 8/3
    S = np.linalg.cholesky(np.array([[4.0, 2.0], [2.0, 3.0]])).T
    mu_c, S_c = ref.conditional(np.array([1.0, 2.0]), S, [0], [1], np.array([5.0]))
    np.testing.assert_allclose(mu_c, [3.0], rtol=1e-14)
    np.testing.assert_allclose(S_c.T @ S_c, [[8.0 / 3.0]], rtol=1e-14)


@random_draws(false_fail=0.0, why="an identity (equation 25) on a well-conditioned square root; the draw only picks the case")
def test_conditional_tail_given_head_is_equation_25(seed: int) -> None:
    rng = np.random.default_rng([seed, 1])
    S = random_upper_sqrt(rng, 5)
    mu = rng.standard_normal(5)
    x_a = rng.standard_normal(2)
    mu_c, S_c = ref.conditional(mu, S, [2, 3, 4], [0, 1], x_a)
    # (25): mu_b + S2^T S1^-T (x_a - mu_a), S_{b|a} = S3 (up to row signs)
    S1, S2, S3 = S[:2, :2], S[:2, 2:], S[2:, 2:]
    np.testing.assert_allclose(mu_c, mu[2:] + S2.T @ np.linalg.solve(S1.T, x_a - mu[:2]), rtol=1e-12)
    np.testing.assert_allclose(np.abs(S_c), np.abs(S3), rtol=1e-12)


@pytest.mark.parametrize("n", range(2, 8))
@random_draws(false_fail=0.0, why="an identity to rtol 1e-9 on the correlation scale between two algebraic forms; the draw only picks the case")
def test_conditional_matches_textbook_formulas(n: int, seed: int) -> None:
    rng = np.random.default_rng([seed, n])
    S = random_upper_sqrt(rng, n, scales=10.0 ** rng.uniform(-3, 3, n))
    mu = rng.standard_normal(n) * np.diag(S)
    P = S.T @ S
    for name, b in index_sets(rng, n):
        a = np.setdiff1d(np.arange(n), b)
        a = rng.permutation(a)  # any order of A, too
        x_b = mu[b] + rng.standard_normal(b.size) * np.sqrt(np.diag(P)[b])
        mu_c, S_c = ref.conditional(mu, S, a, b, x_b)
        mu_exp, P_exp = textbook_conditional(mu, P, a, b, x_b)
        assert S_c.shape == (a.size, a.size), name
        assert_upper_triangular(S_c)
        np.testing.assert_allclose(mu_c, mu_exp, rtol=1e-9, atol=1e-9 * np.sqrt(np.diag(P)[a]).max(), err_msg=name)
        assert_cov_close(S_c.T @ S_c, P_exp, rtol=1e-9)
        # conditioning on the mean leaves the mean of A where it was
        mu_0, _ = ref.conditional(mu, S, a, b, mu[b])
        np.testing.assert_allclose(mu_0, mu[a], rtol=1e-12, atol=1e-12 * np.abs(mu).max())


# ---------------------------------------------------------------------------------------------
# Blank 5: the plot
# ---------------------------------------------------------------------------------------------
@random_draws(false_fail=0.0, why="the figure's data are the arrays passed in, exactly; the draw only picks the curves")
def test_plot_ballistic_coefficient_draws_truth_estimate_and_3_sigma_band(seed: int) -> None:
    rng = np.random.default_rng([seed, 1])
    t = np.linspace(0, 5, 51)
    c_true = 1e-3 + 1e-5 * rng.standard_normal(51)
    c_mean = 1e-3 + 1e-4 * rng.standard_normal(51)
    c_std = rng.uniform(1e-5, 1e-4, 51)
    fig, ax = plt.subplots()
    try:
        assert ref.plot_ballistic_coefficient(ax, t, c_true, c_mean, c_std) is ax
        lines = {line.get_label(): line for line in ax.get_lines()}
        np.testing.assert_array_equal(lines["truth"].get_ydata(), c_true)
        np.testing.assert_array_equal(lines["estimate"].get_ydata(), c_mean)
        bands = [col for col in ax.collections if isinstance(col, PolyCollection)]
        assert len(bands) == 1
        y = bands[0].get_paths()[0].vertices[:, 1]
        assert y.min() == pytest.approx(np.min(c_mean - 3 * c_std), rel=1e-12)
        assert y.max() == pytest.approx(np.max(c_mean + 3 * c_std), rel=1e-12)
        assert "99.7" in bands[0].get_label()
        assert "[s]" in ax.get_xlabel() and "c" in ax.get_ylabel() and ax.get_title()
        assert len(ax.get_legend().get_texts()) == 3
    finally:
        plt.close(fig)


def test_figure_has_three_panels_with_bands(data, result) -> None:
    fig, axes = starship.plot_results(data, result, ref.marginal, ref.plot_ballistic_coefficient)
    try:
        assert len(axes) == 3
        for ax in axes:
            assert ax.get_ylabel() and ax.get_title() and ax.get_legend() is not None
            assert len(ax.get_lines()) == 2 and len(ax.collections) == 1
    finally:
        plt.close(fig)


# ---------------------------------------------------------------------------------------------
# The framework: time and measurement updates against a dense-covariance EKF
# ---------------------------------------------------------------------------------------------
def framework_step(dt: float):
    """The framework's step: (x+, d x+ / d[x; w]) at (mu, 0), for ``sqrt_time_update``."""
    return lambda x: starship.rk4_step_with_jacobian(ref.ballistic_dynamics, ref.ballistic_jacobian, x, np.zeros(3), dt)


@pytest.mark.parametrize("dt", [0.1, 0.05, 1.0])
@random_draws(false_fail=0.0, why="an identity with a dense EKF to rtol 1e-9 on the correlation scale; the draw only picks the states")
def test_sqrt_time_update_equals_dense_ekf(dt: float, seed: int) -> None:
    rng = np.random.default_rng([seed, 1])
    Q = np.diag([0.0, 1e-20, 25e-12])  # equation (12)
    cases = [(starship.MU0, starship.S0)]
    for _ in range(5):
        mu = np.array([rng.uniform(3000, 15000), rng.uniform(-500, -150), rng.uniform(5e-4, 2e-3)])
        cases.append((mu, random_upper_sqrt(rng, 3, scales=np.array([30.0, 3.0, 3e-5]))))
    for mu, S in cases:
        mu_sr, S_sr = ref.sqrt_time_update(mu, S, framework_step(dt), starship.SQRT_Q * np.sqrt(dt))
        # dense EKF: z = [x; w] ~ N([mu; 0], blkdiag(P, Q dt)), x+ = RK4(z), P+ = J Pz J^T
        z = np.concatenate([mu, np.zeros(3)])
        J = complex_step_jacobian(lambda zz: rk4_oracle(zz, dt), z)
        P_dense = J @ np.block([[S.T @ S, np.zeros((3, 3))], [np.zeros((3, 3)), Q * dt]]) @ J.T
        np.testing.assert_allclose(mu_sr, rk4_oracle(z, dt), rtol=1e-12)
        assert_upper_triangular(S_sr)
        assert_cov_close(S_sr.T @ S_sr, P_dense, rtol=1e-9)


@pytest.mark.parametrize("n, q", [(2, 2), (3, 1), (5, 6), (7, 3)])
@random_draws(false_fail=0.0, why="an identity to rtol 1e-9 on the correlation scale; the draw only picks the case")
def test_sqrt_time_update_on_random_linear_steps(n: int, q: int, seed: int) -> None:
    rng = np.random.default_rng([seed, n, q])
    for scales in (np.ones(n), 10.0 ** rng.uniform(-6, 6, n)):
        S = random_upper_sqrt(rng, n, scales=scales)
        S_Q = np.triu(rng.standard_normal((q, q)))
        J = rng.standard_normal((n, n + q))
        mu = rng.standard_normal(n)
        mu_next, S_next = ref.sqrt_time_update(mu, S, lambda x: (2 * x, J), S_Q)
        np.testing.assert_array_equal(mu_next, 2 * mu)
        assert S_next.shape == (n, n)
        assert_upper_triangular(S_next)
        P_z = np.block([[S.T @ S, np.zeros((n, q))], [np.zeros((q, n)), S_Q.T @ S_Q]])
        assert_cov_close(S_next.T @ S_next, J @ P_z @ J.T, rtol=1e-9)


@random_draws(false_fail=0.0, why="an identity with the dense Joseph-form update to rtol 1e-9; the draw only picks the states")
def test_measurement_update_equals_dense_kalman_update(seed: int) -> None:
    rng = np.random.default_rng([seed, 1])
    for _ in range(10):
        mu = np.array([rng.uniform(2000, 15000), rng.uniform(-500, -150), rng.uniform(5e-4, 2e-3)])
        S = random_upper_sqrt(rng, 3, scales=np.array([300.0, 30.0, 3e-4]))
        P = S.T @ S
        y = ref.radar_predict(mu) + 100 * rng.standard_normal(1)
        mu_sr, S_sr = ref.sqrt_measurement_update(
            mu, S, y, lambda x: (ref.radar_predict(x), ref.radar_jacobian(x)), SIGMA_RANGE * np.eye(1)
        )
        # Kalman gain and Joseph-form update with H from complex-step differences of (13)
        H = complex_step_jacobian(lambda x: np.sqrt(RADAR_R1**2 + (x[0] - RADAR_R2) ** 2)[None], mu)
        innovation_cov = H @ P @ H.T + SIGMA_RANGE**2
        K = np.linalg.solve(innovation_cov, H @ P).T
        mu_dense = mu + K @ (y - np.sqrt(RADAR_R1**2 + (mu[0] - RADAR_R2) ** 2))
        IKH = np.eye(3) - K @ H
        P_dense = IKH @ P @ IKH.T + SIGMA_RANGE**2 * K @ K.T
        np.testing.assert_allclose(mu_sr, mu_dense, rtol=1e-9)
        assert_upper_triangular(S_sr)
        assert_cov_close(S_sr.T @ S_sr, P_dense, rtol=1e-9)


@pytest.mark.parametrize("n, m", [(2, 1), (3, 2), (6, 3)])
@random_draws(false_fail=0.0, why="an identity with the Joseph form to rtol 1e-9; the draw only picks the case")
def test_sqrt_measurement_update_matches_joseph_form_with_correlated_noise(n: int, m: int, seed: int) -> None:
    rng = np.random.default_rng([seed, n, m])
    S = random_upper_sqrt(rng, n, scales=10.0 ** rng.uniform(-2, 2, n))
    S_R = np.triu(rng.standard_normal((m, m))) + 2 * np.eye(m)
    H = rng.standard_normal((m, n))
    mu, y = rng.standard_normal(n), rng.standard_normal(m)
    mu_sr, S_sr = ref.sqrt_measurement_update(mu, S, y, lambda x: (H @ x + 1.0, H), S_R)
    P, R_cov = S.T @ S, S_R.T @ S_R
    K = np.linalg.solve(H @ P @ H.T + R_cov, H @ P).T
    IKH = np.eye(n) - K @ H
    np.testing.assert_allclose(mu_sr, mu + K @ (y - H @ mu - 1.0), rtol=1e-9, atol=1e-12)
    assert_upper_triangular(S_sr)
    assert_cov_close(S_sr.T @ S_sr, IKH @ P @ IKH.T + K @ R_cov @ K.T, rtol=1e-9)


def test_framework_rejects_data_that_go_back_in_time(data) -> None:
    t = data.t.copy()
    t[3] = t[1]
    backwards = starship.ReentryData(path="x", n_lines=data.n_lines, t=t, h=data.h, v=data.v, c=data.c,
                                     range_true=data.range_true, range_meas=data.range_meas)
    with pytest.raises(ValueError, match="back in time"):
        ref.run_reference(backwards)


# ---------------------------------------------------------------------------------------------
# Why square roots, errors and NEES: the given comparison and diagnostics
# ---------------------------------------------------------------------------------------------
def _well_conditioned_radar_update(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, Callable]:
    """A prior (mu, S) with well-separated scales, a reading y 20 m off its prediction, and the radar model."""
    rng = np.random.default_rng([seed, 1])
    S = random_upper_sqrt(rng, 3, scales=np.array([300.0, 30.0, 3e-4]))
    mu = np.array([9000.0, -300.0, 1e-3])
    measure = lambda x: (ref.radar_predict(x), ref.radar_jacobian(x))  # noqa: E731
    return mu, S, ref.radar_predict(mu) + 20.0, measure


@random_draws(false_fail=0.0, why="an identity to rtol 1e-9 in float64 and 1e-3 in float32 on a well-conditioned prior; the draw only picks the prior")
def test_covariance_form_update_equals_square_root_update_when_well_conditioned(seed: int) -> None:
    mu, S, y, measure = _well_conditioned_radar_update(seed)
    mu_c, P_c = starship.covariance_measurement_update(mu, S.T @ S, y, measure, SIGMA_RANGE**2 * np.eye(1))
    mu_s, S_s = ref.sqrt_measurement_update(mu, S, y, measure, SIGMA_RANGE * np.eye(1))
    np.testing.assert_allclose(mu_c, mu_s, rtol=1e-12)
    assert_cov_close(P_c, S_s.T @ S_s, rtol=1e-9)
    _, P32 = starship.covariance_measurement_update(mu, S.T @ S, y, measure, SIGMA_RANGE**2 * np.eye(1), np.float32)
    assert_cov_close(P32, S_s.T @ S_s, rtol=1e-3)


def test_first_update_comparison_exact_value_is_the_scalar_kalman_update() -> None:
    sigma = np.array([50.0, 1.0])
    cmp = starship.compare_first_update(ref.sqrt_measurement_update, ref.radar_predict, ref.radar_jacobian, sigma)
    H_h = ref.radar_jacobian(starship.MU0)[0, 0]
    prior = starship.S0[0, 0] ** 2
    # information form: 1 / P+ = 1 / P + H^2 / sigma^2
    np.testing.assert_allclose(cmp.exact, 1 / (1 / prior + H_h**2 / sigma**2), rtol=1e-12)
    np.testing.assert_allclose(cmp.square_root, cmp.exact, rtol=1e-12)
    assert cmp.pd_square_root.all() and cmp.pd_covariance64.all()
    with pytest.raises(ValueError, match="diagonal"):
        starship.compare_first_update(ref.sqrt_measurement_update, ref.radar_predict, ref.radar_jacobian, sigma,
                                      S0=np.triu(np.ones((3, 3))))


def test_first_update_figure_marks_broken_covariances() -> None:
    sigma = np.logspace(2, -10, 13)
    cmp = starship.compare_first_update(ref.sqrt_measurement_update, ref.radar_predict, ref.radar_jacobian, sigma)
    fig, ax = starship.plot_first_update_comparison(cmp)
    try:
        crosses = [line for line in ax.get_lines() if line.get_marker() == "x" and len(line.get_xdata())]
        broken = sum((~getattr(cmp, f"pd_{name}")).sum()
                     for name in ("covariance32", "covariance64", "joseph64", "square_root32", "square_root"))
        assert sum(len(line.get_xdata()) for line in crosses) == broken > 0
        assert ax.get_xscale() == "log" and "[m]" in ax.get_xlabel() and len(fig.legends) == 1
    finally:
        plt.close(fig)


@random_draws(false_fail=0.0, why="an identity to rtol 1e-9 in float64 and 1e-5 in float32 on a well-conditioned prior; the draw only picks the prior")
def test_joseph_form_and_float32_square_root_agree_with_the_update_when_well_conditioned(seed: int) -> None:
    mu, S, y, measure = _well_conditioned_radar_update(seed)
    _, S_s = ref.sqrt_measurement_update(mu, S, y, measure, SIGMA_RANGE * np.eye(1))
    _, P_j = starship.covariance_measurement_update(mu, S.T @ S, y, measure, SIGMA_RANGE**2 * np.eye(1), joseph=True)
    assert_cov_close(P_j, S_s.T @ S_s, rtol=1e-9)
    S32 = ref.posterior_square_root(S, ref.radar_jacobian(mu), SIGMA_RANGE, np.float32)
    assert_cov_close(S32.T @ S32, S_s.T @ S_s, rtol=1e-5)
    S64 = ref.posterior_square_root(S, ref.radar_jacobian(mu), SIGMA_RANGE, np.float64)
    assert_cov_close(S64.T @ S64, S_s.T @ S_s, rtol=1e-12)


@random_draws(false_fail=0.0, fixed_seed=True, why="checks simulate_falls' seeding exactly: fall k draws from "
              "default_rng(k), its initial error after its noise; three falls cost 2 s, so not rerun on 21 seeds")
def test_monte_carlo_draws_each_initial_error_from_the_prior_and_averages_the_nees() -> None:
    simulated = ref.simulated_falls(range(3))
    falls = starship.filter_falls(simulated, ref.ballistic_dynamics, ref.ballistic_jacobian, ref.radar_predict,
                                  ref.radar_jacobian, ref.sqrt_time_update, ref.sqrt_measurement_update)
    assert falls.nees.shape == (3, starship.N_ROWS) and falls.mu.shape == falls.truth.shape == (3, starship.N_ROWS, 3)
    np.testing.assert_array_equal(falls.truth[:, 0], np.tile(starship.X0_TRUE, (3, 1)))
    # each fall is filtered from its own initial mean, on its own ranges
    first = ref.run_reference(simulated.fall(2), simulated.mu0[2])
    np.testing.assert_array_equal(falls.mu[2], first.mu)
    # each fall's initial error is its own: X0_TRUE - mu0 = S0^T e with e drawn after the fall's noise
    whitened = np.linalg.solve(starship.S0.T, (starship.X0_TRUE - falls.mu0).T).T
    assert len({tuple(np.round(w, 12)) for w in whitened}) == 3
    rng = np.random.default_rng(1)
    ref.simulate_reentry(rng)
    np.testing.assert_allclose(whitened[1], rng.standard_normal(3), rtol=1e-12)
    # chi-square(120) quantiles from tables: 91.57 (2.5%) and 152.21 (97.5%), divided by 40 falls
    lower, upper = starship.average_nees_band(40)
    assert lower == pytest.approx(91.573 / 40, abs=1e-3) and upper == pytest.approx(152.211 / 40, abs=1e-3)
    fig, ax = starship.plot_average_nees(falls)
    try:
        line = next(line for line in ax.get_lines() if len(line.get_xdata()) == starship.N_ROWS)
        np.testing.assert_allclose(line.get_ydata(), falls.nees.mean(axis=0))
        assert "[s]" in ax.get_xlabel() and ax.get_legend() is not None
    finally:
        plt.close(fig)


def test_hidden_test_accepts_sign_correct_drag() -> None:
    from solutions.reentry_srekf.hidden_tests import check_ballistic_dynamics

    def ballistic_dynamics(x):
        h, v, c = np.asarray(x, dtype=float)
        T = T0 - L * h
        rho = P0 * (1 - L * h / T0) ** (G * M / (R * L)) * M / (R * T)
        # drag against the motion whatever its direction: -rho v |v| c / 2
        return np.array([v, -0.5 * rho * v * abs(v) * c - G, 0.0])

    check_ballistic_dynamics(ballistic_dynamics)


def test_positive_definite_check() -> None:
    assert starship.is_positive_definite(np.diag([1.0, 2.0]))
    assert not starship.is_positive_definite(np.diag([1.0, -1e-12]))
    assert not starship.is_positive_definite(np.array([[1.0, 2.0], [2.0, 1.0]]))
    assert not starship.is_positive_definite(np.array([[np.nan, 0.0], [0.0, 1.0]]))


def test_nees_equals_the_dense_quadratic_form_and_the_band_is_chi_square_3(data, result) -> None:
    nees = starship.normalised_estimation_error_squared(data.truth, result)
    e = data.truth - result.mu
    P = np.einsum("kji,kjl->kil", result.S, result.S)
    dense = np.einsum("ki,ki->k", e, np.linalg.solve(P, e[:, :, None])[:, :, 0])
    np.testing.assert_allclose(nees, dense, rtol=1e-8)
    lower, upper = starship.nees_band()
    # chi-square(3) quantiles from tables: 0.2158 (2.5%) and 9.348 (97.5%)
    assert lower == pytest.approx(0.2158, abs=1e-4) and upper == pytest.approx(9.348, abs=1e-3)


def test_errors_and_nees_figure(data, result) -> None:
    fig, axes = starship.plot_errors_and_nees(data, result, ref.marginal)
    try:
        assert len(axes) == 4
        for ax in axes:
            assert ax.get_ylabel() and ax.get_title()
        assert axes[3].get_yscale() == "log" and "[s]" in axes[3].get_xlabel()
        assert len(fig.legends) == 1 and len(fig.legends[0].get_texts()) == 5
    finally:
        plt.close(fig)


def test_filter_is_consistent_with_the_truth(data, result) -> None:
    std = starship.marginal_std(result, ref.marginal)
    np.testing.assert_allclose(std**2, np.einsum("kij,kij->kj", result.S, result.S), rtol=1e-12)
    errors = np.abs(result.mu - data.truth) / std
    # a consistent filter keeps nearly every error inside 3 sigma, and ends inside it
    assert np.mean(errors <= 3, axis=0).min() >= 0.95
    assert np.all(errors[-1] <= 3)


# ---------------------------------------------------------------------------------------------
# Data and report
# ---------------------------------------------------------------------------------------------
def test_shipped_data_rebuilds_bit_for_bit(tmp_path: Path) -> None:
    rebuilt, float32_results, falls = ref.write_data(tmp_path)
    assert rebuilt.name == starship.DATA_FILE.name
    assert rebuilt.read_bytes() == starship.DATA_FILE.read_bytes()
    assert float32_results.name == starship.FLOAT32_SQUARE_ROOT_FILE.name
    assert float32_results.read_bytes() == starship.FLOAT32_SQUARE_ROOT_FILE.read_bytes()
    assert falls.name == starship.FALLS_FILE.name
    assert falls.read_bytes() == starship.FALLS_FILE.read_bytes(), "the shipped falls differ from a rebuild"


def test_the_shipped_falls_are_the_notebooks_seeds_and_the_shipped_fall_is_simulated_alike() -> None:
    """The falls of part 9: 40, from reference.FALL_SEEDS, each starting at X0_TRUE, with mu0 drawn after
    the fall's noise; simulated as the shipped fall of part 1 is (the same simulator, from its own seed)."""
    falls = starship.load_falls()
    assert falls.truth.shape == (40, starship.N_ROWS, 3) and falls.mu0.shape == (40, 3)
    np.testing.assert_allclose(falls.t, starship.load().t, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(falls.truth[:, 0], np.tile(starship.X0_TRUE, (40, 1)))
    again = ref.simulated_falls([ref.DATA_SEED])
    shipped = starship.load()
    np.testing.assert_allclose(again.truth[0], shipped.truth, rtol=1e-9)
    np.testing.assert_allclose(again.range_meas[0], shipped.range_meas, rtol=1e-9)


def test_shipped_float32_square_root_results_are_a_float32_qr_of_the_lab_prior() -> None:
    """The shipped values, read back at every fourth sigma, against the QR computed here in float32."""
    sigma = starship.FIRST_UPDATE_SIGMA[::4]
    var_h, positive_definite = starship.float32_square_root_first_update(sigma)
    H = ref.radar_jacobian(starship.MU0)
    for s, v, pd in zip(sigma, var_h, positive_definite):
        S = ref.posterior_square_root(starship.S0, H, s, np.float32)
        assert (S.T @ S)[0, 0] == v and pd == starship.is_positive_definite(S.T @ S)
    # off the shipped grid, or from another prior, there are no float32 values to show
    assert starship.float32_square_root_first_update([50.0]) is None
    other_prior = starship.compare_first_update(ref.sqrt_measurement_update, ref.radar_predict, ref.radar_jacobian,
                                                sigma, S0=2 * starship.S0)
    assert other_prior.square_root32 is None


def test_shipped_data_format_and_truth(data) -> None:
    lines = starship.DATA_FILE.read_text().splitlines()
    assert lines[0] == (
        "Time [sec],Altitude True [m],Velocity True [m/s],Ballistic Coefficient True [],"
        "Range True [m],Range measurement [m],"
    )
    assert len(lines) == 501 and data.n_lines == 501 and len(data) == 500
    assert all(line.endswith(",") and line.count(",") == 6 for line in lines)
    assert data.t[0] == 0.0
    np.testing.assert_allclose(np.diff(data.t), 0.1, rtol=1e-9)
    np.testing.assert_array_equal(data.truth[0], [15000.0, -500.0, 0.001])
    np.testing.assert_allclose(data.range_true, np.hypot(5000.0, data.h - 5000.0), rtol=1e-9)
    assert 45.0 < np.std(data.range_meas - data.range_true) < 55.0
    assert abs(np.mean(data.range_meas - data.range_true)) < 3 * 50 / np.sqrt(500)
    assert np.all(data.v < 0) and np.all(np.diff(data.h) < 0) and data.h[-1] > 0


def test_eigen_style_matrix_format_matches_handout() -> None:
    # the handout's terminal output for mu[0] and P[0]
    assert starship.format_matrix(starship.MU0) == " 14000\n  -450\n0.0005"
    assert starship.format_matrix(starship.S0.T @ starship.S0) == (
        "4.84e+06        0        0\n       0    10000        0\n       0        0    1e-06"
    )
    assert starship.format_matrix([2185.37, -152.739, 0.000982013]) == "    2185.37\n   -152.739\n0.000982013"


# Regression pin. Provenance: printed by `python -m solutions.reentry_srekf.reference` on the shipped
# course/data/starship_reentry.csv (seed 20230503) when the data was first built; it is not an
# independent oracle. The handout's own data gives mu[end] = [2185.37, -152.739, 0.000982013] and
# P[end] of the same size as these (diagonal 215, 1.57, 4.79e-10).
PINNED_REPORT = """\
Found 501 rows within {path}
Initial state estimate
mu[0] =
 14000
  -450
0.0005
P[0] =
4.84e+06        0        0
       0    10000        0
       0        0    1e-06
Run filter with 500 steps.
Final state estimate
mu[end] =
   2354.03
  -149.497
0.00103922
P[end] =
    232.602     10.6467 0.000170708
    10.6467     1.45696  2.4829e-05
0.000170708  2.4829e-05 4.89302e-10
"""


def test_report_regression_pin() -> None:
    path = str(starship.DATA_FILE)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        ref.main(["--data", path])
    assert out.getvalue() == f"Reading data from {path}\n" + PINNED_REPORT.format(path=path)


def test_command_line_entry_point() -> None:
    path = "course/data/starship_reentry.csv"
    done = subprocess.run(
        [sys.executable, "-m", "solutions.reentry_srekf.reference", "--data", path],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    assert done.stdout == f"Reading data from {path}\n" + PINNED_REPORT.format(path=path)


def test_course_module_implements_no_blank_and_hides_solutions() -> None:
    tree = ast.parse(Path(starship.__file__).read_text())
    defined = {node.name for node in ast.walk(tree) if isinstance(node, (ast.FunctionDef, ast.ClassDef))}
    assert not defined & set(BLANKS)
    imported = {
        alias.name.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names
    } | {(node.module or "").split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert "solutions" not in imported
    assert all(hasattr(ref, name) for name in BLANKS)


def test_default_load_names_the_shipped_file_portably() -> None:
    data = starship.load()
    assert data.path == "course/data/starship_reentry.csv"
    assert starship.format_report(data, ref.run_reference(data)) + "\n" == (
        f"Reading data from {data.path}\n" + PINNED_REPORT.format(path=data.path)
    )


# ---------------------------------------------------------------------------------------------
# The check helpers of course.starship accept right answers and reject wrong ones
# ---------------------------------------------------------------------------------------------
@random_draws(false_fail=0.0, why="exact verdicts of the check helpers on a well-conditioned square root; the draw only picks it")
def test_check_helpers_accept_right_and_reject_wrong_answers(seed: int) -> None:
    rng = np.random.default_rng([seed, 1])
    S = random_upper_sqrt(rng, 4, scales=np.array([1e3, 1.0, 1e-3, 1e-6]))
    P = S.T @ S
    starship.check_square_root(-S, P, "S")  # row signs are free
    starship.check_square_root(np.linalg.cholesky(P).T, P, "S")
    with pytest.raises(AssertionError, match="upper triangular"):
        starship.check_square_root(np.linalg.cholesky(P), P, "S")
    with pytest.raises(AssertionError, match="not a square root"):
        starship.check_square_root(np.triu(P), P, "S")
    # a hidden test names its case in a phrase; the message must not paste ".T @ S" onto it
    for show_expected in (True, False):
        with pytest.raises(AssertionError) as failed:
            starship.check_square_root(2 * S, P, "S for the step of a Gaussian, with 3 noise inputs",
                                       show_expected=show_expected)
        assert "inputs.T" not in str(failed.value) and "its S.T @ S" in str(failed.value), str(failed.value)
    x = np.array([9000.0, -300.0, 1e-3])
    starship.check_jacobian(ref.ballistic_jacobian(x), ref.ballistic_dynamics, x, "J")
    with pytest.raises(AssertionError, match="finite differences"):
        starship.check_jacobian(ref.ballistic_jacobian(x).T, ref.ballistic_dynamics, x, "J")
    with pytest.raises(AssertionError, match="shape"):
        starship.check_jacobian(ref.radar_jacobian(x).T, ref.radar_predict, x, "H")

    t = np.linspace(0.0, 2.0, 9)
    truth, mean, std = 1e-3 + 0 * t, 1e-3 + 1e-5 * np.sin(t), 1e-4 * (1 + t)

    def draw(k: float = 3.0, legend: bool = True, xlabel: str = "Time [s]"):
        fig, ax = plt.subplots()
        ax.fill_between(t, mean - k * std, mean + k * std, label="band")
        ax.plot(t, truth, label="truth")
        ax.plot(t, mean, label="estimate")
        ax.set(xlabel=xlabel, ylabel="c [m²/kg]", title="Ballistic coefficient")
        if legend:
            ax.legend()
        return fig, ax

    try:
        fig, ax = draw()
        starship.check_band_plot(ax, ax, t, truth, mean, std, "plot")
        with pytest.raises(AssertionError, match="return ax"):
            starship.check_band_plot(ax, None, t, truth, mean, std, "plot")
        fig, ax = draw(k=2.0)
        with pytest.raises(AssertionError, match="half-width is 2 std"):
            starship.check_band_plot(ax, ax, t, truth, mean, std, "plot")
        fig, ax = draw(legend=False)
        with pytest.raises(AssertionError, match="legend"):
            starship.check_band_plot(ax, ax, t, truth, mean, std, "plot")
        fig, ax = draw(xlabel="Time")
        with pytest.raises(AssertionError, match="unit"):
            starship.check_band_plot(ax, ax, t, truth, mean, std, "plot")
    finally:
        plt.close("all")


@pytest.mark.parametrize("xlabel, ylabel", [("Time (seconds)", "c [m²/kg]"), ("time $t$ / s", "$c$ / m$^2$ kg$^{-1}$"),
                                            ("t in sec", "ballistic coefficient (m^2 kg^-1)")])
def test_band_plot_accepts_every_way_of_writing_the_units(xlabel, ylabel):
    # Issue 30: "Time (seconds)" and ISO's "time $t$ / s" lost the blank's 0.5 points, visible check and
    # grading alike: the time axis had to hold one of "[s]", "(s)", "[sec]", "(sec)" literally.
    t = np.linspace(0.0, 2.0, 9)
    truth, mean, std = 1e-3 + 0 * t, 1e-3 + 1e-5 * np.sin(t), 1e-4 * (1 + t)
    fig, ax = plt.subplots()
    try:
        ref.plot_ballistic_coefficient(ax, t, truth, mean, std)
        ax.set(xlabel=xlabel, ylabel=ylabel)
        starship.check_band_plot(ax, ax, t, truth, mean, std, "plot")
        ax.set(ylabel="c [kg/m^2]")
        with pytest.raises(AssertionError, match="y axis with the quantity and its unit \\(m\\^2/kg\\)"):
            starship.check_band_plot(ax, ax, t, truth, mean, std, "plot")
    finally:
        plt.close(fig)
