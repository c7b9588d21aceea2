"""Checks of the claims that the reentry-srekf notebook makes.

Two kinds of claim. Those about the shipped fall (course/data/starship_reentry.csv) are
deterministic and are checked on that file. Those about the filter in general (the NEES, the
coverage of the bands, the lag of the altitude's uncertainty, the negative c) are checked over the
notebook's Monte Carlo (the 40 shipped simulated falls, ``course/data/starship_falls.npz``, whose filters
start from initial errors drawn from the prior, filtered by ``course.starship.filter_falls``), as rates or
ranges with tolerances stated in each check. The claims of part 9 about the NEES averaged over 40 falls, and the
lag of part 10, are quoted twice: for these 40 falls, and over the nine other sets of 40 falls of ``OTHER_SETS``
(seeds 500-539 and 1000-1039, 2000-2039, ..., 8000-8039), which the checks recompute (``fall_sets``: about 1 s
for all nine). The rate claims' tolerances were also checked on the set of seeds 500-539. The averages that the text
gives over many falls (average-nees-many-falls) and the lag's "nearly all" are checked over 2000 fresh falls
(``MANY_FALL_SEEDS``, 20000-21999), built the same way (about 20 s under load).
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.stats import norm

from autograder.authoring.claims import claim, rate_at_least
from course import starship
from course.starship import G, L, M, P0, R, RADAR_R2, T0
from solutions.reentry_srekf import fall_sets
from solutions.reentry_srekf import reference as ref


@functools.cache
def _shipped() -> tuple[starship.ReentryData, starship.FilterResult, np.ndarray]:
    """The shipped fall, the reference filter's run on it and the standard deviations, (N, 3)."""
    data = starship.load()
    result = ref.run_reference(data)
    return data, result, starship.marginal_std(result, ref.marginal)


@functools.cache
def _falls() -> starship.MonteCarloRun:
    """The notebook's Monte Carlo: the shipped falls (tests/test_reentry_srekf_reference.py rebuilds them from
    ``reference.FALL_SEEDS``), each filtered from its initial mean drawn from the prior."""
    return starship.filter_falls(starship.load_falls(), ref.ballistic_dynamics, ref.ballistic_jacobian, ref.radar_predict,
                                 ref.radar_jacobian, ref.sqrt_time_update, ref.sqrt_measurement_update)


#: The other sets of 40 falls that the text quotes beside the shipped ones (seeds 7100-7139), to tell what holds
#: over draws of 40 falls from what holds in these 40: seeds 500-539, then 1000-1039, 2000-2039, ..., 8000-8039.
OTHER_SETS: tuple[range, ...] = (range(500, 540), *(range(start, start + 40) for start in range(1000, 9000, 1000)))


@functools.cache
def _other_sets() -> tuple[starship.MonteCarloRun, ...]:
    """The sets of OTHER_SETS, simulated and filtered with the reference's model (``fall_sets``, all at once), once
    ``fall_sets`` has reproduced the shipped falls and the reference filter's run on them."""
    seeds = [*ref.FALL_SEEDS, *(seed for seeds in OTHER_SETS for seed in seeds)]
    simulated = fall_sets.simulate_sets(seeds)
    shipped = starship.load_falls()
    # measured: 2.3e-16 relative in the truth; ranges and initial means identical
    assert np.allclose(simulated.truth[:40], shipped.truth, rtol=1e-12, atol=0), "fall_sets simulates other falls"
    assert np.allclose(simulated.range_meas[:40], shipped.range_meas, rtol=1e-12, atol=0), "fall_sets draws other ranges"
    assert np.array_equal(simulated.mu0[:40], shipped.mu0), "fall_sets draws other initial means"
    edges = range(40, len(seeds) + 1, 40)
    sets = [shipped] + [starship.SimulatedFalls(t=simulated.t, truth=simulated.truth[a - 40 : a],
                                                range_true=simulated.range_true[a - 40 : a],
                                                range_meas=simulated.range_meas[a - 40 : a], mu0=simulated.mu0[a - 40 : a])
                        for a in edges[1:]]
    runs = fall_sets.filter_sets(sets)
    # measured against course.starship.filter_falls with the reference: 2.6e-12 (NEES), 1.3e-14 (standard deviations)
    reference = _falls()
    assert np.allclose(runs[0].nees, reference.nees, rtol=1e-9, atol=0), "fall_sets filters otherwise than the reference"
    assert np.allclose(runs[0].std, reference.std, rtol=1e-9, atol=0), "fall_sets filters otherwise than the reference"
    return runs[1:]


def _average_nees_in(start: float, stop: float,
                     falls: starship.MonteCarloRun | None = None) -> tuple[np.ndarray, float, float]:
    """The NEES averaged over the falls (by default the shipped ones) at the steps start <= t < stop, and its 95% band."""
    falls = _falls() if falls is None else falls
    lower, upper = starship.average_nees_band(falls.nees.shape[0])
    window = (falls.t >= start) & (falls.t < stop)
    return falls.nees.mean(axis=0)[window], lower, upper


def _as_quoted(value: float, quoted: float, decimals: int, what: str) -> None:
    """Assert that ``value`` rounds to the ``quoted`` number, given to ``decimals`` decimals."""
    assert abs(value - quoted) <= 0.5 * 10.0**-decimals + 1e-12, f"{what} is {value:.{decimals + 2}f}, quoted as {quoted}"


