"""The reentry-pf reference (solutions.reentry_pf) against independent oracles, and the
statistical hidden test of pf_step (autograder.hidden_tests.reentry_pf): its false-fail budget,
the exact tail behind the chi-square test, 200 seeds passed by the reference, and every
catalogued pf_step mistake failing on all 200."""

from __future__ import annotations

import ast
import importlib.util
import inspect
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

from autograder.hidden_tests import reentry_pf as checks
from autograder.mistakes.reentry_pf import MISTAKES
from course import falling_object as fo
from solutions import reentry_pf as ref

ROOT = Path(__file__).resolve().parent.parent
SEEDS = range(200)


def scalar_rhs(h: float, v: float, beta: float) -> list[float]:
    """Equation (5) for one state, written out with the math module: the oracle for f."""
    rho = 1.754 * math.exp(-1.39e-4 * h)
    return [-v, 9.81 - 9.81 * rho * v * v / (2.0 * beta), 0.0]


def mistaken(mistake) -> object:
    """The reference function of ``mistake.blank`` with the mistake made in its source."""
    source = textwrap.dedent(inspect.getsource(getattr(ref, mistake.blank)))
    namespace = dict(vars(ref))
    exec(compile(mistake.apply(source), f"<mistake {mistake.slug}>", "exec"), namespace)
    return namespace[mistake.blank]


