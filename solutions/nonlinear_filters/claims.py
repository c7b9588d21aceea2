"""Checks of the results the nonlinear-filters notebook states.

Every claim about the Monte Carlo comparison is checked on the shipped 400-run table (which
``python -m autograder data --check`` rebuilds bit for bit from the reference) AND on independent
batches: six batches of 50 runs of the Gaussian filters (seeds 1-6), three batches of 30 runs of all
seven filters with the particle filter (seeds 101-103), and one independent sweep over T with 20 runs
per interval (seeds 201-204). Claims that depend on the draw are checked as rates over the batches.
The claims about the cause of the CKF's and UKF's divergence run two changed set-ups: the flight
without its turns (STRAIGHT_RUNS runs, seed 301) and a ten times smaller turn-rate noise (SMALL_L2_RUNS
runs, seed 302; the EKF also on seed 304, and with L2 = 1e-5 on seeds 305-306); the particle-count claim runs
the PF with 20 000 particles at T = 20 s (MANY_PARTICLE_RUNS runs on each of MANY_PARTICLE_SEEDS).
"""

from __future__ import annotations

import functools

import numpy as np

import solutions.nonlinear_filters.reference as ref
from autograder.authoring.claims import claim, rate_at_least
from course import air_traffic, cut

GAUSSIAN = ("ekf", "ckf", "ukf", "cut4", "cut6", "cut8")
BATCHES, BATCH_RUNS = 6, 50
PF_SEEDS, PF_RUNS = (101, 102, 103), 30
SWEEP_SEED, SWEEP_RUNS = 201, 20
STRAIGHT_RUNS, SMALL_L2_RUNS, MANY_PARTICLES, MANY_PARTICLE_RUNS = 100, 50, 20_000, 16
MANY_PARTICLE_SEEDS = (303, 306)


@functools.cache
def _shipped() -> air_traffic.ShippedResults:
    return air_traffic.load()


def _summaries(err: dict) -> dict:
    """summarise() of each filter, plus the count of runs that diverged but were not lost."""
    return {name: {**air_traffic.summarise(e),
                   "diverged_not_lost": int(np.sum(air_traffic.diverged_runs(e) & ~air_traffic.lost_runs(e)))}
            for name, e in err.items()}


@functools.cache
def _batches() -> list[dict]:
    """Summaries of the Gaussian filters on BATCHES independent batches of BATCH_RUNS runs (seeds 1..BATCHES)."""
    return [_summaries(ref.monte_carlo(BATCH_RUNS, seed, filters=GAUSSIAN)) for seed in range(1, BATCHES + 1)]


@functools.cache
def _pf_batches() -> list[tuple[dict, dict]]:
    """(summaries, position RMSE_k curves) of all seven filters on batches of PF_RUNS runs (seeds PF_SEEDS)."""
    out = []
    for seed in PF_SEEDS:
        err = ref.monte_carlo(PF_RUNS, seed)
        out.append((_summaries(err), {name: air_traffic.rmse_over_time(e)[:, 0] for name, e in err.items()}))
    return out


