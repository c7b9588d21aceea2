"""Hidden tests of the reentry-srekf lab: each ``check_<blank>`` compares a student's blank with
``solutions.reentry_srekf.reference`` on seeded random states, random upper-triangular square roots of
sizes 2 to 7 and random index sets (head, tail, segment, non-contiguous, non-ascending). Every case is
drawn from ``cases.rng(stream)``, a stream of the submission seed (each check's stream is its old fixed seed).
Each case is labelled with the properties that set it apart (autograder/hidden_tests/case_kinds.py): the sign
of c, the altitude against the radar's, the kind of index set, the conditioning of the Gaussian, the number
of noise inputs or measurements.

Square roots are compared through S^T S on the correlation scale (``check_square_root``): the sign
of each row of an upper-triangular square root is free, so the tests are invariant to it."""

from __future__ import annotations

from typing import Callable

import numpy as np
from matplotlib.figure import Figure

import solutions.reentry_srekf.reference as ref
from autograder.hidden_tests import cases
from autograder.hidden_tests.case_kinds import case
from autograder.hidden_tests.diagnosis import diagnosed
from autograder.hidden_tests.isolate import isolate
from autograder.labs import lab_of
from course.checks import check_array, check_close, check_pair
from course.starship import RADAR_R2, check_band_plot, check_square_root

BLANKS = lab_of(__name__).blanks()
"""The lab's blanks, from its notebook: each check isolates the student's function with them."""
SIZES = (2, 3, 4, 5, 6, 7)


def _random_states(rng: np.random.Generator, count: int = 12) -> np.ndarray:
    """States [h, v, c] over the lower atmosphere, falling (v < 0, as equation (10) assumes), some c < 0;
    then two more, so that every seed has a c < 0 and an altitude below the radar's, RADAR_R2 = 5 km (one
    state below it with c > 0, one above it with c < 0)."""
    h = rng.uniform(0.0, 25_000.0, count)
    v = rng.uniform(-900.0, -20.0, count)
    c = rng.uniform(-2e-4, 3e-3, count)
    h_more = np.array([rng.uniform(0.0, 4_500.0), rng.uniform(5_500.0, 25_000.0)])
    c_more = np.array([rng.uniform(1e-4, 3e-3), rng.uniform(-2e-4, -1e-5)])
    return np.vstack([np.column_stack([h, v, c]), np.column_stack([h_more, rng.uniform(-900.0, -20.0, 2), c_more])])


def _drag_kinds(x: np.ndarray) -> dict[str, str]:
    """How a case of the process model names its state (autograder/hidden_tests/case_kinds.py): the sign of
    c, which the drag's sign follows."""
    return {"c": "a positive c" if x[2] > 0 else "a negative c"}


def _range_kinds(x: np.ndarray) -> dict[str, str]:
    """How a case of the radar model names its state: the altitude against the radar's (the sign of h - r2)."""
    return {"h": "an altitude above the radar's (h > r2)" if x[0] > RADAR_R2 else "an altitude below the radar's (h < r2)"}


