"""Hidden tests of the castaway-bob lab: each ``check_<blank>`` compares a student's blank with
``solutions.castaway_bob.reference`` on random cases (sizes, parameters, currents) that differ from the
notebook's examples, drawn from the submission seed (``cases.rng``, one stream per check)."""

from __future__ import annotations

import warnings
from typing import Callable

import numpy as np

import solutions.castaway_bob.reference as ref
from autograder.hidden_tests import cases
from autograder.hidden_tests.case_kinds import case
from autograder.hidden_tests.diagnosis import diagnosed
from autograder.hidden_tests.isolate import isolate
from autograder.labs import lab_of
from course import ocean
from course.checks import check_array, check_close, check_pair, count, random_spd

BLANKS = lab_of(__name__).blanks()
"""The lab's blanks, from its notebook: each check isolates the student's function with them."""
SIZES = ((1, 1), (2, 2), (4, 2), (5, 3), (6, 1))
"""(n, m): state and observation dimensions of the random matrix cases."""


def _state(n: int) -> str:
    """How a case's message names its state size (autograder/hidden_tests/case_kinds.py)."""
    return "a scalar state (n = 1)" if n == 1 else "a state vector (n > 1)"


def _observed(m: int) -> str:
    """How a case's message names its observation size."""
    return "a scalar observation (m = 1)" if m == 1 else "an observation vector (m > 1)"


def _fixes(n: int) -> str:
    """How a case's message names its number of fixes: one (the first estimate only), a few, many."""
    return "a single fix (the first estimate only)" if n == 1 else "a few fixes" if n <= 3 else "many fixes"


@diagnosed
def check_transition_matrix(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5101)
    steps = [*zip(rng.uniform(1.0, 300.0, 5), rng.uniform(0.3, 0.999, 5))]
    # and a step without damping, and a step of one second: where dt or alpha is 1, a factor forgotten is not seen
    steps += [(rng.uniform(1.0, 300.0), 1.0), (1.0, rng.uniform(0.3, 0.999))]
    for dt, alpha in steps:
        label = f"transition_matrix({dt:.3f}, {alpha:.3f})"
        with case(damping="no damping (alpha = 1)" if alpha == 1.0 else "damping (alpha < 1)",
                  step="a step of 1 s" if dt == 1.0 else "a step longer than 1 s"):
            A = check_array(func(float(dt), float(alpha)), label, (4, 4),
                            "A maps the state [x, y, wx, wy] to the next one.")
            check_close(A, ref.transition_matrix(dt, alpha), label, show_expected=False)


