"""The castaway-bob reference, the shipped flow and Bob's drift, against independent oracles.

Oracles: explicit-inverse textbook formulas, FilterPy's KalmanFilter, batch Gaussian
conditioning of a whole trajectory, brute-force sums, SciPy's RegularGridInterpolator, and
physical facts about the flow (incompressible, a periodic vortex street, ocean speeds).
"""

from __future__ import annotations

import inspect
import io
import zipfile

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter
from scipy.interpolate import RegularGridInterpolator

import solutions.castaway_bob.reference as ref
from autograder.release import data
from course import ocean
from course.checks import random_spd
from random_draws import random_draws
from shipped_data import same_bits
from solutions.castaway_bob import flow as flow_build


@pytest.fixture(scope="module")
def flow() -> ocean.Flow:
    return ocean.load()


# ------------------------------------------------------------------------------------------------
# Blank 1: A and H
# ------------------------------------------------------------------------------------------------


def test_transition_matrix_moves_position_by_dt_times_velocity_and_damps_velocity():
    dt, alpha = 60.0, 0.9
    A = ref.transition_matrix(dt, alpha)
    state = np.array([100.0, -20.0, 0.3, -0.1])
    np.testing.assert_allclose(A @ state, [100.0 + 18.0, -20.0 - 6.0, 0.27, -0.09])
    assert sorted(np.linalg.eigvals(A).real) == pytest.approx([alpha, alpha, 1.0, 1.0])


def test_transition_matrices_compose_over_two_steps_without_damping():
    # with alpha = 1 the model is exact kinematics: two steps of dt are one step of 2 dt
    np.testing.assert_allclose(ref.transition_matrix(30.0, 1.0) @ ref.transition_matrix(30.0, 1.0),
                               ref.transition_matrix(60.0, 1.0))


def test_observation_matrix_picks_the_position():
    H = ref.observation_matrix()
    assert H.shape == (2, 4)
    np.testing.assert_array_equal(H @ np.array([1.0, 2.0, 3.0, 4.0]), [1.0, 2.0])
    np.testing.assert_array_equal(H @ H.T, np.eye(2))


# ------------------------------------------------------------------------------------------------
# Blank 2: the trailing mean
# ------------------------------------------------------------------------------------------------


@random_draws(false_fail=0.0,
              why="an identity (two ways of summing at most 5 fixes); the draw only picks the fixes")
@pytest.mark.parametrize("order", [1, 2, 3, 5])
def test_trailing_mean_equals_brute_force_sums(order, seed):
    y = np.random.default_rng([seed, order]).normal(size=(17, 2))
    expected = []
    for n in range(17):
        first = max(0, n - order + 1)
        expected.append(sum(y[k] for k in range(first, n + 1)) / (n + 1 - first))
    # the fixes are O(1): rounding is below 1e-15 absolute, so a mean that cancels to near 0 passes too
    np.testing.assert_allclose(ref.trailing_mean(y, order=order), expected, rtol=1e-12, atol=1e-12)


@random_draws(false_fail=0.0,
              why="exact facts (causality, order one returns the fixes); the draw only picks the fixes")
def test_trailing_mean_is_causal_and_of_order_one_is_the_fixes(seed):
    y = np.random.default_rng([seed, 1]).normal(size=(12, 2))
    changed = y.copy()
    changed[8:] += 100.0
    np.testing.assert_array_equal(ref.trailing_mean(y)[:8], ref.trailing_mean(changed)[:8])
    np.testing.assert_array_equal(ref.trailing_mean(y, order=1), y)


# ------------------------------------------------------------------------------------------------
# Blank 3: the gain (18) and the Joseph form (13)
# ------------------------------------------------------------------------------------------------

SIZES = [(1, 1), (2, 2), (4, 2), (5, 3), (6, 1)]


@random_draws(false_fail=0.0,
              why="an identity on well-conditioned matrices (P, R >= n I); the draw only picks the case")
@pytest.mark.parametrize("n, m", SIZES)
def test_gain_equals_the_explicit_inverse_formula(n, m, seed):
    rng = np.random.default_rng([seed, 1, n, m])
    P, H, R = random_spd(rng, n), rng.standard_normal((m, n)), random_spd(rng, m)
    explicit = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    np.testing.assert_allclose(ref.kalman_gain(P, H, R), explicit, rtol=1e-10, atol=1e-12)


@random_draws(false_fail=0.0,
              why="an identity, and a suboptimal gain built so that the two forms differ by a proven margin")