def _lags(falls: starship.MonteCarloRun) -> np.ndarray:
    """For each fall, the time [s] from passing the radar's altitude to the widest sigma_h after 15 s."""
    return np.array([_widest_altitude_band_after_first_seconds(falls.t, std) - _crossing_time(falls.t, truth[:, 0])
                     for truth, std in zip(falls.truth, falls.std)])


def _crossing_time(t: np.ndarray, h: np.ndarray) -> float:
    """The first time [s] at which the altitude is below the radar's, r2."""
    return float(t[np.argmax(h < RADAR_R2)])


def _widest_altitude_band_after_first_seconds(t: np.ndarray, std: np.ndarray, after: float = 15.0) -> float:
    """The time [s] of the largest sigma_h after ``after`` seconds (the first ranges' band is wider)."""
    late = t > after
    return float(t[late][np.argmax(std[late, 0])])


def _first_update_comparison() -> starship.FirstUpdateComparison:
    """The comparison of part 8, on the notebook's grid of radar precisions."""
    return starship.compare_first_update(ref.sqrt_measurement_update, ref.radar_predict, ref.radar_jacobian,
                                         starship.FIRST_UPDATE_SIGMA)


# ---------------------------------------------------------------------------------------------
# The atmosphere (part 1)
# ---------------------------------------------------------------------------------------------
@claim("reentry-srekf/above-11-km-first-9-s")
def _() -> None:
    """The shipped fall starts at 15 km and is above 11 km for its first 9.5 s (to within 0.1 s)."""
    data, _, _ = _shipped()
    below = float(data.t[np.argmax(data.h < 11_000.0)])
    assert data.h[0] == 15_000.0, f"the fall starts at {data.h[0]} m"
    assert abs(below - 9.5) <= 0.1 + 1e-9, f"the vehicle is first below 11 km at t = {below} s"


def _standard_atmosphere_density(h: float) -> float:
    """ISA density [kg/m^3]: the lapse rate L up to 11 km, then an isothermal layer (an independent formula)."""
    exponent = G * M / (R * L)
    T11 = T0 - L * 11_000.0
    if h <= 11_000.0:
        T = T0 - L * h
        return P0 * (T / T0) ** exponent * M / (R * T)
    p11 = P0 * (T11 / T0) ** exponent
    return p11 * np.exp(-G * M * (h - 11_000.0) / (R * T11)) * M / (R * T11)


@claim("reentry-srekf/atmosphere-density-error")
def _() -> None:
    """The model's density is 2.5-3.5% above the ISA's at 12 km and 8.5-9.5% at 15 km; c then ~8% low."""
    v, c = -100.0, 1.0

    def model_density(h: float) -> float:
        return (ref.ballistic_dynamics([h, v, c])[1] + G) / (0.5 * v**2 * c)

    excess = {h: model_density(h) / _standard_atmosphere_density(h) - 1 for h in (11_000.0, 12_000.0, 15_000.0)}
    assert abs(excess[11_000.0]) < 1e-12, f"the two atmospheres differ at 11 km by {excess[11_000.0]:.2%}"
    assert 0.025 <= excess[12_000.0] <= 0.035, f"the excess at 12 km is {excess[12_000.0]:.2%}"
    assert 0.085 <= excess[15_000.0] <= 0.095, f"the excess at 15 km is {excess[15_000.0]:.2%}"
    # the ranges fix rho c, so c would be estimated low by the factor 1 / (1 + excess)
    c_error = 1 / (1 + excess[15_000.0]) - 1
    assert -0.09 <= c_error <= -0.07, f"c would be off by {c_error:.2%}"


# ---------------------------------------------------------------------------------------------
# The filter on the shipped fall (part 7)
# ---------------------------------------------------------------------------------------------
@claim("reentry-srekf/sigma-h-range")
def _() -> None:
    """sigma_h is 55-60 m after the first range and between 14 and 58 m at every step of the shipped fall."""
    _, _, std = _shipped()
    assert 55.0 <= std[0, 0] <= 60.0, f"sigma_h after the first range is {std[0, 0]:.1f} m"
    assert 14.0 <= std[:, 0].min() and std[:, 0].max() <= 58.0, (
        f"sigma_h ranges from {std[:, 0].min():.1f} to {std[:, 0].max():.1f} m"
    )


@claim("reentry-srekf/c-converges")
def _() -> None:
    """Shipped fall: sigma_v 100 -> 18-22 m/s by t = 5 s; sigma_c < 10% of c from t = 7.5-8.5 s on, ~2% at the end, truth in band."""
    data, result, std = _shipped()
    at_5 = int(np.argmin(np.abs(data.t - 5.0)))
    assert 18.0 <= std[at_5, 1] <= 22.0, f"sigma_v at t = 5 s is {std[at_5, 1]:.1f} m/s"
    relative = std[:, 2] / data.c
    below = relative < 0.10
    first = int(np.argmax(below))
    assert below[first:].all(), "sigma_c rises above 10% of c again after first falling below it"
    assert 7.5 <= data.t[first] <= 8.5, f"sigma_c first falls below 10% of c at t = {data.t[first]} s"
    assert 0.015 <= relative[-1] <= 0.025, f"sigma_c ends at {relative[-1]:.1%} of c"
    assert np.all(np.abs(data.c - result.mu[:, 2]) <= 3 * std[:, 2]), "the true c leaves its 3-sigma band"