@functools.cache
def _independent_sweep() -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The lecture metric (len(SWEEP_T), 3) and the lost and diverged fractions (len(SWEEP_T),) of each filter over
    SWEEP_RUNS fresh runs per interval."""
    sweep, lost, diverged = ({name: [] for name in air_traffic.FILTERS} for _ in range(3))
    for i, T in enumerate(ref.SWEEP_T):
        for name, e in ref.monte_carlo(SWEEP_RUNS, SWEEP_SEED + i, T=T).items():
            sweep[name].append(air_traffic.lecture_metric(e))
            lost[name].append(np.mean(air_traffic.lost_runs(e)))
            diverged[name].append(np.mean(air_traffic.diverged_runs(e)))
    return tuple({name: np.array(v) for name, v in d.items()} for d in (sweep, lost, diverged))


def _all_tables() -> list[dict]:
    """The shipped table, then the six Gaussian batches, then the three batches with the PF."""
    return [_shipped().table] + _batches() + [s for s, _ in _pf_batches()]


def _pf_tables() -> list[dict]:
    """The shipped table, then the three batches with the PF."""
    return [_shipped().table] + [s for s, _ in _pf_batches()]


def _curves() -> list[dict]:
    """Position RMSE_k curves: the shipped 400-run ones, then the three batches with the PF."""
    return [{name: c[:, 0] for name, c in _shipped().rmse_curves.items()}] + [c for _, c in _pf_batches()]


def _batch_tables(name: str) -> list[tuple[dict, int]]:
    """(summaries, runs) of every independent batch that ran this filter."""
    return [(t, BATCH_RUNS) for t in _batches() if name in t] + [(t, PF_RUNS) for t, _ in _pf_batches()]


def _fraction(name: str, key: str = "lost_runs") -> tuple[float, float]:
    """A count (lost_runs, diverged_runs) of a filter as a fraction of the runs: in the shipped table, and pooled
    over every independent batch that ran the filter."""
    batches = _batch_tables(name)
    pooled = sum(t[name][key] for t, _ in batches) / sum(runs for _, runs in batches)
    return _shipped().table[name][key] / _shipped().runs, pooled


def _lost_fraction(name: str) -> tuple[float, float]:
    return _fraction(name, "lost_runs")


def _sweeps() -> list[tuple[str, np.ndarray, dict]]:
    shipped = _shipped()
    return [("shipped sweep", shipped.sweep_T, shipped.sweep), ("independent sweep", np.array(ref.SWEEP_T),
                                                                 _independent_sweep()[0])]


@claim("nonlinear-filters/exactness-degrees")
def _() -> None:
    """CKF and UKF are exact to degree 3, CUT4 to 5, CUT6 to 7, CUT8 to 9 (moment errors < 1e-9, then > 1)."""
    rules = {"CKF": (ref.cubature_points(5), 3), "UKF": (ref.unscented_points(5, 1.0), 3), "CUT4": (ref.cut4_points(5), 5),
             "CUT6": (cut.cut6_points(), 7), "CUT8": (cut.cut8_points(), 9)}
    for name, ((Z, w), degree) in rules.items():
        errors = [ref.moment_error(Z, w, d) for d in range(1, degree + 2)]
        assert max(errors[:-1]) < 1e-9 and errors[-1] > 1.0, f"{name}: moment errors by degree {np.round(errors, 12)}"


@claim("nonlinear-filters/degree-four-errors")
def _() -> None:
    """The CKF's largest degree-4 moment error is 2 and the UKF's is 3 (n = 5, kappa = 1)."""
    ckf = ref.moment_error(*ref.cubature_points(5), 4)
    ukf = ref.moment_error(*ref.unscented_points(5, 1.0), 4)
    assert np.isclose(ckf, 2.0) and np.isclose(ukf, 3.0), f"degree-4 errors: CKF {ckf}, UKF {ukf}"


@claim("nonlinear-filters/pf-best-all")
def _() -> None:
    """The PF has the smallest position, velocity and turn-rate metric of the seven filters: in the 400-run table and in each of the 3 batches of 30 runs."""
    for i, t in enumerate(_pf_tables()):
        for quantity in air_traffic.QUANTITIES:
            best = min(air_traffic.FILTERS, key=lambda name: t[name][quantity])
            assert best == "pf", f"table {i} (0 = shipped): the smallest {quantity} metric is {best}'s"


@claim("nonlinear-filters/position-ordering")
def _() -> None:
    """Position metric CUT8 < CUT6 < CUT4 < min(UKF, CKF): in the 400-run table and in at least 7 of the 9 independent batches (8 of 9 seen)."""
    def ordered(t: dict) -> bool:
        p = {name: t[name]["position"] for name in GAUSSIAN}
        return p["cut8"] < p["cut6"] < p["cut4"] < min(p["ukf"], p["ckf"])

    tables = _all_tables()
    assert ordered(tables[0]), "shipped table: the position ordering does not hold"
    rate_at_least([ordered(t) for t in tables[1:]], 7 / 9, "CUT8 < CUT6 < CUT4 < UKF, CKF in a batch")


@claim("nonlinear-filters/cut8-best-gaussian")
def _() -> None:
    """Of the six Gaussian filters, CUT8 has the smallest velocity metric in the table and every batch, and the smallest position metric in the table and in at least 7 of 9 batches."""
    tables = _all_tables()
    for quantity, minimum in (("velocity", 1.0), ("position", 7 / 9)):
        outcomes = [min(GAUSSIAN, key=lambda name: t[name][quantity]) == "cut8" for t in tables]
        assert outcomes[0], f"shipped table: the best Gaussian {quantity} is not CUT8's"
        rate_at_least(outcomes[1:], minimum, f"CUT8 best Gaussian filter in {quantity} in a batch")


@claim("nonlinear-filters/pf-ahead-of-cut8")
def _() -> None:
    """The PF's position metric is 5-25% below CUT8's, its velocity metric below CUT8's and its turn-rate metric under half of CUT8's: in the table and each PF batch."""
    for i, t in enumerate(_pf_tables()):
        pf, c8 = t["pf"], t["cut8"]
        ratio = pf["position"] / c8["position"]
        assert 0.75 < ratio < 0.95, f"table {i}: PF/CUT8 position ratio {ratio:.3f}"
        assert pf["velocity"] < c8["velocity"] and pf["turn_rate"] < 0.5 * c8["turn_rate"], f"table {i}: {pf}, {c8}"


@claim("nonlinear-filters/pf-near-lecture")
def _() -> None:
    """The PF's position, velocity and turn-rate metrics are within 15% of the lecture's PF row (115.47 m, 24.16 m/s, 0.0393 rad/s): in the table and each PF batch."""
    for i, t in enumerate(_pf_tables()):
        for quantity in air_traffic.QUANTITIES:
            ratio = t["pf"][quantity] / air_traffic.LECTURE_TABLE[quantity]["pf"]
            assert abs(ratio - 1) < 0.15, f"table {i}: PF {quantity} {t['pf'][quantity]}, ratio {ratio:.3f}"


@claim("nonlinear-filters/pf-rarely-lost")
def _() -> None:
    """The PF loses under 2% of the runs at T = 5 s (about 1 in 200): in the 400-run table, and pooled over the 290
    independent runs at T = 5 s (the shipped sweep's 200 and the three batches' 90). With a true rate of 0.5%, 290
    runs show 6 or more lost (2%) with probability about 0.5%."""
    shipped = _shipped()
    i = list(shipped.sweep_T).index(5.0)
    lost = shipped.sweep_lost["pf"][i] * shipped.sweep_runs + sum(t["pf"]["lost_runs"] for t, _ in _pf_batches())
    runs = shipped.sweep_runs + PF_RUNS * len(PF_SEEDS)
    fractions = (shipped.table["pf"]["lost_runs"] / shipped.runs, lost / runs)
    assert runs >= 290 and max(fractions) < 0.02, f"PF lost fractions (shipped, pooled over {runs}) {fractions}"


@claim("nonlinear-filters/cut8-velocity-gap")
def _() -> None:
    """CUT8's velocity metric is below 50 m/s and over 10 times smaller than CUT6's, in the table and in every batch."""
    for i, t in enumerate(_all_tables()):
        v8, v6 = t["cut8"]["velocity"], t["cut6"]["velocity"]
        assert v8 < 50 and 10 * v8 < v6, f"table {i}: velocity metric CUT8 {v8:.1f} m/s, CUT6 {v6:.1f} m/s"


@claim("nonlinear-filters/cut-matches-lecture")
def _() -> None:
    """CUT6's and CUT8's position metrics are within 20% of the lecture's (138.82 m and 135.89 m), in the table and every batch."""
    for t in _all_tables():
        for name in ("cut6", "cut8"):
            lecture = air_traffic.LECTURE_TABLE["position"][name]
            assert abs(t[name]["position"] / lecture - 1) < 0.2, f"{name}: {t[name]['position']:.1f} m vs {lecture} m"


