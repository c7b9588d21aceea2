"""Hidden tests of the train-kf lab: each ``check_<blank>`` compares a student's blank with
``solutions.train_kf.reference`` on random cases of several state and observation sizes, drawn from
the submission seed (``cases.rng``, one stream per check)."""

from __future__ import annotations

from typing import Callable

import numpy as np

import solutions.train_kf.reference as ref
from autograder.hidden_tests import cases
from autograder.hidden_tests.case_kinds import case
from autograder.hidden_tests.diagnosis import diagnosed
from autograder.hidden_tests.isolate import isolate
from autograder.labs import lab_of
from course.checks import check_array, check_close, check_pair, count, random_spd

BLANKS = lab_of(__name__).blanks()
"""The lab's blanks, from its notebook: each check isolates the student's function with them."""
SIZES = ((1, 1), (2, 2), (3, 1), (4, 2), (5, 3))
"""(n, m): state and observation dimensions of the random cases."""


def _state(n: int) -> str:
    """How a case's message names its state size (autograder/hidden_tests/case_kinds.py)."""
    return "a scalar state (n = 1)" if n == 1 else "a state vector (n > 1)"


def _noise(R: np.ndarray) -> str:
    """How a case's message names its observation noise: diagonal (the fixes independent) or full."""
    return "a diagonal R" if np.count_nonzero(R - np.diag(np.diag(R))) == 0 else "a full R"


def _random_R(rng: np.random.Generator, m: int, full: bool) -> np.ndarray:
    """A random observation noise covariance (m x m), with correlations or without."""
    return random_spd(rng, m) if full else np.diag(rng.uniform(0.2, 3.0, m))


def _gain_cases(rng: np.random.Generator):
    for n, m in SIZES:
        for full in (False, True) if m > 1 else (False,):
            yield n, m, random_spd(rng, n), rng.standard_normal((m, n)), _random_R(rng, m, full)


def _check_gain(func: Callable, name: str, reference: Callable, stream: int) -> None:
    func = isolate(func, ref, BLANKS)
    for n, m, B, H, R in _gain_cases(cases.rng(stream)):
        with case(n=_state(n), R=_noise(R)):
            K = check_array(func(B.copy(), H.copy(), R.copy()), f"{name}(B, H, R) with n = {n}, m = {m}", (n, m),
                            "K maps an innovation (m,) to a state correction (n,), so it is n x m.")
            check_close(K, reference(B, H, R), f"{name} on a random case with n = {n}, m = {m}", show_expected=False)


@diagnosed
def check_gain_information_form(func: Callable) -> None:
    _check_gain(func, "gain_information_form", ref.gain_information_form, stream=1101)


@diagnosed
def check_gain_covariance_form(func: Callable) -> None:
    _check_gain(func, "gain_covariance_form", ref.gain_covariance_form, stream=1102)


@diagnosed
def check_process_noise(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1103)
    for sigma, dt_min in zip(rng.uniform(0.5, 30.0, 5), (1.0, 1.0, 0.5, 2.0, 5.0)):
        label = f"process_noise({sigma:.3f}, dt_min={dt_min})"
        with case(step="a step of one minute" if dt_min == 1.0 else "a step of another length"):
            Q = check_array(func(float(sigma), dt_min=dt_min), label, (2, 2))
            check_close(Q, ref.process_noise(sigma, dt_min), label, show_expected=False)


@diagnosed
def check_predict(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1104)
    for n, _ in SIZES:
        x, B, A, Q = rng.standard_normal(n), random_spd(rng, n), rng.standard_normal((n, n)), random_spd(rng, n)
        with case(n=_state(n)):
            x_f, B_f = check_pair(func(x.copy(), B.copy(), A.copy(), Q.copy()), "predict(x, B, A, Q)", "x_f", "B_f")
            want_x, want_B = ref.predict(x, B, A, Q)
            check_close(check_array(x_f, f"x_f with n = {n}", (n,)), want_x, f"x_f on a random case with n = {n}",
                        show_expected=False)
            check_close(check_array(B_f, f"B_f with n = {n}", (n, n)), want_B, f"B_f on a random case with n = {n}",
                        show_expected=False)


@diagnosed
def check_kupdate(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1105)
    for (n, m), full in zip(SIZES * 2, (False,) * len(SIZES) + (True,) * len(SIZES)):
        x_f, B_f, H = rng.standard_normal(n), random_spd(rng, n), rng.standard_normal((m, n))
        R, y = _random_R(rng, m, full), rng.standard_normal(m)
        with case(n=_state(n), R=_noise(R)):
            x_a, B_a = check_pair(func(x_f.copy(), B_f.copy(), y.copy(), H.copy(), R.copy()),
                                  "kupdate(x_f, B_f, y, H, R)", "x_a", "B_a")
            want_x, want_B = ref.kupdate(x_f, B_f, y, H, R)
            label = f"a random case with n = {n}, m = {m}"
            check_close(check_array(x_a, f"x_a with n = {n}", (n,)), want_x, f"x_a on {label}", show_expected=False)
            check_close(check_array(B_a, f"B_a with n = {n}", (n, n)), want_B, f"B_a on {label}", show_expected=False)


@diagnosed
def check_run_filter(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1106)
    for (n, m), T in zip(SIZES, (1, 5, 12, 30, 60)):
        x0, B0, Q, R = rng.standard_normal(n), random_spd(rng, n), random_spd(rng, n), random_spd(rng, m)
        A = np.eye(n) + 0.1 * rng.standard_normal((n, n))
        H, y = rng.standard_normal((m, n)), rng.standard_normal((T, m))
        with case(T="a single observation" if T == 1 else "several observations", n=_state(n)):
            xs, Bs = check_pair(func(y.copy(), x0.copy(), B0.copy(), A, Q, H, R), "run_filter(...)", "x_a", "B_a")
            want_x, want_B = ref.run_filter(y, x0, B0, A, Q, H, R)
            label = f"{count(T, 'random observation')} with n = {n}, m = {m}"
            check_close(check_array(xs, f"the estimates for {label}", (T, n)), want_x, f"the estimates for {label}",
                        show_expected=False)
            check_close(check_array(Bs, f"the covariances for {label}", (T, n, n)), want_B,
                        f"the covariances for {label}", show_expected=False)


@diagnosed
def check_nees(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1107)
    # a single time with n > 1 and several times with n = 1, so that the state size and the number of times never
    # go together: a NEES divided by n is then right on the cases with n = 1 alone, and the message says so
    for n, T in ((1, 1), (3, 1), (1, 7), (2, 20), (4, 3), (5, 60)):
        errors = rng.standard_normal((T, n))
        covariances = np.stack([random_spd(rng, n) for _ in range(T)])
        with case(n=_state(n), T="a single time" if T == 1 else "several times"):
            value = check_array(func(errors.copy(), covariances.copy()),
                                f"nees(errors, covariances) with T = {T}, n = {n}", (T,),
                                "One NEES value per time: errors (T, n) and covariances (T, n, n) give shape (T,).")
            check_close(value, ref.nees(errors, covariances), f"the NEES of {count(T, 'random error')} with n = {n}",
                        show_expected=False)
