"""Hidden tests of the nonlinear-filters lab: each ``check_<blank>`` compares a student's blank with
``solutions.nonlinear_filters.reference`` on random cases of several sizes, drawn from the submission
seed (``cases.rng``, one stream per check; the seed of a generator handed to the student is drawn
from that stream too).

Point sets are compared as sets (any order of the points is right). The filter steps are compared on random
nonlinear f and h (a linear f and h make them the Kalman filter, and the reference is exactly that), and on
measurements with their angle at every place (alone, first of two, in the middle of three) or none, with
differences beyond +-pi in the components that are not angles, so that an answer that wraps a fixed component,
or every one, fails on every seed. The particle filter step is random; its checks are exact where the step is
determined (weights, which runs resample, systematic resampling's offspring counts, with a negligible process
noise), and one statistical check tests the process noise. Its false-fail probability for a correct step is at
most 5 x 1e-7 = 5e-7 on every submission seed (five chi-square tails, see ``_check_pf_noise``).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy import stats

import solutions.nonlinear_filters.reference as ref
from autograder.hidden_tests import cases
from autograder.hidden_tests.case_kinds import case
from autograder.hidden_tests.diagnosis import diagnosed
from autograder.hidden_tests.isolate import isolate
from autograder.hidden_tests.rng_use import check_draws_from_rng
from autograder.labs import lab_of
from course import cut
from course.air_traffic import symmetric_sqrt
from course.checks import check_array, check_close, check_pair, random_spd

BLANKS = lab_of(__name__).blanks()
"""The lab's blanks, from its notebook: each check isolates the student's function with them."""


def _dimension(n: int) -> str:
    """How a case's message names its state size (autograder/hidden_tests/case_kinds.py)."""
    return "a scalar state (n = 1)" if n == 1 else "a state vector (n > 1)"


def _points(name: str) -> str:
    """How a case's message names its point set: every rule of the lab has a point -z for each z, with its weight."""
    return "an asymmetric point set" if name == "random asymmetric" else "a symmetric point set"