@claim("nonlinear-filters/lost-runs")
def _() -> None:
    """Lost runs: CKF 40-60%, UKF 30-50%, CUT4 1-8%, CUT6 under 2%, CUT8 under 1%: in the 400-run table and pooled over the 390 batch runs."""
    ranges = {"ckf": (0.40, 0.60), "ukf": (0.30, 0.50), "cut4": (0.01, 0.08), "cut6": (0.0, 0.02), "cut8": (0.0, 0.01)}
    for name, (low, high) in ranges.items():
        fractions = _lost_fraction(name)
        assert all(low <= f <= high for f in fractions), f"{name}: lost fractions {fractions}, claimed {low}-{high}"


@claim("nonlinear-filters/ekf-loses-most")
def _() -> None:
    """The EKF loses more than nine runs in ten, in the 400-run table and pooled over the batches."""
    fractions = _lost_fraction("ekf")
    assert min(fractions) > 0.9, f"EKF lost fractions {fractions}"


@claim("nonlinear-filters/velocity-best-two")
def _() -> None:
    """The two smallest velocity metrics of the seven filters are the PF's and CUT8's: in the table and each PF batch."""
    for i, t in enumerate(_pf_tables()):
        best = sorted(air_traffic.FILTERS, key=lambda name: t[name]["velocity"])[:2]
        assert best == ["pf", "cut8"], f"table {i}: smallest velocity metrics {best}"