@pytest.mark.parametrize("n, m", SIZES)
def test_joseph_form_equals_the_simple_form_at_the_optimal_gain_only(n, m, seed):
    rng = np.random.default_rng([seed, 2, n, m])
    P, H, R = random_spd(rng, n), rng.standard_normal((m, n)), random_spd(rng, m)
    K = ref.kalman_gain(P, H, R)
    simple = (np.eye(n) - K @ H) @ P
    np.testing.assert_allclose(ref.joseph_covariance(P, K, H, R), simple, rtol=1e-9, atol=1e-10)
    # A suboptimal gain K' = K + E: the simple form is wrong there, the Joseph form is the true covariance.
    # Their difference is E S K'^T (S = H P H^T + R >= I, since H P = S K^T). A gain K + 0.3 N(0, 1) could
    # land next to 0, where both forms are P (allclose held on 2.3e-4 of 4e6 draws for n = m = 1); so E = a V with V
    # orthonormal columns and a = ||K||_2 + 0.3: then sigma_min(K') >= 0.3 and ||E S K'^T||_2 >= 0.09.
    # Over 40 000 draws of each size the smallest ratio |difference| / allclose's tolerance was 1.6e3 and the
    # smallest eigenvalue of the Joseph form 7e-4 of its largest entry: far from rounding.
    V = np.linalg.qr(rng.standard_normal((n, m)))[0]
    K_bad = K + (np.linalg.norm(K, 2) + 0.3) * V
    joseph = ref.joseph_covariance(P, K_bad, H, R)
    assert not np.allclose(joseph, (np.eye(n) - K_bad @ H) @ P)
    np.testing.assert_allclose(joseph, joseph.T, atol=1e-10)
    assert np.linalg.eigvalsh(joseph).min() > 0


def _no_gps_term(P: np.ndarray, K: np.ndarray, H: np.ndarray, R: np.ndarray) -> np.ndarray:
    """(13) without its K K_v K^T term: the mistake the Monte Carlo statistic must reject."""
    I_KH = np.eye(P.shape[0]) - K @ H
    return I_KH @ P @ I_KH.T


def _joseph_monte_carlo_whitened(seed: int, n_samples: int, covariance=ref.joseph_covariance) -> np.ndarray:
    """(1/N) sum z z^T of the updated errors whitened by covariance(P, K, H, R): I_3 if that is their covariance.

    A random problem (P, H, K_v) and a random gain K (3 x 2). K_v is scaled so that the GPS term carries a
    set share of the error: tr(((I - K H) P (I - K H)^T)^-1 K K_v K^T) = 3, so that dropping it is visible
    on every draw (the test of power below needs it).
    """
    # x ~ N(0, P), y = H x + v, v ~ N(0, K_v); the error of x^ = K y is (I - K H) x - K v
    rng = np.random.default_rng([seed, 1])
    P, H, R = random_spd(rng, 3), rng.standard_normal((2, 3)), random_spd(rng, 2)
    K = rng.standard_normal((3, 2))
    R = R * 3.0 / np.trace(np.linalg.solve(_no_gps_term(P, K, H, R), K @ R @ K.T))
    x = rng.multivariate_normal(np.zeros(3), P, size=n_samples)
    v = rng.multivariate_normal(np.zeros(2), R, size=n_samples)
    error = x - (x @ H.T + v) @ K.T
    # z = L^-1 e with L L^T = the Joseph covariance: z ~ N(0, I_3) exactly if (13) is the error's covariance
    z = np.linalg.solve(np.linalg.cholesky(covariance(P, K, H, R)), error.T)
    return z @ z.T / n_samples  # the mean is known (0), so no centring


# False-fail probability of the Monte Carlo test, for a correct (13). With N = 50 000 whitened errors
# z ~ N(0, I_3), each diagonal entry of (1/N) sum z z^T is chi2_N / N, and each off-diagonal entry
# z_j z_k = ((z_j + z_k)^2 - (z_j - z_k)^2) / 4 is (A - B) / (2N) with A, B independent chi2_N. The
# Laurent-Massart bounds P(X - N >= 2 sqrt(N t) + 2t) <= e^-t and P(N - X >= 2 sqrt(N t)) <= e^-t with
# t = 17 keep every chi2_N / N within TOL = 2 sqrt(t / N) + 2t / N = 0.0376 of 1 but for probability
# e^-17 = 4.1e-8 per tail; an off-diagonal entry is then within TOL of 0. Over 3 diagonal entries
# (2 tails each) and 3 off-diagonal ones (2 variables x 2 tails each), 18 tails: <= 18 x 4.1e-8 = 7.5e-7.
# (It was 200 000 samples on one seed; 50 000 cost a quarter as much per seed and keep the power below.)
MC_SAMPLES, MC_T = 50_000, 17.0
MC_TOL = 2.0 * np.sqrt(MC_T / MC_SAMPLES) + 2.0 * MC_T / MC_SAMPLES