def _random_sqrt(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random upper-triangular square root with columns scaled over six decades."""
    S = np.linalg.qr(rng.standard_normal((n, n)) + n * np.eye(n), mode="r")
    return S * 10.0 ** rng.uniform(-3.0, 3.0, n)[None, :]


def _index_sets(rng: np.random.Generator, n: int) -> list[tuple[str, np.ndarray]]:
    """Index sets of 1 to n - 1 entries (so that a complement is left for conditioning)."""
    k = int(rng.integers(1, n))
    k2 = min(max(k, 2), n - 1)
    perm = rng.permutation(n)
    start = int(rng.integers(0, n - k + 1))
    return [
        ("a head", np.arange(k)),
        ("a tail", np.arange(k, n)),
        ("a segment", np.arange(start, start + k)),
        ("a non-contiguous set", np.sort(perm[:k2])),
        ("a non-ascending set", np.sort(perm[:k2])[::-1]),
        ("a shuffled set", perm[:k2]),
    ]


def _index_kinds(idx: np.ndarray) -> dict[str, str]:
    """How a case's message names an index set: the leading entries in order or not (their marginal is the
    block of S, (19)), contiguous and in ascending order or not, and one index or several."""
    ascending = bool(np.all(np.diff(idx) > 0))
    if not ascending:
        kind = "a set in another order"
    else:
        kind = "a contiguous set in ascending order" if np.ptp(idx) == idx.size - 1 else "a spread-out set in ascending order"
    return {
        "leading": ("the leading entries in order (idx = 0..k-1)" if ascending and idx[0] == 0 and idx[-1] == idx.size - 1
                    else "other entries or another order"),
        "set": kind,
        "size": "a single index" if idx.size == 1 else "several indices",
    }


def _check_state_function(func: Callable, name: str, reference: Callable, shape: tuple[int, ...], stream: int,
                          hint: str, kinds: Callable[[np.ndarray], dict[str, str]]) -> None:
    func = isolate(func, ref, BLANKS)
    for x in _random_states(cases.rng(stream)):
        label = f"{name}(x) at x = [{x[0]:.1f}, {x[1]:.1f}, {x[2]:.3g}]"
        with case(**kinds(x)):
            value = check_array(func(x.copy()), label, shape, hint)
            check_close(value, reference(x), label, hint, rtol=1e-9, atol=1e-12 * (1 + np.max(np.abs(reference(x)))),
                        show_expected=False)


@diagnosed
def check_ballistic_dynamics(func: Callable) -> None:
    _check_state_function(func, "ballistic_dynamics", ref.ballistic_dynamics, (3,), 3301,
                          "f = [v, d - g, 0] with the drag d of equation (10).", _drag_kinds)


@diagnosed
def check_ballistic_jacobian(func: Callable) -> None:
    _check_state_function(func, "ballistic_jacobian", ref.ballistic_jacobian, (3, 3), 3302,
                          "Row i holds the derivatives of f_i with respect to h, v and c.", _drag_kinds)


@diagnosed
def check_radar_predict(func: Callable) -> None:
    _check_state_function(func, "radar_predict", ref.radar_predict, (1,), 3303,
                          "The range of equation (13), as an array of shape (1,).", _range_kinds)


@diagnosed
def check_radar_jacobian(func: Callable) -> None:
    _check_state_function(func, "radar_jacobian", ref.radar_jacobian, (1, 3), 3304,
                          "The derivatives of the range with respect to h, v and c, shape (1, 3).", _range_kinds)


@diagnosed
def check_marginal(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(3305)
    for n in SIZES:
        S, mu = _random_sqrt(rng, n), rng.standard_normal(n)
        for what, idx in _index_sets(rng, n):
            label = f"the marginal of {what} idx = {idx.tolist()} of a random Gaussian with n = {n}"
            with case(**_index_kinds(idx)):
                mu_I, S_I = check_pair(func(mu.copy(), S.copy(), idx.copy()), "marginal(mu, S, idx)", "mu_I", "S_I")
                want_mu, want_S = ref.marginal(mu, S, idx)
                check_close(check_array(mu_I, f"mu_I for {label}", (idx.size,)), want_mu, f"mu_I for {label}",
                            "The entries of mu_I come in the order of idx.", show_expected=False)
                check_square_root(check_array(S_I, f"S_I for {label}", (idx.size, idx.size)), want_S.T @ want_S,
                                  f"S_I for {label}", "Take a Q-less QR of the columns S[:, idx].", rtol=1e-8,
                                  show_expected=False)


def _conditional_kinds(idx_a: np.ndarray, idx_b: np.ndarray) -> dict[str, str]:
    """How a case's message names a conditioning: one known entry or several (R1 is then 1 x 1, and R1^-T
    is R1^-1); the known entries first and the rest after them in order (where the blocks of S give the
    answer, (25)) or not; one wanted entry, or several in ascending order or not."""
    n_b = idx_b.size
    head = np.array_equal(idx_b, np.arange(n_b)) and np.array_equal(idx_a, np.arange(n_b, n_b + idx_a.size))
    if idx_a.size == 1:
        wanted = "a single wanted entry x_A"
    else:
        wanted = "several wanted entries in ascending order" if np.all(np.diff(idx_a) > 0) else "several wanted entries in another order"
    return {
        "known": "a single known entry x_B" if n_b == 1 else "several known entries x_B",
        "blocks": "x_B first and x_A after it in order" if head else "another arrangement of x_B and x_A",
        "wanted": wanted,
    }


@diagnosed
def check_conditional(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(3306)
    for n in SIZES:
        S, mu = _random_sqrt(rng, n), rng.standard_normal(n)
        std = np.sqrt(np.sum(S**2, axis=0))
        mu = mu * std
        for what, idx_b in _index_sets(rng, n):
            idx_a = rng.permutation(np.setdiff1d(np.arange(n), idx_b))
            x_b = mu[idx_b] + std[idx_b] * rng.standard_normal(idx_b.size)
            label = f"x[{idx_a.tolist()}] given x[{idx_b.tolist()}] ({what}) with n = {n}"
            with case(**_conditional_kinds(idx_a, idx_b)):
                mu_c, S_c = check_pair(func(mu.copy(), S.copy(), idx_a.copy(), idx_b.copy(), x_b.copy()),
                                       "conditional(mu, S, idx_a, idx_b, x_b)", "mu_c", "S_c")
                want_mu, want_S = ref.conditional(mu, S, idx_a, idx_b, x_b)
                check_close(check_array(mu_c, f"mu_c for {label}", (idx_a.size,)), want_mu, f"mu_c for {label}",
                            "mu_A + R2^T R1^-T (x_B - mu_B), equation (31).", rtol=1e-8,
                            atol=1e-8 * float(np.max(std[idx_a])), show_expected=False)
                check_square_root(check_array(S_c, f"S_c for {label}", (idx_a.size, idx_a.size)), want_S.T @ want_S,
                                  f"S_c for {label}", "S_c = R3 of the QR of [S[:, idx_b], S[:, idx_a]].", rtol=1e-8,
                                  show_expected=False)


def _conditioning(ratio: float) -> str:
    """How a case's message names its Gaussian: a badly conditioned one loses the covariance form its digits."""
    return "a well-conditioned P" if ratio == 1.0 else "a badly conditioned P (far wider than the noise)"