# ---------------------------------------------------------------------------------------------
# Why square roots (part 8)
# ---------------------------------------------------------------------------------------------
@claim("reentry-srekf/covariance-form-breaks")
def _() -> None:
    """Short covariance form: float32 wrong by 100% (variance exactly 0) for every sigma <= 0.2-0.5 m; float64 not PD (variance 0, then -2^-30 m^2: 7 times the exact at 1e-5 m, 7e10 at 1e-10 m) from 1e-5-3e-5 m down, error growing before."""
    comparison = _first_update_comparison()
    error = {
        name: np.abs(getattr(comparison, name) - comparison.exact) / comparison.exact
        for name in ("covariance32", "covariance64")
    }
    # measured: float32 from 0.32 m down, float64 from 1.8e-5 m down (grid of 4 points a decade)
    for name, low, high in (("covariance32", 0.2, 0.5), ("covariance64", 1e-5, 3e-5)):
        broken = ~getattr(comparison, f"pd_{name}")
        assert broken.any(), f"the {name} form stays positive definite"
        threshold = comparison.sigma[broken].max()
        assert low <= threshold <= high, f"the {name} form breaks from sigma = {threshold:.3g} m"
        assert broken[comparison.sigma <= threshold].all(), f"the {name} form recovers below {threshold:.3g} m"
        assert np.all(getattr(comparison, name)[broken] <= 0.0), f"the {name} form breaks with a positive variance"
    assert np.all(comparison.covariance32[~comparison.pd_covariance32] == 0.0), "float32 breaks with a non-zero variance"
    # float64: the error grows as the radar gets more precise (by over eight decades before breaking)
    working = comparison.pd_covariance64
    assert error["covariance64"][working][-1] > 1e8 * error["covariance64"][working][0], "float64's error does not grow"
    # once broken, the variance is exactly 0, then -2^-30 m^2 (one rounding unit of P_hh) at every finer radar: about
    # 7 times the exact variance at 1e-5 m and 7e10 times at 1e-10 m
    broken64 = comparison.covariance64[~working]
    assert broken64[0] == 0.0 and np.all(broken64[1:] == -(2.0**-30)), f"the broken float64 variances are {broken64}"
    ratio = np.abs(broken64) / comparison.exact[~working]
    at = {s: float(ratio[np.argmin(np.abs(np.log(comparison.sigma[~working] / s)))]) for s in (1e-5, 1e-10)}
    assert 5 <= at[1e-5] <= 10 and 5e10 <= at[1e-10] <= 1e11, f"the broken variance against the exact one: {at}"


@claim("reentry-srekf/square-root-form-holds")
def _() -> None:
    """The square-root update is within 1e-15 (float64) and 1e-6 (float32) of the exact variance and positive definite at every sigma."""
    comparison = _first_update_comparison()
    # measured: largest relative errors 5.2e-16 (float64) and 1.7e-7 (float32, whose epsilon is 6e-8)
    for name, bound in (("square_root", 1e-15), ("square_root32", 1e-6)):
        error = np.abs(getattr(comparison, name) - comparison.exact) / comparison.exact
        assert getattr(comparison, f"pd_{name}").all(), f"the {name} form loses positive definiteness"
        assert error.max() <= bound, f"the {name} form's largest relative error is {error.max():.2g}"


@claim("reentry-srekf/joseph-form-holds")
def _() -> None:
    """Joseph's covariance form in float64 stays positive definite at every sigma, with relative error <= 1e-4 (1.8e-5 at 1e-10 m)."""
    comparison = _first_update_comparison()
    error = np.abs(comparison.joseph64 - comparison.exact) / comparison.exact
    assert comparison.pd_joseph64.all(), "Joseph's form loses positive definiteness"
    assert 1e-6 <= error.max() <= 1e-4, f"Joseph's form's largest relative error is {error.max():.2g}"