@random_draws(false_fail=7.5e-7,
              why="18 chi-square tails of the whitened sample covariance, Laurent-Massart bound e^-17 each")
def test_joseph_form_is_the_covariance_of_the_updated_error_by_monte_carlo(seed):
    whitened = _joseph_monte_carlo_whitened(seed, MC_SAMPLES)
    np.testing.assert_allclose(whitened, np.eye(3), rtol=0, atol=MC_TOL)


@random_draws(false_fail=7.5e-7,
              why="power is certain on the same 18-tail event as the Monte Carlo test (Laurent-Massart)")
def test_the_monte_carlo_check_can_fail(seed):
    # The same statistic rejects (13) without its K K_v K^T term, on every draw. Whitened by the wrong
    # L_b (L_b L_b^T = (I - K H) P (I - K H)^T) the statistic is W = B S_N B^T with B = L_b^-1 L and S_N
    # the sample covariance of the correctly whitened errors; its mean is M = B B^T = I + L_b^-1 K K_v K^T L_b^-T.
    # K_v's scaling makes tr(M - I) = 3 with M - I >= 0: max |M - I| >= 1 and ||B||^2 = lambda_max(M) <= 4.
    # On the event of the test above (max |S_N - I| <= TOL, so ||S_N - I||_2 <= 3 TOL), |W - M| <= 4 x 3 TOL
    # entrywise: max |W - I| >= 1 - 12 TOL = 0.55 > 10 TOL = 0.38. (With a random K_v, as before, M was within
    # 10 TOL of I on about 6% of draws: the lucky-seed defect of issue 17.)
    whitened = _joseph_monte_carlo_whitened(seed, MC_SAMPLES, _no_gps_term)
    assert np.abs(whitened - np.eye(3)).max() > 10 * MC_TOL


@random_draws(false_fail=0.0,
              why="an identity, with perturbations of a set size so rounding stays 1e7 times below the gap")
@pytest.mark.parametrize("n, m", SIZES)
def test_the_gain_minimises_the_trace_of_the_joseph_form(n, m, seed):
    rng = np.random.default_rng([seed, 3, n, m])
    P, H, R = random_spd(rng, n), rng.standard_normal((m, n)), random_spd(rng, m)
    K = ref.kalman_gain(P, H, R)
    best = np.trace(ref.joseph_covariance(P, K, H, R))
    for scale in (1e-3, 1e-1, 1.0):
        for _ in range(20):
            # a random direction of norm `scale`: with scale * N(0, 1) entries a 1 x 1 perturbation below
            # 3e-5 (once in 4e4 draws) would leave a gap under the rounding of the traces (1e-15)
            U = rng.standard_normal(K.shape)
            E = scale * U / np.linalg.norm(U)
            # tr P^(K + E) - tr P^(K) = tr(E S E^T) > 0 exactly, S = H P H^T + R >= R >= m I, so >= 1e-6
            gap = np.trace(ref.joseph_covariance(P, K + E, H, R)) - best
            np.testing.assert_allclose(gap, np.trace(E @ (H @ P @ H.T + R) @ E.T), rtol=1e-6, atol=1e-9)
            assert gap > 0


# The gaps tr(E S E^T) are > 0 exactly; rounding (a few eps tr P^; 100 eps tr P^ is a generous bound) could
# make one <= 0 only for a tiny perturbation of a small gain. Over 1 000 000 gaps drawn as the experiment draws
# them (n, m, P, H, K_v, E), the smallest gap / (eps tr P^) was 4.3e4; the fraction below x was 7e-6 at 1e6,
# 6.6e-5 at 1e7, 4.7e-4 at 1e8: linear in x at the low end, so P(gap / (eps tr P^) < 100) is about
# 7e-6 x 1e-4 = 7e-10 per gap, 3.5e-7 for the 500 gaps of a run; stated as 4e-7.
@random_draws(false_fail=4e-7, why="rounding of 500 gaps > 0, from the lower tail of 1 000 000 simulated gaps")
def test_gain_trace_experiment_in_course_finds_no_better_gain(seed):
    rng = np.random.default_rng([seed, 1])
    gaps = ocean.gain_trace_experiment(ref.kalman_gain, ref.joseph_covariance, rng, 50, 10)
    assert gaps.shape == (50, 10) and gaps.min() > 0