@claim("nonlinear-filters/orders-of-magnitude")
def _() -> None:
    """The seven filters' velocity metrics span more than two orders of magnitude, in the table and every PF batch."""
    for t in _pf_tables():
        v = [t[name]["velocity"] for name in air_traffic.FILTERS]
        assert max(v) > 100 * min(v), f"velocity metrics {v}"


@claim("nonlinear-filters/initial-error-settles")
def _() -> None:
    """The expected initial position RMSE is sqrt(P0_xx + P0_yy) = sqrt(2) km; every filter's position RMSE_k is 1.3-1.7 km (1.5 km to 0.05) at t = 0 in the 400-run curves, and below 500 m at t = 10 s in those and in each PF batch."""
    assert np.isclose(np.sqrt(air_traffic.P0[0, 0] + air_traffic.P0[1, 1]), np.sqrt(2) * 1000.0)
    for name, curve in _curves()[0].items():
        assert 1300 < curve[0] < 1700 and abs(curve[0] - 1500) < 50, f"shipped curves, {name}: {curve[0]:.0f} m at t = 0"
    for i, curves in enumerate(_curves()):
        for name, curve in curves.items():
            assert curve[2] < 500, f"curves {i}, {name}: {curve[2]:.0f} m at t = 10 s"


@claim("nonlinear-filters/pf-below-cut8-after-75s")
def _() -> None:
    """From t = 75 s on, the PF's position RMSE_k is below CUT8's at more than 80% of the returns (shipped curves and each PF batch; 87% in the shipped curves, 99-100% in the batches)."""
    for i, curves in enumerate(_curves()):
        below = np.mean(curves["pf"][15:] < curves["cut8"][15:])
        assert below > 0.8, f"curves {i}: PF below CUT8 at {below:.0%} of the returns from t = 75 s"


@claim("nonlinear-filters/ckf-ukf-error-grows")
def _() -> None:
    """After t = 125 s, the CKF's and UKF's position RMSE_k exceed 3 times their value at t = 125 s (shipped curves and each PF batch)."""
    for i, curves in enumerate(_curves()):
        for name in ("ckf", "ukf"):
            assert curves[name][25:].max() > 3 * curves[name][25], f"curves {i}: {name}"


@claim("nonlinear-filters/turn-noise-size")
def _() -> None:
    """Q[4, 4] = T L2 = 0.05 (rad/s)^2 at T = 5 s: a turn-rate standard deviation of 0.22 rad/s (12.8 deg/s) per step, more than 4 times the sharpest true turn (3 deg/s); over a 5 s step, 1.1 rad of heading against the true turns' 0.26 rad."""
    sd = np.sqrt(air_traffic.ct_process_noise(5.0)[4, 4])
    sharpest = max(abs(rate) for _, rate in air_traffic.LEGS)
    assert np.isclose(sd, 0.2236, atol=1e-4) and np.isclose(sd / air_traffic.DEG, 12.8, atol=0.05), sd
    assert sd > 4 * sharpest, f"turn-rate noise sd {sd} rad/s, sharpest turn {sharpest} rad/s"
    assert np.isclose(5.0 * sd, 1.1, atol=0.05) and np.isclose(5.0 * sharpest, 0.26, atol=0.005), "angles per 5 s step"


