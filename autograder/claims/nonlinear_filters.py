"""Checks of the results the nonlinear-filters notebook states.

The 400-run table with the particle filter is the shipped file, which ``python -m autograder
data --check`` (and tests/test_release.py) rebuilds bit for bit from the reference, so checking it
checks the reference. The particle filter is too slow to rerun here; the Gaussian filters are
rerun on independent batches, and claims about them must hold at the stated rate there too.
"""

from __future__ import annotations

import functools

import numpy as np

import solutions.nonlinear_filters as ref
from autograder.claims import claim, rate_at_least
from course import air_traffic, cut

GAUSSIAN = ("ekf", "ckf", "ukf", "cut4", "cut6", "cut8")
BATCHES = 6
BATCH_RUNS = 50


@functools.cache
def _shipped() -> air_traffic.ShippedResults:
    return air_traffic.load()


@functools.cache
def _batches() -> list[dict]:
    """Summaries of the Gaussian filters on BATCHES independent batches of BATCH_RUNS runs (seeds 1..BATCHES)."""
    return [{name: air_traffic.summarise(e) for name, e in ref.monte_carlo(BATCH_RUNS, seed, filters=GAUSSIAN).items()}
            for seed in range(1, BATCHES + 1)]


def _lost_fraction_pooled(name: str) -> float:
    return sum(b[name]["lost_runs"] for b in _batches()) / (BATCHES * BATCH_RUNS)


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


@claim("nonlinear-filters/cut8-best-gaussian")
def _() -> None:
    """CUT8 has the smallest position and velocity metric of the Gaussian filters: in the 400-run table and in every one of 6 batches of 50 runs."""
    tables = [_shipped().table] + _batches()
    for quantity in ("position", "velocity"):
        outcomes = [min(GAUSSIAN, key=lambda name: t[name][quantity]) == "cut8" for t in tables]
        assert outcomes[0], f"shipped table: the best {quantity} is not CUT8"
        rate_at_least(outcomes[1:], 1.0, f"CUT8 best in {quantity} in a batch of {BATCH_RUNS} runs")


@claim("nonlinear-filters/position-ordering")
def _() -> None:
    """Position metric CUT8 < CUT6 < CUT4 < min(UKF, CKF), in the 400-run table and in at least 5 of 6 batches of 50 runs."""
    def ordered(t: dict) -> bool:
        p = {name: t[name]["position"] for name in GAUSSIAN}
        return p["cut8"] < p["cut6"] < p["cut4"] < min(p["ukf"], p["ckf"])

    assert ordered(_shipped().table), "shipped table: the position ordering does not hold"
    rate_at_least([ordered(b) for b in _batches()], 5 / 6, "CUT8 < CUT6 < CUT4 < UKF, CKF in a batch of 50 runs")


@claim("nonlinear-filters/lost-runs")
def _() -> None:
    """Lost runs: CKF and UKF 35-60%, CUT4 1-8%, CUT6 under 2%, CUT8 under 1%: in the 400-run table and pooled over 300 batch runs."""
    ranges = {"ckf": (0.35, 0.60), "ukf": (0.35, 0.60), "cut4": (0.01, 0.08), "cut6": (0.0, 0.02), "cut8": (0.0, 0.01)}
    shipped = _shipped()
    for name, (low, high) in ranges.items():
        fractions = [shipped.table[name]["lost_runs"] / shipped.runs, _lost_fraction_pooled(name)]
        assert all(low <= f <= high for f in fractions), f"{name}: lost fractions {fractions}, claimed {low}-{high}"


@claim("nonlinear-filters/ekf-loses-most")
def _() -> None:
    """The EKF loses more than three quarters of the runs, in the 400-run table and pooled over the batches."""
    fractions = [_shipped().table["ekf"]["lost_runs"] / _shipped().runs, _lost_fraction_pooled("ekf")]
    assert min(fractions) > 0.75, f"EKF lost fractions {fractions}"


@claim("nonlinear-filters/cut8-velocity-gap")
def _() -> None:
    """CUT8's velocity metric is below 50 m/s and over 30 times smaller than CUT6's, in the table and in every batch."""
    for t in [_shipped().table] + _batches():
        v8, v6 = t["cut8"]["velocity"], t["cut6"]["velocity"]
        assert v8 < 50 and 30 * v8 < v6, f"velocity metric CUT8 {v8:.1f} m/s, CUT6 {v6:.1f} m/s"


@claim("nonlinear-filters/cut-matches-lecture")
def _() -> None:
    """CUT6's and CUT8's position metrics are within 20% of the lecture's (138.82 m and 135.89 m), in the table and every batch."""
    for t in [_shipped().table] + _batches():
        for name in ("cut6", "cut8"):
            lecture = air_traffic.LECTURE_TABLE["position"][name]
            assert abs(t[name]["position"] / lecture - 1) < 0.2, f"{name}: {t[name]['position']:.1f} m vs {lecture} m"


# --- the particle filter: the shipped 400-run table only (rebuilt bit for bit by `autograder data --check`) ---


@claim("nonlinear-filters/pf-lost-fraction")
def _() -> None:
    """The 5000-particle PF loses between a fifth and a third of the 400 shipped runs."""
    fraction = _shipped().table["pf"]["lost_runs"] / _shipped().runs
    assert 0.2 <= fraction <= 1 / 3, f"PF lost fraction {fraction:.3f}"


