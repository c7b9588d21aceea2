"""Checks of the claims that the reentry-srekf notebook makes.

Two kinds of claim. Those about the shipped fall (course/data/starship_reentry.csv) are
deterministic and are checked on that file. Those about the filter in general (the NEES, the
coverage of the bands, the lag of the altitude's uncertainty) are checked over simulated falls,
drawn with ``solutions.reentry_srekf.simulate_reentry`` from fixed seeds, as rates or ranges with
tolerances stated in each check.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.stats import norm

from autograder.claims import claim, rate_at_least
from course import starship
from course.starship import G, L, M, P0, R, RADAR_R2, T0
from solutions import reentry_srekf as ref

FALL_SEEDS = range(7100, 7140)
"""Seeds of the simulated falls (40 falls; one fall takes about 0.25 s to simulate and filter)."""


@functools.cache
def _shipped() -> tuple[starship.ReentryData, starship.FilterResult, np.ndarray]:
    """The shipped fall, the reference filter's run on it and the standard deviations, (N, 3)."""
    data = starship.load()
    result = ref.run_reference(data)
    return data, result, starship.marginal_std(result, ref.marginal)


@functools.cache
def _falls() -> dict[str, np.ndarray]:
    """Per simulated fall: NEES inside its 95% band (fraction of steps), mean NEES, every error inside
    its 3-sigma band at every step, and the lag [s] of the altitude's widest band after passing r2."""
    lower, upper = starship.nees_band()
    out: dict[str, list] = {"nees_inside": [], "nees_mean": [], "all_inside": [], "lag": []}
    for seed in FALL_SEEDS:
        t, truth, range_true, range_meas = ref.simulate_reentry(np.random.default_rng(seed))
        data = starship.ReentryData(path=f"simulated fall {seed}", n_lines=t.size + 1, t=t, h=truth[:, 0],
                                    v=truth[:, 1], c=truth[:, 2], range_true=range_true, range_meas=range_meas)
        result = ref.run_reference(data)
        std = np.sqrt(np.einsum("kij,kij->kj", result.S, result.S))
        nees = starship.normalised_estimation_error_squared(truth, result)
        out["nees_inside"].append(np.mean((nees >= lower) & (nees <= upper)))
        out["nees_mean"].append(nees.mean())
        out["all_inside"].append(bool(np.all(np.abs(truth - result.mu) <= 3 * std)))
        out["lag"].append(_widest_altitude_band_after_first_seconds(t, std) - _crossing_time(t, truth[:, 0]))
    return {key: np.array(value) for key, value in out.items()}


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
                                         np.logspace(2, -10, 49))


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
    """Covariance form: float32 wrong by >= 100% and not PD for every sigma <= 0.3-1 m; float64 from 1e-5-1e-4 m down, error growing before."""
    comparison = _first_update_comparison()
    error = {
        name: np.abs(getattr(comparison, name) - comparison.exact) / comparison.exact
        for name in ("covariance32", "covariance64")
    }
    for name, low, high in (("covariance32", 0.1, 1.0), ("covariance64", 1e-5, 1e-4)):
        broken = ~getattr(comparison, f"pd_{name}")
        assert broken.any(), f"the {name} form stays positive definite"
        threshold = comparison.sigma[broken].max()
        assert low <= threshold <= high, f"the {name} form breaks from sigma = {threshold:.3g} m"
        assert broken[comparison.sigma <= threshold].all(), f"the {name} form recovers below {threshold:.3g} m"
        if name == "covariance32":
            assert np.all(error[name][broken] >= 1.0 - 1e-6), "float32 breaks with an error below 100%"
    # float64: the error grows as the radar gets more precise (by over eight decades before breaking)
    working = comparison.pd_covariance64
    assert error["covariance64"][working][-1] > 1e8 * error["covariance64"][working][0], "float64's error does not grow"