@functools.cache
def _straight_run() -> tuple[dict, dict]:
    """(summaries, position RMSE_k curves) of CKF, UKF and CUT8 on the flight without turns (STRAIGHT_RUNS runs, seed 301)."""
    err = ref.monte_carlo(STRAIGHT_RUNS, 301, filters=("ckf", "ukf", "cut8"), legs=air_traffic.STRAIGHT_LEGS)
    return _summaries(err), {name: air_traffic.rmse_over_time(e)[:, 0] for name, e in err.items()}


def _straight() -> dict:
    return _straight_run()[0]


def _departure(curve: np.ndarray) -> float:
    """The first time (s, T = 5 s) from t = 125 s at which a position RMSE_k curve exceeds 1.5 times its value at 125 s."""
    return 5.0 * (25 + int(np.argmax(curve[25:] > 1.5 * curve[25])))


def _closest_approach(legs: tuple) -> tuple[float, float]:
    """(time s, range m) of the sample (T = 5 s) at which the true flight is closest to the radar."""
    truth = air_traffic.scenario(5.0, legs).truth
    r = np.hypot(truth[:, 0], truth[:, 1])
    return 5.0 * int(np.argmin(r)), float(r.min())


@claim("nonlinear-filters/closest-approach")
def _() -> None:
    """The flight passes closest to the radar at t = 240 s (3.1 km, inside the first turn), the flight without turns at
    t = 210 s (10 km); on both, the bearing changes fastest within 5 s of that sample."""
    for legs, (t, r) in ((air_traffic.LEGS, (240.0, 3127.0)), (air_traffic.STRAIGHT_LEGS, (210.0, 10002.0))):
        found = _closest_approach(legs)
        assert found[0] == t and abs(found[1] - r) < 1.0, f"closest approach {found}"
        truth = air_traffic.scenario(5.0, legs).truth
        rate = np.abs(air_traffic.wrap_angle(np.diff(np.arctan2(truth[:, 1], truth[:, 0]))))
        fastest = 5.0 * int(np.argmax(rate))
        assert t - 5.0 <= fastest <= t, f"fastest bearing change in the step starting at {fastest} s, closest at {t} s"


@claim("nonlinear-filters/straight-curves-depart")
def _() -> None:
    """With and without the turns, the CKF's and UKF's position RMSE_k first exceed 1.5 times their value at t = 125 s
    at 190-220 s in the shipped curves (400 runs each; seen 195-215 s), and at 160-250 s in the 100 straight-flight
    runs of seed 301 and the three 30-run PF batches (seen 170-230 s); and all later grow past 3 times it."""
    shipped = _shipped()
    sets = [("shipped, turns", {n: c[:, 0] for n, c in shipped.rmse_curves.items()}, 190.0, 220.0),
            ("shipped, no turns", shipped.straight_position_rmse, 190.0, 220.0),
            ("seed 301, no turns", _straight_run()[1], 160.0, 250.0)]
    sets += [(f"PF batch {i}, turns", c, 160.0, 250.0) for i, (_, c) in enumerate(_pf_batches())]
    for what, curves, earliest, latest in sets:
        for name in ("ckf", "ukf"):
            curve = curves[name]
            assert earliest <= _departure(curve) <= latest, f"{what}, {name}: departs at {_departure(curve)} s"
            assert curve[25:].max() > 3 * curve[25], f"{what}, {name}: grows to {curve[25:].max() / curve[25]:.1f} times"


@claim("nonlinear-filters/sweep-cut8-diverges-least")
def _() -> None:
    """At every interval T, CUT8 diverges in no more runs than any other Gaussian filter, and in under 10% of them:
    in the shipped sweep (200 runs per T; seen 0-5%) and in the independent one (20 runs per T)."""
    shipped = _shipped()
    for what, diverged in (("shipped sweep", shipped.sweep_diverged), ("independent sweep", _independent_sweep()[2])):
        others = np.min([diverged[name] for name in GAUSSIAN[:-1]], axis=0)
        assert np.all(diverged["cut8"] <= others) and np.all(diverged["cut8"] < 0.1), \
            f"{what}: CUT8 diverged {diverged['cut8']}, fewest of the others {others}"


