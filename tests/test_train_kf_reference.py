"""The train-kf reference against independent implementations and hand-derived facts."""

import functools

import numpy as np
import pytest
import scipy.linalg
from filterpy.kalman import KalmanFilter

import solutions.train_kf.reference as ref
from autograder.release import data
from autograder.labs import get_lab
from course import train
from course.checks import random_spd
from random_draws import random_draws


@pytest.mark.parametrize("n, m", [(1, 1), (2, 2), (2, 1), (4, 3), (6, 2)])
@random_draws(false_fail=0.0, why="an identity between three formulas; the draw only picks well-conditioned B, H, R")
def test_gain_forms_agree_with_each_other_and_with_explicit_inverses(n, m, seed):
    rng = np.random.default_rng([seed, n, m])
    B, H, R = random_spd(rng, n), rng.standard_normal((m, n)), random_spd(rng, m)
    inv = np.linalg.inv
    # The textbook formulas, written with explicit inverses as an independent oracle.
    information = inv(inv(B) + H.T @ inv(R) @ H) @ (inv(R) @ H).T
    covariance = B @ H.T @ inv(H @ B @ H.T + R)
    np.testing.assert_allclose(ref.gain_information_form(B, H, R), information, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ref.gain_covariance_form(B, H, R), covariance, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(information, covariance, rtol=1e-9, atol=1e-12)


def test_gain_with_direct_observation_is_B_over_B_plus_R():
    # Derivation 1: with H = I the gain is B (R + B)^-1.
    B, R = np.diag([4.0, 9.0]), np.diag([4.0, 1.0])
    np.testing.assert_allclose(ref.gain_covariance_form(B, np.eye(2), R), np.diag([0.5, 0.9]))


@random_draws(false_fail=3e-10, why="(n-1) s^2 / sigma^2 is chi-square(n-1) with n = 200 000; a 2% band has both tails at 2.6e-10")
def test_process_noise_is_the_covariance_of_the_simulated_noise(seed):
    # Q must be the covariance of one step of the true process (course.train.forward), which
    # simulates Z = (z/60, z) without using Q. The residuals x_{t+1} - A x_t of one 200 000-step path
    # are 200 000 independent draws of Z = z (1/60, 1), so their sample covariance is s^2 (1/60, 1)(1/60, 1)^T,
    # with (n - 1) s^2 / 15^2 ~ chi-square(n - 1): every entry is off by the one ratio s^2 / 15^2.
    # P(|s^2 / 15^2 - 1| > 0.02) = chi2.sf(1.02 (n-1), n-1) + chi2.cdf(0.98 (n-1), n-1) = 2.6e-10 (scipy),
    # and a Q wrong by more than 2% fails.
    states = train.forward(np.zeros(2), 200_000, np.random.default_rng(seed))
    residuals = states[1:] - states[:-1] @ train.model_matrix().T
    np.testing.assert_allclose(np.cov(residuals.T), ref.process_noise(15.0), rtol=0.02)
    h = 1 / 60
    np.testing.assert_allclose(ref.process_noise(15.0), 225 * np.array([[h * h, h], [h, 1]]))


def test_process_noise_scales_with_the_step_length():
    # For dt = 2 min, h = 1/30 h: the position noise is z/30.
    np.testing.assert_allclose(ref.process_noise(15.0, dt_min=2.0)[0, 0], (15 / 30) ** 2)
    np.testing.assert_allclose(ref.process_noise(15.0, dt_min=2.0)[0, 1], 15**2 / 30)


def test_filter_matches_filterpy_on_the_shipped_data():
    data = train.load()
    x0, B0 = train.initial_belief()
    A, H, R, Q = train.model_matrix(), train.gps_operator(), train.gps_covariance(), ref.process_noise(15.0)
    xs, Bs = ref.run_filter(data.gps, x0, B0, A, Q, H, R)
    kf = KalmanFilter(dim_x=2, dim_z=2)
    kf.x, kf.P, kf.F, kf.H, kf.R, kf.Q = x0.copy(), B0.copy(), A, H, R, Q
    for t, y in enumerate(data.gps):
        kf.predict()
        kf.update(y)
        np.testing.assert_allclose(xs[t], kf.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(Bs[t], kf.P, rtol=1e-7, atol=1e-9)


@random_draws(false_fail=0.0, why="an identity: two implementations of one recursion; the draw only picks the model")
def test_filter_matches_filterpy_with_partial_observations(seed):
    rng = np.random.default_rng(seed)
    n, m, T = 4, 2, 25
    A = np.eye(n) + 0.1 * rng.standard_normal((n, n))
    Q, R, B0 = random_spd(rng, n), random_spd(rng, m), random_spd(rng, n)
    H, y, x0 = rng.standard_normal((m, n)), rng.standard_normal((T, m)), rng.standard_normal(n)
    xs, Bs = ref.run_filter(y, x0, B0, A, Q, H, R)
    kf = KalmanFilter(dim_x=n, dim_z=m)
    kf.x, kf.P, kf.F, kf.H, kf.R, kf.Q = x0.copy(), B0.copy(), A, H, R, Q
    for t in range(T):
        kf.predict()
        kf.update(y[t])
        np.testing.assert_allclose(xs[t], kf.x, rtol=1e-8, atol=1e-9)
        np.testing.assert_allclose(Bs[t], kf.P, rtol=1e-7, atol=1e-9)


def _error_covariance(T: int) -> tuple[np.ndarray, np.ndarray]:
    """The joint covariance C (2T x 2T) of the analysis errors e_1..e_T over one simulated hour, and P_t (T, 2, 2).

    The simulation draws the state at minute 0 from the filter's initial belief and follows the filter's
    model, so e_t = F_t e_{t-1} + (noise independent of the past) with F_t = (I - K_t H) A, and
    Cov(e_t, e_s) = F_t ... F_{s+1} P_s for t >= s. filterpy computes P_t and K_t (independently of ref).
    """
    A, H, R, Q = train.model_matrix(), train.gps_operator(), train.gps_covariance(), ref.process_noise(15.0)
    x0, B0 = train.initial_belief()
    kf = KalmanFilter(dim_x=2, dim_z=2)
    kf.x, kf.P, kf.F, kf.H, kf.R, kf.Q = x0.copy(), B0.copy(), A, H, R, Q
    P, F = np.empty((T, 2, 2)), np.empty((T, 2, 2))
    for t in range(T):
        kf.predict()
        kf.update(np.zeros(2))
        P[t], F[t] = kf.P, (np.eye(2) - kf.K @ H) @ A
    C = np.zeros((2 * T, 2 * T))
    for s in range(T):
        block = P[s]
        for t in range(s, T):
            if t > s:
                block = F[t] @ block
            C[2 * t:2 * t + 2, 2 * s:2 * s + 2] = block
            C[2 * s:2 * s + 2, 2 * t:2 * t + 2] = block.T
    return C, P


def _chernoff_tolerance(weights: np.ndarray, n_hours: int, probability: float) -> float:
    """Smallest a with P(|S - E S| >= a) <= probability, by Chernoff bounds on each tail.

    S is the sum over n_hours independent hours of sum_j w_j X_j, X_j independent chi-square(1), so
    log E exp(s (S - E S)) = n_hours sum_j (-log(1 - 2 s w_j)/2 - s w_j) for 2 s max(w) < 1; each tail
    gets probability / 2.
    """
    w = weights[weights > 1e-12]

    def log_bound(a: float, sign: int) -> float:
        # s on a log grid up to 1/(2 max w), where the upper tail's generating function ends
        s = (0.5 / w.max()) * np.geomspace(1e-6, 1.0 - 1e-9, 1500)[:, None]
        cumulant = n_hours * np.sum(-0.5 * np.log1p(-2 * sign * s * w) - sign * s * w, axis=1)
        return float(np.min(cumulant - s[:, 0] * a))

    target = np.log(probability / 2)
    low, high = 0.0, 10.0 * n_hours * w.sum()
    for _ in range(40):
        a = (low + high) / 2
        if max(log_bound(a, +1), log_bound(a, -1)) <= target:
            high = a
        else:
            low = a
    return high


def _quadratic_form_weights(C: np.ndarray, M: np.ndarray) -> np.ndarray:
    """The weights w of e^T M e = sum_j w_j X_j for e ~ N(0, C): the eigenvalues of L^T M L, C = L L^T."""
    L = np.linalg.cholesky(C)
    return np.linalg.eigvalsh(L.T @ M @ L)


@functools.cache
def _consistency_bounds(T: int, n_hours: int) -> tuple[dict, dict, dict]:
    """The matrices M of the three statistics e^T M e, their expected means, and their tolerances.

    The same for every seed, so computed once.
    """
    C, P = _error_covariance(T)
    selectors = {"nees": np.linalg.inv(P), "position": np.array([[1.0, 0.0], [0.0, 0.0]]),
                 "velocity": np.array([[0.0, 0.0], [0.0, 1.0]])}
    expected = {"nees": 2.0, "position": np.mean(P[:, 0, 0]), "velocity": np.mean(P[:, 1, 1])}
    tolerance = {}
    for name, M in selectors.items():
        weights = _quadratic_form_weights(C, scipy.linalg.block_diag(*np.broadcast_to(M, (T, 2, 2))))
        np.testing.assert_allclose(weights.sum(), T * expected[name], rtol=1e-9)
        tolerance[name] = _chernoff_tolerance(weights, n_hours, 1e-6 / 3) / (n_hours * T)
    # Before sampling: the filter's own variances are far below the GPS's (100 mi^2, 100 mph^2).
    assert np.sqrt(expected["position"] + tolerance["position"]) < 0.2 * 10.0
    assert expected["velocity"] + tolerance["velocity"] < 100.0
    return selectors, expected, tolerance


@random_draws(false_fail=1e-6, why="Chernoff bounds on each statistic's two tails, 1e-6 / 3 per statistic, from its exact chi-square weights")
def test_filter_beats_gps_and_is_consistent_over_many_hours(seed):
    # Over 200 simulated hours, the mean NEES of the filter is its state dimension 2 (a consistent
    # filter), and its mean squared position and velocity errors are the means of its own P_t, which are
    # far below the GPS's. Each statistic is a sum of independent hours of a quadratic form e^T M e of
    # the hour's Gaussian errors e ~ N(0, C), so it is a weighted sum of chi-square(1) variables with
    # weights known exactly (the eigenvalues of L^T M L). Each tolerance is the Chernoff bound for a
    # two-sided false-fail probability of 1e-6 / 3, so the test fails wrongly with probability <= 1e-6.
    # (The old check, |mean NEES - 2| < 0.1 over 200 hours, ignored that the NEES of one hour is strongly
    # correlated from minute to minute: its standard deviation is about 0.08, and it failed for about a
    # quarter of the seeds.) For 200 hours the tolerances are about 0.51 for the mean NEES (about 7 of its
    # standard deviations, 0.076), 0.67 mi^2 for the position and 5.9 mph^2 for the velocity mean squared
    # errors. Power: a filter that takes R off by a factor of 2 has a mean NEES of 3.46 (R / 2) or
    # 1.30 (2 R) and fails; the NEES hardly sees Q off by 2 (2.26 and 1.93), as section 9 shows.
    T, n_hours = 60, 200
    selectors, expected, tolerance = _consistency_bounds(T, n_hours)
    rng = np.random.default_rng(seed)
    A, H, R, Q = train.model_matrix(), train.gps_operator(), train.gps_covariance(), ref.process_noise(15.0)
    x0, B0 = train.initial_belief()
    totals = {name: 0.0 for name in selectors}
    for _ in range(n_hours):
        data = train.simulate(T, rng)
        xs, Bs = ref.run_filter(data.gps, x0, B0, A, Q, H, R)
        e = xs - data.truth
        totals["nees"] += np.sum(np.einsum("ti,tij,tj->t", e, np.linalg.inv(Bs), e))
        totals["position"] += np.sum(e[:, 0] ** 2)
        totals["velocity"] += np.sum(e[:, 1] ** 2)
    for name, total in totals.items():
        mean = total / (n_hours * T)
        assert abs(mean - expected[name]) < tolerance[name], (
            f"mean {name} statistic {mean:.4f}, expected {expected[name]:.4f} +- {tolerance[name]:.4f}")


def test_kupdate_moves_towards_the_observation():
    # The handout's typo (+ H x^f) would move the estimate away; the corrected update moves towards y.
    x_a, B_a = ref.kupdate(np.array([10.0, 60.0]), np.diag([4.0, 9.0]), np.array([12.0, 70.0]), np.eye(2), np.diag([4.0, 1.0]))
    np.testing.assert_allclose(x_a, [11.0, 69.0])
    np.testing.assert_allclose(B_a, np.diag([2.0, 0.9]))


@random_draws(false_fail=0.0, why="an identity of the simulated process: x_{t+1} - x_t = v_{t+1} / 60 for every draw")
def test_forward_follows_the_true_process(seed):
    rng = np.random.default_rng(seed)
    states = train.forward(np.array([0.0, 100.0]), 60, rng)
    assert states.shape == (61, 2)
    # x_{t+1} = x_t + v_{t+1}/60 holds exactly for the simulated process (x gets z/60 too).
    np.testing.assert_allclose(np.diff(states[:, 0]), states[1:, 1] / 60)


def test_shipped_data_is_rebuilt_bit_for_bit():
    assert data.stale_files([get_lab("train-kf")]) == []