@claim("reentry-srekf/square-root-form-holds")
def _() -> None:
    """The square-root update is within 1e-15 relative error of the exact variance and positive definite at every sigma."""
    comparison = _first_update_comparison()
    error = np.abs(comparison.square_root - comparison.exact) / comparison.exact
    assert comparison.pd_square_root.all(), "the square-root form loses positive definiteness"
    assert error.max() <= 1e-15, f"the square-root form's largest relative error is {error.max():.2g}"


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


@claim("reentry-srekf/nees-over-falls")
def _() -> None:
    """Over 40 falls: NEES inside its 95% band at 92-98% of steps on average, mean NEES 2.8-3.8, single falls from < 90% to >= 99%."""
    falls = _falls()
    # Spread, measured over 100 other falls (seeds 1000-1099): the fraction inside the band averaged
    # 0.954 with a standard deviation of 0.049 between falls, so the average of 40 falls has one of
    # about 0.008 (the band is over 3 of those either side of 0.95); the mean NEES averaged 2.98 with
    # a standard deviation of 1.14 between falls, so the average of 40 has one of about 0.18 (the band
    # reaches 3 of those above 3.1, the average over all 140 falls, with a heavy upper tail).
    average = falls["nees_inside"].mean()
    assert 0.92 <= average <= 0.98, f"the NEES is inside its band at {average:.1%} of the steps on average"
    mean_nees = falls["nees_mean"].mean()
    assert 2.8 <= mean_nees <= 3.8, f"the mean NEES over the falls is {mean_nees:.2f}"
    # 11 of the 100 falls had a fraction below 0.9 (none of 40 does so with probability 0.89^40 = 0.01)
    # and 16 a fraction of 1
    assert falls["nees_inside"].min() < 0.90 and falls["nees_inside"].max() >= 0.99, (
        f"single falls range from {falls['nees_inside'].min():.1%} to {falls['nees_inside'].max():.1%}"
    )


@claim("reentry-srekf/coverage-over-falls")
def _() -> None:
    """In about three falls in four (at least 60%, at most 95% of 40), every error stays inside its 3-sigma band."""
    falls = _falls()
    # over 100 other falls the rate was 0.81; with that rate, 40 falls give fewer than 24 (60%) with
    # probability 0.0005 and more than 38 (95%) with probability 0.002 (binomial)
    rate = rate_at_least(falls["all_inside"], 0.60, "every error inside its 3-sigma band throughout a fall")
    assert rate <= 0.95, f"every error stays inside its band in {rate:.0%} of the falls, more than about three in four"


# ---------------------------------------------------------------------------------------------
# Observability (part 10)
# ---------------------------------------------------------------------------------------------
@claim("reentry-srekf/sigma-h-peak-after-crossing")
def _() -> None:
    """Shipped fall: crossing at 33.9 s, sigma_h ~20 m at 30 s, widest (27-31 m) at 38-39 s; 4-5 s lag in every one of 40 falls."""
    data, _, std = _shipped()
    crossing = _crossing_time(data.t, data.h)
    widest = _widest_altitude_band_after_first_seconds(data.t, std)
    at_30 = int(np.argmin(np.abs(data.t - 30.0)))
    assert abs(crossing - 33.9) <= 0.05, f"the vehicle passes r2 at t = {crossing} s"
    assert 18.0 <= std[at_30, 0] <= 22.0, f"sigma_h at t = 30 s is {std[at_30, 0]:.1f} m"
    assert 38.0 <= widest <= 39.0, f"sigma_h is widest at t = {widest} s"
    peak = std[int(np.argmin(np.abs(data.t - widest))), 0]
    assert 27.0 <= peak <= 31.0, f"the widest sigma_h is {peak:.1f} m"
    lags = _falls()["lag"]
    # over 100 other falls the lag ranged from 4.2 to 5.0 s (one measurement interval is 0.1 s)
    assert np.all((lags >= 4.0 - 1e-9) & (lags <= 5.0 + 1e-9)), f"the lags range from {lags.min():.1f} to {lags.max():.1f} s"


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