@functools.cache
def _small_turn_noise() -> dict:
    """Summaries of the six Gaussian filters with L2 = 1e-3 (SMALL_L2_RUNS runs, seed 302)."""
    return _summaries(ref.monte_carlo(SMALL_L2_RUNS, 302, filters=GAUSSIAN, turn_noise=1e-3))


@claim("nonlinear-filters/straight-flight-still-lost")
def _() -> None:
    """With the turns removed (495 s straight), the CKF still loses 25-50% of the runs and the UKF 15-45%, and the CKF diverges in more than half, the UKF in more than 40% (100 runs, seed 301: lost 32% and 19%, diverged 63% and 46%; on seeds 931-933 lost 34-42% and 25-30%, diverged 70-74% and 56-60%; binomial sd about 5%)."""
    t = _straight()
    for name, (low, high, diverging) in {"ckf": (0.25, 0.50, 0.5), "ukf": (0.15, 0.45, 0.4)}.items():
        lost, diverged = t[name]["lost_runs"] / STRAIGHT_RUNS, t[name]["diverged_runs"] / STRAIGHT_RUNS
        assert low <= lost <= high and diverged > diverging, f"straight flight, {name}: lost {lost:.0%}, diverged {diverged:.0%}"


@claim("nonlinear-filters/small-turn-noise-no-loss")
def _() -> None:
    """With L2 ten times smaller (1e-3), no sigma-point filter loses or diverges in any of 50 runs, and their position metrics are within 1.5% of each other."""
    t = {name: row for name, row in _small_turn_noise().items() if name != "ekf"}
    for name, row in t.items():
        assert row["lost_runs"] == 0 and row["diverged_runs"] == 0, f"L2 = 1e-3, {name}: {row['lost_runs']} lost, {row['diverged_runs']} diverged"
    positions = [row["position"] for row in t.values()]
    assert max(positions) < 1.015 * min(positions), f"L2 = 1e-3: position metrics {positions}"


@claim("nonlinear-filters/ekf-small-turn-noise")
def _() -> None:
    """At L2 = 1e-3 the EKF still loses 60-90% of the runs while the CKF loses none, in each of two batches of 50 runs
    (seed 302 with all five sigma-point filters, seed 304 with the CKF; seen: 37 and 42 of 50 lost, 74% and 84%); with
    L2 = 1e-5 it loses none of 50 runs on seeds 305 and 306. Pooled over these and the review's batch (117 of 150),
    the EKF's lost rate at L2 = 1e-3 is about 78%; 50 runs then fall outside 30-45 lost with probability about 1%."""
    batches = [_small_turn_noise(), _summaries(ref.monte_carlo(SMALL_L2_RUNS, 304, filters=("ekf", "ckf"), turn_noise=1e-3))]
    for seed, t in zip((302, 304), batches):
        lost = t["ekf"]["lost_runs"] / SMALL_L2_RUNS
        assert 0.6 <= lost <= 0.9 and t["ckf"]["lost_runs"] == 0, f"L2 = 1e-3, seed {seed}: EKF lost {lost:.0%}, CKF {t['ckf']}"
    for seed in (305, 306):
        lost = air_traffic.lost_runs(ref.monte_carlo(SMALL_L2_RUNS, seed, filters=("ekf",), turn_noise=1e-5)["ekf"])
        assert not lost.any(), f"L2 = 1e-5, seed {seed}: the EKF loses {lost.sum()} of {SMALL_L2_RUNS} runs"


@claim("nonlinear-filters/diverged-runs")
def _() -> None:
    """Runs whose velocity error ever exceeds 1 km/s: CKF 65-90%, UKF 50-75%, CUT4 and CUT6 3-12%, CUT8 none of the 400 (under 0.5% pooled): in the table and pooled over the 390 batch runs."""
    ranges = {"ckf": (0.65, 0.90), "ukf": (0.50, 0.75), "cut4": (0.03, 0.12), "cut6": (0.03, 0.12), "cut8": (0.0, 0.005)}
    for name, (low, high) in ranges.items():
        fractions = _fraction(name, "diverged_runs")
        assert all(low <= f <= high for f in fractions), f"{name}: diverged fractions {fractions}, claimed {low}-{high}"
    assert _shipped().table["cut8"]["diverged_runs"] == 0, "CUT8 diverges in the shipped table"