def _update_cases(rng: np.random.Generator) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
    """(what, mu, S, ratio): well-conditioned and badly conditioned Gaussians of sizes 2 to 7.

    ``ratio`` sets how much larger the prior is than the noise in the updates (1 for a
    well-conditioned case, up to 1e5 for a badly conditioned one, where the covariance form loses
    about ten digits and the square-root form none).
    """
    updates = []
    for n in SIZES:
        S = _random_sqrt(rng, n)
        updates.append((f"a well-conditioned Gaussian with n = {n}", rng.standard_normal(n), S, 1.0))
        # columns over twelve decades and one nearly dependent column: P is badly conditioned
        S_bad = np.linalg.qr(rng.standard_normal((n, n)) + n * np.eye(n), mode="r")
        S_bad[:, -1] = S_bad[:, 0] + 1e-7 * S_bad[:, -1]
        S_bad = np.linalg.qr(S_bad, mode="r") * 10.0 ** rng.uniform(-6.0, 6.0, n)[None, :]
        updates.append((f"a badly conditioned Gaussian with n = {n}", rng.standard_normal(n), S_bad, 1e5))
    return updates


@diagnosed
def check_sqrt_time_update(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(3308)
    for what, mu, S, ratio in _update_cases(rng):
        n = mu.size
        for q in sorted({n, int(rng.integers(1, n + 2))}):
            A = np.eye(n) + 0.3 * rng.standard_normal((n, n))
            B = rng.standard_normal((n, q)) * np.sqrt(np.sum(S**2, axis=0)).max() / ratio
            J = np.hstack([A, B])
            S_Q = np.triu(rng.standard_normal((q, q))) + np.eye(q)
            S_Q[0, :] = 0.0  # a noise component of variance zero, like the altitude's in Q
            offset = rng.standard_normal(n)

            def f_and_jacobian(x, A=A, J=J, offset=offset):
                x = np.asarray(x, dtype=float)
                return A @ x + 0.1 * np.sin(x) + offset, J.copy()

            label = f"the step of {what}, with {q} noise input{'s' if q > 1 else ''}"
            inputs = "as many noise inputs as states (q = n)" if q == n else "another number of noise inputs (q != n)"
            with case(P=_conditioning(ratio), q=inputs):
                mu_next, S_next = check_pair(func(mu.copy(), S.copy(), f_and_jacobian, S_Q.copy()),
                                             "sqrt_time_update(mu, S, f_and_jacobian, S_Q)", "mu", "S")
                want_mu, want_S = ref.sqrt_time_update(mu, S, f_and_jacobian, S_Q)
                check_close(check_array(mu_next, f"the predicted mean for {label}", (n,)), want_mu,
                            f"the predicted mean for {label}", "Return the mean that f_and_jacobian(mu) gives.",
                            rtol=1e-12, atol=0.0, show_expected=False)
                check_square_root(check_array(S_next, f"S for {label}", (n, n)), want_S.T @ want_S, f"S for {label}",
                                  "S+ is the R factor of a Q-less QR of blkdiag(S, S_Q) @ J.T (J's columns are [x; w]).",
                                  rtol=1e-8, show_expected=False)


@diagnosed
def check_sqrt_measurement_update(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(3309)
    for what, mu, S, ratio in _update_cases(rng):
        n = mu.size
        for m in sorted({1, int(rng.integers(1, n + 1))}):
            H = rng.standard_normal((m, n))
            offset = rng.standard_normal(m)
            spread = np.sqrt(np.diag(H @ S.T @ S @ H.T))
            S_R = (np.triu(rng.standard_normal((m, m))) + 2 * np.eye(m)) * (spread / ratio)[None, :]
            S_R = np.linalg.qr(S_R, mode="r")

            def h_and_jacobian(x, H=H, offset=offset):
                x = np.asarray(x, dtype=float)
                return H @ x + offset, H.copy()

            y = H @ mu + offset + spread * rng.standard_normal(m)
            label = f"{m} measurement{'s' if m > 1 else ''} of {what}"
            with case(P=_conditioning(ratio), m="a single measurement (m = 1)" if m == 1 else "several measurements (m > 1)"):
                mu_post, S_post = check_pair(func(mu.copy(), S.copy(), y.copy(), h_and_jacobian, S_R.copy()),
                                             "sqrt_measurement_update(mu, S, y, h_and_jacobian, S_R)", "mu", "S")
                want_mu, want_S = ref.sqrt_measurement_update(mu, S, y, h_and_jacobian, S_R)
                std_post = np.sqrt(np.sum(want_S**2, axis=0))
                check_close(check_array(mu_post, f"the updated mean for {label}", (n,)), want_mu,
                            f"the updated mean for {label}",
                            "Condition the joint of [y; x], with mean [h(mu); mu], on y with your conditional.",
                            rtol=1e-8, atol=1e-6 * float(np.min(std_post)), show_expected=False)
                check_square_root(check_array(S_post, f"S for {label}", (n, n)), want_S.T @ want_S, f"S for {label}",
                                  "The joint square root of [y; x] is the R factor of the QR of [[S @ H.T, S], [S_R, 0]].",
                                  rtol=1e-8, show_expected=False)


@diagnosed
def check_plot_ballistic_coefficient(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(3307)
    for size in (7, 40):
        t = np.cumsum(rng.uniform(0.05, 0.2, size)) - 0.05
        c_true = 1e-3 + 5e-5 * rng.standard_normal(size)
        c_mean = c_true + 2e-4 * rng.standard_normal(size)
        c_std = rng.uniform(1e-5, 5e-4, size)
        with case(times=f"a series of {size} times"):
            ax = Figure().subplots()
            returned = func(ax, t.copy(), c_true.copy(), c_mean.copy(), c_std.copy())
            check_band_plot(ax, returned, t, c_true, c_mean, c_std, "plot_ballistic_coefficient")
