"""The reentry-pf reference (solutions.reentry_pf.reference) against independent oracles, and the
statistical hidden test of pf_step (solutions.reentry_pf.hidden_tests): its false-fail budget,
the exact tail behind the chi-square test, the reference passing every check on each seed, the
posterior statistic Gaussian over 400 submission seeds, and every catalogued pf_step mistake failing on each
seed (tests/random_draws.py's 21)."""

from __future__ import annotations

import ast
import bisect
import importlib.util
import inspect
import itertools
import math
import textwrap
import warnings
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from scipy.integrate import solve_ivp
from scipy.special import gammaln

from autograder.hidden_tests import cases
from autograder.hidden_tests.diagnosis import mistake_function
from solutions.reentry_pf import hidden_tests as checks
from solutions.reentry_pf.mistakes import MISTAKES
from course import falling_object as fo
from random_draws import random_draws
from solutions.reentry_pf import reference as ref

ROOT = Path(__file__).resolve().parent.parent
GAUSSIAN_SEEDS = range(400)


def scalar_rhs(h: float, v: float, beta: float) -> list[float]:
    """Equation (5) for one state, written out with the math module: the oracle for f."""
    rho = 1.754 * math.exp(-1.39e-4 * h)
    return [-v, 9.81 - 9.81 * rho * v * v / (2.0 * beta), 0.0]


def mistaken(mistake) -> object:
    """The reference function of ``mistake.blank`` with the mistake made in its source."""
    return mistake_function(ref, mistake)