@claim("nonlinear-filters/diverged-but-pinned")
def _() -> None:
    """CUT4 and CUT6 diverge in at least twice as many runs as they lose, in the 400-run table and pooled over the 390
    batch runs (a single batch of 50 need not show it), and most of their diverged runs end with the position within
    1 km, pooled over the 390 batch runs."""
    for name in ("cut4", "cut6"):
        diverged, lost = _fraction(name, "diverged_runs"), _fraction(name, "lost_runs")
        assert all(d >= 2 * l for d, l in zip(diverged, lost)), f"{name}: diverged {diverged}, lost {lost}"
        batches = _batch_tables(name)
        pinned = sum(t[name]["diverged_not_lost"] for t, _ in batches) / sum(t[name]["diverged_runs"] for t, _ in batches)
        assert pinned > 0.5, f"{name}: {pinned:.0%} of the diverged batch runs end within 1 km"


@claim("nonlinear-filters/velocity-without-diverged")
def _() -> None:
    """Without their diverged runs, CUT4's and CUT6's velocity metrics are below 50 m/s, less than 1.5 times CUT8's: in the table and every batch (seen: 42-47 m/s against CUT8's 34-36)."""
    for i, t in enumerate(_all_tables()):
        v8 = t["cut8"]["excluding_diverged"]["velocity"]
        for name in ("cut4", "cut6"):
            v = t[name]["excluding_diverged"]["velocity"]
            assert v < 50 and v < 1.5 * v8, f"table {i}: {name} {v:.1f} m/s without diverged runs, CUT8 {v8:.1f} m/s"


@claim("nonlinear-filters/lost-criterion-misses-divergence")
def _() -> None:
    """CUT4's and CUT6's velocity metrics without their lost runs exceed 10 times those without their diverged runs: in the 400-run table."""
    t = _shipped().table
    for name in ("cut4", "cut6"):
        without_lost, without_diverged = (t[name][k]["velocity"] for k in ("excluding_lost", "excluding_diverged"))
        assert without_lost > 10 * without_diverged, f"{name}: {without_lost:.0f} vs {without_diverged:.0f} m/s"


@claim("nonlinear-filters/ukf-ahead-of-ckf")
def _() -> None:
    """The UKF loses fewer runs than the CKF: in the table, pooled over the batches, and in at least 7 of the 9 batches."""
    shipped, pooled = zip(*(_fraction(name) for name in ("ukf", "ckf")))
    assert shipped[0] < shipped[1] and pooled[0] < pooled[1], f"lost UKF vs CKF: shipped {shipped}, pooled {pooled}"
    tables = _batches() + [s for s, _ in _pf_batches()]
    rate_at_least([t["ukf"]["lost_runs"] < t["ckf"]["lost_runs"] for t in tables], 7 / 9, "UKF loses fewer than CKF")


@claim("nonlinear-filters/pf-best-at-five-seconds")
def _() -> None:
    """At T = 5 s the PF has the smallest position metric of the seven filters, in the shipped sweep and an independent one."""
    for what, T, sweep in _sweeps():
        i = list(T).index(5.0)
        best = min(air_traffic.FILTERS, key=lambda name: sweep[name][i, 0])
        assert best == "pf", f"{what}, T = 5 s: smallest position metric is {best}'s"


@claim("nonlinear-filters/pf-falls-behind")
def _() -> None:
    """At T = 15 s CUT8 has the smallest position metric of the seven filters, and at T = 15 s and 20 s the PF's is more than 3 times CUT8's (shipped and independent sweep)."""
    for what, T, sweep in _sweeps():
        i15, i20 = list(T).index(15.0), list(T).index(20.0)
        best = min(air_traffic.FILTERS, key=lambda name: sweep[name][i15, 0])
        assert best == "cut8", f"{what}, T = 15 s: smallest position metric is {best}'s"
        for i in (i15, i20):
            assert sweep["pf"][i, 0] > 3 * sweep["cut8"][i, 0], f"{what}, T = {T[i]}: PF {sweep['pf'][i, 0]:.0f} m"


