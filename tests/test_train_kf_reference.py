"""The train-kf reference against independent implementations and hand-derived facts."""

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

import solutions.train_kf as ref
from course import train
from course.checks import random_spd


@pytest.mark.parametrize("n, m", [(1, 1), (2, 2), (2, 1), (4, 3), (6, 2)])
def test_gain_forms_agree_with_each_other_and_with_explicit_inverses(n, m):
    rng = np.random.default_rng(n * 10 + m)
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


def test_process_noise_is_the_covariance_of_the_simulated_noise():
    # Q must be the covariance of one step of the true process (course.train.forward), which
    # simulates Z = (z/60, z) without using Q. 200 000 one-step samples: 4 sigma tolerance.
    rng = np.random.default_rng(7)
    steps = np.array([train.forward(np.zeros(2), 1, rng)[1] for _ in range(20_000)])
    np.testing.assert_allclose(np.cov(steps.T), ref.process_noise(15.0), rtol=0.05)
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


def test_filter_matches_filterpy_with_partial_observations():
    rng = np.random.default_rng(5)
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


def test_filter_beats_gps_and_is_consistent_over_many_hours():
    # Over 200 simulated hours the filter's position error is far below the GPS error, and its
    # normalised estimation error squared averages the state dimension (a consistent filter).
    rng = np.random.default_rng(11)
    A, H, R, Q = train.model_matrix(), train.gps_operator(), train.gps_covariance(), ref.process_noise(15.0)
    x0, B0 = train.initial_belief()
    nees, kf_err, gps_err = [], [], []
    for _ in range(200):
        data = train.simulate(60, rng)
        xs, Bs = ref.run_filter(data.gps, x0, B0, A, Q, H, R)
        e = xs - data.truth
        nees.append(np.mean(np.einsum("ti,tij,tj->t", e, np.linalg.inv(Bs), e)))
        kf_err.append(train.rmse(xs, data.truth))
        gps_err.append(train.rmse(data.gps, data.truth))
    assert abs(np.mean(nees) - 2.0) < 0.1
    assert np.mean(kf_err, axis=0)[0] < 0.2 * np.mean(gps_err, axis=0)[0]
    assert np.mean(kf_err, axis=0)[1] < np.mean(gps_err, axis=0)[1]


def test_kupdate_moves_towards_the_observation():
    # The handout's typo (+ H x^f) would move the estimate away; the corrected update moves towards y.
    x_a, B_a = ref.kupdate(np.array([10.0, 60.0]), np.diag([4.0, 9.0]), np.array([12.0, 70.0]), np.eye(2), np.diag([4.0, 1.0]))
    np.testing.assert_allclose(x_a, [11.0, 69.0])
    np.testing.assert_allclose(B_a, np.diag([2.0, 0.9]))


def test_forward_follows_the_true_process():
    rng = np.random.default_rng(3)
    states = train.forward(np.array([0.0, 100.0]), 60, rng)
    assert states.shape == (61, 2)
    # x_{t+1} = x_t + v_{t+1}/60 holds exactly for the simulated process (x gets z/60 too).
    np.testing.assert_allclose(np.diff(states[:, 0]), states[1:, 1] / 60)