def load_benchmark():
    spec = importlib.util.spec_from_file_location("reentry_pf_benchmark", ROOT / "benchmarks" / "reentry_pf.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# --- tracking_dynamics ----------------------------------------------------------------------
@random_draws(false_fail=0.0, why="an identity to rtol 1e-13 (atol 1e-12 covers the drag's cancellation); the draw only picks the states")
def test_dynamics_match_the_written_out_equations(seed):
    rng = np.random.default_rng([seed, 1])
    cloud = np.vstack([rng.uniform(0, 70_000, 50), rng.uniform(100, 4000, 50), rng.uniform(5000, 40_000, 50)])
    expected = np.array([scalar_rhs(*column) for column in cloud.T]).T
    np.testing.assert_allclose(ref.tracking_dynamics(0.0, cloud), expected, rtol=1e-13, atol=1e-12)
    one = ref.tracking_dynamics(3.0, cloud[:, 7])
    assert one.shape == (3,)
    np.testing.assert_allclose(one, expected[:, 7], rtol=1e-13)


def test_dynamics_limits_free_fall_and_terminal_speed():
    # far above the atmosphere rho -> 0: free fall, v' = g
    np.testing.assert_allclose(ref.tracking_dynamics(0.0, np.array([1e7, 3000.0, 2e4])), [-3000.0, 9.81, 0.0], atol=1e-12)
    # at the terminal speed v_t = sqrt(2 beta / rho(h)) drag balances gravity: v' = 0
    h, beta = 10_000.0, 19_161.0
    v_t = math.sqrt(2 * beta / (1.754 * math.exp(-1.39e-4 * h)))
    assert abs(ref.tracking_dynamics(0.0, np.array([h, v_t, beta]))[1]) < 1e-12


# --- simulate_radar ---------------------------------------------------------------------------
@random_draws(false_fail=0.0, why="the truth does not depend on the draw (it is the readings' noise only); an identity to the solver's accuracy")
def test_truth_agrees_with_an_independent_high_accuracy_solve(seed):
    t = fo.time_grid()
    x_true, _ = ref.simulate_radar(fo.X0_TRUE, t, fo.SIGMA, np.random.default_rng([seed, 1]))

    def rhs(_t, y):
        return scalar_rhs(*y)

    oracle = solve_ivp(rhs, (0.0, t[-1]), list(fo.X0_TRUE), method="DOP853", t_eval=t, rtol=1e-13, atol=1e-10).y
    assert x_true.shape == (3, 301)
    assert np.all(np.max(np.abs(x_true - oracle), axis=1) < [1e-3, 1e-3, 1e-9])
    # the stated accuracy: far below the radar noise, and far below a default-tolerance solve
    default = solve_ivp(ref.tracking_dynamics, (0.0, t[-1]), fo.X0_TRUE, t_eval=t).y
    assert np.max(np.abs(default[0] - oracle[0])) > 1.0


@random_draws(false_fail=0.0, why="sigma = 0, so the draw changes nothing: an identity, the parabola to rtol 1e-12")
def test_truth_without_drag_is_the_ballistic_parabola(seed):
    t = np.linspace(2.0, 12.0, 41)  # a grid that does not start at 0
    x0 = np.array([500_000.0, 100.0, 1e300])  # thin air and a huge beta: no drag
    x_true, b = ref.simulate_radar(x0, t, 0.0, np.random.default_rng([seed, 1]))
    s = t - t[0]
    np.testing.assert_allclose(x_true[0], x0[0] - x0[1] * s - 9.81 * s**2 / 2, rtol=1e-12)
    np.testing.assert_allclose(x_true[1], x0[1] + 9.81 * s, rtol=1e-10)
    np.testing.assert_array_equal(b, x_true[0])


@random_draws(false_fail=0.0, why="an identity: the readings are the truth plus 250 times the same seeded draw")
def test_readings_are_the_truth_plus_one_seeded_draw(seed):
    t = fo.time_grid(50)
    x_true, b = ref.simulate_radar(fo.X0_TRUE, t, 250.0, np.random.default_rng([seed, 1]))
    e = np.random.default_rng([seed, 1]).standard_normal(51)
    np.testing.assert_allclose(b - x_true[0], 250.0 * e, rtol=1e-9, atol=1e-8)


TUNING_SEEDS_REBUILT = (0, fo.TUNING_SEEDS - 1)
"""The tuning study's seeds that CI rebuilds: the first and the last."""


@random_draws(false_fail=0.0, fixed_seed=True,
              why="a rebuild of the radar file and of two seeds' rows of the tuning study, compared byte for byte")
def test_shipped_data_is_rebuilt_byte_for_byte():
    """The radar file is rebuilt whole, and the tuning study on its first and last seeds; both byte for byte.

    Covers: every byte of the radar file (truth, noise and seed); the tuning file's header, the number and
    order of its rows and the (setting, seed) that opens each; and every byte of the rows of seeds 0 and
    49, i.e. 2 x 14 whole runs that use every setting (both filters, every N and every innovation noise)
    over all 301 readings. A change in the filters, the settings, the scoring, the seeding scheme or a
    library's numerics changes those runs, so it fails here (in about 8 s instead of 169 s).
    Only the full rebuild (`python -m autograder data --check`, which maintainers run after changing the
    lab) adds the numbers of seeds 1 to 48: a hand edit of those rows, or a change whose effect would be
    confined to them (each seed runs the same code on its own generators, default_rng([seed, 1]) and
    default_rng([seed, 2]), so such a change would have to single out seeds).
    """
    assert fo.DATA_FILE.read_text() == ref.radar_data_text(), "the radar file differs from a rebuild"
    shipped = fo.TUNING_FILE.read_text().splitlines(keepends=True)
    settings = len(fo.TUNING_SETTINGS)
    assert len(shipped) == 1 + settings * fo.TUNING_SEEDS
    rebuilt = {seed: fo.format_tuning_csv(ref.tuning_runs(range(seed, seed + 1))).splitlines(keepends=True)
               for seed in TUNING_SEEDS_REBUILT}
    assert all(lines[0] == shipped[0] for lines in rebuilt.values()), "the tuning file's header differs from a rebuild"
    for seed, lines in rebuilt.items():
        assert shipped[1 + seed * settings:1 + (seed + 1) * settings] == lines[1:], f"seed {seed}'s rows differ from a rebuild"
    # every row: the setting of the rebuilt row in its place (filter, N, three noise levels), then its seed
    for row, line in enumerate(shipped[1:]):
        seed, setting = divmod(row, settings)
        fields = line.split(",")
        assert fields[:5] == rebuilt[0][1 + setting].split(",")[:5] and fields[5] == str(seed), f"row {row + 1} is out of place"
        assert len(fields) == len(shipped[0].split(",")), f"row {row + 1} has a missing or an extra column"


def test_shipped_data_is_the_lab_case():
    data = fo.load()
    assert data.t.shape == (301,) and data.x_true.shape == (3, 301) and data.b.shape == (301,)
    np.testing.assert_allclose(data.t, fo.time_grid(), atol=1e-12)
    np.testing.assert_allclose(data.x_true[:, 0], fo.X0_TRUE)
    np.testing.assert_array_equal(data.x_true[2], 19_161.0)
    assert np.all(np.diff(data.x_true[0]) < 0) and data.x_true[0, -1] > 0  # falls, never lands
    noise = data.b - data.x_true[0]
    assert 400 < np.std(noise) < 600 and abs(np.mean(noise)) < 5 * 500 / math.sqrt(301)


# --- initial_cloud ----------------------------------------------------------------------------
@random_draws(false_fail=0.0, why="an identity: the cloud is the prior formula applied to the same seeded draw")
def test_initial_cloud_is_the_prior_sample_formula(seed):
    x, w = ref.initial_cloud(60_500.0, 7, np.random.default_rng([seed, 1]))
    z = np.random.default_rng([seed, 1]).standard_normal((3, 7))
    expected = np.array([[60_500.0], [3000.0], [20_000.0]]) + np.array([[500.0], [200.0], [1500.0]]) * z
    np.testing.assert_allclose(x, expected, rtol=1e-15)
    np.testing.assert_array_equal(w, np.full(7, 1 / 7))


@random_draws(false_fail=1.2e-8, why="three sample means, exactly normal, at 6 standard errors (2.0e-9 each) and three "
              "sample spreads, exactly chi-square(N - 1), outside 1 -+ 6/sqrt(2N) (2.0e-9 each)")
def test_initial_cloud_moments(seed):
    N = 200_000
    x, w = ref.initial_cloud(61_000.0, N, np.random.default_rng([seed, 1]))
    std = np.array([500.0, 200.0, 1500.0])
    # each mean is exactly N(mu_i, std_i^2 / N): outside 6 standard errors with probability
    # 2 stats.norm.sf(6) = 2.0e-9; each N std^2 / std_i^2 is exactly chi-square(N - 1), outside
    # N (1 -+ 6 / sqrt(2N))^2 with probability stats.chi2.cdf + stats.chi2.sf = 2.0e-9; 1.2e-8 for the six
    assert np.all(np.abs(x.mean(axis=1) - [61_000.0, 3000.0, 20_000.0]) < 6 * std / math.sqrt(N))
    assert np.all(np.abs(x.std(axis=1) / std - 1) < 6 / math.sqrt(2 * N))
    assert abs(w.sum() - 1) < 1e-12


# --- credibility_interval (given code in course.falling_object since issue 33; it was a blank) ---------------
def exact_weighted_quantiles(samples: np.ndarray, weights: np.ndarray, orders: list[Fraction]) -> list[float]:
    """Oracle: walk up the sorted samples in exact rational arithmetic of the weights until the
    cumulative weight reaches the fraction a of the total, for each order a."""
    pairs = sorted(zip(samples.tolist(), (Fraction(x) for x in weights.tolist())))
    cumulative = list(itertools.accumulate(w for _, w in pairs))
    last = len(pairs) - 1
    return [pairs[min(bisect.bisect_left(cumulative, a * cumulative[-1]), last)][0] for a in orders]


def exact_weighted_quantile(samples: np.ndarray, weights: np.ndarray, a: Fraction) -> float:
    return exact_weighted_quantiles(samples, weights, [a])[0]


@random_draws(false_fail=0.0, why="an identity: the weights are multiples of 2^-40 summing to 1, so every cumulative "
              "weight is exact in floating point and the oracle and the function compare the same numbers")
def test_credibility_interval_matches_the_exact_weighted_oracle(seed):
    # Dirichlet(0.5) weights (flat to a few heavy ones, and tiny or zero ones), rounded to multiples of
    # 2^-40 by a multinomial draw of 2^40 units: their cumulative sums are exact in floating point, so
    # the function's float cumulative weight equals the oracle's exact one and no rounding can tip a
    # comparison (with raw Dirichlet weights a cumulative weight within rounding of an order, or a
    # last weight below one ulp of the total, would do so with probability near 1e-7 per seed).
    rng = np.random.default_rng([seed, 1])
    checked = 0
    percents = [0, 1, 25, 50, 68, 90, 95, 99, 100]
    for N in [1, 2, 3, 5, 10, 99, 1000, *rng.integers(6, 3000, 20)]:
        samples = rng.standard_normal(int(N))
        weights = rng.multinomial(2**40, rng.dirichlet(np.full(int(N), 0.5))) / 2**40 if N > 1 else np.ones(1)
        # the orders (1 -+ p/100)/2 as exact fractions
        lower = exact_weighted_quantiles(samples, weights, [Fraction(100 - p, 200) for p in percents])
        upper = exact_weighted_quantiles(samples, weights, [Fraction(100 + p, 200) for p in percents])
        for p, want_lo, want_hi in zip(percents, lower, upper):
            lo, hi = fo.credibility_interval(samples, weights, p)
            assert lo == want_lo and hi == want_hi, (N, p)
            checked += 1
    assert checked > 200


@random_draws(false_fail=0.0, why="an identity: scaling the weights by 4, a power of two, is exact, so both calls see the same cumulative weights")
def test_credibility_interval_hand_cases_and_arrays_of_p(seed):
    samples = np.array([4.0, 1.0, 3.0, 2.0])
    # equal weights: cumulative 0.25, 0.5, 0.75, 1 over 1, 2, 3, 4; the median (order 0.5) is 2
    assert fo.credibility_interval(samples, np.ones(4), 0) == (2.0, 2.0)
    # all the weight on 3: every quantile is 3
    assert fo.credibility_interval(samples, np.array([0.0, 0.0, 1.0, 0.0]), 90) == (3.0, 3.0)
    # weights 0.1 (1), 0.1 (2), 0.7 (3), 0.1 (4): the 50% interval runs from order 0.25 (3) to 0.75 (3)
    lo, hi = fo.credibility_interval(samples, np.array([0.1, 0.1, 0.7, 0.1]), np.array([50.0, 90.0, 100.0]))
    np.testing.assert_array_equal(lo, [3.0, 1.0, 1.0])
    np.testing.assert_array_equal(hi, [3.0, 4.0, 4.0])
    # the interval depends on the weights only through their normalised values (a scale of 4 is exact)
    w = np.random.default_rng([seed, 1]).random(500)
    x = np.random.default_rng([seed, 2]).standard_normal(500)
    assert fo.credibility_interval(x, w, 90) == fo.credibility_interval(x, 4.0 * w, 90)


@random_draws(false_fail=1e-9, why="each weighted quantile is asymptotically normal with the self-normalised importance "
              "sampling variance; the tolerances are 7.1 and 6.3 standard errors: 2.5e-10 in all")
def test_weighted_interval_of_a_weighted_sample_covers_its_target(seed):
    # importance sampling: n = 200000 N(0, 1) samples weighted by w = N(1, 1)/N(0, 1) = exp(x - 1/2)
    # describe N(1, 1), whose central 90% interval is 1 -+ 1.645. The weighted quantile of order a
    # (true value xi) is asymptotically normal with variance E_q[w^2 (1{x <= xi} - a)^2] / (phi(xi - 1)^2 n),
    # and w^2 q = e N(2, 1), so the expectation is e ((1 - a)^2 Phi(xi - 2) + a^2 (1 - Phi(xi - 2))):
    # standard errors 0.0028 (a = 0.05) and 0.0174 (a = 0.95; the heavy weights sit in the upper tail).
    # (The old tolerance 0.05 with an ESS-based 0.008 was 2.9 standard errors of the upper end: it
    # failed a correct function about 4 times in 1000.) Tolerances 0.02 and 0.11 are 7.1 and 6.3
    # standard errors: 2 stats.norm.sf(7.1) + 2 stats.norm.sf(6.33) = 2.5e-10, stated as 1e-9 for the
    # normal approximation. Power: an unweighted interval is 1 off at both ends.
    rng = np.random.default_rng([seed, 1])
    x = rng.standard_normal(200_000)
    lo, hi = fo.credibility_interval(x, np.exp(x - 0.5), 90)
    assert abs(lo - (1 - 1.6449)) < 0.02 and abs(hi - (1 + 1.6449)) < 0.11, (lo, hi)


@random_draws(false_fail=0.0, why="the worst corner of the draws bounds every case; the seed picks the cases checked "
              "beside it, and the readings' noise does not move the truth")
def test_hidden_radar_cases_stay_well_above_the_ground(seed):
    # the lowest, fastest, least braked start of simulate_radar_cases' ranges, over its longest grid (30 s)
    # (the readings' noise does not move the truth, so any generator will do)
    corner, _ = ref.simulate_radar(np.array([60_000.0, 3_200.0, 20_000.0]), 0.1 * np.arange(301), 100.0,
                                   np.random.default_rng([seed, 1]))
    assert corner[0].min() > 1_000.0
    with cases.seeded(seed):
        radar_cases = checks.simulate_radar_cases()
    for x0, t, sigma, _ in radar_cases:
        x_true, _ = ref.simulate_radar(x0, t, sigma, np.random.default_rng([seed, 2]))
        assert x_true[0].min() > 1_000.0 and t[0] > 0


# --- the statistical checks of pf_step ---------------------------------------------------------
def test_false_fail_budget_is_at_most_one_in_a_million():
    assert checks.FALSE_FAIL_TOTAL <= 1e-6
    assert checks.resampling_threshold() == pytest.approx(-2 * math.log(checks.RESAMPLING_NOMINAL_TAIL))
    lower, upper, z_max = checks.innovation_bounds(11_999)
    a = checks.ALPHA_INNOVATION / 24
    assert stats.chi2.cdf(lower, 11_999) == pytest.approx(a) and stats.chi2.sf(upper, 11_999) == pytest.approx(a)
    assert 24 * a == pytest.approx(checks.ALPHA_INNOVATION) and stats.norm.sf(z_max) == pytest.approx(a)


def exact_pearson_tail(N: int, p: np.ndarray, c: float, width: float = 9.0) -> float:
    """P(Pearson's statistic > c) for Multinomial(N, p), K = 3, by summing the pmf over every
    count vector within `width` standard deviations, plus a bound on the mass outside."""
    sd = np.sqrt(N * p * (1 - p))
    lo = np.maximum(0, np.floor(N * p - width * sd)).astype(int)
    hi = np.minimum(N, np.ceil(N * p + width * sd)).astype(int)
    n1 = np.arange(lo[0], hi[0] + 1)[:, None]
    n2 = np.arange(lo[1], hi[1] + 1)[None, :]
    n3 = N - n1 - n2
    valid = n3 >= 0
    n3 = np.where(valid, n3, 0)
    log_pmf = gammaln(N + 1) - gammaln(n1 + 1) - gammaln(n2 + 1) - gammaln(n3 + 1)
    log_pmf = log_pmf + n1 * np.log(p[0]) + n2 * np.log(p[1]) + n3 * np.log(p[2])
    e = N * p
    pearson = (n1 - e[0]) ** 2 / e[0] + (n2 - e[1]) ** 2 / e[1] + (n3 - e[2]) ** 2 / e[2]
    inside = np.sum(np.where(valid & (pearson > c), np.exp(log_pmf), 0.0))
    outside = sum(stats.binom.cdf(lo[g] - 1, N, p[g]) + stats.binom.sf(hi[g], N, p[g]) for g in range(2))
    return float(inside + outside)


@pytest.mark.parametrize("case", [checks.near_case(), checks.far_case()], ids=["near", "far"])
def test_resampling_threshold_has_exact_tail_below_its_share(case):
    N = case.w.shape[0]
    assert N * case.p.min() > 1500
    tail = exact_pearson_tail(N, case.p, checks.resampling_threshold())
    assert checks.RESAMPLING_NOMINAL_TAIL < tail <= checks.ALPHA_RESAMPLING / 2, tail


def test_family_cases_do_not_depend_on_the_seed_except_for_order():
    with cases.seeded(1):
        a = checks.near_case()
    with cases.seeded(2):
        b = checks.near_case()
    np.testing.assert_array_equal(a.p, b.p)
    assert not np.array_equal(a.family, b.family)
    np.testing.assert_allclose(np.bincount(a.family, weights=a.w), checks.FAMILY_WEIGHT, rtol=1e-12)
    np.testing.assert_allclose(a.x_hat[0] - a.b_next, checks.NEAR_OFFSETS, atol=1e-9)


@random_draws(false_fail=9e-7, why="the hidden test's own budget FALSE_FAIL_TOTAL: exact multinomial tails of the two "
              "resampling tests (2.6e-7), 24 exact normal and chi-square tails (3e-7), Student's t of the posterior (3e-7)")
def test_reference_passes_every_check(seed):
    # every statistical check of pf_step, as grading runs it with submission seed `seed`; the budget is
    # derived in the hidden test's module and checked by test_false_fail_budget_is_at_most_one_in_a_million
    with cases.seeded(seed):
        checks.statistical_checks(ref.pf_step)


@random_draws(false_fail=4e-7, own_seeds=400, why="Shapiro-Wilk and the kurtosis test at p-value 1e-7 each, and the "
              "upper confidence limits of sigma and of |mu - m_R| at 1e-7 each")
def test_posterior_check_fails_a_correct_step_rarely_over_submission_seeds():
    # check_posterior compares a submission's final posterior mean m of beta (N = 1000, the shipped data)
    # with the fixed reference ensemble: over submission seeds only m varies. It assumes m Gaussian; its
    # false-fail probability is then P(|m - m_R| > POSTERIOR_SIGMAS s_R) for m ~ N(mu, sigma^2). m on 400
    # submission seeds, drawn as check_posterior draws it:
    b = fo.load().b
    m = []
    for seed in GAUSSIAN_SEEDS:
        with cases.seeded(seed):
            m.append(checks.final_beta_mean(ref.pf_step, b, checks.POSTERIOR_PARTICLES, checks._rng(6)))
    m = np.array(m)
    # for Gaussian m each p-value is uniform: below 1e-7 with probability 1e-7 (the kurtosis test's
    # p-value through its normal approximation)
    assert stats.shapiro(m).pvalue > 1e-7, stats.shapiro(m)
    assert stats.kurtosistest(m).pvalue > 1e-7, (stats.kurtosis(m), stats.kurtosistest(m))
    # sigma at its upper 1e-7 confidence limit ((n - 1) s^2 / sigma^2 is chi-square(n - 1)), and
    # |mu - m_R| at its upper 1e-7 limit (the mean of m is normal, with sigma at its limit)
    n = m.size
    ensemble = checks.reference_ensemble()
    tolerance = checks.POSTERIOR_SIGMAS * ensemble.std(ddof=1)
    sigma = m.std(ddof=1) * math.sqrt((n - 1) / stats.chi2.ppf(1e-7, n - 1))
    offset = abs(m.mean() - ensemble.mean()) + stats.norm.isf(0.5e-7) * sigma / math.sqrt(n)
    tail = stats.norm.sf((tolerance - offset) / sigma) + stats.norm.sf((tolerance + offset) / sigma)
    assert tail < checks.ALPHA_POSTERIOR, tail


PF_MISTAKES = [m for m in MISTAKES if m.blank == "pf_step"]


@random_draws(false_fail=0.0, why="a power test: each mistake fails an exact check, or a statistic whose "
              "probability of passing underflows to 0 (log-probabilities below -10000), on every seed")
@pytest.mark.parametrize("mistake", PF_MISTAKES, ids=[m.slug for m in PF_MISTAKES])
def test_every_pf_step_mistake_fails_on_every_seed(mistake, seed):
    # The test fails if a mistake passes. How each mistake is caught, on any seed:
    # - exact checks (no randomness in the verdict): unnormalised-weights (the weights sum to about N,
    #   not 1), no-parent-term (weights off step (d) by factors exp(0.08) to exp(0.98)), no-log-weights
    #   (exp(-800) underflows to 0/0 for the far reading), fitness-ignores-old-weights,
    #   fitness-before-propagation and ess-of-old-weights (info['ess'] differs from the oracle's);
    # - argmax-resampling: all N = 12000 particles in one family, a chi-square in the tens of thousands;
    # - innovation-before-resampling: it passes only if the 12000 parents are all distinct, at most
    #   12000! / 12000^12000 = exp(-11995) (the uniform draw is the likeliest to be distinct);
    # - variance-innovation: the h scatter is 10^4 chi-square(11999), below the upper bound 12883 with
    #   probability stats.chi2.cdf(1.29, 11999), 0 in double precision;
    # - ignores-innovation-std: with innovation_std (40, 250, 2) the h scatter is 6.25 chi-square(11999),
    #   below 12883 with probability stats.chi2.cdf(2061, 11999), 0 in double precision.
    step = mistaken(mistake)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a mistake's own warnings are reported by the checks
        with pytest.raises(AssertionError), cases.seeded(seed):
            checks.check_pf_step(step)


@random_draws(false_fail=9.9e-7, why="the checks' tails: plain step resampling near 1.3e-7, innovation 1.5e-7, "
              "posterior 3e-7; loop step resampling 2.6e-7, innovation 1.5e-7 (weights exact): 9.8e-7")
def test_other_correct_implementations_pass_the_checks(seed):
    # each check's false-fail probability as the hidden test's module derives it: resampling, the exact
    # multinomial tails 1.26e-7 (near) and 1.29e-7 (far); innovation with the default, 12 tails of 1.25e-8;
    # posterior, Student's t tail 3e-7; weights exact. 1.26e-7 + 1.5e-7 + 3e-7 + 2.55e-7 + 1.5e-7 = 9.8e-7.
    bench = load_benchmark()
    with cases.seeded(seed):
        # the plain step has no log-weights, so only the near reading suits it
        checks.check_weights(bench.plain_pf_step, readings=("near",))
        checks.check_resampling(bench.plain_pf_step, readings=("near",))
        checks.check_innovation(bench.plain_pf_step)
        checks.check_posterior(bench.plain_pf_step)
        for check in (checks.check_weights, checks.check_resampling, checks.check_innovation):
            check(bench.loop_pf_step)
        # with the far reading its weights are 0/0, and the checks say so
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with pytest.raises(AssertionError, match="log-weights"):
                checks.check_weights(bench.plain_pf_step)


@random_draws(false_fail=5.2e-7, why="two of the mistakes pass through the resampling check with a correct "
              "resampling first; its exact multinomial tails are 2.6e-7 a run; every other verdict is exact")
def test_check_messages_name_the_fix(seed):
    # Each mistake must fail with the message that names it. Every mistake fails an exact check first,
    # except innovation-before-resampling and variance-innovation, which resample correctly and reach the
    # innovation check after check_resampling: a correct resampling fails that with probability
    # 1.26e-7 + 1.29e-7 (exact multinomial tails), so 5.2e-7 for the two.
    by_slug = {m.slug: mistaken(m) for m in PF_MISTAKES}
    expected = {
        "unnormalised-weights": "sum to 1",
        "argmax-resampling": "Resampling does not follow",
        "innovation-before-resampling": "exact copies",
        "fitness-ignores-old-weights": "old weights",
        "no-parent-term": "step \\(d\\)",
        "no-log-weights": "log-weights",
        "variance-innovation": "standard deviation",
    }
    for slug, pattern in expected.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with pytest.raises(AssertionError, match=pattern), cases.seeded(seed):
                checks.check_pf_step(by_slug[slug])


@random_draws(false_fail=0.0, why="an identity: two calls with generators of the same seed give the same result")
def test_pf_step_is_reproducible_and_leaves_its_inputs_alone(seed):
    x, w = ref.initial_cloud(60_000.0, 1000, np.random.default_rng([seed, 1]))
    x0, w0 = x.copy(), w.copy()
    a = ref.pf_step(x, w, 59_800.0, np.random.default_rng([seed, 2]))
    b = ref.pf_step(x, w, 59_800.0, np.random.default_rng([seed, 2]))
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    np.testing.assert_array_equal(x, x0)
    np.testing.assert_array_equal(w, w0)


def test_pf_step_has_no_python_loop():
    tree = ast.parse(textwrap.dedent(inspect.getsource(ref.pf_step)))
    loops = [node for node in ast.walk(tree) if isinstance(node, (ast.For, ast.While, ast.comprehension))]
    assert loops == []


# --- run_particle_filter and the lab's figures --------------------------------------------------
@pytest.fixture(scope="module")
def lab_run():
    """The lab's own run (the notebook's figures); the tests on it are fixed_seed (pytest cannot mark a fixture)."""
    data = fo.load()
    seed = fo.RUN_SEED
    return data, ref.run_particle_filter(data.b, fo.N_PARTICLES, np.random.default_rng(seed))


@random_draws(false_fail=0.0, fixed_seed=True, why="checks the lab's own run, RUN_SEED, the one the notebook's figures "
              "and report show; its orderings and ESS bounds hold on any run")
def test_run_history_is_consistent(lab_run):
    data, history = lab_run
    assert history.missing() == [] and history.n_times == 301 and history.n_particles == 5000
    assert np.all(history.lo90 <= history.lo50) and np.all(history.lo50 <= history.median)
    assert np.all(history.median <= history.hi50) and np.all(history.hi50 <= history.hi90)
    assert np.all((1 <= history.ess) & (history.ess <= 5000 + 1e-6))
    assert history.ess[0] == pytest.approx(5000)
    # the filter beats the raw radar on altitude
    assert np.sqrt(np.mean((history.mean[0] - data.x_true[0]) ** 2)) < 0.5 * fo.SIGMA


@random_draws(false_fail=1e-9, why="an identity, except that the exact-fraction oracle of a quantile can differ from the "
              "float one by rounding: 9 quantiles of 300 weights, 1.8e-10")
def test_run_reproduces_a_hand_written_loop(seed):
    # The oracle sums the float weights exactly; the function sums them in floating point (error at most
    # N u, u = 1.1e-16, for N = 300). They disagree only if a cumulative weight falls within that of an
    # order: the N cumulative weights have density about N, so probability at most 2 N u N = 2e-11 per
    # quantile, 1.8e-10 for the 9 quantiles.
    b = fo.load().b[:21]
    history = ref.run_particle_filter(b, 300, np.random.default_rng([seed, 1]))
    rng = np.random.default_rng([seed, 1])
    x, w = ref.initial_cloud(b[0], 300, rng)
    root = np.arange(300)
    for j in range(1, 21):
        info = {}
        x, w = ref.pf_step(x, w, b[j], rng, info=info)
        root = root[info["parents"]]
    assert history.roots[-1] == len(set(root.tolist())) and history.parents[-1] == len(set(info["parents"].tolist()))
    assert history.ess_resample[-1] == pytest.approx(info["ess"]) and history.roots[0] == 300
    np.testing.assert_allclose(history.mean[:, -1], np.sum(w * x, axis=1), rtol=1e-12)
    np.testing.assert_allclose(history.ess[-1], 1 / np.sum(w**2))
    for i in range(3):
        assert history.median[i, -1] == exact_weighted_quantile(x[i], w, Fraction(1, 2))
        assert history.lo90[i, -1] == exact_weighted_quantile(x[i], w, Fraction(1, 20))
        assert history.hi90[i, -1] == exact_weighted_quantile(x[i], w, Fraction(19, 20))


@random_draws(false_fail=1e-11, why="the three innovation spreads of 400 draws are exactly chi-square(399): outside 1 -+ 0.25 "
              "with probability 3.2e-12 each; the rest is an identity")
def test_bootstrap_step_is_a_bootstrap_filter(seed):
    # the given step resamples with the old weights, propagates, and weighs by the likelihood alone:
    # with all the weight on one particle, every parent is that particle
    x, _ = ref.initial_cloud(60_000.0, 400, np.random.default_rng([seed, 1]))
    w = np.zeros(400)
    w[17] = 1.0
    info = {}
    x_new, w_new = fo.bootstrap_step(x, w, 59_700.0, np.random.default_rng([seed, 2]), ref.tracking_dynamics, info=info)
    assert np.all(info["parents"] == 17) and info["ess"] == pytest.approx(1.0)
    log_w = -((x_new[0] - 59_700.0) ** 2) / (2 * fo.SIGMA**2)
    np.testing.assert_allclose(w_new, np.exp(log_w) / np.exp(log_w).sum(), rtol=1e-9)
    # the spread around the propagated parent is the artificial noise: 400 N std^2 / innovation_std^2 is
    # chi-square(399), outside 400 (1 -+ 0.25)^2 with probability stats.chi2.cdf + stats.chi2.sf = 3.2e-12
    parent = x[:, 17] + fo.DT * ref.tracking_dynamics(0.0, x[:, 17])
    assert np.all(np.abs(np.std(x_new - parent[:, None], axis=1) / fo.INNOVATION_STD - 1) < 0.25)


def test_beta_linearised_sd_matches_a_variational_solve():
    # oracle: the sensitivities dh/dx0 from the variational equations S' = (df/dx) S, S(0) = I
    t = fo.time_grid()

    def rhs(_t, y):
        h, v, beta = y[:3]
        rho = 1.754 * math.exp(-1.39e-4 * h)
        A = np.array([[0.0, -1.0, 0.0],
                      [9.81 * 1.39e-4 * rho * v * v / (2 * beta), -9.81 * rho * v / beta, 9.81 * rho * v * v / (2 * beta**2)],
                      [0.0, 0.0, 0.0]])
        return np.concatenate([scalar_rhs(h, v, beta), (A @ y[3:].reshape(3, 3)).ravel()])

    y = solve_ivp(rhs, (0, 30), np.concatenate([fo.X0_TRUE, np.eye(3).ravel()]), t_eval=t, rtol=1e-11, atol=1e-11).y
    S = y[3:6].T  # dh_j / dx0, (T + 1, 3)
    J = np.diag(1 / fo.PRIOR_STD**2) + S[1:].T @ S[1:] / fo.SIGMA**2
    sd = fo.beta_linearised_sd(ref.tracking_dynamics, fo.X0_TRUE, t)
    assert sd[0] == pytest.approx(fo.PRIOR_STD[2])
    assert sd[-1] == pytest.approx(math.sqrt(np.linalg.inv(J)[2, 2]), rel=1e-5)
    assert np.all(np.diff(sd) <= 1e-9)  # information only accumulates


BAND_SEEDS = range(100, 121)  # 21 fresh seeds, outside the tuning study's 0..49


@pytest.fixture(scope="module")
def handout_runs():
    """21 runs of the handout's setting, N = 2000, each on its own simulated readings."""
    t = fo.time_grid()
    runs = []
    for seed in BAND_SEEDS:
        x_true, b = ref.simulate_radar(fo.X0_TRUE, t, fo.SIGMA, np.random.default_rng([seed, 1]))
        runs.append((x_true, ref.run_particle_filter(b, 2000, np.random.default_rng([seed, 2]))))
    return runs


@random_draws(false_fail=6.2e-8, own_seeds=21, why="three properties each held in 50 of 50 study runs; at a per-run "
              "rate of at least 0.95, 10 or more misses of 21 has binomial tail 2.1e-8, 6.2e-8 for the three")
def test_handout_setting_over_seeds_wide_beta_band_collapsed_ancestry_upward_v(handout_runs):
    # What holds for the handout's setting run by run (the old test asserted a narrowing beta band on one
    # pinned seed; over seeds the band does not reliably narrow). Three properties, each held in 50 of 50
    # runs of the tuning study (N = 2000): at 30 s the beta band is wider than the yardstick (linearised posterior sd),
    # fewer than 30 particles of t_0 have descendants, and the 90% interval of v reaches below 0. Each
    # must hold in at least 12 of 21 fresh runs (BAND_SEEDS). If a property's per-run rate is at least
    # 0.95 (50 of 50 puts it above 0.94 with 95% confidence), failing that needs 10 or more misses of 21:
    # stats.binom.sf(9, 21, 0.05) = 2.1e-8, so 6.2e-8 for the three together.
    yardstick = 2 * fo.Z90 * fo.beta_linearised_sd(ref.tracking_dynamics, fo.X0_TRUE, fo.time_grid())[-1]
    wide = [h.hi90[2, -1] - h.lo90[2, -1] > yardstick for _, h in handout_runs]
    collapsed = [h.roots[-1] < 30 for _, h in handout_runs]
    upward = [h.lo90[1, -1] < 0 for _, h in handout_runs]
    for name, held in (("wide beta band", wide), ("collapsed ancestry", collapsed), ("v interval below 0", upward)):
        assert sum(held) >= 12, (name, held)


@random_draws(false_fail=0.0, fixed_seed=True, why="draws the figures and report of the lab's own run, RUN_SEED; "
              "what it asserts is their structure, which holds on any run")
def test_figures_and_report_draw(lab_run):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data, history = lab_run
    yardstick = fo.beta_linearised_sd(ref.tracking_dynamics, fo.X0_TRUE, data.t)
    axes = fo.plot_tracking(data, history, yardstick=yardstick)
    assert axes.shape == (2, 3) and all(ax.get_xlabel() == "time t [s]" for ax in axes[1])
    axes = fo.plot_health(data, {"auxiliary": history})
    assert axes[0].get_ylabel().startswith("ESS")
    study = fo.load_tuning()
    handout = [s for s in fo.TUNING_SETTINGS if s.innovation_std == fo.HANDOUT_STD and s.filter == "auxiliary"]
    ax = fo.plot_band_widths(study, handout, data.t, yardstick)
    assert len(ax.get_lines()) == len(handout) + 2
    axes = fo.plot_tuning(study)
    assert len(axes) == 3
    report = fo.format_report(data, history)
    assert "beta" in report and "19161" in report
    assert "auxiliary" in fo.format_tuning_table(study)
    plt.close("all")
    with pytest.raises(ValueError, match="NaN"):
        fo.plot_health(data, {"empty": fo.FilterHistory.empty(301)})


def test_tuning_study_has_every_setting_on_every_seed():
    study = fo.load_tuning()
    assert set(study.runs) == set(fo.TUNING_SETTINGS)
    for run in study.runs.values():
        assert run["rmse_h"].shape == (fo.TUNING_SEEDS,) and run["width90_beta"].shape == (fo.TUNING_SEEDS, 31)
        assert np.all((0 <= run["cover50_h"]) & (run["cover50_h"] <= run["cover90_h"]) & (run["cover90_h"] <= 1))


def test_tuning_table_pairs_each_setting_with_the_handouts_on_the_same_runs():
    """Issue 33 (science review): the table's diff column is the run-by-run difference of beta's RMSE from the
    handout's setting's, with its own two standard errors; the exact posterior's RMSE is in the table's metric
    (the mean of each run's RMSE), below the root of its mean squared error."""
    study = fo.load_tuning()
    diff = study.runs[fo.TUNED_SETTING]["rmse_beta"] - study.runs[fo.HANDOUT_SETTING]["rmse_beta"]
    two_se = 2 * np.std(diff, ddof=1) / np.sqrt(diff.size)
    tuned_row = next(line for line in fo.format_tuning_table(study).splitlines() if "the tuned setting" in line)
    assert f"{np.mean(diff):+.0f}" in tuned_row and f"+-{two_se:.0f}" in tuned_row, tuned_row
    ideal = fo.ideal_scores(ref.tracking_dynamics, fo.X0_TRUE, fo.time_grid())
    assert np.all(ideal["rmse"] < ideal["rms"]) and np.all(ideal["rmse"] > 0.8 * ideal["rms"]), ideal
    again = fo.ideal_scores(ref.tracking_dynamics, fo.X0_TRUE, fo.time_grid())
    assert np.array_equal(ideal["rmse"], again["rmse"])


# --- ResamplingHealth (issue 33: the resampling's books are given; a fairness review found its misuses) ------------


def test_resampling_health_counts_roots_as_a_hand_run_does():
    health, history = fo.ResamplingHealth(3), fo.FilterHistory.empty(3, 3)
    health.record(history, 0, {})
    health.record(history, 1, {"ess": 2.5, "parents": np.array([0, 0, 1])})
    health.record(history, 2, {"ess": 1.5, "parents": np.array([2, 2, 1])})
    # roots [0, 0, 1] (2), then root[[2, 2, 1]] = [1, 1, 0] (still 2); distinct parents 2, then 2
    assert history.roots.tolist() == [3, 2, 2] and history.parents.tolist() == [3, 2, 2]
    assert history.ess_resample.tolist() == [3, 2.5, 1.5]
    # t_0 filled by hand and the helper started at j = 1 is allowed (a correct alternative of the fairness review)
    late = fo.ResamplingHealth(3)
    late.record(history, 1, {"ess": 3.0, "parents": np.array([0, 0, 1])})
    assert history.roots[1] == 2


@pytest.mark.parametrize("misuse, says", [
    ("made-in-the-loop", "before the loop"),
    ("twice", "called twice"),
    ("unfilled-dict", "pass this same dict to the step"),
    ("wrong-n", "made for 5 particles"),
    ("t0-last", "record t_0 first"),
])
def test_resampling_health_refuses_each_misuse_and_says_how_to_call_it(misuse, says):
    history = fo.FilterHistory.empty(3, 3)
    step1, step2 = {"ess": 2.5, "parents": np.array([0, 0, 1])}, {"ess": 1.5, "parents": np.array([2, 2, 1])}
    with pytest.raises(fo.HelperMisused, match=says):
        if misuse == "made-in-the-loop":
            fo.ResamplingHealth(3).record(history, 1, step1)
            fo.ResamplingHealth(3).record(history, 2, step2)
        elif misuse == "twice":
            health = fo.ResamplingHealth(3)
            health.record(history, 0)
            health.record(history, 1, step1)
            health.record(history, 1, step1)
        elif misuse == "unfilled-dict":
            health = fo.ResamplingHealth(3)
            health.record(history, 0)
            health.record(history, 1, {})
        elif misuse == "wrong-n":
            health = fo.ResamplingHealth(5)
            health.record(history, 0)
            health.record(history, 1, step1)
        else:
            health = fo.ResamplingHealth(3)
            health.record(history, 1, step1)
            health.record(history, 0)