def load_benchmark():
    spec = importlib.util.spec_from_file_location("reentry_pf_benchmark", ROOT / "benchmarks" / "reentry_pf.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# --- tracking_dynamics ----------------------------------------------------------------------
def test_dynamics_match_the_written_out_equations():
    rng = np.random.default_rng(1)
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
def test_truth_agrees_with_an_independent_high_accuracy_solve():
    t = fo.time_grid()
    x_true, _ = ref.simulate_radar(fo.X0_TRUE, t, fo.SIGMA, np.random.default_rng(0))

    def rhs(_t, y):
        return scalar_rhs(*y)

    oracle = solve_ivp(rhs, (0.0, t[-1]), list(fo.X0_TRUE), method="DOP853", t_eval=t, rtol=1e-13, atol=1e-10).y
    assert x_true.shape == (3, 301)
    assert np.all(np.max(np.abs(x_true - oracle), axis=1) < [1e-3, 1e-3, 1e-9])
    # the stated accuracy: far below the radar noise, and far below a default-tolerance solve
    default = solve_ivp(ref.tracking_dynamics, (0.0, t[-1]), fo.X0_TRUE, t_eval=t).y
    assert np.max(np.abs(default[0] - oracle[0])) > 1.0


def test_truth_without_drag_is_the_ballistic_parabola():
    t = np.linspace(2.0, 12.0, 41)  # a grid that does not start at 0
    x0 = np.array([500_000.0, 100.0, 1e300])  # thin air and a huge beta: no drag
    x_true, b = ref.simulate_radar(x0, t, 0.0, np.random.default_rng(3))
    s = t - t[0]
    np.testing.assert_allclose(x_true[0], x0[0] - x0[1] * s - 9.81 * s**2 / 2, rtol=1e-12)
    np.testing.assert_allclose(x_true[1], x0[1] + 9.81 * s, rtol=1e-10)
    np.testing.assert_array_equal(b, x_true[0])


def test_readings_are_the_truth_plus_one_seeded_draw():
    t = fo.time_grid(50)
    x_true, b = ref.simulate_radar(fo.X0_TRUE, t, 250.0, np.random.default_rng(11))
    e = np.random.default_rng(11).standard_normal(51)
    np.testing.assert_allclose(b - x_true[0], 250.0 * e, rtol=1e-9, atol=1e-8)


def test_shipped_data_is_rebuilt_byte_for_byte(tmp_path):
    [written] = ref.write_data(tmp_path)
    assert written.name == fo.DATA_FILE.name
    assert written.read_bytes() == fo.DATA_FILE.read_bytes()


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
def test_initial_cloud_is_the_prior_sample_formula():
    x, w = ref.initial_cloud(60_500.0, 7, np.random.default_rng(5))
    z = np.random.default_rng(5).standard_normal((3, 7))
    expected = np.array([[60_500.0], [3000.0], [20_000.0]]) + np.array([[500.0], [200.0], [1500.0]]) * z
    np.testing.assert_allclose(x, expected, rtol=1e-15)
    np.testing.assert_array_equal(w, np.full(7, 1 / 7))


def test_initial_cloud_moments():
    N = 200_000
    x, w = ref.initial_cloud(61_000.0, N, np.random.default_rng(6))
    std = np.array([500.0, 200.0, 1500.0])
    assert np.all(np.abs(x.mean(axis=1) - [61_000.0, 3000.0, 20_000.0]) < 6 * std / math.sqrt(N))
    assert np.all(np.abs(x.std(axis=1) / std - 1) < 6 / math.sqrt(2 * N))
    assert abs(w.sum() - 1) < 1e-12


# --- credibility_interval ---------------------------------------------------------------------
def exact_interval(samples: np.ndarray, p: int) -> tuple[float, float]:
    """Oracle: exact rational arithmetic, halves away from zero, 1-based list indexing."""
    h = [None] + sorted(samples.tolist())  # h[1] <= h[2] <= ... <= h[N]
    N = len(samples)

    def matlab_round(value: Fraction) -> int:
        return math.floor(value + Fraction(1, 2))  # value >= 0

    i_min = min(max(matlab_round((1 - Fraction(p, 100)) * Fraction(N, 2)), 1), N)
    i_max = min(max(matlab_round((1 + Fraction(p, 100)) * Fraction(N, 2)), 1), N)
    return h[i_min], h[i_max]


def test_credibility_interval_matches_the_exact_oracle():
    rng = np.random.default_rng(8)
    checked = 0
    for N in [1, 2, 3, 4, 5, 10, 11, 20, 99, 100, 1000, 5000, *rng.integers(6, 3000, 40)]:
        samples = rng.standard_normal(int(N))
        for p in [0, 1, 25, 50, 68, 90, 95, 99, 100]:
            if checks.float_rule_is_exact(int(N), p):
                assert ref.credibility_interval(samples, p) == exact_interval(samples, p), (N, p)
                checked += 1
    assert checked > 400


def test_credibility_interval_rounds_halves_away_from_zero():
    samples = np.arange(10.0)[::-1]  # 9, 8, ..., 0: sorted 0..9, so h_i = i - 1
    # i_min = [0.5 x 5] = [2.5] = 3, i_max = [1.5 x 5] = [7.5] = 8 (Python's round gives 2 and 8)
    assert ref.credibility_interval(samples, 50) == (2.0, 7.0)
    # N = 5, p = 80: i_min = [0.5] -> 1 in exact arithmetic; the float formula gives 0.4999... -> 0,
    # clamped to 1: both readings agree here
    assert ref.credibility_interval(np.arange(5.0), 80) == (0.0, 4.0)
    # p = 100 and N = 1: indices clamped to 1..N
    assert ref.credibility_interval(np.array([3.0, 1.0, 2.0]), 100) == (1.0, 3.0)
    assert ref.credibility_interval(np.array([4.2]), 90) == (4.2, 4.2)


def test_hidden_interval_cases_avoid_float_ambiguity_but_keep_halves():
    ambiguous = [(N, p) for N in range(1, 200) for p in range(101) if not checks.float_rule_is_exact(N, p)]
    assert (10, 90) in ambiguous and (5, 80) in ambiguous  # exact halves that floating point misses
    cases = checks.credibility_cases()
    assert all(checks.float_rule_is_exact(N, p) for N, p in cases)
    halves = [(N, p) for N, p in cases if round((1 - p / 100) * N / 2) != math.floor((1 - p / 100) * N / 2 + 0.5)]
    assert len(halves) >= 2  # where Python's round (halves to even) and MATLAB's differ


def test_hidden_radar_cases_stay_well_above_the_ground():
    for x0, t, sigma, seed in checks.simulate_radar_cases():
        x_true, _ = ref.simulate_radar(x0, t, sigma, np.random.default_rng(seed))
        assert x_true[0].min() > 1_000.0 and t[0] > 0


def test_credibility_interval_of_rows():
    x = np.random.default_rng(9).standard_normal((3, 501))
    lo, hi = ref.credibility_interval(x, 90)
    assert lo.shape == hi.shape == (3,)
    for i in range(3):
        assert (lo[i], hi[i]) == exact_interval(x[i], 90)


# --- the statistical checks of pf_step ---------------------------------------------------------
def test_false_fail_budget_is_at_most_one_in_a_million():
    assert checks.FALSE_FAIL_TOTAL <= 1e-6
    assert checks.resampling_threshold() == pytest.approx(-2 * math.log(checks.RESAMPLING_NOMINAL_TAIL))
    lower, upper, z_max = checks.innovation_bounds(11_999)
    a = checks.ALPHA_INNOVATION / 12
    assert stats.chi2.cdf(lower, 11_999) == pytest.approx(a) and stats.chi2.sf(upper, 11_999) == pytest.approx(a)
    assert 12 * a == pytest.approx(checks.ALPHA_INNOVATION) and stats.norm.sf(z_max) == pytest.approx(a)
    R = checks.POSTERIOR_RUNS
    assert 2 * stats.t.sf(checks.posterior_threshold(), R - 1) == pytest.approx(checks.ALPHA_POSTERIOR)


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


@pytest.mark.parametrize("case", [checks.near_case(0), checks.far_case(0)], ids=["near", "far"])
def test_resampling_threshold_has_exact_tail_below_its_share(case):
    N = case.w.shape[0]
    assert N * case.p.min() > 1500
    tail = exact_pearson_tail(N, case.p, checks.resampling_threshold())
    assert checks.RESAMPLING_NOMINAL_TAIL < tail <= checks.ALPHA_RESAMPLING / 2, tail


def test_family_cases_do_not_depend_on_the_seed_except_for_order():
    a, b = checks.near_case(1), checks.near_case(2)
    np.testing.assert_array_equal(a.p, b.p)
    assert not np.array_equal(a.family, b.family)
    np.testing.assert_allclose(np.bincount(a.family, weights=a.w), checks.FAMILY_WEIGHT, rtol=1e-12)
    np.testing.assert_allclose(a.x_hat[0] - a.b_next, checks.NEAR_OFFSETS, atol=1e-9)


def test_reference_passes_every_check_on_200_seeds_and_the_posterior_statistic_is_gaussian():
    statistics = []
    for seed in SEEDS:  # check_pf_step, keeping the posterior statistic
        checks.check_weights(ref.pf_step, seed)
        checks.check_resampling(ref.pf_step, seed)
        checks.check_innovation(ref.pf_step, seed)
        statistics.append(checks.check_posterior(ref.pf_step, seed))
    # the posterior check assumes the final posterior mean of beta is Gaussian across seeds
    m = np.array(statistics)
    assert stats.shapiro(m).pvalue > 1e-3
    assert abs(stats.kurtosis(m)) < 1.0
    ensemble = checks.reference_ensemble()
    z = (m - ensemble.mean()) / (ensemble.std(ddof=1) * math.sqrt(1 + 1 / ensemble.shape[0]))
    assert np.max(np.abs(z)) < checks.posterior_threshold()


PF_MISTAKES = [m for m in MISTAKES if m.blank == "pf_step"]


@pytest.mark.parametrize("mistake", PF_MISTAKES, ids=[m.slug for m in PF_MISTAKES])
def test_every_pf_step_mistake_fails_on_every_seed(mistake):
    step = mistaken(mistake)
    for seed in SEEDS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a mistake's own warnings are reported by the checks
            with pytest.raises(AssertionError):
                checks.check_pf_step(step, seed=seed)


def test_other_correct_implementations_pass_the_checks():
    bench = load_benchmark()
    for seed in range(3):
        # the plain step has no log-weights, so only the near reading suits it
        checks.check_weights(bench.plain_pf_step, seed, readings=("near",))
        checks.check_resampling(bench.plain_pf_step, seed, readings=("near",))
        checks.check_innovation(bench.plain_pf_step, seed)
        checks.check_posterior(bench.plain_pf_step, seed)
        for check in (checks.check_weights, checks.check_resampling, checks.check_innovation):
            check(bench.loop_pf_step, seed)
    # with the far reading its weights are 0/0, and the checks say so
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(AssertionError, match="log-weights"):
            checks.check_weights(bench.plain_pf_step, 0)


def test_check_messages_name_the_fix():
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
            with pytest.raises(AssertionError, match=pattern):
                checks.check_pf_step(by_slug[slug], seed=0)


def test_pf_step_is_reproducible_and_leaves_its_inputs_alone():
    x, w = ref.initial_cloud(60_000.0, 1000, np.random.default_rng(1))
    x0, w0 = x.copy(), w.copy()
    a = ref.pf_step(x, w, 59_800.0, np.random.default_rng(2))
    b = ref.pf_step(x, w, 59_800.0, np.random.default_rng(2))
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
    data = fo.load()
    return data, ref.run_particle_filter(data.b, fo.N_PARTICLES, np.random.default_rng(fo.RUN_SEED))


def test_run_history_is_consistent(lab_run):
    data, history = lab_run
    assert history.missing() == [] and history.n_times == 301 and history.n_particles == 5000
    assert np.all(history.lo90 <= history.lo50) and np.all(history.lo50 <= history.median)
    assert np.all(history.median <= history.hi50) and np.all(history.hi50 <= history.hi90)
    assert np.all((1 <= history.ess) & (history.ess <= 5000 + 1e-6))
    assert history.ess[0] == pytest.approx(5000)
    # the filter beats the raw radar on altitude
    assert np.sqrt(np.mean((history.mean[0] - data.x_true[0]) ** 2)) < 0.5 * fo.SIGMA


def test_run_reproduces_a_hand_written_loop():
    b = fo.load().b[:21]
    history = ref.run_particle_filter(b, 300, np.random.default_rng(4))
    rng = np.random.default_rng(4)
    x, w = ref.initial_cloud(b[0], 300, rng)
    for j in range(1, 21):
        x, w = ref.pf_step(x, w, b[j], rng)
    np.testing.assert_allclose(history.mean[:, -1], np.sum(w * x, axis=1), rtol=1e-12)
    np.testing.assert_allclose(history.median[:, -1], np.median(x, axis=1))
    np.testing.assert_allclose(history.ess[-1], 1 / np.sum(w**2))
    lo, hi = (np.sort(x, axis=1)[:, i - 1] for i in (round(0.05 * 300), round(0.95 * 300)))
    np.testing.assert_array_equal(history.lo90[:, -1], lo)
    np.testing.assert_array_equal(history.hi90[:, -1], hi)


def test_lab_beta_panel_narrows_and_keeps_the_truth_in_the_90_band(lab_run):
    data, history = lab_run
    beta = 19_161.0
    assert np.all((history.lo90[2] <= beta) & (beta <= history.hi90[2]))
    for lo, hi in ((history.lo90[2], history.hi90[2]), (history.lo50[2], history.hi50[2])):
        width = hi - lo
        assert np.mean(width[-30:]) < 0.75 * np.mean(width[:30])


def test_figures_and_report_draw(lab_run):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data, history = lab_run
    axes = fo.plot_tracking(data, history)
    assert axes.shape == (2, 3) and all(ax.get_xlabel() == "time t [s]" for ax in axes[1])
    ax = fo.plot_ess(data, history)
    assert ax.get_ylabel().startswith("ESS")
    ax = fo.plot_band_widths(data, {"N = 5000": history})
    assert len(ax.get_lines()) == 2
    report = fo.format_report(data, history)
    assert "beta" in report and "19161" in report
    plt.close("all")
    with pytest.raises(ValueError, match="NaN"):
        fo.plot_ess(data, fo.FilterHistory.empty(301))