@diagnosed
def check_observation_matrix(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    with case(call="the one call, observation_matrix()"):
        H = check_array(func(), "observation_matrix()", (2, 4), "H maps the state [x, y, wx, wy] to a GPS fix [x, y].")
        check_close(H, ref.observation_matrix(), "observation_matrix()", show_expected=False)


@diagnosed
def check_trailing_mean(func: Callable) -> None:
    # warnings fail here, with a hint of this check's own: a warning that failed inside the isolated call would hide
    # the results of a window that took in the next fix (NaN where it is empty) from the diagnosis
    func = isolate(func, ref, BLANKS, warnings_fail=False)
    rng = cases.rng(5102)
    for n, order in ((1, 3), (2, 3), (7, 1), (9, 2), (40, 3), (25, 5), (6, 10)):
        y = rng.normal(0.0, 50.0, (n, 2)) + 1000.0 * rng.standard_normal(2)
        label = f"trailing_mean(y, order={order}) on {count(n, 'random fix')}"
        with case(fixes="a single fix" if n == 1 else "several fixes",
                  window="a window of one fix (order = 1)" if order == 1 else "a window of several fixes (order > 1)",
                  length="fewer fixes than the order" if n < order else "at least as many fixes as the order"):
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                estimates = func(y.copy(), order=order)
            if caught:
                raise AssertionError(
                    f"{label} gave the warning {caught[0].category.__name__}: {caught[0].message}. A graded function "
                    "must run without warnings: the mean of a window with no fix in it gives one; the window of fix n "
                    "holds the fixes up to n, and fix n itself.")
            estimates = check_array(estimates, label, (n, 2), "There is one estimate per fix.")
            check_close(estimates, ref.trailing_mean(y, order=order), label, show_expected=False)


def _matrix_cases(rng: np.random.Generator):
    for n, m in SIZES:
        yield n, m, random_spd(rng, n), rng.standard_normal((m, n)), random_spd(rng, m)


@diagnosed
def check_kalman_gain(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    for n, m, P, H, R in _matrix_cases(cases.rng(5103)):
        label = f"kalman_gain(P, H, R) with n = {n}, m = {m}"
        with case(n=_state(n), m=_observed(m)):
            K = check_array(func(P.copy(), H.copy(), R.copy()), label, (n, m),
                            "K maps an innovation (m,) to a state correction (n,), so it is n x m.")
            check_close(K, ref.kalman_gain(P, H, R), label, show_expected=False)


@diagnosed
def check_joseph_covariance(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5104)
    gains = []
    for n, m, P, H, R in _matrix_cases(rng):
        # an arbitrary gain, not the optimal one: (13) holds for every K, the simple form does not
        gains.append((n, m, P, H, R, rng.standard_normal((n, m)), "an arbitrary gain"))
    for n, m in ((2, 2), (5, 3)):
        # and the optimal gain, where the simple form is right too: a form right only there is not (13)
        P, H, R = random_spd(rng, n), rng.standard_normal((m, n)), random_spd(rng, m)
        gains.append((n, m, P, H, R, ref.kalman_gain(P, H, R), "the optimal gain"))
    for n, m, P, H, R, K, gain in gains:
        label = f"joseph_covariance(P, K, H, R) with {gain}, n = {n}, m = {m}"
        with case(gain=gain, n=_state(n), m=_observed(m)):
            P_new = check_array(func(P.copy(), K.copy(), H.copy(), R.copy()), label, (n, n))
            check_close(P_new, ref.joseph_covariance(P, K, H, R), label, show_expected=False,
                        hint="Check each factor and transpose of (13), (I - K H) P (I - K H)^T + K R K^T: it must "
                             "hold for any gain K, not only the optimal one.")


@diagnosed
def check_kalman_step(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5105)
    steps = []
    for (n, m, P, H, R), with_input in zip(_matrix_cases(rng), (False, True, True, False, True)):
        x, Q, y = rng.standard_normal(n), random_spd(rng, n), rng.standard_normal(m)
        A = np.eye(n) + 0.3 * rng.standard_normal((n, n))
        steps.append((n, m, x, P, y, A, H, Q, R, rng.standard_normal(n) if with_input else None))
    for n, m, with_input in ((2, 2, True), (4, 2, False)):
        # and a model without process noise (Q = 0): there the predicted covariance is A P A^T alone
        x, P, y = rng.standard_normal(n), random_spd(rng, n), rng.standard_normal(m)
        A, H, R = np.eye(n) + 0.3 * rng.standard_normal((n, n)), rng.standard_normal((m, n)), random_spd(rng, m)
        steps.append((n, m, x, P, y, A, H, np.zeros((n, n)), R, rng.standard_normal(n) if with_input else None))
    for n, m, x, P, y, A, H, Q, R, u in steps:
        args = (x.copy(), P.copy(), y.copy(), A.copy(), H.copy(), Q.copy(), R.copy())
        label = f"a random case with n = {n}, m = {m}, {'no' if u is None else 'a'} known input u"
        label += ", no process noise (Q = 0)" if not Q.any() else ""
        with case(u="no known input u" if u is None else "a known input u",
                  Q="no process noise (Q = 0)" if not Q.any() else "process noise Q", n=_state(n)):
            result = func(*args, u=None if u is None else u.copy())
            x_new, P_new = check_pair(result, "kalman_step(x, P, y, A, H, Q, R, u)", "x", "P")
            want_x, want_P = ref.kalman_step(x, P, y, A, H, Q, R, u=u)
            check_close(check_array(x_new, f"x on {label}", (n,)), want_x, f"the new estimate x on {label}",
                        show_expected=False)
            check_close(check_array(P_new, f"P on {label}", (n, n)), want_P, f"the new covariance P on {label}",
                        show_expected=False)


def _random_fixes(rng: np.random.Generator, n: int, speed: float) -> np.ndarray:
    heading = rng.uniform(0, 2 * np.pi)
    drift = 60.0 * speed * np.arange(n)[:, None] * np.array([np.cos(heading), np.sin(heading)])
    return drift + rng.normal(0.0, 20.0, (n, 2)).cumsum(axis=0) + rng.normal(0.0, 50.0, (n, 2))


@diagnosed
def check_run_rank2(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5106)
    # the default sigma_gps with a few and with many fixes, and another one with both too: a mistake that shows only
    # with another sigma_gps (the notebook's SIGMA_GPS for the argument) is then not told apart by the number of fixes
    for n, sigma_walk, sigma_gps in ((1, 30.0, 50.0), (2, 10.0, 50.0), (3, 20.0, 25.0), (15, 45.0, 20.0),
                                     (40, 30.0, 50.0), (80, 25.0, 70.0)):
        y = _random_fixes(rng, n, rng.uniform(0.0, 0.6))
        label = f"run_rank2 on {count(n, 'random fix')} with sigma_walk = {sigma_walk}, sigma_gps = {sigma_gps}"
        with case(fixes=_fixes(n), gps="the default sigma_gps (50 m)" if sigma_gps == 50.0 else "another sigma_gps"):
            xs, Ps = check_pair(func(y.copy(), sigma_walk=sigma_walk, sigma_gps=sigma_gps), label, "estimates",
                                "covariances")
            want_x, want_P = ref.run_rank2(y, sigma_walk=sigma_walk, sigma_gps=sigma_gps)
            check_close(check_array(xs, f"the estimates of {label}", (n, 2)), want_x, f"the estimates of {label}",
                        show_expected=False, rtol=1e-6, atol=1e-6)
            check_close(check_array(Ps, f"the covariances of {label}", (n, 2, 2)), want_P,
                        f"the covariances of {label}", show_expected=False, rtol=1e-6, atol=1e-6)


def _random_current(rng: np.random.Generator, steady: bool = False) -> Callable[[np.ndarray, float], np.ndarray]:
    """A smooth, time-dependent (or, ``steady``, constant in time), divergence-free current of about 0.1-0.6 m/s
    (a stream function)."""
    mean = rng.uniform(-0.5, 0.5, 2)
    a, k, omega, phase = rng.uniform(0.05, 0.3), rng.uniform(1e-3, 3e-3), rng.uniform(1e-4, 1e-3), rng.uniform(0, 6.3)
    omega = 0.0 if steady else omega

    def current(p: np.ndarray, t: float) -> np.ndarray:
        p = np.asarray(p, dtype=float)
        # psi = a / k sin(k x + phase - omega t) sin(k y): u = d psi / dy, v = -d psi / dx
        sx, cx = np.sin(k * p[..., 0] + phase - omega * t), np.cos(k * p[..., 0] + phase - omega * t)
        sy, cy = np.sin(k * p[..., 1]), np.cos(k * p[..., 1])
        return np.stack((mean[0] + a * sx * cy, mean[1] - a * cx * sy), axis=-1)

    return current


def _tidal_current(rng: np.random.Generator) -> Callable[[np.ndarray, float], np.ndarray]:
    """A current the same everywhere that turns in time, of about 0.1-0.6 m/s (a tide)."""
    mean, a = rng.uniform(-0.3, 0.3, 2), rng.uniform(0.1, 0.3)
    omega, phase = rng.uniform(1e-4, 1e-3), rng.uniform(0, 6.3)

    def current(p: np.ndarray, t: float) -> np.ndarray:
        p = np.asarray(p, dtype=float)
        turn = np.array([np.cos(omega * t + phase), np.sin(omega * t + phase)])
        return np.broadcast_to(mean + a * turn, p.shape[:-1] + (2,)).copy()

    return current


_CHANGING = "a current that changes in time and from place to place"
_STEADY, _TIDAL = "a current constant in time", "a current the same everywhere"
_UNUSED = "a single fix (no step: the current is not used)"


@diagnosed
def check_run_rank4(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5107)
    runs = [(1, 0.9, 0.02, 50.0, 60.0), (3, 0.95, 0.01, 50.0, 60.0), (20, 0.8, 0.05, 30.0, 30.0),
            (60, 0.97, 0.02, 60.0, 120.0)]
    kinds = [_CHANGING] * len(runs)
    # and a current constant in time (it varies from place to place), and one the same everywhere (it changes in
    # time): where the current is the same at every time, or at every place, taking it at another is not seen
    runs += [(15, 0.9, 0.03, 40.0, 60.0), (15, 0.9, 0.03, 40.0, 60.0)]
    kinds += [_STEADY, _TIDAL]
    for (n, alpha, sigma_F, sigma_gps, dt), kind in zip(runs, kinds):
        current = _tidal_current(rng) if kind == _TIDAL else _random_current(rng, steady=kind == _STEADY)
        name = {_CHANGING: "a random current", _STEADY: "a steady current", _TIDAL: "a tidal current"}[kind]
        t = rng.uniform(0.0, 3000.0) + dt * np.arange(n)
        y = _random_fixes(rng, n, 0.4)
        label = (f"run_rank4 on {count(n, 'fix')} in {name} (alpha = {alpha}, sigma_F = {sigma_F}, "
                 f"sigma_gps = {sigma_gps}, dt = {dt})")
        with case(fixes=_fixes(n), current=_UNUSED if n == 1 else kind):
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
    with case(fixes=_fixes(30), current=_CHANGING):
        xs, Ps = check_pair(func(drift.fixes.copy(), flow, drift.t.copy()), "run_rank4(y, flow, t)", "estimates",
                            "covariances")
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
        with case(estimates="a single estimate" if n == 1 else "several estimates"):
            value = func(estimates.copy(), truth.copy())
            check_close(check_array(value, label, (), "track_rmse returns one number, in metres."),
                        ref.track_rmse(estimates, truth), label, show_expected=False)


@diagnosed
def check_ellipse_area(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(5110)
    stacks = []
    for shape, n_sigma in (((), 2.0), ((5,), 2.0), ((3, 4), 1.0), ((7,), 3.0)):
        P = np.array([random_spd(rng, 2) * rng.uniform(10.0, 3000.0) for _ in range(int(np.prod(shape)))])
        stacks.append((P.reshape(shape + (2, 2)), n_sigma))
    # and ellipses along the axes (diagonal P), whose area the product of the two standard deviations gives too
    for shape, n_sigma in (((), 2.0), ((4,), 3.0)):
        P = np.array([np.diag(rng.uniform(10.0, 3000.0, 2)) for _ in range(int(np.prod(shape)))])
        stacks.append((P.reshape(shape + (2, 2)), n_sigma))
    for P, n_sigma in stacks:
        shape = P.shape[:-2]
        label = f"ellipse_area(P, n_sigma={n_sigma}) for covariances of shape {P.shape}"
        tilted = bool(np.any(P[..., 0, 1]))
        with case(P="tilted ellipses (correlated P)" if tilted else "ellipses along the axes (diagonal P)",
                  n_sigma=f"n_sigma = {n_sigma:g}",
                  shape="a single covariance" if shape == () else "a stack of covariances"):
            area = check_array(func(P.copy(), n_sigma=n_sigma), label, shape, "There is one area per 2 x 2 covariance.")
            check_close(area, ref.ellipse_area(P, n_sigma=n_sigma), label, show_expected=False)