@claim("nonlinear-filters/errors-grow-with-interval")
def _() -> None:
    """Every filter's position metric is larger at T = 20 s than at T = 5 s (shipped and independent sweep)."""
    for what, T, sweep in _sweeps():
        first, last = list(T).index(5.0), list(T).index(20.0)
        for name in air_traffic.FILTERS:
            assert sweep[name][last, 0] > sweep[name][first, 0], f"{what}: {name}"


@claim("nonlinear-filters/cut-matches-published")
def _() -> None:
    """Every radius and weight of the solved CUT6 and CUT8 is one the authors' MATLAB prints (CUTpoints, n = 5), to 1e-8."""
    published = {
        "cut6": [(2.121320343559643, 0.03292181069958846), (1.1338934190276817 * np.sqrt(5), 0.014703360768175577),
                 (3.0 * np.sqrt(2), 0.000685871056241427)],
        "cut8": [(1 / np.sqrt(0.1866956121576737), 0.010529034221546607), (np.sqrt(5 / 1.420294749459945), 0.015144019639537572),
                 (np.sqrt(2 / 0.29836021128926843), 0.0052828996967816825), (np.sqrt(5 / 0.5123685659872401), 0.0010671298950159158),
                 (2 * np.sqrt(3), 0.0006510416666666666), (np.sqrt(13 / 0.8065591548429262), 0.00013776017592074394)],
    }
    for name, pairs in published.items():
        Z, w = getattr(cut, f"{name}_points")()
        radius = np.linalg.norm(Z, axis=1)
        for r, weight in pairs:
            at = np.isclose(radius, r, rtol=1e-8)
            assert at.any() and np.allclose(w[at], weight, rtol=1e-8), f"{name}: radius {r}, weight {weight}"
        assert np.all(np.isclose(radius[1:, None], [r for r, _ in pairs], rtol=1e-8).any(axis=1)), f"{name}: extra radii"


@claim("nonlinear-filters/pf-lost-at-long-intervals")
def _() -> None:
    """At T = 20 s the PF loses more than 80% of the runs and its velocity metric is above that of estimating zero velocity (120/sqrt(5) = 53.7 m/s): shipped and independent sweep."""
    shipped = _shipped()
    metric, lost, _ = _independent_sweep()
    for what, T, sweep, lost_fraction in (("shipped sweep", shipped.sweep_T, shipped.sweep, shipped.sweep_lost),
                                          ("independent sweep", np.array(ref.SWEEP_T), metric, lost)):
        i = list(T).index(20.0)
        assert lost_fraction["pf"][i] > 0.8, f"{what}: PF lost fraction at T = 20 s {lost_fraction['pf'][i]:.2f}"
        assert sweep["pf"][i, 1] > air_traffic.ZERO_VELOCITY_METRIC, f"{what}: PF velocity {sweep['pf'][i, 1]:.1f} m/s"


@functools.cache
def _many_particles() -> list[int]:
    """The PF's lost runs at T = 20 s with MANY_PARTICLES particles, out of MANY_PARTICLE_RUNS, on each of MANY_PARTICLE_SEEDS."""
    return [int(np.sum(air_traffic.lost_runs(ref.monte_carlo(MANY_PARTICLE_RUNS, seed, T=20.0, particles=MANY_PARTICLES,
                                                               filters=("pf",))["pf"])))
            for seed in MANY_PARTICLE_SEEDS]


@claim("nonlinear-filters/more-particles-help")
def _() -> None:
    """At T = 20 s, 20 000 particles lose about half of the runs (25-75%, pooled over two seeds of 16 runs; seen: 10
    and 6 of 16, and 8 of 16 on seed 307), where 5000 lose over 85% of the shipped sweep's 200. With a true rate of
    50%, 32 runs fall outside 8-24 lost with probability about 0.2%."""
    shipped = _shipped()
    few = shipped.sweep_lost["pf"][list(shipped.sweep_T).index(20.0)]
    lost = _many_particles()
    many = sum(lost) / (MANY_PARTICLE_RUNS * len(MANY_PARTICLE_SEEDS))
    assert few > 0.85 and 0.25 <= many <= 0.75, f"PF lost at T = 20 s: {few:.0%} with {shipped.particles}, {lost} of {MANY_PARTICLE_RUNS} with 20 000"