# ------------------------------------------------------------------------------------------------
# Blank 4: one step
# ------------------------------------------------------------------------------------------------


def _condition(mean: np.ndarray, cov: np.ndarray, H: np.ndarray, R: np.ndarray, y: np.ndarray):
    """Posterior of x ~ N(mean, cov) given y = H x + N(0, R), from the joint Gaussian (explicit inverse)."""
    C_xy = cov @ H.T
    C_yy = H @ cov @ H.T + R
    gain = C_xy @ np.linalg.inv(C_yy)
    return mean + gain @ (y - H @ mean), cov - gain @ C_xy.T


@random_draws(false_fail=0.0,
              why="an identity (Gaussian conditioning) on well-conditioned covariances; the draw picks the case")
@pytest.mark.parametrize("n, m", SIZES)
@pytest.mark.parametrize("with_input", [False, True])
def test_kalman_step_is_gaussian_conditioning_of_the_prediction(n, m, with_input, seed):
    rng = np.random.default_rng([seed, n, m, int(with_input)])
    x, P, Q = rng.standard_normal(n), random_spd(rng, n), random_spd(rng, n)
    A, H, R = rng.standard_normal((n, n)), rng.standard_normal((m, n)), random_spd(rng, m)
    y = rng.standard_normal(m)
    u = rng.standard_normal(n) if with_input else None
    x_new, P_new = ref.kalman_step(x, P, y, A, H, Q, R, u=u)
    mean = A @ x + (u if with_input else 0.0)
    want_x, want_P = _condition(mean, A @ P @ A.T + Q, H, R, y)
    np.testing.assert_allclose(x_new, want_x, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(P_new, want_P, rtol=1e-9, atol=1e-10)


# ------------------------------------------------------------------------------------------------
# Blank 5: the two filters
# ------------------------------------------------------------------------------------------------


@random_draws(false_fail=0.0,
              why="an identity (recursive and batch posteriors agree); the draw only picks the fixes")
def test_rank2_last_estimate_is_the_batch_posterior_of_the_whole_random_walk(seed):
    # Oracle: the positions x_0..x_k given all fixes y_0..y_k at once (flat prior on x_0, random
    # walk steps N(0, q^2), fixes N(x, r^2)), in information form, each axis on its own:
    # precision L = I / r^2 + D^T D / q^2 with D the difference operator, mean = L^-1 y / r^2.
    # The filter's estimate at k is that posterior's last entry.
    rng = np.random.default_rng([seed, 1])
    T, q, r = 9, 20.0, 50.0
    y = np.cumsum(rng.normal(0, q, (T, 2)), axis=0) + rng.normal(0, r, (T, 2))
    xs, Ps = ref.run_rank2(y, sigma_walk=q, sigma_gps=r)
    for k in range(T):
        D = np.diff(np.eye(k + 1), axis=0)
        L = np.eye(k + 1) / r**2 + D.T @ D / q**2
        mean = np.linalg.solve(L, y[: k + 1] / r**2)
        np.testing.assert_allclose(xs[k], mean[-1], rtol=1e-10, atol=1e-8)
        np.testing.assert_allclose(Ps[k], np.linalg.inv(L)[-1, -1] * np.eye(2), rtol=1e-10, atol=1e-8)


def _filterpy_rank4(y, flow, t, alpha, sigma_F, sigma_gps, dt):
    kf = KalmanFilter(dim_x=4, dim_z=2)
    kf.F = np.array([[1, 0, dt, 0], [0, 1, 0, dt], [0, 0, alpha, 0], [0, 0, 0, alpha]], dtype=float)
    kf.H = np.array([[1, 0, 0, 0], [0, 1, 0, 0]], dtype=float)
    kf.Q = np.diag([0.0, 0.0, sigma_F**2, sigma_F**2])
    kf.R = sigma_gps**2 * np.eye(2)
    kf.B = np.vstack((dt * np.eye(2), np.zeros((2, 2))))
    var_w = sigma_F**2 / (1 - alpha**2)
    kf.x = np.array([y[0, 0], y[0, 1], 0.0, 0.0])
    kf.P = np.diag([sigma_gps**2, sigma_gps**2, var_w, var_w])
    xs, Ps = [kf.x.copy()], [kf.P.copy()]
    for k in range(1, len(y)):
        kf.predict(u=flow(kf.x[:2], t[k - 1]))
        kf.update(y[k])
        xs.append(kf.x.copy())
        Ps.append(kf.P.copy())
    return np.array(xs), np.array(Ps)


@random_draws(false_fail=0.0, why="an identity (the same filter written twice); the draw only picks the drift")
def test_rank4_matches_filterpy_with_the_current_as_control_input(flow, seed):
    drift = ocean.simulate_drift(flow, np.random.default_rng([seed, 1]), n_fixes=60)
    xs, Ps = ref.run_rank4(drift.fixes, flow, drift.t)
    want_x, want_P = _filterpy_rank4(drift.fixes, flow, drift.t, ocean.ALPHA, ocean.SIGMA_F, ocean.SIGMA_GPS, ocean.DT)
    np.testing.assert_allclose(xs, want_x, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(Ps, want_P, rtol=1e-9, atol=1e-9)


@random_draws(false_fail=0.0, why="an identity (Galilean invariance of the filter); the draw only picks the fixes")
def test_rank4_in_a_uniform_current_is_rank4_in_still_water_seen_from_a_moving_boat(seed):
    # Galilean check: fixes in a uniform current c are still-water fixes shifted by c t
    rng = np.random.default_rng([seed, 1])
    c = np.array([0.4, -0.1])
    t = 60.0 * np.arange(30)
    still = rng.normal(0, 50, (30, 2)).cumsum(axis=0) * 0.1
    moving = still + t[:, None] * c
    xs_moving, P_moving = ref.run_rank4(moving, lambda p, s: c, t)
    xs_still, P_still = ref.run_rank4(still, lambda p, s: np.zeros(2), t)
    np.testing.assert_allclose(xs_moving[:, :2] - t[:, None] * c, xs_still[:, :2], atol=1e-8)
    np.testing.assert_allclose(xs_moving[:, 2:], xs_still[:, 2:], atol=1e-12)
    np.testing.assert_allclose(P_moving, P_still)


def test_filter_defaults_are_bobs_parameters():
    rank2 = inspect.signature(ref.run_rank2).parameters
    rank4 = inspect.signature(ref.run_rank4).parameters
    assert (rank2["sigma_walk"].default, rank2["sigma_gps"].default) == (ocean.SIGMA_WALK, ocean.SIGMA_GPS)
    assert (rank4["alpha"].default, rank4["sigma_F"].default, rank4["sigma_gps"].default, rank4["dt"].default) == (
        ocean.ALPHA, ocean.SIGMA_F, ocean.SIGMA_GPS, ocean.DT)


@random_draws(false_fail=0.0,
              why="exact facts: these covariances do not depend on the fixes, which the draw picks")
def test_filter_covariances_are_symmetric_and_shrink_from_the_gps_covariance(seed):
    rng = np.random.default_rng([seed, 1])
    y = rng.normal(0, 50, (40, 2))
    for xs, Ps in (ref.run_rank2(y), ref.run_rank4(y, lambda p, s: np.zeros(2), 60.0 * np.arange(40))):
        np.testing.assert_allclose(Ps, np.swapaxes(Ps, 1, 2), atol=1e-9)
        assert np.all(np.linalg.eigvalsh(Ps).min(axis=1) >= 0)
        assert np.all(Ps[1:, 0, 0] < ocean.SIGMA_GPS**2)


# ------------------------------------------------------------------------------------------------
# Blank 6: RMSE and ellipse area
# ------------------------------------------------------------------------------------------------


def test_track_rmse_on_a_hand_case():
    truth = np.zeros((4, 2))
    estimates = np.array([[3.0, 4.0], [0.0, 5.0], [-5.0, 0.0], [1.0, 0.0]])
    # distances 5, 5, 5, 1: RMSE = sqrt((25 + 25 + 25 + 1) / 4) = sqrt(19)
    assert ref.track_rmse(estimates, truth) == pytest.approx(np.sqrt(19.0))


@random_draws(false_fail=0.0,
              why="a grid count with a proven error bound (Steiner's formula); the draw only picks P")
def test_ellipse_area_matches_the_axes_and_a_grid_count(seed):
    # diag(a^2, b^2): the 2-sigma ellipse has semi-axes 2a, 2b
    assert ref.ellipse_area(np.diag([9.0, 4.0])) == pytest.approx(np.pi * 6.0 * 4.0)
    rng = np.random.default_rng([seed, 1])
    P = random_spd(rng, 2)
    areas = ref.ellipse_area(np.stack([P, 4 * P, np.eye(2)]), n_sigma=1.0)
    assert areas.shape == (3,) and areas[1] == pytest.approx(4 * areas[0])
    # count grid points inside {d : d^T P^-1 d <= 4}, a grid that covers it (its half-widths are 2 sqrt(P_ii))
    half = 2.5 * np.sqrt(P.diagonal().max())
    g = np.linspace(-half, half, 801)
    h = g[1] - g[0]
    d = np.stack(np.meshgrid(g, g), axis=-1)
    inside = np.einsum("...i,ij,...j->...", d, np.linalg.inv(P), d) <= 4.0
    # Error of the count: the h x h cells of the points inside cover every point of the ellipse farther than
    # r = h / sqrt(2) from its edge and nothing farther than r outside it, so by Steiner's formula for a convex
    # set of perimeter L <= 4 (a + b) (its bounding box's), |count h^2 - area| <= L r + pi r^2, a and b the
    # semi-axes. That is 0.6% of the area for a circle and 1.4% at the axis ratio 4 (for random_spd(2), rarer
    # than 1e-5); a wrong n_sigma (area off by 2 or 4), a missing pi or sqrt(det) is off by far more.
    a, b = 2.0 * np.sqrt(np.linalg.eigvalsh(P))
    r = h / np.sqrt(2.0)
    bound = 4.0 * (a + b) * r + np.pi * r**2
    assert bound < 0.05 * ref.ellipse_area(P)
    assert abs(ref.ellipse_area(P) - inside.sum() * h**2) <= bound


# ------------------------------------------------------------------------------------------------
# The shipped flow
# ------------------------------------------------------------------------------------------------


@random_draws(false_fail=0.0, why="an identity (interpolation at grid nodes); the draw only picks the nodes")
def test_flow_interpolation_reproduces_grid_values(flow, seed):
    rng = np.random.default_rng([seed, 1])
    k, i, j = rng.integers(0, len(flow.t), 50), rng.integers(0, len(flow.x), 50), rng.integers(0, len(flow.y), 50)
    p = np.column_stack((flow.x[i], flow.y[j]))
    np.testing.assert_allclose(flow(p, flow.t[k]), flow.velocity[k, i, j], atol=1e-12)


@random_draws(false_fail=0.0, why="an identity (two trilinear interpolators); the draw only picks the points")
def test_flow_interpolation_matches_scipy_regular_grid_interpolator(flow, seed):
    rng = np.random.default_rng([seed, 1])
    p = np.column_stack((rng.uniform(flow.x[0], flow.x[-1], 500), rng.uniform(flow.y[0], flow.y[-1], 500)))
    t = rng.uniform(flow.t[0], flow.t[-1], 500)
    oracle = RegularGridInterpolator((flow.t, flow.x, flow.y), flow.velocity)
    np.testing.assert_allclose(flow(p, t), oracle(np.column_stack((t, p))), atol=1e-12)
    # broadcasting: one time for a (5, 7, 2) block of positions
    block = p[:35].reshape(5, 7, 2)
    assert flow(block, 1000.0).shape == (5, 7, 2)


def test_flow_is_nearly_divergence_free(flow):
    # centred differences of an incompressible field on this grid: |div u| << |curl u|
    wake = (np.abs(flow.x[:, None]) > 1.5e3) | (np.abs(flow.y[None, :]) > 1.5e3)  # away from the island's edge
    for t in flow.t[::10]:
        div, vort = np.abs(flow.divergence(t))[wake], np.abs(flow.vorticity(t))[wake]
        assert div.mean() < 0.05 * vort.mean(), (t, div.mean(), vort.mean())


def test_flow_has_ocean_speeds_and_a_periodic_vortex_street(flow):
    speed = np.linalg.norm(flow.velocity, axis=-1)
    assert 0.6 < speed.max() < 1.0
    upstream = flow(np.array([-4500.0, 0.0]), flow.t)
    np.testing.assert_allclose(upstream[:, 0], 0.5, atol=0.05)
    # cross-stream velocity 5 km behind the island swings from side to side
    v = flow(np.array([5000.0, 0.0]), flow.t)[:, 1]
    assert v.max() > 0.1 and v.min() < -0.1
    ups = np.flatnonzero((v[:-1] < 0) & (v[1:] >= 0))
    assert len(ups) >= 1
    crossings = np.flatnonzero(np.sign(v[:-1]) != np.sign(v[1:]))
    half_periods = np.diff(flow.t[crossings]) / 60.0
    # Strouhal number f D / U of a Re = 150 wake on this grid: 0.12-0.22, a period of 2.5-4.6 h
    period_s = 2 * half_periods.mean() * 60.0
    strouhal = 1000.0 / (0.5 * period_s)
    assert 0.12 < strouhal < 0.22, strouhal


def test_shipped_file_says_how_it_was_built(flow):
    with np.load(ocean.DATA_FILE) as data:
        assert int(data["seed"]) == flow_build.FLOW_SEED
        assert float(data["reynolds"]) == flow_build.REYNOLDS
        assert data["velocity_m_s"].dtype == np.float16
        assert "phiflow" in str(data["solver"])
    assert flow.velocity.shape == (flow_build.N_SNAPSHOTS, 120, 50, 2)
    np.testing.assert_allclose(np.diff(flow.t), 360.0)


def test_the_file_writer_is_a_function_of_the_arrays(tmp_path):
    # rewriting the shipped arrays gives the shipped bytes: no timestamps, fixed order and level
    with np.load(ocean.DATA_FILE) as data:
        arrays = {name: data[name] for name in data.files}
    flow_build.write_npz(tmp_path / "again.npz", arrays)
    assert (tmp_path / "again.npz").read_bytes() == ocean.DATA_FILE.read_bytes()
    with zipfile.ZipFile(io.BytesIO(ocean.DATA_FILE.read_bytes())) as archive:
        assert {info.date_time for info in archive.infolist()} == {(1980, 1, 1, 0, 0, 0)}


@random_draws(false_fail=0.0, fixed_seed=True,
              why="reproducibility: one seed's exact output, computed twice, and another seed's differs")
def test_the_solver_is_reproducible_from_its_seed():
    # The shipped files are compared with rebuilt parts of the run below; here a short run shows
    # that the seed fixes the result bit for bit.
    # Three solver steps (each about 1 s): the seeded kick, advection, diffusion and the pressure solve
    # warm-started from the previous step's pressure all take part; the kick already differs at the
    # first kept snapshot (by 0.49 m/s between seeds 1 and 2).
    first = flow_build.simulate_wake(seed=1, n_snapshots=2, spin_up_steps=1)
    again = flow_build.simulate_wake(seed=1, n_snapshots=2, spin_up_steps=1)
    other = flow_build.simulate_wake(seed=2, n_snapshots=2, spin_up_steps=1)
    np.testing.assert_array_equal(first["velocity"], again["velocity"])
    assert not np.array_equal(first["velocity"], other["velocity"])


CHECKPOINTS = data.RECORDS_DIR / flow_build.CHECKPOINT_FILE_NAME


@random_draws(false_fail=0.0, fixed_seed=True,
              why="a rebuild of the first 34 solver steps from the seed, compared bit for bit with the shipped state")
def test_shipped_checkpoint_after_the_cross_current_is_rebuilt_from_the_seed(tmp_path):
    """The first KICK_STEPS (34) solver steps are rerun from the seed; the state they end in (both velocity
    components and the pressure) must equal the shipped checkpoint bit for bit, and the checkpoint file
    written from it and the shipped state at step 300 must be the shipped file, byte for byte.

    Covers the start of the build: the seed and the cross current it draws (every step that has it), the
    initial and sponge fields, the island, advection, diffusion and the warm-started pressure solve, in
    the installed PhiFlow and NumPy (a change in any of them, or in a constant they use, changes the
    state). The next test starts from the checkpoint at the first kept snapshot (step 300); steps 34 to
    300 are rerun only by the full rebuild, `python -m autograder data --check` (136 s), which maintainers
    run after changing the lab or its environment.
    """
    _, states = flow_build.run_solver(
        stop=flow_build.KICK_STEPS, checkpoint_steps=(flow_build.KICK_STEPS,))
    shipped = flow_build.shipped_checkpoint(flow_build.KICK_STEPS, CHECKPOINTS)
    for part in flow_build.STATE_PARTS:
        assert same_bits(states[flow_build.KICK_STEPS][part], shipped[part]), f"{part} differs from a rebuild"
    states[flow_build.SPIN_UP_STEPS] = flow_build.shipped_checkpoint(flow_build.SPIN_UP_STEPS, CHECKPOINTS)
    flow_build.write_npz(tmp_path / "checkpoints.npz", flow_build.checkpoint_arrays(states))
    assert (tmp_path / "checkpoints.npz").read_bytes() == CHECKPOINTS.read_bytes(), "the checkpoint file has other contents"


@random_draws(false_fail=0.0, fixed_seed=True,
              why="a rebuild of the kept 5 h from the shipped checkpoint, compared byte for byte with the shipped files")
def test_shipped_flow_is_rebuilt_bit_for_bit_from_its_checkpoint(tmp_path):
    """The 100 kept solver steps are rerun from the shipped state at the first kept snapshot (step
    SPIN_UP_STEPS = 300); the flow file written from them must equal the shipped file byte for byte.

    Covers every byte students load (all 51 snapshots, the grid, the times and the metadata), so any edit
    of the flow file fails, and the solver's steps, the snapshot spacing, the coarsening and the units of
    the kept window (a change there changes the snapshots). Together with the previous test, a change of
    the seed, the solver, a constant or PhiFlow's or NumPy's numerics fails in 134 of the 400 steps (about
    50 s instead of 136 s). What only the full rebuild (`python -m autograder data --check`) adds: that
    the shipped state at step 300 is where steps 34 to 300 lead, i.e. a hand edit of that state, or a change
    that would act only in those steps.
    """
    start = flow_build.shipped_checkpoint(flow_build.SPIN_UP_STEPS, CHECKPOINTS)
    snapshots, _ = flow_build.run_solver(start=start)
    flow_build.write_npz(tmp_path / "flow.npz", flow_build.flow_arrays(flow_build.kept_flow(snapshots)))
    assert (tmp_path / "flow.npz").read_bytes() == ocean.DATA_FILE.read_bytes(), "the flow file differs from a rebuild"


# ------------------------------------------------------------------------------------------------
# Bob's drift (course.ocean): the truth the filters are scored against
# ------------------------------------------------------------------------------------------------


@random_draws(false_fail=0.0, why="an identity (in still water RK4 moves by dt w); the draw only picks the drift")
def test_drift_in_still_water_moves_by_dt_times_own_velocity(flow, seed):
    still = flow.scaled(0.0)
    drift = ocean.simulate_drift(still, np.random.default_rng([seed, 1]), n_fixes=30)
    np.testing.assert_allclose(np.diff(drift.position, axis=0), ocean.DT * drift.truth[:-1, 2:], rtol=0, atol=1e-9)


@random_draws(false_fail=4e-7,
              why="4 chi-square tails of sample variances and a t tail of a correlation, from scipy.stats")
def test_drift_statistics_of_the_force_and_the_gps(flow, seed):
    drifts = ocean.simulate_drifts(flow.scaled(0.0), np.random.default_rng([seed, 1]), 400, n_fixes=30)
    w = np.stack([d.truth[:, 2:] for d in drifts])
    force = (w[:, 1:] - ocean.ALPHA * w[:, :-1]).reshape(-1, 2)
    gps = np.concatenate([d.fixes - d.position for d in drifts])
    # N = 400 x 29 = 11 600 forces and 400 x 30 = 12 000 GPS errors per axis, i.i.d. normal: N s^2 / sigma^2
    # ~ chi2_{N-1}, so P(|s / sigma - 1| > 0.035) = chi2.cdf(N 0.965^2, N - 1) + chi2.sf(N 1.035^2, N - 1)
    # = 9.8e-8 for the forces and 5.9e-8 for the GPS errors (scipy.stats), per axis.
    np.testing.assert_allclose(force.std(axis=0), ocean.SIGMA_F, rtol=0.035)
    np.testing.assert_allclose(gps.std(axis=0), ocean.SIGMA_GPS, rtol=0.035)
    # the x and y forces are independent: r sqrt(N - 2) / sqrt(1 - r^2) ~ t_{N-2}, P(|r| > 0.05) = 7.1e-8.
    # In all, 2 x 9.8e-8 + 2 x 5.9e-8 + 7.1e-8 = 3.9e-7.
    np.testing.assert_allclose(np.corrcoef(force.T)[0, 1], 0.0, atol=0.05)


@random_draws(false_fail=0.0,
              why="bounds that hold at every point of the box (checked on a 10 m grid); the draw picks points")
def test_drift_follows_the_current_and_rk4_converges(flow, seed):
    # with w = 0, one minute of RK4 with 3 substeps agrees with 50 substeps to far below a metre.
    # Both bounds hold with room at every point of the box at t = 1 h: on a 10 m grid of it (195 951
    # points) the largest RK4 difference is 0.0023 m (bound 0.05) and the largest departure from
    # 60 s x u is 0.40 m (bound 3), and neither can change by a factor of 7 within 5 m.
    rng = np.random.default_rng([seed, 1])
    p = np.column_stack((rng.uniform(1500, 8000, 20), rng.uniform(-1500, 1500, 20)))
    t = 3600.0
    coarse = ocean.drift_step(flow, p, np.zeros_like(p), t)
    fine = ocean.drift_step(flow, p, np.zeros_like(p), t, substeps=50)
    assert np.abs(coarse - fine).max() < 0.05
    # and it moves with the current: the displacement is about 60 s times the local velocity
    np.testing.assert_allclose(coarse - p, 60.0 * flow(p, t), atol=3.0)
