"""Hidden tests of the castaway-bob lab: each ``check_<blank>`` compares a student's blank with
``solutions.castaway_bob.reference`` on random cases (sizes, parameters, currents) that differ from the
notebook's examples, drawn from the submission seed (``cases.rng``, one stream per check)."""

from __future__ import annotations

from typing import Callable

import numpy as np

import solutions.castaway_bob.reference as ref
from autograder.hidden_tests import cases
from autograder.hidden_tests.diagnosis import diagnosed
from autograder.hidden_tests.isolate import isolate
from autograder.labs import lab_of
from course import ocean
from course.checks import check_array, check_close, check_pair, count, random_spd

BLANKS = lab_of(__name__).blanks()
"""The lab's blanks, from its notebook: each check isolates the student's function with them."""
SIZES = ((1, 1), (2, 2), (4, 2), (5, 3), (6, 1))
"""(n, m): state and observation dimensions of the random matrix cases."""


@diagnosed
def check_transition_matrix(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5101)
    for dt, alpha in zip(rng.uniform(1.0, 300.0, 5), rng.uniform(0.3, 0.999, 5)):
        label = f"transition_matrix({dt:.3f}, {alpha:.3f})"
        A = check_array(func(float(dt), float(alpha)), label, (4, 4), "A maps the state [x, y, wx, wy] to the next one.")
        check_close(A, ref.transition_matrix(dt, alpha), label, show_expected=False)


