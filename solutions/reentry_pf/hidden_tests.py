"""Hidden tests of the reentry-pf lab: each ``check_<blank>`` tests a student's blank against
``solutions.reentry_pf.reference``, with every other blank bound to the reference. run_particle_filter is
also run with another innovation_std and with the given bootstrap step.

The deterministic blanks (tracking_dynamics, simulate_radar, initial_cloud, run_particle_filter) are
compared with the reference on random inputs of several sizes. Every case, and the seed of every generator a student's function is given, is drawn from ``cases.rng(stream)``, a
stream of the submission seed (each check's stream is its old fixed seed), so that no two submissions
see the same cases. Each case is labelled with the properties that set it apart
(autograder/hidden_tests/case_kinds.py): one state or a cloud, one reading or several, the step and
innovation_std of a run.
``pf_step`` is stochastic, so its test is statistical (the second half of this module): weights
normalised and following step (d), the diagnostics it reports in ``info`` (exact), resampling
following the fitness weights (chi-square), the spread and centre of the artificial process noise
(the handout's "innovation") for the default and another ``innovation_std``, and the posterior of beta after a whole run against an ensemble of
reference runs. Each statistical check states its false-fail probability for a correct step,
derived from its statistic's distribution; together they stay below ``FALSE_FAIL_TOTAL`` = 1e-6.
tests/test_reentry_pf_reference.py shows the reference passing every check and every catalogued
pf_step mistake failing on each of 21 seeds, and the posterior statistic Gaussian over 400 submission seeds.
"""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import stats

import solutions.reentry_pf.reference as ref
from autograder.hidden_tests import cases
from autograder.hidden_tests.case_kinds import case
from autograder.hidden_tests.diagnosis import diagnosed
from autograder.hidden_tests.isolate import isolate, with_globals
from autograder.hidden_tests.rng_use import check_draws_from_rng
from autograder.labs import lab_of
from course import falling_object
from course.checks import check_array, check_close, check_pair, count
from course.falling_object import DT, INNOVATION_STD, SIGMA, FilterHistory

BLANKS = lab_of(__name__).blanks()
"""The lab's blanks, from its notebook: each check isolates the student's function with them."""
PF_STEP_STREAM = 4004
"""The stream of pf_step's statistical test: its draws come from cases.rng(PF_STEP_STREAM, k), one k per use."""

# =============================================================================================
# The deterministic blanks: compared with the reference on seeded random inputs
# =============================================================================================
def _random_states(rng: np.random.Generator, count: int) -> np.ndarray:
    """States (3, count) across the lab's range: h 0-80 km, v 100-4000 m/s, beta 5000-40000."""
    return np.vstack([rng.uniform(0.0, 80_000.0, count), rng.uniform(100.0, 4000.0, count), rng.uniform(5_000.0, 40_000.0, count)])