@claim("nonlinear-filters/pf-mean-dominated")
def _() -> None:
    """The PF's mean position metric is more than ten times its median over runs (shipped table)."""
    pf = _shipped().table["pf"]
    assert pf["position"] > 10 * pf["median"]["position"], f"PF mean {pf['position']}, median {pf['median']['position']}"


@claim("nonlinear-filters/pf-best-velocity-when-kept")
def _() -> None:
    """Without its lost runs and in the median, the PF has the smallest velocity and turn-rate errors of all seven filters (shipped table)."""
    table = _shipped().table
    for summary in ("excluding_lost", "median"):
        for quantity in ("velocity", "turn_rate"):
            best = min(air_traffic.FILTERS, key=lambda name: table[name][summary][quantity])
            assert best == "pf", f"{summary} {quantity}: smallest is {best}"


@claim("nonlinear-filters/pf-median-position-behind-cuts")
def _() -> None:
    """The PF's median position error is larger than the medians of CUT4, CUT6 and CUT8 (shipped table)."""
    table = _shipped().table
    pf = table["pf"]["median"]["position"]
    assert all(pf > table[name]["median"]["position"] for name in ("cut4", "cut6", "cut8")), f"PF median {pf}"


@claim("nonlinear-filters/velocity-best-two")
def _() -> None:
    """The two smallest velocity metrics (over all runs) of the seven filters are CUT8's and the PF's (shipped table)."""
    table = _shipped().table
    best = sorted(air_traffic.FILTERS, key=lambda name: table[name]["velocity"])[:2]
    assert set(best) == {"cut8", "pf"}, f"smallest velocity metrics: {best}"


@claim("nonlinear-filters/pf-rises-before-turn")
def _() -> None:
    """From t = 25 s to 125 s the PF's position RMSE_k more than doubles; the CKF's, UKF's and CUTs' change by less than +10% (shipped curves)."""
    curves = _shipped().rmse_curves
    assert curves["pf"][25, 0] > 2 * curves["pf"][5, 0], "the PF's RMSE does not double before the turn"
    for name in ("ckf", "ukf", "cut4", "cut6", "cut8"):
        assert curves[name][25, 0] < 1.1 * curves[name][5, 0], f"{name}'s RMSE rises by 10% or more before the turn"


@claim("nonlinear-filters/ckf-ukf-lost-in-turn")
def _() -> None:
    """After the first turn starts (t >= 125 s), the CKF's and UKF's position RMSE_k exceed 3 times their value at t = 125 s (shipped curves)."""
    curves = _shipped().rmse_curves
    for name in ("ckf", "ukf"):
        assert curves[name][25:, 0].max() > 3 * curves[name][25, 0], name


@claim("nonlinear-filters/cut8-stays-below-400")
def _() -> None:
    """CUT8's position RMSE_k is below 400 m from t = 10 s on (shipped curves, 400 runs)."""
    assert _shipped().rmse_curves["cut8"][2:, 0].max() < 400


@claim("nonlinear-filters/cut8-best-every-interval")
def _() -> None:
    """In the shipped sweep over T (50 runs each), CUT8 has the smallest position metric of the seven filters at every T."""
    shipped = _shipped()
    for i, T in enumerate(shipped.sweep_T):
        best = min(air_traffic.FILTERS, key=lambda name: shipped.sweep[name][i, 0])
        assert best == "cut8", f"T = {T}: smallest position metric is {best}'s"


@claim("nonlinear-filters/errors-grow-with-interval")
def _() -> None:
    """Every filter's position metric but the EKF's (kilometres at every T) is larger at T = 20 s than at T = 5 s (shipped sweep)."""
    shipped = _shipped()
    first, last = list(shipped.sweep_T).index(5.0), list(shipped.sweep_T).index(20.0)
    assert shipped.sweep["ekf"][:, 0].min() > 1000, "the EKF's position metric"
    for name in air_traffic.FILTERS:
        if name != "ekf":
            assert shipped.sweep[name][last, 0] > shipped.sweep[name][first, 0], name


@claim("nonlinear-filters/orders-of-magnitude")
def _() -> None:
    """The seven filters' velocity metrics span more than two orders of magnitude (shipped table)."""
    v = [_shipped().table[name]["velocity"] for name in air_traffic.FILTERS]
    assert max(v) > 100 * min(v), f"velocity metrics {v}"


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


@claim("nonlinear-filters/pf-kept-near-lecture")
def _() -> None:
    """The PF without its lost runs is within a factor 2 of the lecture's PF row in position, velocity and turn rate (shipped table)."""
    kept = _shipped().table["pf"]["excluding_lost"]
    for quantity in air_traffic.QUANTITIES:
        ratio = kept[quantity] / air_traffic.LECTURE_TABLE[quantity]["pf"]
        assert 0.5 < ratio < 2, f"{quantity}: ours {kept[quantity]}, ratio {ratio:.2f}"


@claim("nonlinear-filters/initial-error-settles")
def _() -> None:
    """Every filter's position RMSE_k is 1.3-1.7 km at t = 0 and below 500 m at t = 10 s (shipped curves)."""
    for name, curve in _shipped().rmse_curves.items():
        assert 1300 < curve[0, 0] < 1700 and curve[2, 0] < 500, f"{name}: {curve[0, 0]:.0f} m, then {curve[2, 0]:.0f} m"