@functools.cache
def _float32_covariance_filter_on_shipped_fall() -> tuple[np.ndarray, np.ndarray, bool]:
    """The shipped fall filtered by a covariance-form EKF in float32 (short form): (mu (N, 3), P (N, 3, 3), always PD)."""
    data = starship.load()
    Q = starship.SQRT_Q.T @ starship.SQRT_Q

    def measure(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return ref.radar_predict(x), ref.radar_jacobian(x)

    mu, P, time = starship.MU0.copy(), starship.S0.T @ starship.S0, 0.0
    mus, Ps, always_pd = [], [], True
    for k in range(len(data)):
        dt = float(data.t[k] - time)
        if dt > 0:
            mu, J = starship.rk4_step_with_jacobian(ref.ballistic_dynamics, ref.ballistic_jacobian, mu, np.zeros(3), dt)
            J32 = J.astype(np.float32)
            # P+ = J blkdiag(P, Q dt) J^T, in float32
            Pz = np.zeros((6, 6), dtype=np.float32)
            Pz[:3, :3], Pz[3:, 3:] = P, Q * dt
            P = (J32 @ Pz @ J32.T).astype(float)
        time = float(data.t[k])
        mu, P = starship.covariance_measurement_update(mu, P, data.range_meas[k : k + 1], measure,
                                                       starship.SIGMA_RANGE**2 * np.eye(1), np.float32)
        always_pd &= starship.is_positive_definite(P)
        mus.append(mu)
        Ps.append(P)
    return np.array(mus), np.array(Ps), always_pd


@claim("reentry-srekf/radar-50m-safe")
def _() -> None:
    """At the lab's radar (sigma 50 m) float32 covariance updates are fine: first update within 1e-4; over the shipped fall variances within 1e-4, means within 1e-3 sigma, always PD."""
    comparison = _starship_50m_comparison()
    error = np.abs(comparison.covariance32 - comparison.exact) / comparison.exact
    assert error.max() <= 1e-4, f"float32's first update at 50 m is off by {error.max():.2g}"
    _, result, std = _shipped()
    mu, P, always_pd = _float32_covariance_filter_on_shipped_fall()
    variance = std**2
    variance_error = np.max(np.abs(np.diagonal(P, axis1=1, axis2=2) - variance) / variance)
    mean_error = np.max(np.abs(mu - result.mu) / std)
    # measured: 4.4e-5 (variances) and 3.2e-4 (means)
    assert always_pd, "the float32 covariance filter loses positive definiteness on the shipped fall"
    assert variance_error <= 1e-4, f"the float32 covariance filter's variances differ by up to {variance_error:.2g}"
    assert mean_error <= 1e-3, f"the float32 covariance filter's means differ by up to {mean_error:.2g} sigma"


def _starship_50m_comparison() -> starship.FirstUpdateComparison:
    """The comparison of part 8 at the lab's radar, sigma = 50 m."""
    return starship.compare_first_update(ref.sqrt_measurement_update, ref.radar_predict, ref.radar_jacobian,
                                         np.array([starship.SIGMA_RANGE]))


# ---------------------------------------------------------------------------------------------
# Errors and NEES (part 9)
# ---------------------------------------------------------------------------------------------
@claim("reentry-srekf/shipped-coverage")
def _() -> None:
    """On the shipped fall every error of h, v and c is inside its 3-sigma band at every step."""
    data, result, std = _shipped()
    inside = np.abs(data.truth - result.mu) <= 3 * std
    assert inside.all(), f"errors leave their bands at {np.sum(~inside)} state-steps"


@claim("reentry-srekf/shipped-nees")
def _() -> None:
    """On the shipped fall the NEES is inside its 95% band at 95-97% of steps, with mean 3.1-3.5."""
    data, result, _ = _shipped()
    nees = starship.normalised_estimation_error_squared(data.truth, result)
    lower, upper = starship.nees_band()
    inside = np.mean((nees >= lower) & (nees <= upper))
    assert 0.95 <= inside <= 0.97, f"the NEES is inside its band at {inside:.1%} of the steps"
    assert 3.1 <= nees.mean() <= 3.5, f"the mean NEES is {nees.mean():.2f}"


@claim("reentry-srekf/average-nees-overconfident-early")
def _() -> None:
    """These 40 falls: the NEES averaged over them is above its band at every step of the first 10 s, 7.3 on average over
    5-10 s and 4.4 over 10-20 s (above the band at about two steps in three). Nine other sets: above the band at every step
    of 5-10 s in every set (5.3 to 48 over that window); above it on average over 10-20 s in eight of nine (3.3 to 14);
    over the first 5 s above at a quarter to all of the steps, by set."""
    # Measured, shipped set (7100-7139) / other sets 500-539, 1000-1039, 2000-2039, ..., 8000-8039:
    # share of 0-10 s above the band 1.00 / 1.00 0.63 1.00 1.00 0.69 1.00 0.70 0.92 0.79; of 0-5 s 1.00 / 1.00 0.26 1.00
    # 1.00 0.38 1.00 0.40 0.84 0.58; of 5-10 s 1.00 in every set. Window averages 5-10 s: 7.29 / 9.10 5.29 29.4 12.3 7.52
    # 48.5 6.90 7.24 8.17; 10-20 s: 4.40 / 5.50 3.31 9.80 5.69 4.68 13.8 4.98 4.32 4.75 (the band's top is 3.81). The
    # largest averages come from one fall each with a large early error (its own average over 5-10 s 820 in 2000-2039,
    # 1540 in 5000-5039). Four more sets (9000-9039 to 12000-12039) agree: 5-10 s above at every step (7.5 to 9.0),
    # 10-20 s above on average (4.2 to 5.5). The old wording (above the band at >= 95% of the steps of 0-10 s, and on
    # average over 10-20 s, in any 40 falls) fails on five of the nine other sets: 1000, 4000, 6000, 7000, 8000.
    early, _, upper = _average_nees_in(0.0, 10.0)
    assert np.all(early > upper), (
        f"in the shipped falls the average NEES is inside its band at {np.sum(early <= upper)} steps of 0-10 s")
    mid, _, _ = _average_nees_in(5.0, 10.0)
    _as_quoted(mid.mean(), 7.3, 1, "the shipped falls' average NEES over 5-10 s")
    late, _, _ = _average_nees_in(10.0, 20.0)
    _as_quoted(late.mean(), 4.4, 1, "the shipped falls' average NEES over 10-20 s")
    above = np.mean(late > upper)
    assert 0.6 <= above <= 0.7, f"the shipped falls' average NEES is above its band at {above:.0%} of the steps of 10-20 s"
    # over the other sets: the general statement, then the spreads quoted
    mids, lates, firsts = [], [], []
    for falls in _other_sets():
        mid, _, upper = _average_nees_in(5.0, 10.0, falls)
        assert np.all(mid > upper), (
            f"in a set of falls the average NEES is inside its band at {np.sum(mid <= upper)} steps of 5-10 s")
        mids.append(mid.mean())
        late, _, _ = _average_nees_in(10.0, 20.0, falls)
        lates.append(late.mean())
        first, _, _ = _average_nees_in(0.0, 5.0, falls)
        firsts.append(np.mean(first > upper))
    _as_quoted(min(mids), 5.3, 1, "the lowest average NEES over 5-10 s")
    _as_quoted(max(mids), 48.0, 0, "the highest average NEES over 5-10 s")
    above_sets = int(np.sum(np.array(lates) > upper))
    assert above_sets == 8, f"the average NEES over 10-20 s is above its band in {above_sets} of {len(lates)} sets"
    _as_quoted(min(lates), 3.3, 1, "the lowest average NEES over 10-20 s")
    _as_quoted(max(lates), 14.0, 0, "the highest average NEES over 10-20 s")
    assert 0.2 <= min(firsts) <= 0.3 and max(firsts) == 1.0, (
        f"over 0-5 s the average is above its band at {min(firsts):.0%} to {max(firsts):.0%} of the steps, by set")
def _() -> None:
    """Averaged over 40 falls, the NEES is above its band chi2(120)/40 at >= 95% of the steps of the first 10 s, >= 5 on average over 5-10 s, and above 3.81 on average over 10-20 s."""
    # Measured (seeds 7100-7139 / 500-539): every step of 0-10 s above the band's upper end 3.81, the
    # lowest at 3.87 / 4.17 (near 3.5 s); window averages 4.8 / 5.2 (0-2 s), 4.5 / 5.1 (2-5 s),
    # 7.3 / 9.1 (5-10 s), 4.4 / 5.5 (10-20 s).
    early, _, upper = _average_nees_in(0.0, 10.0)
    above = np.mean(early > upper)
    assert above >= 0.95, f"the average NEES is above its band at only {above:.0%} of the steps of 0-10 s"
    mid, _, _ = _average_nees_in(5.0, 10.0)
    assert mid.mean() >= 5.0, f"the average NEES over 5-10 s is {mid.mean():.2f}"
    late, _, _ = _average_nees_in(10.0, 20.0)
    assert late.mean() > upper, f"the average NEES over 10-20 s is {late.mean():.2f}, inside its band (up to {upper:.2f})"


def _first_update_nees(sigma_h: float, n: int, seed: int) -> np.ndarray:
    """The NEES after the first range update alone, (n,): the true state X0_TRUE, initial means drawn from a
    prior with standard deviations [sigma_h (m), S0's for v and c], one noisy range each, the reference update."""
    rng = np.random.default_rng(seed)
    S0 = np.diag([sigma_h, starship.S0[1, 1], starship.S0[2, 2]])
    measure = lambda x: (ref.radar_predict(x), ref.radar_jacobian(x))  # noqa: E731
    nees = np.empty(n)
    for k in range(n):
        mu0 = starship.X0_TRUE - S0.T @ rng.standard_normal(3)
        y = ref.radar_predict(starship.X0_TRUE) + starship.SIGMA_RANGE * rng.standard_normal(1)
        mu, S = ref.sqrt_measurement_update(mu0, S0, y, measure, starship.SIGMA_RANGE * np.eye(1))
        whitened = np.linalg.solve(S.T, starship.X0_TRUE - mu)
        nees[k] = whitened @ whitened
    return nees


@claim("reentry-srekf/first-update-nees-spike")
def _() -> None:
    """The average NEES at t = 0 of the shipped falls is 7-13 (above its band); alone, about one first update in
    seven (10-19%) has a NEES above 9.35, against at most 3.5% (2.5% when consistent) when sigma_h is 1000 m."""
    # Measured: 9.74 at t = 0 over the shipped falls. Over 2000 first updates: 13.8% / 14.8% above 9.35 (seeds 1 / 2)
    # at sigma_h = 2200 m, 3.8% / 2.7% at 1000 m, 2.8% / 2.2% at 500 m; a consistent update has 2.5%. The mean of
    # those NEES is no statistic to quote: a heavy tail puts it at 9.4, 18 or 13 by batch, while the median stays
    # near 3. The binomial standard deviation of a rate near 0.14 over 2000 updates is 0.008. An independent review
    # (200,000 first updates a sigma_h) found 0.137 at 2200 m and 0.030 at 1000 m; a first update linearised exactly
    # gives 0.025 at every sigma_h, so the excess is the range's curvature. The average at t = 0 is a mean of 40
    # heavy-tailed values: 3.9 to 45 over eight other sets of 40 falls, so the text quotes it for these falls only.
    falls = _falls()
    _, upper = starship.average_nees_band(falls.nees.shape[0])
    first = falls.nees[:, 0].mean()
    assert upper < 7.0 <= first <= 13.0, f"the average NEES at t = 0 is {first:.2f}"
    _, single_upper = starship.nees_band()
    for seed in (1, 2):
        wide = np.mean(_first_update_nees(2200.0, 2000, seed) > single_upper)
        assert 0.10 <= wide <= 0.19, f"{wide:.1%} of the first updates from sigma_h = 2200 m have a NEES above {single_upper:.2f}"
        narrow = np.mean(_first_update_nees(1000.0, 2000, seed) > single_upper)
        assert narrow <= 0.04, f"{narrow:.1%} of the first updates from sigma_h = 1000 m have a NEES above {single_upper:.2f}"


@claim("reentry-srekf/average-nees-consistent-late")
def _() -> None:
    """These 40 falls: from 20 s on the NEES averaged over them stays between 2.7 and 3.7, inside its band at every step.
    Nine other sets: the average over 20-30 s ranges from 2.3 to 6.0 by set."""
    # Measured, shipped set (7100-7139) / other sets 500-539, 1000-1039, 2000-2039, ..., 8000-8039: window averages
    # 20-30 s 3.24 / 3.82 2.27 4.66 3.36 3.64 5.98 3.46 2.94 3.64; 30-40 s 3.34 / 3.50 2.35 3.85 2.90 3.28 3.83 3.03 2.80
    # 3.75; 40-50 s 3.17 / 3.38 3.19 3.13 3.30 3.17 3.24 2.71 3.02 3.47. The text said until the science review that
    # by 40 s every set of 40 had settled (2.7 to 3.5 over 40-50 s, inside the band at >= 90% of the steps): true of
    # these nine, but random sets of 40 fresh falls miss 2.7-3.5 about one time in four (the review: 22% on 400 falls of
    # the lab's simulator, 27% on 2000 of its own), so the late part is now stated over many falls
    # (average-nees-many-falls).
    late, lower, upper = _average_nees_in(20.0, np.inf)
    assert np.all((late >= lower) & (late <= upper)), "from 20 s on the shipped falls' average NEES leaves its band"
    _as_quoted(late.min(), 2.7, 1, "the lowest average NEES of the shipped falls from 20 s on")
    _as_quoted(late.max(), 3.7, 1, "the highest average NEES of the shipped falls from 20 s on")
    settling = [_average_nees_in(20.0, 30.0, falls)[0].mean() for falls in _other_sets()]
    _as_quoted(min(settling), 2.3, 1, "the lowest average NEES over 20-30 s")
    _as_quoted(max(settling), 6.0, 1, "the highest average NEES over 20-30 s")


MANY_FALL_SEEDS = range(20000, 22000)
"""Seeds of the 2000 fresh falls of the many-fall claims (no other check, and no set of the notebook, uses them)."""


@functools.cache
def _many_falls() -> starship.MonteCarloRun:
    """2000 fresh falls (MANY_FALL_SEEDS), simulated and filtered with the reference's model by ``fall_sets`` (about
    20 s of one core under load), once ``_other_sets`` has checked that ``fall_sets`` reproduces the shipped falls (the
    lab's own simulator, ``course.starship.simulate_falls``) and the reference filter's run on them."""
    _other_sets()
    return fall_sets.filter_sets([fall_sets.simulate_sets(list(MANY_FALL_SEEDS))])[0]


@claim("reentry-srekf/average-nees-many-falls")
def _() -> None:
    """Over 2000 fresh falls the NEES averaged over the falls is well above 3 in every window up to 20 s (0-5, 5-10 and
    10-20 s), about 3.7 over 20-30 s, 3.3-3.4 over 30-40 s and 3.1 over 40-50 s; each half of the falls (1000 each) agrees:
    falling from window to window, above 3.3 over 20-30 s and 2.9-3.3 over 40-50 s. And 40 falls cannot tell 3.4 from 3:
    the 50 sets of 40 that the 2000 make spread by 0.3 to 0.8 (sd) in their averages over 20-30, 30-40 and 40-50 s."""
    # Measured (seeds 20000-21999): window averages 5.39 (0-5 s), 13.3 (5-10 s), 5.89 (10-20 s), 3.81 (20-30 s), 3.38
    # (30-40 s), 3.11 (40-50 s); halves 3.97 / 3.66, 3.42 / 3.35, 3.14 / 3.08 over the last three windows; without the
    # worst 1% of falls in each window 3.47, 3.21, 3.02. Sets of 40: sd 0.72, 0.46, 0.36 over the last three windows. The
    # band of an average over 2000 falls is [2.89, 3.11]. The science review found 3.61, 3.24, 2.97 over 400 falls of
    # the lab's simulator and 3.89, 3.44, 3.10 over 2000 of its own: heavy tails (one fall with a large early error
    # lifts an average a long way) make these averages settle slowly, hence the tolerances.
    falls = _many_falls()
    assert falls.nees.shape[0] == 2000
    windows = ((0.0, 5.0), (5.0, 10.0), (10.0, 20.0), (20.0, 30.0), (30.0, 40.0), (40.0, 50.0))

    def averages(nees: np.ndarray) -> list[float]:
        return [float(nees[:, (falls.t >= a) & (falls.t < b)].mean()) for a, b in windows]

    def between(value: float, low: float, high: float, what: str) -> None:
        assert low <= value <= high, f"{what} is {value:.3f}, outside {low:g} to {high:g}"

    every = averages(falls.nees)
    assert min(every[:3]) >= 4.5, f"the window averages up to 20 s are {np.round(every[:3], 2)}"
    between(every[3], 3.55, 3.9, "the average over 20-30 s (about 3.7)")
    between(every[4], 3.2, 3.5, "the average over 30-40 s (3.3 to 3.4)")
    between(every[5], 3.0, 3.2, "the average over 40-50 s (about 3.1)")
    for half in (falls.nees[:1000], falls.nees[1000:]):
        late = averages(half)[3:]
        assert late[0] > late[1] > late[2], f"in half of the falls the averages over 20-50 s are {np.round(late, 2)}"
        between(late[0], 3.3, np.inf, "in half of the falls the average over 20-30 s")
        between(late[2], 2.9, 3.3, "in half of the falls the average over 40-50 s")
    for a, b in windows[3:]:
        sets = falls.nees[:, (falls.t >= a) & (falls.t < b)].mean(axis=1).reshape(50, 40).mean(axis=1)
        between(float(sets.std()), 0.3, 0.8, f"the sd of the averages of 50 sets of 40 falls over {a:g}-{b:g} s")


def _() -> None:
    """From 20 s on, the NEES averaged over 40 falls is 2.8-4.2 in every 10 s window and inside its band at >= 60% of the steps."""
    # Measured (seeds 7100-7139 / 500-539): window averages 3.2 / 3.8 (20-30 s), 3.3 / 3.5 (30-40 s),
    # 3.2 / 3.4 (40-50 s); inside the band at 100% / 79% of the steps from 20 s on. A few falls with
    # large errors can lift the average of 40 just above the band, hence the tolerances.
    for start in (20.0, 30.0, 40.0):
        window, _, _ = _average_nees_in(start, start + 10.0)
        assert 2.8 <= window.mean() <= 4.2, f"the average NEES over {start:g}-{start + 10:g} s is {window.mean():.2f}"
    late, lower, upper = _average_nees_in(20.0, np.inf)
    inside = np.mean((late >= lower) & (late <= upper))
    assert inside >= 0.60, f"from 20 s on the average NEES is inside its band at only {inside:.0%} of the steps"


@claim("reentry-srekf/pooled-nees-hides-it")
def _() -> None:
    """Pooled over all steps of these 40 falls, 91% of the NEES values lie in the single-step band [0.22, 9.35] (85% before
    20 s, 96% after); over nine other sets 86 to 94%, below 95% in each and lower before 20 s than after in each."""
    # Measured, shipped set (7100-7139) / other sets 500-539, 1000-1039, 2000-2039, ..., 8000-8039: pooled 0.913 / 0.889
    # 0.944 0.860 0.910 0.898 0.872 0.907 0.894 0.900 (the old range 0.85-0.94 fails on 1000-1039); before 20 s 0.848 /
    # 0.77 to 0.91; from 20 s on 0.957 / 0.92 to 0.97. A consistent filter gives 0.95.
    lower, upper = starship.nees_band()

    def inside(falls: starship.MonteCarloRun) -> tuple[float, float, float]:
        held = (falls.nees >= lower) & (falls.nees <= upper)
        return float(held.mean()), float(held[:, falls.t < 20.0].mean()), float(held[:, falls.t >= 20.0].mean())

    pooled, before, after = inside(_falls())
    _as_quoted(100 * pooled, 91, 0, "the percentage of the shipped falls' NEES values inside the single-step band")
    _as_quoted(100 * before, 85, 0, "the percentage before 20 s")
    _as_quoted(100 * after, 96, 0, "the percentage from 20 s on")
    others = [inside(falls) for falls in _other_sets()]
    for pooled, before, after in others:
        assert pooled < 0.95 and before < after, (
            f"in a set of falls {pooled:.1%} inside, {before:.1%} before 20 s, {after:.1%} after")
    _as_quoted(100 * min(o[0] for o in others), 86, 0, "the lowest percentage over the other sets")
    _as_quoted(100 * max(o[0] for o in others), 94, 0, "the highest percentage over the other sets")
def _() -> None:
    """Pooled over all falls and steps, 85-94% of the NEES values lie in the single-step band [0.22, 9.35]."""
    # Measured: 0.913 (seeds 7100-7139) and 0.889 (500-539); a consistent filter gives 0.95.
    falls = _falls()
    lower, upper = starship.nees_band()
    pooled = np.mean((falls.nees >= lower) & (falls.nees <= upper))
    assert 0.85 <= pooled <= 0.94, f"the pooled fraction inside the single-step band is {pooled:.3f}"


@claim("reentry-srekf/coverage-over-falls")
def _() -> None:
    """In about three falls in five (40-85% of 40), every error stays inside its 3-sigma band throughout."""
    falls = _falls()
    all_inside = np.all(np.abs(falls.truth - falls.mu) <= 3 * falls.std, axis=(1, 2))
    # measured 0.65 (seeds 7100-7139) and 0.60 (500-539); with a rate of 0.62, 40 falls give a rate
    # below 0.40 or above 0.85 with probability about 0.004 (binomial, standard deviation 0.077)
    rate = rate_at_least(all_inside, 0.40, "every error inside its 3-sigma band throughout a fall")
    assert rate <= 0.85, f"every error stays inside its band in {rate:.0%} of the falls, more than about three in five"


# ---------------------------------------------------------------------------------------------
# Observability (part 10)
# ---------------------------------------------------------------------------------------------
@claim("reentry-srekf/sigma-h-peak-after-crossing")
def _() -> None:
    """Shipped fall: crossing at 33.9 s, sigma_h ~20 m at 30 s, widest (27-31 m) at 38-39 s. Lag from crossing to widest:
    4.1 to 4.9 s in the 40 falls of part 9; 3.6 to 5.0 s over nine other sets of 40, 4 to 5 s in nearly all falls (at
    least 95% of those 360 and of 2000 fresh falls)."""
    data, _, std = _shipped()
    crossing = _crossing_time(data.t, data.h)
    widest = _widest_altitude_band_after_first_seconds(data.t, std)
    at_30 = int(np.argmin(np.abs(data.t - 30.0)))
    assert abs(crossing - 33.9) <= 0.05, f"the vehicle passes r2 at t = {crossing} s"
    assert 18.0 <= std[at_30, 0] <= 22.0, f"sigma_h at t = 30 s is {std[at_30, 0]:.1f} m"
    assert 38.0 <= widest <= 39.0, f"sigma_h is widest at t = {widest} s"
    peak = std[int(np.argmin(np.abs(data.t - widest))), 0]
    assert 27.0 <= peak <= 31.0, f"the widest sigma_h is {peak:.1f} m"
    # Measured (one measurement interval is 0.1 s), shipped set (7100-7139) / other sets 500-539, 1000-1039, 2000-2039,
    # ..., 8000-8039: shortest 4.1 / 4.2 4.3 3.9 4.1 4.1 3.6 4.2 4.1 4.1 s, longest 4.9 / 4.7 5.0 4.8 4.8 5.0 5.0 4.8 5.0
    # 4.9 s, median 4.5 to 4.6 s in every set (the old "4 to 5 s in every fall" fails on 2000-2039 and 5000-5039). Four
    # more sets (9000-9039 to 12000-12039): 4.1 to 5.0 s.
    lags = _lags(_falls())
    _as_quoted(lags.min(), 4.1, 1, "the shortest lag in the shipped falls [s]")
    _as_quoted(lags.max(), 4.9, 1, "the longest lag in the shipped falls [s]")
    others = np.concatenate([_lags(falls) for falls in _other_sets()])
    _as_quoted(others.min(), 3.6, 1, "the shortest lag over the other sets [s]")
    _as_quoted(others.max(), 5.0, 1, "the longest lag over the other sets [s]")
    # "4 to 5 s in nearly all falls": 2 of these 360 outside; the science review found about 10 of 400 fresh falls
    # outside (3.6-5.1 s), so the check asks for at most 5% outside, here and over the 2000 fresh falls.
    for lags, what in ((others, "the other sets"), (_lags(_many_falls()), "2000 fresh falls")):
        outside = np.mean((lags < 4.0 - 1e-9) | (lags > 5.0 + 1e-9))
        assert outside <= 0.05, f"over {what} the lag is outside 4-5 s in {outside:.1%} of the falls"


# ---------------------------------------------------------------------------------------------
# The negative drag coefficient (part 11)
# ---------------------------------------------------------------------------------------------
@claim("reentry-srekf/prior-mass-below-zero")
def _() -> None:
    """The prior N(0.0005, 0.001^2) of c puts 0.30-0.32 of its mass below zero (about a third)."""
    mass = norm.cdf(0.0, starship.MU0[2], starship.S0[2, 2])
    assert 0.30 <= mass <= 0.32, f"the prior mass below zero is {mass:.3f}"


@claim("reentry-srekf/c-estimate-negative")
def _() -> None:
    """Shipped fall: the c estimate is negative at 5-7 steps, all within t = 2.5-3.5 s, lowest -2.0e-4 to -2.4e-4 m^2/kg."""
    data, result, _ = _shipped()
    negative = result.mu[:, 2] < 0
    times = data.t[negative]
    assert 5 <= negative.sum() <= 7, f"the c estimate is negative at {negative.sum()} steps"
    assert 2.5 <= times[0] and times[-1] <= 3.5, f"negative from t = {times[0]} to {times[-1]} s"
    assert -2.4e-4 <= result.mu[:, 2].min() <= -2.0e-4, f"the lowest estimate is {result.mu[:, 2].min():.3g}"


@claim("reentry-srekf/c-negative-velocity-correlation")
def _() -> None:
    """Shipped fall: corr(v, c) is 0.75-0.8 at t = 2 s and 0.92-0.96 at 3 s; with the true v0 (and h0) c still goes negative."""
    data, result, _ = _shipped()
    for time, low, high in ((2.0, 0.75, 0.80), (3.0, 0.92, 0.96)):
        k = int(np.argmin(np.abs(data.t - time)))
        P = result.S[k].T @ result.S[k]
        correlation = P[1, 2] / np.sqrt(P[1, 1] * P[2, 2])
        assert low <= correlation <= high, f"corr(v, c) at t = {time:g} s is {correlation:.2f}"
    for mu0 in (np.array([starship.MU0[0], data.v[0], starship.MU0[2]]), np.array([data.h[0], data.v[0], starship.MU0[2]])):
        run = starship.run_square_root_ekf(data, ref.ballistic_dynamics, ref.ballistic_jacobian, ref.radar_predict,
                                           ref.radar_jacobian, ref.sqrt_time_update, ref.sqrt_measurement_update, mu0=mu0)
        assert np.any(run.mu[:, 2] < 0), f"from mu0 = {mu0} the c estimate never goes negative"


@claim("reentry-srekf/c-negative-over-falls")
def _() -> None:
    """In about a quarter to a third of the simulated falls (10-50% of 40) the c estimate goes negative at some step."""
    falls = _falls()
    negative = np.any(falls.mu[:, :, 2] < 0, axis=1)
    # measured 0.25 (seeds 7100-7139) and 0.35 (500-539); with a rate of 0.3, 40 falls give a rate
    # outside 0.10-0.50 with probability about 0.005 (binomial, standard deviation 0.072)
    rate = rate_at_least(negative, 0.10, "the c estimate negative at some step of a fall")
    assert rate <= 0.50, f"the c estimate goes negative in {rate:.0%} of the falls"