@diagnosed
def check_tracking_dynamics(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(4001)
    for N in (1, 7, 1000):
        x = _random_states(rng, N)
        label = f"tracking_dynamics(t, x) for a cloud x of shape (3, {N})"
        with case(x="a cloud of one particle (3, 1)" if N == 1 else "a cloud of particles (3, N)"):
            f = check_array(func(float(rng.uniform(0.0, 30.0)), x.copy()), label, (3, N),
                            "Return one column of derivatives per particle: rows dh/dt, dv/dt, dbeta/dt.")
            check_close(f, ref.tracking_dynamics(0.0, x), label, "Check each term of the drag in (2), g rho(h) v^2 / (2 beta): the factor g, rho(h) = gamma exp(-eta h), v^2 and 2 beta; and the signs of (1) and (2).",
                        rtol=1e-10, atol=1e-9, show_expected=False)
    for x in _random_states(rng, 5).T:
        label = "tracking_dynamics(t, x) for one state x of shape (3,)"
        with case(x="one state of shape (3,)"):
            f = check_array(func(float(rng.uniform(0.0, 30.0)), x.copy()), label, (3,))
            check_close(f, ref.tracking_dynamics(0.0, x), label, rtol=1e-10, atol=1e-9, show_expected=False)


def simulate_radar_cases() -> list[tuple[np.ndarray, np.ndarray, float, int]]:
    """(x0, t, sigma, rng seed) of the hidden test: lab-like starts and grids of 2 to 301 times, with
    steps of 0.1-0.2 s that do not start at 0. The long ones reach the dense air, where a loose
    tolerance shows. On every seed the object stays above 1 km: the lowest start, the fastest and the
    least braked (beta up to 20000; the lab's is 19161) is still 1.1 km up after 30 s, where a beta of
    30000 would reach -1.5 km."""
    rng = cases.rng(4002)
    radar_cases = []
    for n, step in ((2, 0.1), (40, 0.2), (160, 0.15), (301, 0.1)):
        x0 = np.array([rng.uniform(60_000.0, 70_000.0), rng.uniform(2_500.0, 3_200.0), rng.uniform(12_000.0, 20_000.0)])
        t = rng.uniform(0.0, 5.0) + step * np.arange(n)
        radar_cases.append((x0, t, float(rng.uniform(100.0, 800.0)), int(rng.integers(2**63))))
    return radar_cases


@diagnosed
def check_simulate_radar(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    tolerance_hint = ("The truth should be accurate to well under 1 m: set solve_ivp's rtol and atol "
                      "(the default rtol = 1e-3 is off by about 20 m).")
    for x0, t, sigma, seed in simulate_radar_cases():
        n = t.shape[0]
        label = f"a random start, {count(n, 'time')} from t = {t[0]:.2f} s, sigma = {sigma:.0f} m"
        span = "a span under 10 s" if t[-1] - t[0] < 10.0 else "a span of 20 s or more (into the dense air)"
        with case(times="two times" if n == 2 else "many times", span=span):
            x_true, b = check_pair(func(x0.copy(), t.copy(), sigma, np.random.default_rng(seed)),
                                   "simulate_radar(x0, t, sigma, rng)", "x_true", "b")
            x_true = check_array(x_true, f"x_true for {label}", (3, n), "One column per time t_j; rows h, v, beta.")
            b = check_array(b, f"b for {label}", (n,), "One reading per time t_j.")
            # x(t_0) = x0: a truth that starts anywhere else is off for a reason no tolerance explains
            check_close(x_true[:, 0], x0, f"the truth at the first time t[0] for {label}",
                        "The object is at x0 at the first time t[0], which is not 0 here: start the integration at t[0].",
                        rtol=1e-9, atol=1e-6, show_expected=False)
            want_x, want_b = ref.simulate_radar(x0, t, sigma, np.random.default_rng(seed))
            check_close(x_true[0], want_x[0], f"the true altitude for {label}", tolerance_hint, rtol=0.0, atol=1.0,
                        show_expected=False)
            check_close(x_true[1], want_x[1], f"the true speed for {label}", tolerance_hint, rtol=0.0, atol=0.25,
                        show_expected=False)
            check_close(x_true[2], want_x[2], f"the true beta for {label}", "beta' = 0: beta stays at x0[2].",
                        rtol=1e-9, atol=1e-6, show_expected=False)
            check_close(b - x_true[0], want_b - want_x[0], f"the radar noise b - h for {label}",
                        "Draw e = rng.standard_normal(len(t)) in one call and add sigma * e to the true altitude.",
                        rtol=1e-9, atol=1e-6, show_expected=False)


@diagnosed
def check_initial_cloud(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(4003)
    for N in (1, 5, 2000):
        b0, seed = float(rng.uniform(50_000.0, 70_000.0)), int(rng.integers(2**63))
        with case(N="a single particle (N = 1)" if N == 1 else "several particles (N > 1)"):
            x, w = check_pair(func(b0, N, np.random.default_rng(seed)), f"initial_cloud(b0, {N}, rng)", "x", "w")
            x = check_array(x, f"the prior cloud with N = {N}", (3, N), "One column per particle: rows h, v, beta.")
            w = check_array(w, f"the prior weights with N = {N}", (N,))
            want_x, want_w = ref.initial_cloud(b0, N, np.random.default_rng(seed))
            check_close(x, want_x, f"the prior cloud for a random b0 and N = {N}",
                        "Draw rng.standard_normal((3, N)) in one call; scale row i by the prior standard deviation of "
                        "variable i and add the prior mean [b0, v_init, beta_init].", rtol=1e-12, atol=1e-9,
                        show_expected=False)
            check_close(w, want_w, f"the prior weights for N = {N}", "Equal weights 1/N.", rtol=1e-12, atol=0.0,
                        show_expected=False)


def _exact(weights: np.ndarray, orders: np.ndarray) -> bool:
    """Whether every correct way of computing the cumulative weights and the orders is exact here:
    integer weights whose total is a power of two, and orders that are multiples of 1/1024."""
    total = float(np.sum(weights))
    return bool(np.all(weights == np.round(weights)) and total > 0 and total == 2.0 ** np.round(np.log2(total))
                and total < 2.0**40 and np.all(np.mod(np.asarray(orders) * 1024, 1.0) == 0.0))


def acceptable_quantiles(samples: np.ndarray, weights: np.ndarray, orders: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The smallest and the largest sample that a correct weighted quantile of each order may return.

    The text's rule, the first sorted sample whose normalised cumulative weight F_i reaches the order
    a, is decided by rounding wherever some F_i lies within rounding of a: at a = 0 and a = 1 (p = 100)
    always, and at equal weights. Every correct answer computes F_i = (w_1 + ... + w_i) / total in some
    order: accumulated one by one (np.cumsum, a loop), normalised before or after, divided by the last
    cumulative weight or by a pairwise sum. Each of those is within 2N u of the exact F_i (u = 2^-53:
    at most N - 1 roundings in the running sum of non-negative terms, each at most u times the total,
    as many in the total, and one in the division), and the order (1 -+ p/100) / 2 is within 2u of
    its exact value. (With integer weights whose total is a power of two, and orders that are multiples
    of 1/1024, every one of those computations is exact, and the tolerance is 0: ``_exact``.) So a
    correct answer's index is the first i with F_i >= a' for some a' within (2N + 2) u of a. F here is itself computed in floating point, within 2N u, and the tolerance
    4 (N + 2) u covers both. The answers accepted are the sorted samples from the first i with
    F_i >= a - tolerance to the first with F_i >= a + tolerance (the last sample if none), and
    nothing else: a mistake that moves the order or the cumulative weights by more than rounding
    still fails.
    """
    order = np.argsort(samples, kind="stable")
    s = samples[order]
    F = np.cumsum(weights[order]) / np.sum(weights)
    tolerance = 0.0 if _exact(weights, orders) else 4 * (s.shape[0] + 2) * 2.0**-53
    last = s.shape[0] - 1
    first = np.minimum(np.searchsorted(F, orders - tolerance), last)
    final = np.minimum(np.searchsorted(F, orders + tolerance), last)
    return s[first], s[final]


RUN_HINTS = {
    "mean": "the weighted mean sum_l w_l x_l of each variable at every t_j",
    "median": "the weighted median of each variable, credibility_interval(x[i], w, 0), at every t_j",
    "lo50": "the 50% intervals from credibility_interval(x[i], w, 50)",
    "hi50": "the 50% intervals from credibility_interval(x[i], w, 50)",
    "lo90": "the 90% intervals from credibility_interval(x[i], w, 90)",
    "hi90": "the 90% intervals from credibility_interval(x[i], w, 90)",
    "ess": "the effective sample size 1 / sum_l w_l^2 of the weights the step returned, at every t_j",
    "ess_resample": "info['ess'] from the step (N at t_0): health.record(history, j, info) after each step",
    "parents": "the number of distinct indices in info['parents'] (N at t_0): health.record(history, j, info) after each step",
    "roots": "the number of distinct particles of t_0 with descendants: one ResamplingHealth for the run, "
             "health.record(history, j, info) once after each step",
}


@diagnosed
def check_run_particle_filter(func: Callable) -> None:
    func = isolate(func, ref, BLANKS)
    rng = cases.rng(4006)
    bootstrap = functools.partial(falling_object.bootstrap_step, dynamics=ref.tracking_dynamics)
    runs = ((1, 50, {}), (6, 200, {}), (25, 1000, {}),
             (12, 300, {"innovation_std": np.array([30.0, 20.0, 40.0])}),
             (12, 300, {"step": bootstrap, "innovation_std": np.array([10.0, 10.0, 50.0])}))
    for n_times, N, options in runs:
        t = DT * np.arange(n_times)
        b = rng.uniform(55_000.0, 65_000.0) - rng.uniform(2_500.0, 3_500.0) * t + SIGMA * rng.standard_normal(n_times)
        seed = int(rng.integers(2**63))
        label = f"{n_times} random reading{'s' if n_times != 1 else ''}, N = {N}" + "".join(f", {key}={'bootstrap_step' if key == 'step' else value}"
                                                                 for key, value in options.items())
        with case(readings="a single reading" if n_times == 1 else "several readings",
                  step="the bootstrap step" if "step" in options else "pf_step",
                  innovation_std="another innovation_std" if "innovation_std" in options else "the default innovation_std"):
            history = func(b.copy(), N, np.random.default_rng(seed), **options)
            if not isinstance(history, FilterHistory):
                raise AssertionError(f"run_particle_filter should return a FilterHistory, not {type(history).__name__}.")
            want, low, high = _run_with_quantile_ranges(b, N, np.random.default_rng(seed), options)
            for name, hint in RUN_HINTS.items():
                shape = getattr(want, name).shape
                got = check_array(getattr(history, name), f"history.{name} for {label}", shape,
                                  "Fill every entry: one column per reading time t_j.")
                message = (f"It should hold {hint}. Start from initial_cloud(b[0], N, rng) at t_0, then call the step "
                           "(pf_step unless step is given) once with each later reading b_j, passing innovation_std "
                           "and info, using the rng you were given.")
                if name in low:
                    # any sample that a correct credibility_interval may return (acceptable_quantiles)
                    got = np.where((got >= low[name]) & (got <= high[name]), getattr(want, name), got)
                check_close(got, getattr(want, name), f"history.{name} for {label}", message,
                            rtol=1e-9, atol=1e-9, show_expected=False)


QUANTILE_FIELDS = {"median": (0, 0), "lo50": (0, 1), "hi50": (1, 1), "lo90": (0, 2), "hi90": (1, 2)}
"""history field -> (lo or hi, index among the orders of p = 0, 50, 90) of the reference run's call."""


def _run_with_quantile_ranges(b: np.ndarray, N: int, rng: np.random.Generator,
                              options: dict) -> tuple[FilterHistory, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The reference run, and for each quantile field of its history the smallest and the largest value
    that a correct weighted quantile may give there (acceptable_quantiles): a student's run may compute
    the quantiles its own way rather than with the given credibility_interval (issue 33 made it given
    code; it was a blank), which may break a tie within rounding otherwise."""
    ranges: list[tuple[np.ndarray, np.ndarray]] = []

    def recording(samples, weights, p):
        orders = np.concatenate([0.5 - np.asarray(p) / 200, 0.5 + np.asarray(p) / 200])
        ranges.append(acceptable_quantiles(np.asarray(samples), np.asarray(weights), orders))
        return ref.credibility_interval(samples, weights, p)

    want = with_globals(ref.run_particle_filter, {"credibility_interval": recording})(b, N, rng, **options)
    low = {name: np.empty_like(getattr(want, name)) for name in QUANTILE_FIELDS}
    high = {name: np.empty_like(getattr(want, name)) for name in QUANTILE_FIELDS}
    n_times = b.shape[0]
    for call, (first, final) in enumerate(ranges):  # calls in the run's order: time j, variable i
        j, i = divmod(call, 3)
        for name, (side, k) in QUANTILE_FIELDS.items():
            low[name][i, j], high[name][i, j] = first[side * 3 + k], final[side * 3 + k]
    assert len(ranges) == 3 * n_times, "the reference run calls credibility_interval once per variable and time"
    return want, low, high

# =============================================================================================
# pf_step: statistical checks
# =============================================================================================
# The test bed ("families"): K = 3 families of particles. All members of a family share one
# state (so they share one propagated candidate x^ and one fitness), and the families' ballistic
# coefficients are 5000 apart, 1000 innovation standard deviations, so every new particle names
# its parent's family without doubt (beta does not change in the propagation). The prior weights
# are random within a family, with fixed family totals, and the particles come in a random
# order. Two readings are used: one near the cloud (the fitness shapes the resampling), and one
# 40 sigma below every particle, where exp(-(h - b)^2 / (2 sigma^2)) underflows to zero for all
# of them unless the step works with log-weights.

PfStep = Callable[[np.ndarray, np.ndarray, float, np.random.Generator], tuple[np.ndarray, np.ndarray]]

# --- false-fail budget (probability that a correct pf_step fails) -----------------------------
ALPHA_RESAMPLING = 3e-7
"""Chi-square tests of the resampling counts: two tests (near and far reading), 1.5e-7 each."""
RESAMPLING_NOMINAL_TAIL = 1.25e-7
"""The chi-square(2) tail at the resampling threshold. The exact multinomial tail of Pearson's
statistic at that threshold is a little larger (1.26e-7 and 1.29e-7 for the two readings, by
exact enumeration in tests/), and below the 1.5e-7 each test is allowed."""
ALPHA_INNOVATION = 3e-7
"""Innovation spread and centre: 24 one-sided tails (2 settings of innovation_std x 3 coordinates
x mean and sum of squares x 2 sides), 1.25e-8 each."""
INNOVATION_TAILS = 24
OTHER_INNOVATION_STD = np.array([40.0, 250.0, 2.0])
"""A second setting of the keyword innovation_std for the innovation check (beta's stays far below
the 5000 between the families)."""
ALPHA_POSTERIOR = 3e-7
"""Posterior of beta after a whole run, against the fixed ensemble of reference runs (over the
submission seeds, with the ensemble as shipped: see check_posterior)."""
POSTERIOR_SIGMAS = 8.0
"""check_posterior's tolerance, in standard deviations s_R of the reference ensemble."""
TIE_BOUND = 1e-15
"""Bound on the probability that two fresh innovations coincide exactly (see check_innovation)."""
HEAVY_BOUND = 1e-9
"""The false-fail probability of check_heavy_last_particle (at most N (N - 1) 1e-15 with N = 1000)."""
FALSE_FAIL_TOTAL = ALPHA_RESAMPLING + ALPHA_INNOVATION + ALPHA_POSTERIOR + TIE_BOUND + HEAVY_BOUND
"""check_weights and check_info are exact (false-fail probability 0), so this bounds all the checks together."""

# --- the test bed ------------------------------------------------------------------------------
FAMILY_BETA = np.array([15_000.0, 20_000.0, 25_000.0])  # [kg/(m s^2)], 5000 apart
FAMILY_WEIGHT = np.array([0.2, 0.3, 0.5])  # total prior weight of each family
FAMILY_SIZE = 4000  # particles per family, so N = 12000
FAMILY_SPEED = 3000.0  # [m/s]
READING = 20_000.0  # b_{j+1} [m]: low enough that the drag changes v by 20-30 m/s in a step
NEAR_OFFSETS = np.array([-300.0, 200.0, 700.0])  # x^_1 - b_{j+1} of each family [m]
FAR_OFFSETS = 40 * SIGMA + np.array([0.0, 15.0, 30.0])  # [m]: 40 sigma away, a few sigma^2/(2 D) apart

_STDS = ", ".join(f"{s:g}" for s in INNOVATION_STD)

POSTERIOR_PARTICLES = 1000
POSTERIOR_RUNS = 30


@dataclass(frozen=True)
class FamilyCase:
    """One test-bed input for pf_step and what a correct step does with it.

    x (3, N), w (N,) and b_next are the input; family (N,) gives each particle's family;
    x_hat (3, K) is each family's propagated candidate (a), and p (K,) the probability that a
    resampled index falls in each family, from the fitness weights (b).
    """

    x: np.ndarray
    w: np.ndarray
    b_next: float
    family: np.ndarray
    x_hat: np.ndarray
    p: np.ndarray
    name: str


def family_case(offsets: np.ndarray, name: str) -> FamilyCase:
    """The K = 3 family test bed with propagated altitudes b_next + offsets, shuffled and weighted by a
    draw of the submission seed (the family totals, and so p, are the same for every seed)."""
    f = ref.tracking_dynamics
    rng = _rng(9)
    K = FAMILY_BETA.shape[0]
    # family states chosen so that the Forward Euler candidate x^_1 = h - dt v lands at b + offset
    states = np.vstack([READING + offsets + DT * FAMILY_SPEED, np.full(K, FAMILY_SPEED), FAMILY_BETA])
    x_hat = states + DT * f(0.0, states)
    family = rng.permutation(np.repeat(np.arange(K), FAMILY_SIZE))
    # random weights within each family, scaled so that family g carries FAMILY_WEIGHT[g]
    raw = rng.uniform(0.5, 1.5, size=family.shape[0])
    totals = np.bincount(family, weights=raw, minlength=K)
    w = raw * (FAMILY_WEIGHT / totals)[family]
    w /= np.sum(w)
    # p_g = W_g exp(-|x^_1g - b|^2 / (2 sigma^2)) / sum(...), in logarithms
    log_p = np.log(FAMILY_WEIGHT) - (x_hat[0] - READING) ** 2 / (2 * SIGMA**2)
    p = np.exp(log_p - log_p.max())
    return FamilyCase(states[:, family], w, READING, family, x_hat, p / p.sum(), name)


def near_case() -> FamilyCase:
    return family_case(NEAR_OFFSETS, "a reading within 2 sigma of the cloud")


def far_case() -> FamilyCase:
    return family_case(FAR_OFFSETS, "a reading 40 sigma below every particle")


def _run_step(pf_step: PfStep, case: FamilyCase, rng: np.random.Generator, **options: object) -> tuple[np.ndarray, np.ndarray]:
    """Call pf_step on a copy of the case (with the keyword ``options``); turn warnings and bad
    output into clear failures."""
    N = case.w.shape[0]
    underflow_hint = (
        " With a reading far from every particle, exp(-(h - b)^2 / (2 sigma^2)) is 0 for all of them; "
        "work with log-weights and subtract the largest one before you exponentiate."
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = pf_step(case.x.copy(), case.w.copy(), case.b_next, rng, **options)
        except Exception as error:
            numeric = [w for w in caught if issubclass(w.category, RuntimeWarning)]
            if not numeric:
                raise
            raise AssertionError(
                f"pf_step gave the warning '{numeric[0].message}' and then failed with "
                f"{type(error).__name__}: {error} (input: {case.name}).{underflow_hint}"
            ) from error
    for warning in caught:
        if issubclass(warning.category, RuntimeWarning):
            raise AssertionError(f"pf_step gave the warning '{warning.message}' for {case.name}.{underflow_hint}")
    x_new, w_new = check_pair(result, "pf_step", "x", "w")
    hint = f"(input: {case.name}, N = {N})."
    x_new = check_array(x_new, "The new particles x", (3, N), hint)
    w_new = check_array(w_new, "The new weights w", (N,), hint + underflow_hint)
    return x_new, w_new


def _parent_family(case: FamilyCase, x_new: np.ndarray) -> np.ndarray:
    """The family of each new particle, read off its beta (innovation std 5, families 5000 apart)."""
    distance = np.abs(x_new[2][:, None] - FAMILY_BETA[None, :])
    family = np.argmin(distance, axis=1)
    worst = float(np.max(distance[np.arange(family.shape[0]), family]))
    if worst > 1000.0:
        raise AssertionError(
            f"A new particle's beta is {worst:.0f} away from every candidate's beta ({case.name}). "
            "Each new particle should be a resampled candidate plus an innovation with standard "
            f"deviations ({_STDS}) (the beta innovation is only 5)."
        )
    return family


def _rng(stream: int) -> np.random.Generator:
    """The generator of one use within pf_step's test: a stream of the submission seed."""
    return cases.rng(PF_STEP_STREAM, stream)


def _cases(readings: tuple[str, ...]) -> list[tuple[FamilyCase, int]]:
    """The requested test-bed inputs ("near", "far") with their rng stream numbers."""
    builders = {"near": (near_case, 0), "far": (far_case, 1)}
    return [(builders[r][0](), builders[r][1]) for r in readings]


def check_weights(pf_step: PfStep, readings: tuple[str, ...] = ("near", "far")) -> None:
    """The returned weights are finite, non-negative, sum to 1, and follow step (d).

    Exact check (false-fail probability 0): given the new particles, step (d) fixes the weights,
    w(l) proportional to exp(-(|x_new_1(l) - b|^2 - |x^_1(k_l) - b|^2) / (2 sigma^2)), with x^(k_l)
    the parent's propagated candidate before the innovation. Both readings are tried; the far one
    overflows or underflows a step that does not work with log-weights.
    """
    for case, stream in _cases(readings):
        x_new, w_new = _run_step(pf_step, case, _rng(1 + stream))
        if np.any(w_new < 0):
            raise AssertionError(f"Some weights are negative ({case.name}).")
        total = float(np.sum(w_new))
        if abs(total - 1.0) > 1e-9:
            raise AssertionError(f"The weights should sum to 1, but they sum to {total:.6g} ({case.name}). Normalise them.")
        parent_h = case.x_hat[0, _parent_family(case, x_new)]
        # (d) in logarithms, normalised: the oracle for the weights
        log_w = -((x_new[0] - case.b_next) ** 2 - (parent_h - case.b_next) ** 2) / (2 * SIGMA**2)
        expected = np.exp(log_w - log_w.max())
        expected /= expected.sum()
        error = np.abs(w_new - expected)
        if np.any(error > 1e-6 * expected + 1e-12 * expected.max()):
            worst = int(np.argmax(error / (expected + 1e-300)))
            raise AssertionError(
                f"The weights do not follow step (d) ({case.name}): particle {worst} has weight "
                f"{w_new[worst]:.4g}, step (d) gives {expected[worst]:.4g}. In (d) compare the new "
                "particle's altitude with its parent's propagated altitude x^_1(k_l) before the "
                "innovation; do not multiply by the old or the fitness weights (resampling used them)."
            )


def chi2_counts(counts: np.ndarray, p: np.ndarray) -> float:
    """Pearson's statistic sum_g (n_g - N p_g)^2 / (N p_g) of family counts n against p."""
    expected = counts.sum() * p
    return float(np.sum((counts - expected) ** 2 / expected))


def resampling_threshold(alpha: float = RESAMPLING_NOMINAL_TAIL, df: int = 2) -> float:
    """The chi-square threshold with tail probability alpha: for df = 2 it is -2 log(alpha)."""
    return float(stats.chi2.isf(alpha, df))


def check_resampling(pf_step: PfStep, readings: tuple[str, ...] = ("near", "far")) -> None:
    """Resampling draws parents with the fitness weights (b) and with replacement.

    For a correct step the family counts (n_1, n_2, n_3) of the N = 12000 new particles are
    Multinomial(N, p), p from (b) (the families' weights are 0.2/0.3/0.5 before the fitness; near:
    p = (0.26, 0.44, 0.30), far: p = (0.60, 0.27, 0.13)). Pearson's statistic is then chi-square
    with 2 degrees of freedom (asymptotically; every expected count is over 1500), whose tail
    is exp(-c/2). Each of the two readings uses the threshold with chi-square tail 1.25e-7
    (c = 31.8); the exact multinomial probability of exceeding it, enumerated in tests/, is
    below 1.5e-7 for both p, so the false-fail probability is below 3e-7.
    """
    K = FAMILY_BETA.shape[0]
    threshold = resampling_threshold()
    for case, stream in _cases(readings):
        x_new, _ = _run_step(pf_step, case, _rng(3 + stream))
        counts = np.bincount(_parent_family(case, x_new), minlength=K)
        statistic = chi2_counts(counts, case.p)
        if statistic > threshold:
            expected = np.round(counts.sum() * case.p).astype(int)
            raise AssertionError(
                f"Resampling does not follow the fitness weights ({case.name}): the three groups of "
                f"particles were drawn {counts.tolist()} times, but step (b) gives about {expected.tolist()} "
                f"(chi-square {statistic:.1f} > {threshold:.1f}; a correct step exceeds it with probability "
                "below 1.5e-7). Draw N indices with replacement with probabilities w^ = w exp(-(x^_1 - b)^2 / "
                "(2 sigma^2)) / sum, using the propagated altitudes x^_1 and the old weights w."
            )


def innovation_bounds(n: int, alpha: float = ALPHA_INNOVATION / INNOVATION_TAILS) -> tuple[float, float, float]:
    """(lower, upper) bounds on a chi-square(n) sum of squares, and the bound on |N(0,1)|, each
    with one-sided tail alpha."""
    return float(stats.chi2.ppf(alpha, n)), float(stats.chi2.isf(alpha, n)), float(stats.norm.isf(alpha))


def check_info(pf_step: PfStep) -> None:
    """With info={}, the step reports the ESS of its resampling weights and the parents it drew.

    Exact check (false-fail probability 0): the ESS of the fitness weights (b) follows from the
    input alone, and each reported parent must belong to the family that the new particle's beta
    names.
    """
    case = near_case()
    info: dict = {}
    x_new, _ = _run_step(pf_step, case, _rng(7), info=info)
    missing = [key for key in ("ess", "parents") if key not in info]
    if missing:
        raise AssertionError(f"pf_step(..., info=info) should store {missing} in the dict info: "
                             "info['ess'] = 1 / sum(w_hat**2) and info['parents'] = k.")
    # (b) for every particle, in logarithms: the oracle of the resampling weights
    log_w_hat = np.log(case.w) - (case.x_hat[0, case.family] - case.b_next) ** 2 / (2 * SIGMA**2)
    w_hat = np.exp(log_w_hat - log_w_hat.max())
    w_hat /= w_hat.sum()
    check_close(float(np.asarray(info["ess"])), 1.0 / np.sum(w_hat**2), "info['ess']",
                "It is the effective sample size 1 / sum w^2 of the fitness weights w^ of step (b), the weights the "
                "resampling draws with (not of the old weights, nor of the new ones).", rtol=1e-9, atol=0.0, show_expected=False)
    parents = check_array(info["parents"], "info['parents']", (case.w.shape[0],), "One parent index k_l per new particle.")
    if not np.all((parents >= 0) & (parents < case.w.shape[0]) & (parents == np.round(parents))):
        raise AssertionError("info['parents'] should hold the indices k_l, integers from 0 to N - 1.")
    if np.any(case.family[parents.astype(int)] != _parent_family(case, x_new)):
        raise AssertionError("info['parents'] does not name the particles the new ones were copied from: store the "
                             "indices k that you used in x_hat[:, k].")


HEAVY_N = 1000
HEAVY_REST = 1e-15
"""The weight of every particle but the last in check_heavy_last_particle."""


def check_heavy_last_particle(pf_step: PfStep) -> None:
    """A cloud whose whole weight, but 1e-15 a particle, sits on its last particle, all particles in one
    state (so the fitness weights are the weights): every resampled parent is that last particle.

    False-fail probability: each of the N = 1000 draws picks another particle with probability
    (N - 1) 1e-15, so all N pick the last with probability at least 1 - N (N - 1) 1e-15 > 1 - 1e-9.
    A step that normalises its cumulative weights by another entry than the last, or that cannot reach
    the last particle, never picks it."""
    rng = _rng(11)
    state = np.array([[READING + DT * FAMILY_SPEED], [FAMILY_SPEED], [FAMILY_BETA[0]]])
    x = np.repeat(state, HEAVY_N, axis=1)
    w = np.full(HEAVY_N, HEAVY_REST)
    w[-1] = 1.0 - (HEAVY_N - 1) * HEAVY_REST
    info: dict = {}
    result = pf_step(x.copy(), w.copy(), READING, rng, info=info)
    check_pair(result, "pf_step", "x", "w")
    parents = check_array(info.get("parents"), "info['parents']", (HEAVY_N,), "One parent index k_l per new particle.")
    if np.any(parents != HEAVY_N - 1):
        raise AssertionError(
            f"With all the weight on the last of {HEAVY_N} particles (every other has weight 1e-15, all in one "
            f"state), {int(np.sum(parents != HEAVY_N - 1))} resampled parents are another particle. Draw k_l as the "
            "first index whose cumulative weight, normalised by the total (the last cumulative weight), exceeds u_l.")


def check_innovation(pf_step: PfStep, innovation_std: np.ndarray | None = None) -> None:
    """New particles are the parents' propagated candidates plus fresh N(0, D) innovations.

    With z = (x_new - x^(k_l)) / D^(1/2) per coordinate, a correct step gives N independent
    N(0, 1) values in each of the 3 coordinates, so the scatter sum (z - mean z)^2 is exactly
    chi-square(N - 1) and, independently, sum z / sqrt(N) exactly N(0, 1). The check runs with the
    handout's default and with innovation_std=OTHER_INNOVATION_STD; each of the 24 one-sided tails
    has probability 1.25e-8, 3e-7 in all. This catches a missing or wrongly scaled innovation (variance for standard
    deviation) and a missing or wrong propagation (a) (v dt = 300 m in h, 20-30 m/s in v).
    It also requires all N new particles to differ: an innovation added before resampling
    repeats the copies of each parent exactly. For a correct step a repeat needs two independent
    normal draws to agree to the last bit in all three coordinates; even if two draws agreed with
    probability 2^-32 (a generous bound for 53-bit doubles), the union over the N^2/2 = 7.2e7
    pairs is below 7.2e7 x 2^-96 < 1e-15 (for each of the two runs; TIE_BOUND covers both).
    """
    case = near_case()
    if innovation_std is None:  # the default: the handout's setting
        std, options, stream = INNOVATION_STD, {}, 5
    else:
        std, options, stream = np.asarray(innovation_std, dtype=float), {"innovation_std": np.array(innovation_std)}, 8
    stds = ", ".join(f"{value:g}" for value in std)
    x_new, _ = _run_step(pf_step, case, _rng(stream), **options)
    N = x_new.shape[1]
    distinct = np.unique(x_new, axis=1).shape[1]
    if distinct < N:
        raise AssertionError(
            f"Only {distinct} of the {N} new particles are different: some are exact copies. After resampling, give "
            "each new particle its own draw of the innovation D^(1/2) z: one fresh draw per particle, "
            "rng.standard_normal((3, N)), not one for all and not before resampling."
        )
    z = (x_new - case.x_hat[:, _parent_family(case, x_new)]) / std[:, None]
    lower, upper, z_max = innovation_bounds(N - 1)
    for i, name in enumerate(falling_object.STATE_NAMES):
        # spread about the sample mean: sum (z - mean z)^2 ~ chi-square(N - 1), independent of the mean
        scatter = float(np.sum((z[i] - np.mean(z[i])) ** 2))
        if not lower <= scatter <= upper:
            spread = math.sqrt(scatter / (N - 1)) * std[i]
            raise AssertionError(
                f"The innovation in {name} has standard deviation about {spread:.4g}; it should be "
                f"{std[i]:g} (the innovation is D^(1/2) z with D^(1/2) = diag(innovation_std), here diag({stds}), "
                "z ~ N(0, I_3), one fresh draw per new particle; use the keyword argument innovation_std)."
            )
        centre = float(np.sum(z[i]) / np.sqrt(N))
        if abs(centre) > z_max:
            mean_offset = float(np.mean(z[i]) * std[i])
            raise AssertionError(
                f"The new particles' {name} is off its parent's propagated candidate x^ by {mean_offset:.3g} "
                f"on average; it should be 0 (z = {centre:.1f}, limit {z_max:.1f}). Propagate with Forward Euler, "
                "x^ = x + dt f(x) with dt = DT, and resample the propagated candidates."
            )


def final_beta_mean(pf_step: PfStep, b: np.ndarray, N: int, rng: np.random.Generator) -> float:
    """Run the filter over the readings b with the reference prior cloud and pf_step; return the
    weighted posterior mean of beta at the last reading."""
    x, w = ref.initial_cloud(b[0], N, rng)
    for j in range(1, b.shape[0]):
        x, w = pf_step(x, w, b[j], rng)
    return float(np.asarray(x)[2] @ np.asarray(w))


@functools.lru_cache(maxsize=4)
def reference_ensemble(n_runs: int = POSTERIOR_RUNS, N: int = POSTERIOR_PARTICLES) -> np.ndarray:
    """Final posterior means of beta from n_runs reference runs on the shipped data (own seeds)."""
    b = falling_object.load().b
    # Fixed seeds, not the submission seed: the ensemble is the yardstick every submission is measured
    # against, computed once per grading process (prepare) and the same for all; what a submission's
    # seed decides is its own run alone (check_posterior), and a student learns nothing from it.
    runs = [final_beta_mean(ref.pf_step, b, N, np.random.default_rng([2019, 12, r])) for r in range(n_runs)]
    result = np.array(runs)
    result.setflags(write=False)
    return result


def prepare() -> None:
    """Called by the grader once per process, before it forks the checks: the reference ensemble that
    check_posterior compares with (a few seconds) is then computed once, not once per submission."""
    reference_ensemble()


def check_posterior(pf_step: PfStep) -> float:
    """After a run over the shipped data, the posterior mean of beta agrees with the reference's.

    The student's run (N = 1000, all 300 steps, the reference prior cloud, a generator drawn from the
    submission seed) gives m; R = 30 reference runs with fixed seeds give the ensemble mean m_R and
    standard deviation s_R, the same for every submission. The check fails when
    |m - m_R| > POSTERIOR_SIGMAS s_R = 8 s_R. Over submission seeds only m varies: for a correct step
    it is Gaussian (the particle filter's central limit theorem, Chopin 2004) with some mean mu and
    standard deviation sigma, and the false-fail probability is P(|m - m_R| > 8 s_R) with the
    ensemble as it is. tests/test_reentry_pf_reference.py estimates mu and sigma from 400 submission
    seeds, checks the Gaussian shape, and bounds that probability by 2e-8, below 3e-7, with sigma
    and |mu - m_R| at their upper 1e-7 confidence limits (point estimate 2e-12). (The old threshold,
    6.7 s_R sqrt(1 + 1/R) from Student's t, had tail 3e-7 on average over ensembles; for the shipped
    one its point estimate is 3e-9, but its bound at the same confidence 2e-6, so 400 seeds could not
    show that it held.)
    Returns m.
    """
    ensemble = reference_ensemble()
    b = falling_object.load().b
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = final_beta_mean(pf_step, b, POSTERIOR_PARTICLES, _rng(6))
    for warning in caught:
        if issubclass(warning.category, RuntimeWarning):
            raise AssertionError(f"pf_step gave the warning '{warning.message}' while filtering the shipped data.")
    centre, spread = float(ensemble.mean()), float(ensemble.std(ddof=1))
    tolerance = POSTERIOR_SIGMAS * spread
    if not np.isfinite(m) or abs(m - centre) > tolerance:
        raise AssertionError(
            f"After filtering the shipped data with N = {POSTERIOR_PARTICLES} particles, the posterior mean "
            f"of beta is {m:.0f}; reference runs give {centre:.0f} +- {tolerance:.0f} (a correct step "
            "falls outside with probability 3e-7). Check the whole step (a)-(d)."
        )
    return m


def statistical_checks(pf_step: PfStep) -> None:
    """Every statistical check, cheapest first, on the draws of the current submission seed. A correct
    step fails with probability below FALSE_FAIL_TOTAL over the submission seeds. Each check is one case,
    labelled with the part of the step it tests (autograder/hidden_tests/case_kinds.py), and with the
    innovation_std it runs with."""
    default = "the default innovation_std"
    with case(part="the weights of step (d)", innovation_std=default):
        check_weights(pf_step)
    with case(part="the ESS and the parents reported in info", innovation_std=default):
        check_info(pf_step)
    with case(part="all the weight on the last particle", innovation_std=default):
        check_heavy_last_particle(pf_step)
    with case(part="the resampling with the fitness weights of (b)", innovation_std=default):
        check_resampling(pf_step)
    with case(part="the artificial process noise", innovation_std=default):
        check_innovation(pf_step)
    with case(part="the artificial process noise", innovation_std="another innovation_std"):
        check_innovation(pf_step, OTHER_INNOVATION_STD)
    with case(part="the posterior after a whole run", innovation_std=default):
        check_posterior(pf_step)
    with case(part="the generator it draws from", innovation_std=default):
        near = near_case()
        check_draws_from_rng(lambda rng: _run_step(pf_step, near, rng), "pf_step", PF_STEP_STREAM, 99)


@diagnosed
def check_pf_step(func: Callable) -> None:
    """The statistical test of pf_step, with the reference tracking_dynamics."""
    # the statistical checks turn warnings into failures with a hint about log-weights
    statistical_checks(isolate(func, ref, BLANKS, warnings_fail=False))