def _sorted_rule(Z: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    order = np.lexsort(np.round(Z, 9).T[::-1])
    return Z[order], w[order]


def _check_rule(result, reference: tuple[np.ndarray, np.ndarray], label: str) -> None:
    Z, w = check_pair(result, label, "Z", "w")
    Zr, wr = reference
    Z = check_array(Z, f"Z from {label}", Zr.shape, "Z has one row per point and one column per state.")
    w = check_array(w, f"w from {label}", wr.shape, "w has one weight per point.")
    check_close(w.sum(), 1.0, f"the sum of the weights from {label}", "Weights of a rule for a probability sum to 1.",
                show_expected=False)
    (Z, w), (Zr, wr) = _sorted_rule(Z, w), _sorted_rule(Zr, wr)
    check_close(Z, Zr, f"the points from {label} (compared in any order)", show_expected=False)
    check_close(w, wr, f"the weights from {label} (matched to the points)", show_expected=False)


def _dimensions(stream: int, lowest: int, highest: int, count: int) -> list[int]:
    """``count`` different state dimensions from ``lowest`` to ``highest``, the lowest always among them,
    drawn from the submission seed: a rule's answer depends on n alone, so a table of answers learned
    from one submission's feedback misses the next submission's dimensions."""
    rng = cases.rng(stream)
    return sorted({lowest, *(int(n) for n in rng.choice(np.arange(lowest + 1, highest + 1), count - 1, replace=False))})


@diagnosed
def check_cubature_points(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    for n in _dimensions(1511, 1, 16, 6):
        with case(n="n = 1" if n == 1 else "n > 1"):
            _check_rule(func(n), ref.cubature_points(n), f"cubature_points({n})")


@diagnosed
def check_unscented_points(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    with case(call="kappa left at its default", kappa="kappa = 1", n="n > 1"):
        _check_rule(func(4), ref.unscented_points(4), "unscented_points(4) (kappa left at its default)")
    kappas = (2.0, 1.0, 0.5, 3.0, 1.0) + tuple(np.round(cases.rng(1512).uniform(0.1, 4.0, 1), 3))
    for n, kappa in zip(_dimensions(1513, 1, 16, 6), kappas):
        with case(call="kappa given", kappa=f"kappa {'=' if kappa == 1.0 else '<' if kappa < 1.0 else '>'} 1",
                  n="n = 1" if n == 1 else "n > 1"):
            _check_rule(func(n, kappa), ref.unscented_points(n, kappa), f"unscented_points({n}, kappa={kappa})")


@diagnosed
def check_cut4_points(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    for n in _dimensions(1514, 3, 10, 4):
        with case(n=f"n = {n}"):
            _check_rule(func(n), ref.cut4_points(n), f"cut4_points({n})")


def _symmetric_rule(rng: np.random.Generator, n: int, half: int) -> tuple[np.ndarray, np.ndarray]:
    """A random rule of 2 half points +-z_i with equal weights on each pair: every odd moment is exact (0),
    the even ones are not, so at an odd degree it is exact and one degree lower it is not."""
    Z, w = rng.standard_normal((half, n)), rng.dirichlet(np.ones(half))
    return np.vstack((Z, -Z)), np.concatenate((w, w)) / 2


@diagnosed
def check_moment_error(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1501)
    symmetric, asymmetric = _points("a rule"), _points("random asymmetric")
    rules = [(ref.cut4_points(4), d, symmetric) for d in (2, 4, 6)]
    rules += [(cut.cut8_points(), 8, symmetric), (ref.unscented_points(2), 4, symmetric)]
    # rules exact at this degree but not below: only the monomials of exactly this degree count
    rules += [(ref.cubature_points(3), 5, symmetric), (ref.unscented_points(3, 2.0), 5, symmetric)]
    for n, N, degree in [(1, 3, 1), (1, 5, 4), (2, 6, 3), (3, 7, 2), (4, 9, 5), (5, 11, 4), (6, 8, 3)]:
        rules.append(((rng.standard_normal((N, n)), rng.dirichlet(np.ones(N))), degree, asymmetric))
    for n, half, degree in [(1, 3, 3), (2, 4, 5), (3, 5, 3), (4, 6, 7)]:
        rules.append((_symmetric_rule(rng, n, half), degree, symmetric))
    failures = 0
    for (Z, w), degree, points in rules:
        if failures and degree >= 6:
            # once a case has failed, the rules of high degree are left out: a function that takes the number of
            # points for the dimension makes C(N + d - 1, d) monomials there, billions for CUT8 at degree 8
            continue
        label = f"moment_error on a rule of {len(w)} points in {Z.shape[1]} dimensions, degree {degree}"
        with case(points=points, weights="equal weights" if np.allclose(w, w[0]) else "unequal weights",
                  degree="an odd degree" if degree % 2 else "an even degree"):
            failures += 1  # taken back when the case's checks pass
            value = func(Z.copy(), w.copy(), degree)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise AssertionError(
                    f"{label} should return one number (a float), not {type(value).__name__}.") from None
            # Two correct answers differ by rounding: at most about 1e-16 times the sum of |w_i z_i^a|, below 1e-12
            # for these points (a few units from the origin) and degrees (<= 8), so atol = 1e-11 holds for every
            # correct answer where the error is 0, and rtol = 1e-8 where it is not.
            check_close(value, ref.moment_error(Z, w, degree), label, rtol=1e-8, atol=1e-11, show_expected=False)
            failures -= 1


def _random_map(rng: np.random.Generator, n: int, p: int) -> Callable:
    """A smooth nonlinear map of the last axis, R^n -> R^p, that works on stacks of points."""
    A, B, c = rng.standard_normal((p, n)), 0.3 * rng.standard_normal((p, n)), rng.standard_normal(p)
    return lambda X: np.sin(X) @ A.T + (X**2) @ B.T + c


def _rules_for(n: int, rng: np.random.Generator) -> list[tuple[str, tuple[np.ndarray, np.ndarray]]]:
    rules = [("cubature", ref.cubature_points(n)), ("unscented", ref.unscented_points(n))]
    if n >= 3:
        rules.append(("CUT4", ref.cut4_points(n)))
    if n == 5:
        rules.append(("CUT8", cut.cut8_points()))
    # a point set with no symmetry (weights summing to one): every rule above has a point -z for each
    # z, under which x_i = m - S z_i gives the same points as m + S z_i
    rules.append(("random asymmetric", (rng.standard_normal((n + 2, n)), rng.dirichlet(np.ones(n + 2)))))
    return rules


def _check_mean_cov(result, reference, n: int, label: str, hint: str = "") -> None:
    m, P = check_pair(result, label, "m", "P")
    check_close(check_array(m, f"the mean from {label}", (n,)), reference[0], f"the mean from {label}", hint,
                show_expected=False)
    check_close(check_array(P, f"the covariance from {label}", (n, n)), reference[1], f"the covariance from {label}",
                hint, rtol=1e-7, atol=1e-9, show_expected=False)


@diagnosed
def check_sigma_point_predict(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1502)
    models = []
    for n in range(1, 7):
        m, P, Q = rng.standard_normal(n), 0.5 * random_spd(rng, n), random_spd(rng, n)
        models.append((n, m, P, Q, _random_map(rng, n, n), "a nonlinear f", _rules_for(n, rng)))
    for n in (2, 4):
        # and a linear f with the symmetric rules: there the predicted mean is f(m), as in the Kalman filter
        m, P, Q = rng.standard_normal(n), 0.5 * random_spd(rng, n), random_spd(rng, n)
        A, c = rng.standard_normal((n, n)), rng.standard_normal(n)
        rules = [(name, rule) for name, rule in _rules_for(n, rng) if name != "random asymmetric"]
        models.append((n, m, P, Q, lambda X, A=A, c=c: X @ A.T + c, "a linear f", rules))
    for n, m, P, Q, f, model, rules in models:
        for name, (Z, w) in rules:
            label = f"sigma_point_predict with {name} points, n = {n}, a random {model.removeprefix('a ')}"
            with case(n=_dimension(n), points=_points(name), f=model):
                _check_mean_cov(func(m.copy(), P.copy(), f, Z.copy(), w.copy(), Q.copy()),
                                ref.sigma_point_predict(m, P, f, Z, w, Q), n, label)


_NEAR_PI, _AWAY = "a bearing near +-pi", "no bearing (no angle to wrap)"


def _bearing_case(rng: np.random.Generator) -> tuple:
    """A target almost due west of a radar: its predicted bearings straddle the cut at +-pi."""
    m = np.array([-3000.0, -40.0, 10.0])
    P = np.diag([100.0**2, 300.0**2, 4.0])
    h = lambda X: np.stack((np.hypot(X[..., 0], X[..., 1]) + X[..., 2], np.arctan2(X[..., 1], X[..., 0])), axis=-1)  # noqa: E731
    y = np.array([3005.0, np.pi - 0.02 + 0.01 * rng.standard_normal()])
    return m, P, y, h, np.diag([25.0, 0.02**2])


# The angle cases: measurements of a target almost due west of a radar at the origin, made of
# components at fixed places, so that an answer that wraps a fixed component (the radar's bearing,
# the second of two), or every component, fails on every submission seed; the numbers are drawn.
_COMPONENTS = ("range", "bearing", "range from a second radar")
_SECOND_RADAR = np.array([800.0, -600.0])


def _component(X, name: str):
    """One measurement component of states X (..., 3) = (xi, eta, range bias)."""
    if name == "bearing":
        return np.arctan2(X[..., 1], X[..., 0])
    if name == "range":
        return np.hypot(X[..., 0], X[..., 1]) + X[..., 2]
    return np.hypot(X[..., 0] - _SECOND_RADAR[0], X[..., 1] - _SECOND_RADAR[1])


def _component_jacobian(x: np.ndarray, name: str) -> np.ndarray:
    """The gradient of one component at a state x (3,)."""
    if name == "bearing":
        r2 = x[0] ** 2 + x[1] ** 2
        return np.array([-x[1] / r2, x[0] / r2, 0.0])
    if name == "range":
        r = np.hypot(x[0], x[1])
        return np.array([x[0] / r, x[1] / r, 1.0])
    d = x[:2] - _SECOND_RADAR
    return np.array([d[0] / np.hypot(*d), d[1] / np.hypot(*d), 0.0])


_ORDINALS = ("first", "second", "third")


def _angles_kind(angles: tuple[int, ...], p: int) -> str:
    """How a case's message names where its angle is."""
    if not angles:
        return "no angle (angles=())"
    if p == 1:
        return "an angle as the only component"
    return f"an angle as the {_ORDINALS[angles[0]]} of {p} components"


def _other_kind(beyond: bool) -> str:
    """How a case's message names the size of its differences in components that are not angles."""
    return "a difference beyond +-pi in a component that is not an angle" if beyond else \
        "no difference beyond +-pi in a component that is not an angle"


def _beyond_pi(differences: np.ndarray, angles: tuple[int, ...]) -> bool:
    """Whether a component that is not an angle differs by more than pi (there, wrapping changes it)."""
    others = [i for i in range(differences.shape[-1]) if i not in angles]
    return bool(others) and bool(np.any(np.abs(differences[..., others]) > np.pi))


def _angle_cases(rng: np.random.Generator) -> list[tuple]:
    """Cases (m, P, y, h, H_jacobian, R, angles) of every layout: a bearing alone (p = 1); range, bearing and a
    second radar's range (the bearing in the middle of p = 3); bearing then range (the bearing first of p = 2);
    and two ranges, no angle. Each range is measured 5 to 20 m (more than pi) from the predicted one, and each
    bearing across the cut at +-pi from the predicted bearing."""
    found = []
    for names, angles in [(("bearing",), (0,)), (("range", "bearing", "range from a second radar"), (1,)),
                          (("bearing", "range"), (0,)), (("range", "range from a second radar"), ())]:
        m = np.array([-3000.0 + 50.0 * rng.standard_normal(), -rng.uniform(20.0, 60.0), 10.0 + rng.standard_normal()])
        P = np.diag([100.0**2, 300.0**2, 4.0])
        y = np.array([np.pi - rng.uniform(0.005, 0.03) if name == "bearing"
                      else _component(m, name) + rng.choice((-1.0, 1.0)) * rng.uniform(5.0, 20.0) for name in names])
        R = np.diag([0.02**2 if name == "bearing" else 25.0 for name in names]) * rng.uniform(0.5, 2.0)
        h = lambda X, names=names: np.stack([_component(X, name) for name in names], axis=-1)  # noqa: E731
        H_jacobian = lambda x, names=names: np.stack([_component_jacobian(x, name) for name in names])  # noqa: E731
        found.append((m, P, y, h, H_jacobian, R, angles))
    return found


def _point_differences(m, P, y, h, Z) -> np.ndarray:
    """h(x_i) - y at the points of a rule (a case's label, not a comparison)."""
    return h(m + Z @ symmetric_sqrt(P)) - y


@diagnosed
def check_sigma_point_update(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1503)
    for n, p in [(1, 1), (2, 1), (3, 2), (4, 3), (5, 2), (6, 3)]:
        m, P, R, y = rng.standard_normal(n), 0.5 * random_spd(rng, n), random_spd(rng, p), rng.standard_normal(p)
        h = _random_map(rng, n, p)
        for name, (Z, w) in _rules_for(n, rng):
            label = f"sigma_point_update with {name} points, n = {n}, p = {p}, a random nonlinear h"
            with case(n=_dimension(n), points=_points(name), bearing=_AWAY, angles=_angles_kind((), p),
                      other=_other_kind(_beyond_pi(_point_differences(m, P, y, h, Z), ()))):
                _check_mean_cov(func(m.copy(), P.copy(), y.copy(), h, R.copy(), Z.copy(), w.copy()),
                                ref.sigma_point_update(m, P, y, h, R, Z, w), n, label)
    m, P, y, h, R = _bearing_case(rng)
    for name, (Z, w) in _rules_for(3, rng):
        label = (f"sigma_point_update with {name} points for a target due west (bearings near +-pi, angles=(1,)): "
                 "are the bearing differences wrapped to (-pi, pi]?")
        with case(n=_dimension(3), points=_points(name), bearing=_NEAR_PI, angles=_angles_kind((1,), 2),
                  other=_other_kind(_beyond_pi(_point_differences(m, P, y, h, Z), (1,)))):
            _check_mean_cov(func(m.copy(), P.copy(), y.copy(), h, R.copy(), Z.copy(), w.copy(), (1,)),
                            ref.sigma_point_update(m, P, y, h, R, Z, w, (1,)), 3, label)
    # the angle at other places, or none with differences beyond +-pi: only the components in angles are wrapped
    for m, P, y, h, _, R, angles in _angle_cases(rng):
        p = len(y)
        for name, (Z, w) in _rules_for(3, rng):
            label = (f"sigma_point_update with {name} points for a target due west, p = {p}, angles={angles}: "
                     "are exactly the components listed in angles wrapped?")
            with case(n=_dimension(3), points=_points(name), bearing=_NEAR_PI if angles else _AWAY,
                      angles=_angles_kind(angles, p), other=_other_kind(_beyond_pi(_point_differences(m, P, y, h, Z),
                                                                                   angles))):
                _check_mean_cov(func(m.copy(), P.copy(), y.copy(), h, R.copy(), Z.copy(), w.copy(), angles),
                                ref.sigma_point_update(m, P, y, h, R, Z, w, angles), 3, label)


def _measured(p: int) -> str:
    """How a case's message names its measurement size."""
    return "a scalar measurement (p = 1)" if p == 1 else "a measurement vector (p > 1)"


@diagnosed
def check_ekf_update(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(1504)
    for n, p in [(1, 1), (2, 1), (3, 2), (4, 3), (5, 2), (6, 3)]:
        m, P, R, y = rng.standard_normal(n), random_spd(rng, n), random_spd(rng, p), rng.standard_normal(p)
        A, B, c = rng.standard_normal((p, n)), 0.3 * rng.standard_normal((p, n)), rng.standard_normal(p)
        h = lambda x, A=A, B=B, c=c: np.sin(x) @ A.T + (x**2) @ B.T + c  # noqa: E731
        H_jacobian = lambda x, A=A, B=B: A * np.cos(x) + 2 * B * x  # noqa: E731
        label = f"ekf_update with n = {n}, p = {p}, a random nonlinear h"
        with case(n=_dimension(n), p=_measured(p), bearing=_AWAY, angles=_angles_kind((), p),
                  other=_other_kind(_beyond_pi(y - h(m), ()))):
            _check_mean_cov(func(m.copy(), P.copy(), y.copy(), h, H_jacobian, R.copy()),
                            ref.ekf_update(m, P, y, h, H_jacobian, R), n, label)
    m, P, y, h, R = _bearing_case(rng)
    H_jacobian = lambda x: np.array([[x[0] / np.hypot(x[0], x[1]), x[1] / np.hypot(x[0], x[1]), 1.0],  # noqa: E731
                                     [-x[1] / (x[0] ** 2 + x[1] ** 2), x[0] / (x[0] ** 2 + x[1] ** 2), 0.0]])
    label = "ekf_update for a target due west (bearing near +-pi, angles=(1,)): is the bearing innovation wrapped?"
    with case(n=_dimension(3), p=_measured(2), bearing=_NEAR_PI, angles=_angles_kind((1,), 2),
              other=_other_kind(_beyond_pi(y - h(m), (1,)))):
        _check_mean_cov(func(m.copy(), P.copy(), y.copy(), h, H_jacobian, R.copy(), (1,)),
                        ref.ekf_update(m, P, y, h, H_jacobian, R, (1,)), 3, label)
    # the angle at other places, or none with innovations beyond +-pi: only the components in angles are wrapped
    for m, P, y, h, H_jacobian, R, angles in _angle_cases(rng):
        p = len(y)
        label = (f"ekf_update for a target due west, p = {p}, angles={angles}: are exactly the components listed "
                 "in angles wrapped?")
        with case(n=_dimension(3), p=_measured(p), bearing=_NEAR_PI if angles else _AWAY,
                  angles=_angles_kind(angles, p), other=_other_kind(_beyond_pi(y - h(m), angles))):
            _check_mean_cov(func(m.copy(), P.copy(), y.copy(), h, H_jacobian, R.copy(), angles),
                            ref.ekf_update(m, P, y, h, H_jacobian, R, angles), 3, label)


# --- the particle filter step ------------------------------------------------------------------

PF_N = 2000
TINY_Q = 1e-20 * np.eye(3)
"""A process noise so small (1e-10 per state) that the propagated particles are f(X) to rounding."""
PF_ANGLES_N = 500
"""Particles in each angle case: the residuals of the ranges spread over tens of metres, the bearings over +-pi."""
NOISE_N = 100_000
NOISE_ALPHA = 1e-7
"""Each of the five chi-square checks of the process noise fails a correct step with probability NOISE_ALPHA."""


def _pf_model(rng: np.random.Generator):
    A = 0.9 * np.eye(3) + 0.05 * rng.standard_normal((3, 3))
    f = lambda X: X @ A.T + 0.1 * np.sin(X)  # noqa: E731
    h = lambda X: np.stack((X[..., 0] + 0.5 * X[..., 2], np.arctan2(X[..., 1], X[..., 0])), axis=-1)  # noqa: E731
    return f, h


def _pf_particles(rng: np.random.Generator, N: int) -> np.ndarray:
    """Particles west of the radar, so that their bearings straddle +-pi."""
    return np.column_stack((-1000 + 50 * rng.standard_normal(N), 60 * rng.standard_normal(N), rng.standard_normal(N)))


def _normalised(logw: np.ndarray) -> np.ndarray:
    return logw - np.logaddexp.reduce(logw)


_CORRELATED, _DIAGONAL = "a likelihood with a correlated R", "a likelihood with a diagonal R"
_FLAT = "a flat likelihood"
_NEGLIGIBLE, _NOISY = "a negligible process noise", "a process noise Q"


_RADAR_LAYOUT = _angles_kind((1,), 2)
"""The measurement of every case but the angle cases: (range, bearing), angles=(1,)."""


def _pf_case(resampled: bool, likelihood: str, noise: str = _NEGLIGIBLE, angles: str = _RADAR_LAYOUT):
    """One case of the particle filter step, by what sets it apart (autograder/hidden_tests/case_kinds.py)."""
    return case(resampling="resampling" if resampled else "no resampling", likelihood=likelihood, noise=noise,
                angles=angles)


def _pf_call(func: Callable, X, logw, y, rng, f, h, Q, R, ess_fraction: float, label: str,
             angles: tuple[int, ...] = (1,)):
    result = func(X.copy(), logw.copy(), y.copy(), rng, f, h, Q.copy(), R.copy(), angles, ess_fraction)
    X_new, logw_new = check_pair(result, label, "X", "logw")
    X_new = check_array(X_new, f"the particles from {label}", X.shape, "Return the particles as an (N, n) array.")
    logw_new = check_array(logw_new, f"the log-weights from {label}", logw.shape, "Return one log-weight per particle.")
    return X_new, logw_new


def _check_pf_weights(func: Callable) -> None:
    """Exact: without resampling (ess_fraction = 0), the particles are f(X) and the log-weights the reference's."""
    rng = cases.rng(1505)
    step_seed = int(rng.integers(2**63))  # the seed of the generator the step draws from
    f, h = _pf_model(rng)
    X = _pf_particles(rng, PF_N)
    logw = _normalised(rng.standard_normal(PF_N))
    # a correlated R: with a diagonal one, e^T R^-1 e cannot tell L^-1 e from L^-T e (R = L L^T)
    y, R = np.array([-1010.0, np.pi - 0.01]), np.array([[30.0**2, 0.6 * 30.0 * 0.05], [0.6 * 30.0 * 0.05, 0.05**2]])
    label = "bootstrap_pf_step with ess_fraction=0 (no resampling), bearings near +-pi and correlated noise R"
    with _pf_case(False, _CORRELATED):
        X_new, logw_new = _pf_call(func, X, logw, y, np.random.default_rng(step_seed), f, h, TINY_Q, R, 0.0, label)
        check_close(X_new, f(X), f"the particles from {label}",
                    "With a negligible Q, each particle should move to f(x) and keep its place in the array.",
                    rtol=1e-9, atol=1e-6, show_expected=False)
        _, want = ref.bootstrap_pf_step(X, logw, y, np.random.default_rng(step_seed), f, h, TINY_Q, R, (1,), 0.0)
        check_close(np.logaddexp.reduce(logw_new), 0.0, f"log(sum of the weights) from {label}",
                    "Return normalised log-weights: subtract the log of the sum of the weights.", atol=1e-9,
                    show_expected=False)
        check_close(logw_new, want, f"the log-weights from {label}",
                    "w_new is proportional to w_old p(y | x): check the likelihood, R^-1, and the wrapping of the bearing.",
                    rtol=1e-7, atol=1e-6, show_expected=False)


def _check_pf_angles(func: Callable) -> None:
    """Exact, as _check_pf_weights: the log-weights without resampling, for a bearing alone (p = 1), a bearing in
    the middle of p = 3, a bearing first of p = 2, and two ranges without an angle (residuals of tens of metres):
    an answer that wraps a fixed component, or every one, fails on every submission seed."""
    rng = cases.rng(1510)
    f = lambda X: X + 0.1 * np.sin(X)  # noqa: E731 (a model that keeps the particles' bearings on both sides of +-pi)
    for names, angles in [(("bearing",), (0,)), (("range", "bearing", "range from a second radar"), (1,)),
                          (("bearing", "range"), (0,)), (("range", "range from a second radar"), ())]:
        step_seed = int(rng.integers(2**63))  # the seed of the generator the step draws from
        X = _pf_particles(rng, PF_ANGLES_N)
        logw = _normalised(0.3 * rng.standard_normal(PF_ANGLES_N))
        h = lambda X, names=names: np.stack([_component(X, name) for name in names], axis=-1)  # noqa: E731
        y = np.array([np.pi - 0.01 if name == "bearing" else np.median(_component(f(X), name))
                      + rng.uniform(-20.0, 20.0) for name in names])
        R = np.diag([0.05**2 if name == "bearing" else 30.0**2 for name in names])
        p = len(names)
        label = (f"bootstrap_pf_step with ess_fraction=0 (no resampling), p = {p}, angles={angles}: are exactly the "
                 "residual components listed in angles wrapped?")
        with _pf_case(False, _DIAGONAL, angles=_angles_kind(angles, p)):
            _, logw_new = _pf_call(func, X, logw, y, np.random.default_rng(step_seed), f, h, TINY_Q, R, 0.0, label,
                                   angles)
            _, want = ref.bootstrap_pf_step(X, logw, y, np.random.default_rng(step_seed), f, h, TINY_Q, R, angles, 0.0)
            check_close(logw_new, want, f"the log-weights from {label}",
                        "Wrap the residual components listed in angles, wherever they are, and no other.",
                        rtol=1e-7, atol=1e-6, show_expected=False)


def _moderate_case(rng: np.random.Generator) -> tuple:
    """f, h, particles X (PF_N, n), normalised log-weights, y and a diagonal R of a case whose effective sample
    size stays above 0.7 N."""
    f, h = _pf_model(rng)
    X = _pf_particles(rng, PF_N)
    logw = _normalised(0.3 * rng.standard_normal(PF_N))
    return f, h, X, logw, np.array([-1010.0, np.pi - 0.01]), np.diag([1e8, 1e2])


def _check_pf_generator(func: Callable) -> None:
    """Exact: the step's draws come from the rng it is given (``rng_use``): the noise makes every result depend on them."""
    rng = cases.rng(1580)
    f, h, X, logw, y, R = _moderate_case(rng)
    label = "bootstrap_pf_step on one case, with generators in the same and in different states"
    with _pf_case(False, _DIAGONAL):
        check_draws_from_rng(lambda step_rng: _pf_call(func, X, logw, y, step_rng, f, h, TINY_Q, R, 0.7, label),
                             "bootstrap_pf_step", 1581)


def _check_pf_no_resampling(func: Callable) -> None:
    """Exact: when the effective sample size stays above the threshold, nothing is resampled."""
    rng = cases.rng(1506)
    step_seed = int(rng.integers(2**63))  # the seed of the generator the step draws from
    f, h, X, logw, y, R = _moderate_case(rng)
    label = "bootstrap_pf_step with weights whose effective sample size stays above 0.7 N"
    with _pf_case(False, _DIAGONAL):
        X_new, logw_new = _pf_call(func, X, logw, y, np.random.default_rng(step_seed), f, h, TINY_Q, R, 0.7, label)
        check_close(X_new, f(X), f"the particles from {label}",
                    "Resample only when the effective sample size 1/sum(w^2) falls below ess_fraction * N.",
                    rtol=1e-9, atol=1e-6, show_expected=False)
        _, want = ref.bootstrap_pf_step(X, logw, y, np.random.default_rng(step_seed), f, h, TINY_Q, R, (1,), 0.7)
        check_close(logw_new, want, f"the log-weights from {label}", "Without resampling the weights are kept.",
                    rtol=1e-7, atol=1e-6, show_expected=False)


def _check_pf_resampling(func: Callable) -> None:
    """Exact: systematic resampling gives parent i floor(N w_i) or ceil(N w_i) offspring, and equal weights."""
    rng = cases.rng(1507)
    step_seed = int(rng.integers(2**63))  # the seed of the generator the step draws from
    f, h = _pf_model(rng)
    X = _pf_particles(rng, PF_N)
    logw = _normalised(np.zeros(PF_N))
    y, R = np.array([-1010.0, np.pi - 0.01]), np.diag([20.0**2, 0.03**2])
    _, logw_ref = ref.bootstrap_pf_step(X, logw, y, np.random.default_rng(step_seed), f, h, TINY_Q, R, (1,), 0.0)
    w = np.exp(logw_ref)
    assert 1.0 / np.sum(w**2) < 0.7 * PF_N, "test set-up: this case must need resampling"
    label = "bootstrap_pf_step with weights whose effective sample size falls below 0.7 N"
    with _pf_case(True, _DIAGONAL):
        X_new, logw_new = _pf_call(func, X, logw, y, np.random.default_rng(step_seed), f, h, TINY_Q, R, 0.7, label)
        check_close(logw_new, np.full(PF_N, -np.log(PF_N)), f"the log-weights after resampling from {label}",
                    "After resampling every particle has weight 1/N, so log-weight -log(N).", atol=1e-9,
                    show_expected=False)
        moved = f(X)
        # each new particle is a copy of one propagated particle: find its parent
        parent = np.argmin(np.abs(X_new[:, None, 0] - moved[None, :, 0])
                           + np.abs(X_new[:, None, 1] - moved[None, :, 1]), axis=1)
        check_close(X_new, moved[parent], f"the resampled particles from {label}",
                    "Each resampled particle should be a copy of one propagated particle f(x_i).", rtol=1e-9, atol=1e-6,
                    show_expected=False)
        counts = np.bincount(parent, minlength=PF_N)
        low, high = np.floor(PF_N * w - 1e-6), np.ceil(PF_N * w + 1e-6)
        bad = int(np.sum((counts < low) | (counts > high)))
        if bad:
            raise AssertionError(
                f"{label}: {bad} particles got a number of copies that systematic resampling cannot give (it gives "
                "particle i either floor(N w_i) or ceil(N w_i) copies). Use systematic_resample with the normalised "
                "weights, not multinomial resampling or unnormalised weights."
            )


def _check_pf_threshold(func: Callable) -> None:
    """Exact: with a flat likelihood, weights whose effective sample size is 0.6 N are resampled (ESS
    below 0.7 N) and weights whose effective sample size is 0.8 N are kept. Half the particles have
    weight a times the other half's: ESS / N = (a + 1)^2 / (2 (a^2 + 1)), which is 0.6 for
    a = 5 + sqrt(24) and 0.8 for a = 3 (the likelihood moves it by less than 1e-9)."""
    rng = cases.rng(1509)
    f, h = _pf_model(rng)
    X = _pf_particles(rng, PF_N)
    flat = np.diag([1e12, 1e12])
    for a, fraction, resampled in ((5.0 + np.sqrt(24.0), 0.6, True), (3.0, 0.8, False)):
        logw = _normalised(np.log(np.where(rng.permutation(PF_N) < PF_N // 2, a, 1.0)))
        label = f"bootstrap_pf_step with a flat likelihood and weights whose effective sample size is {fraction} N"
        step_seed = int(rng.integers(2**63))  # the seed of the generator the step draws from
        with _pf_case(resampled, _FLAT):
            _, logw_new = _pf_call(func, X, logw, np.array([-1000.0, np.pi]), np.random.default_rng(step_seed), f, h,
                                   TINY_Q, flat, 0.7, label)
            want = np.full(PF_N, -np.log(PF_N)) if resampled else logw
            check_close(logw_new, want, f"the log-weights from {label}",
                        "Resample exactly when the effective sample size 1 / sum_i w_i^2 (of the normalised weights) is "
                        "below ess_fraction * N; after resampling every log-weight is -log(N).",
                        rtol=1e-7, atol=1e-6, show_expected=False)


def _chi2_outside(value: float, dof: int, alpha: float) -> bool:
    """Whether a chi-square(dof) statistic falls outside its central 1 - alpha interval."""
    return not (stats.chi2.ppf(alpha / 2, dof) <= value <= stats.chi2.isf(alpha / 2, dof))


def _check_pf_noise(func: Callable) -> None:
    """Statistical: x_new - f(x) ~ N(0, Q) for every particle (flat likelihood, no resampling).

    u = L^-1 (x_new - f(x)), with Q = L L^T, is N(0, I) for a correct step. Five chi-square checks,
    each failing a correct step with probability NOISE_ALPHA = 1e-7: sum |u|^2 ~ chi2(N n), N |mean u|^2
    ~ chi2(n), and sum (d . u)^2 ~ chi2(N) for three fixed unit directions d. Together they fail a
    correct step with probability at most 5e-7, over the submission seeds: the case and the seed of
    the step's generator are drawn from stream 1508.
    """
    rng = cases.rng(1508)
    A = np.array([[1.5, 0.4, 0.0], [-0.3, 0.8, 0.2], [0.1, 0.0, 1.2]])
    f = lambda X: X @ A.T  # noqa: E731
    h = lambda X: np.stack((X[..., 0], np.arctan2(X[..., 1], X[..., 0])), axis=-1)  # noqa: E731
    # Q = L L^T from a Cholesky factor with off-diagonal entries as large as its diagonal: rows z @ L (covariance
    # L^T L) then differ from N(0, Q) by at least 20% in total variance, far beyond what the checks let through
    L = np.diag(rng.uniform(0.5, 1.2, 3))
    L[np.tril_indices(3, -1)] = rng.choice((-1.0, 1.0), 3) * rng.uniform(0.8, 1.5, 3)
    Q = L @ L.T
    X = _pf_particles(rng, NOISE_N)
    logw = np.full(NOISE_N, -np.log(NOISE_N))
    label = "bootstrap_pf_step's process noise (a flat likelihood, no resampling)"
    step_rng = np.random.default_rng(int(rng.integers(2**63)))  # the generator the step draws its noise from
    with _pf_case(False, _FLAT, _NOISY):  # one case: the five chi-square checks are one statistical test
        X_new, _ = _pf_call(func, X, logw, np.array([-1000.0, np.pi]), step_rng, f, h, Q, np.diag([1e12, 1e12]), 0.0,
                            label)
        u = np.linalg.solve(L, (X_new - f(X)).T).T
        directions = np.array([[1.0, 1.0, 0.0], [0.0, 1.0, -1.0], [1.0, -1.0, 1.0]])
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        checks = [(np.sum(u**2), NOISE_N * 3, "the total variance"),
                  (NOISE_N * np.sum(u.mean(axis=0) ** 2), 3, "the mean")]
        checks += [(np.sum((u @ d) ** 2), NOISE_N, f"the variance along the direction {np.round(d, 3)}")
                   for d in directions]
        for value, dof, what in checks:
            if _chi2_outside(value, dof, NOISE_ALPHA):
                raise AssertionError(
                    f"{label}: {what} of the noise x_new - f(x), whitened by Q, is not that of N(0, Q) "
                    f"(a correct step fails this with probability 1e-7). Add v ~ N(0, Q) after f: "
                    "v = standard normals @ L.T with Q = L L^T."
                )


@diagnosed
def check_bootstrap_pf_step(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    _check_pf_weights(func)
    _check_pf_angles(func)
    _check_pf_no_resampling(func)
    _check_pf_resampling(func)
    _check_pf_threshold(func)
    _check_pf_noise(func)
    _check_pf_generator(func)