@diagnosed
def check_observation_matrix(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    H = check_array(func(), "observation_matrix()", (2, 4), "H maps the state [x, y, wx, wy] to a GPS fix [x, y].")
    check_close(H, ref.observation_matrix(), "observation_matrix()", show_expected=False)


@diagnosed
def check_trailing_mean(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5102)
    for n, order in ((1, 3), (2, 3), (7, 1), (9, 2), (40, 3), (25, 5), (6, 10)):
        y = rng.normal(0.0, 50.0, (n, 2)) + 1000.0 * rng.standard_normal(2)
        label = f"trailing_mean(y, order={order}) on {count(n, 'random fix')}"
        estimates = check_array(func(y.copy(), order=order), label, (n, 2), "There is one estimate per fix.")
        check_close(estimates, ref.trailing_mean(y, order=order), label, show_expected=False)


def _matrix_cases(rng: np.random.Generator):
    for n, m in SIZES:
        yield n, m, random_spd(rng, n), rng.standard_normal((m, n)), random_spd(rng, m)


@diagnosed
def check_kalman_gain(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    for n, m, P, H, R in _matrix_cases(cases.rng(5103)):
        label = f"kalman_gain(P, H, R) with n = {n}, m = {m}"
        K = check_array(func(P.copy(), H.copy(), R.copy()), label, (n, m),
                        "K maps an innovation (m,) to a state correction (n,), so it is n x m.")
        check_close(K, ref.kalman_gain(P, H, R), label, show_expected=False)


@diagnosed
def check_joseph_covariance(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5104)
    for n, m, P, H, R in _matrix_cases(rng):
        # an arbitrary gain, not the optimal one: (13) holds for every K, the simple form does not
        K = rng.standard_normal((n, m))
        label = f"joseph_covariance(P, K, H, R) with an arbitrary gain, n = {n}, m = {m}"
        P_new = check_array(func(P.copy(), K.copy(), H.copy(), R.copy()), label, (n, n))
        check_close(P_new, ref.joseph_covariance(P, K, H, R), label, show_expected=False,
                    hint="Equation (13) must hold for any gain K, not only the optimal one.")


@diagnosed
def check_kalman_step(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5105)
    for (n, m, P, H, R), with_input in zip(_matrix_cases(rng), (False, True, True, False, True)):
        x, Q, y = rng.standard_normal(n), random_spd(rng, n), rng.standard_normal(m)
        A = np.eye(n) + 0.3 * rng.standard_normal((n, n))
        u = rng.standard_normal(n) if with_input else None
        args = (x.copy(), P.copy(), y.copy(), A.copy(), H.copy(), Q.copy(), R.copy())
        result = func(*args, u=None if u is None else u.copy())
        x_new, P_new = check_pair(result, "kalman_step(x, P, y, A, H, Q, R, u)", "x", "P")
        want_x, want_P = ref.kalman_step(x, P, y, A, H, Q, R, u=u)
        case = f"a random case with n = {n}, m = {m}, {'a' if with_input else 'no'} known input u"
        check_close(check_array(x_new, f"x on {case}", (n,)), want_x, f"the new estimate x on {case}",
                    show_expected=False)
        check_close(check_array(P_new, f"P on {case}", (n, n)), want_P, f"the new covariance P on {case}",
                    show_expected=False)


def _random_fixes(rng: np.random.Generator, n: int, speed: float) -> np.ndarray:
    heading = rng.uniform(0, 2 * np.pi)
    drift = 60.0 * speed * np.arange(n)[:, None] * np.array([np.cos(heading), np.sin(heading)])
    return drift + rng.normal(0.0, 20.0, (n, 2)).cumsum(axis=0) + rng.normal(0.0, 50.0, (n, 2))


@diagnosed
def check_run_rank2(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5106)
    for n, sigma_walk, sigma_gps in ((1, 30.0, 50.0), (2, 10.0, 50.0), (15, 45.0, 20.0), (80, 25.0, 70.0)):
        y = _random_fixes(rng, n, rng.uniform(0.0, 0.6))
        label = f"run_rank2 on {count(n, 'random fix')} with sigma_walk = {sigma_walk}, sigma_gps = {sigma_gps}"
        xs, Ps = check_pair(func(y.copy(), sigma_walk=sigma_walk, sigma_gps=sigma_gps), label, "estimates", "covariances")
        want_x, want_P = ref.run_rank2(y, sigma_walk=sigma_walk, sigma_gps=sigma_gps)
        check_close(check_array(xs, f"the estimates of {label}", (n, 2)), want_x, f"the estimates of {label}",
                    show_expected=False, rtol=1e-6, atol=1e-6)
        check_close(check_array(Ps, f"the covariances of {label}", (n, 2, 2)), want_P,
                    f"the covariances of {label}", show_expected=False, rtol=1e-6, atol=1e-6)


def _random_current(rng: np.random.Generator) -> Callable[[np.ndarray, float], np.ndarray]:
    """A smooth, time-dependent, divergence-free current of about 0.1-0.6 m/s (a stream function)."""
    mean = rng.uniform(-0.5, 0.5, 2)
    a, k, omega, phase = rng.uniform(0.05, 0.3), rng.uniform(1e-3, 3e-3), rng.uniform(1e-4, 1e-3), rng.uniform(0, 6.3)

    def current(p: np.ndarray, t: float) -> np.ndarray:
        p = np.asarray(p, dtype=float)
        # psi = a / k sin(k x + phase - omega t) sin(k y): u = d psi / dy, v = -d psi / dx
        sx, cx = np.sin(k * p[..., 0] + phase - omega * t), np.cos(k * p[..., 0] + phase - omega * t)
        sy, cy = np.sin(k * p[..., 1]), np.cos(k * p[..., 1])
        return np.stack((mean[0] + a * sx * cy, mean[1] - a * cx * sy), axis=-1)

    return current


@diagnosed
def check_run_rank4(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5107)
    runs = ((1, 0.9, 0.02, 50.0, 60.0), (3, 0.95, 0.01, 50.0, 60.0), (20, 0.8, 0.05, 30.0, 30.0),
             (60, 0.97, 0.02, 60.0, 120.0))
    for n, alpha, sigma_F, sigma_gps, dt in runs:
        current = _random_current(rng)
        t = rng.uniform(0.0, 3000.0) + dt * np.arange(n)
        y = _random_fixes(rng, n, 0.4)
        label = (f"run_rank4 on {count(n, 'fix')} in a random current (alpha = {alpha}, sigma_F = {sigma_F}, "
                 f"sigma_gps = {sigma_gps}, dt = {dt})")
        result = func(y.copy(), current, t.copy(), alpha=alpha, sigma_F=sigma_F, sigma_gps=sigma_gps, dt=dt)
        xs, Ps = check_pair(result, label, "estimates", "covariances")
        want_x, want_P = ref.run_rank4(y, current, t, alpha=alpha, sigma_F=sigma_F, sigma_gps=sigma_gps, dt=dt)
        check_close(check_array(xs, f"the estimates of {label}", (n, 4)), want_x, f"the estimates of {label}",
                    show_expected=False, rtol=1e-6, atol=1e-6)
        check_close(check_array(Ps, f"the covariances of {label}", (n, 4, 4)), want_P,
                    f"the covariances of {label}", show_expected=False, rtol=1e-6, atol=1e-9)
    # and on a drift in the shipped ocean, with the default parameters
    flow = ocean.load()
    drift = ocean.simulate_drift(flow, cases.rng(5108), n_fixes=30)
    xs, Ps = check_pair(func(drift.fixes.copy(), flow, drift.t.copy()), "run_rank4(y, flow, t)", "estimates", "covariances")
    want_x, want_P = ref.run_rank4(drift.fixes, flow, drift.t)
    check_close(check_array(xs, "the estimates of a drift in the ocean", (30, 4)), want_x,
                "the estimates of a drift in the ocean", show_expected=False, rtol=1e-6, atol=1e-6)
    check_close(check_array(Ps, "the covariances of a drift in the ocean", (30, 4, 4)), want_P,
                "the covariances of a drift in the ocean", show_expected=False, rtol=1e-6, atol=1e-9)


@diagnosed
def check_track_rmse(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5109)
    for n in (1, 2, 10, 120):
        truth = rng.uniform(-5e3, 5e3, (n, 2))
        estimates = truth + rng.normal(0.0, 40.0, (n, 2)) * rng.uniform(0.2, 3.0, (n, 1))
        label = f"track_rmse on {count(n, 'random estimate')}"
        value = func(estimates.copy(), truth.copy())
        check_close(check_array(value, label, (), "track_rmse returns one number, in metres."),
                    ref.track_rmse(estimates, truth), label, show_expected=False)


@diagnosed
def check_ellipse_area(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5110)
    for shape, n_sigma in (((), 2.0), ((5,), 2.0), ((3, 4), 1.0), ((7,), 3.0)):
        P = np.array([random_spd(rng, 2) * rng.uniform(10.0, 3000.0) for _ in range(int(np.prod(shape)))])
        P = P.reshape(shape + (2, 2))
        label = f"ellipse_area(P, n_sigma={n_sigma}) for covariances of shape {P.shape}"
        area = check_array(func(P.copy(), n_sigma=n_sigma), label, shape, "There is one area per 2 x 2 covariance.")
        check_close(area, ref.ellipse_area(P, n_sigma=n_sigma), label, show_expected=False)
