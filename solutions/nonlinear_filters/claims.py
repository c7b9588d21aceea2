"""Checks of the results the nonlinear-filters notebook states.

Filters are ranked by the median over runs of each run's own metric (the lecture's metric of one run), the
same statistic for every filter, in the text, the tables and here. Every ranking claim that involves the
particle filter is checked twice: on the runs as they are, and with one lost run added to the particle
filter's runs (LOST_RUN_KM: an 11 km time-RMS position error), so that it holds whichever way such a run
falls. The study below saw one such catastrophe in 4000 runs (exact 95% interval 0.0006-0.14%), so one in the
400-run table is a conservative case, kept as a check. The lost-run study (4000 runs of every filter at
T = 5 s in 40 batches of 100, seeds LOST_STUDY_SEED + b, shipped as a record: solutions/records/
nonlinear_filters_lost_runs.records.npz, rebuilt in part by tests/test_nonlinear_filters_reference.py) gives
the particle filter's lost-run rate and the independent batches of the ranking claims.

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
import scipy.stats

import solutions.nonlinear_filters.reference as ref
from autograder.authoring.claims import claim, rate_at_least
from autograder.release import data
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


LOST_RUN_KM = 11.0
"""The injected lost run: a time-RMS position error of 11 km (and 11 km at the last return; a lecture metric of
11/sqrt(5) = 4.9 km), a time-RMS velocity error of 1 km/s and a turn-rate error of 1 rad/s: the size of a
catastrophe (the study's was 16.8 km). One such run in 400 is about ten times the study's rate of one in 4000,
and above its 95% upper bound (0.14%): a conservative check, not an estimate."""
STUDY_BATCHES = ref.LOST_STUDY_BATCHES


def _lost_run() -> dict[str, np.ndarray]:
    """The per-run summary (reference.per_run_summary's keys) of LOST_RUN_KM's run, for one run."""
    rms = np.array([1000.0 * LOST_RUN_KM, 1000.0, 1.0])
    return {"metric": rms[None, :] / np.sqrt(5.0), "time_rms_position": rms[:1], "final_position": rms[:1],
            "peak_velocity": np.array([1000.0])}


def _summary(runs: dict[str, np.ndarray]) -> dict:
    """What the claims read of a filter, from its per-run summary: the lecture's metric (a mean), the median,
    the metric without the lost runs, and the counts of lost and diverged runs."""
    metric = runs["metric"]
    lost = runs["final_position"] > 1000.0 * air_traffic.LOST_KM
    diverged = runs["peak_velocity"] > 1000.0 * air_traffic.DIVERGED_KMS

    def named(values):
        return {q: float(v) for q, v in zip(air_traffic.QUANTITIES, values)}

    return {**named(np.sqrt(np.mean(metric**2, axis=0))), "median": named(np.median(metric, axis=0)),
            "excluding_lost": named(np.sqrt(np.mean(metric[~lost] ** 2, axis=0)) if np.any(~lost) else np.full(3, np.nan)),
            "lost_runs": int(lost.sum()), "diverged_runs": int(diverged.sum()), "runs": len(metric)}


def _with_lost_run(runs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """A filter's per-run summary with the lost run added."""
    return {key: np.concatenate([value, _lost_run()[key]]) for key, value in runs.items()}


@functools.cache
def _study() -> dict[str, np.ndarray]:
    """The lost-run study's record: per-run summaries of every filter (``<filter>/<quantity>``) and seeds."""
    with np.load(data.RECORDS_DIR / ref.LOST_STUDY_FILE) as archive:
        return {name: archive[name] for name in archive.files}


def _study_runs(name: str, rows: slice = slice(None)) -> dict[str, np.ndarray]:
    """One filter's per-run summary in the study (the rows given: all 4000 by default)."""
    return {key: _study()[f"{name}/{key}"][rows] for key in ("metric", "time_rms_position", "final_position",
                                                             "peak_velocity")}


def _tables(inject: bool) -> list[dict]:
    """Summaries of every filter: the shipped 400-run table (the PF from its shipped per-run errors), then the
    study's 40 batches of 100 runs; with ``inject``, the PF has the lost run added in each."""
    def pf(runs):
        return _summary(_with_lost_run(runs) if inject else runs)

    table_runs = ref.per_run_summary(_pf_errors()["table"])
    shipped = {**{name: {**row, "runs": _shipped().runs} for name, row in _shipped().table.items()},
               "pf": pf(table_runs)}
    batches = []
    for b in range(STUDY_BATCHES):
        rows = slice(b * ref.LOST_STUDY_RUNS, (b + 1) * ref.LOST_STUDY_RUNS)
        batches.append({name: pf(_study_runs(name, rows)) if name == "pf" else _summary(_study_runs(name, rows))
                        for name in air_traffic.FILTERS})
    return [shipped] + batches


@functools.cache
def _pooled(inject: bool) -> dict:
    """Summaries of every filter over the study's 4000 runs (the PF with the lost run added if ``inject``)."""
    return {name: _summary(_with_lost_run(_study_runs(name)) if inject and name == "pf" else _study_runs(name))
            for name in air_traffic.FILTERS}


@functools.cache
def _pf_errors() -> dict[str, np.ndarray]:
    """The PF's shipped errors (runs, K, 3) of each batch of the shipped results."""
    with np.load(data.RECORDS_DIR / ref.PF_ERRORS_FILE) as archive:
        return {name: archive[name] for name in archive.files}


def _ranking_holds(check, minimum: float = 1.0) -> None:
    """Run ``check(table) -> str | None`` (None: the ranking holds, else why not) on the shipped table and the
    pooled study (both must hold), and on the study's batches (at least ``minimum`` of them), each without and
    with the lost run added to the PF's runs."""
    for inject in (False, True):
        tables = _tables(inject)
        what = "with one lost PF run added" if inject else "as run"
        for label, t in (("shipped table", tables[0]), ("4000 study runs", _pooled(inject))):
            problem = check(t)
            assert problem is None, f"{label}, {what}: {problem}"
        rate_at_least([check(t) is None for t in tables[1:]], minimum, f"the ranking in a study batch, {what}")


def _clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """The exact (Clopper-Pearson) interval of a binomial rate, k of n."""
    a = (1 - level) / 2
    low = scipy.stats.beta.ppf(a, k, n - k + 1) if k > 0 else 0.0
    high = scipy.stats.beta.ppf(1 - a, k + 1, n - k) if k < n else 1.0
    return float(low), float(high)


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
def _independent_sweep() -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], dict[str, np.ndarray], dict[str, np.ndarray],
                                  list[dict[str, np.ndarray]]]:
    """The lecture metric and the median of each run's metric (len(SWEEP_T), 3), the lost and diverged fractions
    (len(SWEEP_T),) of each filter over SWEEP_RUNS fresh runs per interval, and the PF's per-run summary at each T."""
    sweep, median, lost, diverged = ({name: [] for name in air_traffic.FILTERS} for _ in range(4))
    pf_runs = []
    for i, T in enumerate(ref.SWEEP_T):
        for name, e in ref.monte_carlo(SWEEP_RUNS, SWEEP_SEED + i, T=T).items():
            sweep[name].append(air_traffic.lecture_metric(e))
            median[name].append(np.median(air_traffic.lecture_metric(e, axis=1), axis=0))
            lost[name].append(np.mean(air_traffic.lost_runs(e)))
            diverged[name].append(np.mean(air_traffic.diverged_runs(e)))
            if name == "pf":
                pf_runs.append(ref.per_run_summary(e))
    return (*({name: np.array(v) for name, v in d.items()} for d in (sweep, median, lost, diverged)), pf_runs)


def _median_sweeps(inject: bool) -> list[tuple[str, np.ndarray, dict]]:
    """(name, T, median (len(T), 3) per filter) of the shipped sweep (the PF's from its shipped errors) and of the
    independent one; with ``inject``, one lost run added to the PF's runs at every T."""
    def pf_medians(per_T: list[dict[str, np.ndarray]]) -> np.ndarray:
        return np.array([np.median((_with_lost_run(r) if inject else r)["metric"], axis=0) for r in per_T])

    shipped = _shipped()
    shipped_pf = [ref.per_run_summary(_pf_errors()[f"sweep_T{T:g}"]) for T in shipped.sweep_T]
    independent = _independent_sweep()
    return [("shipped sweep", shipped.sweep_T, {**shipped.sweep_median, "pf": pf_medians(shipped_pf)}),
            ("independent sweep", np.array(ref.SWEEP_T), {**independent[1], "pf": pf_medians(independent[4])})]


def _all_tables() -> list[dict]:
    """The shipped table, then the six Gaussian batches, then the three batches with the PF."""
    return [_shipped().table] + _batches() + [s for s, _ in _pf_batches()]


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
    """By the median, the PF has the smallest position, velocity and turn-rate error of the seven filters: in the shipped table, the 4000 study runs and every study batch, with and without one lost PF run added."""
    def check(t: dict) -> str | None:
        for quantity in air_traffic.QUANTITIES:
            best = min(air_traffic.FILTERS, key=lambda name: t[name]["median"][quantity])
            if best != "pf":
                return f"the smallest median {quantity} is {best}'s"
        return None

    _ranking_holds(check)


@claim("nonlinear-filters/position-ordering")
def _() -> None:
    """By the median position error, CUT6 and CUT8 (within 3% of each other in the table and the 4000 study runs) come before CUT4, then the UKF, the CKF and the EKF: in the table, the study and at least 95% of its batches."""
    def check(t: dict) -> str | None:
        p = {name: t[name]["median"]["position"] for name in GAUSSIAN}
        if not max(p["cut6"], p["cut8"]) < p["cut4"] < p["ukf"] < p["ckf"] < p["ekf"]:
            return f"median positions {p}"
        return None

    _ranking_holds(check, 0.95)
    for label, t in (("shipped table", _tables(False)[0]), ("4000 study runs", _pooled(False))):
        ratio = t["cut6"]["median"]["position"] / t["cut8"]["median"]["position"]
        assert abs(ratio - 1) < 0.03, f"{label}: CUT6/CUT8 median position {ratio:.3f}"


@claim("nonlinear-filters/cut8-best-gaussian")
def _() -> None:
    """Of the six Gaussian filters, CUT8 has the smallest median velocity and turn-rate errors: in the table, the 4000 study runs and every study batch."""
    def check(t: dict) -> str | None:
        for quantity in ("velocity", "turn_rate"):
            best = min(GAUSSIAN, key=lambda name: t[name]["median"][quantity])
            if best != "cut8":
                return f"the best Gaussian median {quantity} is {best}'s"
        return None

    _ranking_holds(check)


@claim("nonlinear-filters/pf-ahead-of-cut8")
def _() -> None:
    """By the median, the PF's position error is 17% below CUT8's in the table (to the percent) and 10-25% below in the study and every study batch of 100 runs, its velocity error below CUT8's and its turn-rate error about half of CUT8's (0.35-0.6 times): in the table, the study and every study batch, with and without one lost PF run added."""
    def check(t: dict) -> str | None:
        pf, c8 = t["pf"]["median"], t["cut8"]["median"]
        position, turn = pf["position"] / c8["position"], pf["turn_rate"] / c8["turn_rate"]
        if not (0.75 < position < 0.9 and pf["velocity"] < c8["velocity"] and 0.35 < turn < 0.6):
            return f"PF/CUT8 median position {position:.3f}, turn rate {turn:.3f}, velocity {pf['velocity']:.1f} vs {c8['velocity']:.1f}"
        return None

    _ranking_holds(check)
    for inject in (False, True):
        t = _tables(inject)[0]
        below = 1 - t["pf"]["median"]["position"] / t["cut8"]["median"]["position"]
        assert round(100 * below) == 17, f"the table (lost run added: {inject}): PF {100 * below:.1f}% below CUT8"


@claim("nonlinear-filters/pf-near-lecture")
def _() -> None:
    """Without its lost runs, the PF's lecture metric (position, velocity, turn rate) is within 3% of the lecture's PF row (115.47 m, 24.16 m/s, 0.0393 rad/s): in the 400-run table and over the 4000 study runs (seen 1.5-2.5%).

    Each of the study's 10 batches of 400 runs is within 5% in position, 1% in velocity and 2% in turn rate (seen
    -4.4% to +4.2%, within 0.9%, within 1.8%; a science review saw -4.0% to +1.1% in position over 11 other batches)."""
    for label, t in (("shipped table", _tables(False)[0]), ("4000 study runs", _pooled(False))):
        for quantity in air_traffic.QUANTITIES:
            ratio = t["pf"]["excluding_lost"][quantity] / air_traffic.LECTURE_TABLE[quantity]["pf"]
            assert abs(ratio - 1) < 0.03, f"{label}: PF {quantity} without lost runs, {ratio:.3f} times the lecture's"
    for k in range(10):
        batch = _summary(_study_runs("pf", slice(400 * k, 400 * (k + 1))))["excluding_lost"]
        for quantity, within in zip(air_traffic.QUANTITIES, (0.05, 0.01, 0.02)):
            ratio = batch[quantity] / air_traffic.LECTURE_TABLE[quantity]["pf"]
            assert abs(ratio - 1) < within, f"study batch {k}: PF {quantity} without lost runs, {ratio:.3f} times the lecture's"


CATASTROPHE_KM = 5.0
"""A catastrophe: a run whose time-RMS position error is above 5 km (the particles lost the aircraft for good)."""
PF_LOST, PF_LOST_INTERVAL = 7, (0.07, 0.36)
"""The PF's lost runs of the study (final position error above 1 km) and their exact 95% interval, in % to 2 decimals."""
PF_CATASTROPHES, PF_CATASTROPHE_INTERVAL, PF_WORST_KM, PF_OTHERS_BELOW_KM = 1, (0.0006, 0.14), 16.8, 1.5
"""The PF's catastrophes in the study, their exact 95% interval (%, the lower end to 4 decimals, the upper to 2), the
largest time-RMS position error (km, to 0.1), and a bound (km) on the time-RMS position error of every other run."""
NEAR_MISS_FINAL_KM = (1.1, 2.1)
"""The final position errors (km, to 0.1) of the PF's lost runs that are not catastrophes: their least and largest."""


@claim("nonlinear-filters/pf-lost-rate")
def _() -> None:
    """Over the study's 4000 runs the PF lost 7 (about 0.2%; exact 95% interval 0.07-0.36%), from 6 near misses (1.1 to 2.1 km off at the end, time-RMS errors up to about 1.1 km) to 1 catastrophe (a time-RMS position error of 16.8 km; exact 95% interval 0.0006-0.14%), with every other run below 1.5 km."""
    runs = _study_runs("pf")
    lost = runs["final_position"] > 1000.0 * air_traffic.LOST_KM
    catastrophe = runs["time_rms_position"] > 1000.0 * CATASTROPHE_KM
    n = len(lost)
    assert n == ref.LOST_STUDY_BATCHES * ref.LOST_STUDY_RUNS == 4000, f"{n} study runs"
    for what, flags, count, interval in (("lost", lost, PF_LOST, PF_LOST_INTERVAL),
                                         ("catastrophes", catastrophe, PF_CATASTROPHES, PF_CATASTROPHE_INTERVAL)):
        k = int(flags.sum())
        low, high = _clopper_pearson(k, n)
        assert k == count, f"the PF's {what}: {k} of {n}"
        digits = 4 if what == "catastrophes" else 2
        assert (round(100 * low, digits), round(100 * high, 2)) == interval, f"{what}: 95% interval {100 * low:.5f}-{100 * high:.3f}%"
    assert np.all(lost[catastrophe]), "a catastrophe that is not lost"
    worst, others = runs["time_rms_position"].max() / 1000, runs["time_rms_position"][~catastrophe].max() / 1000
    assert round(worst, 1) == PF_WORST_KM and others < PF_OTHERS_BELOW_KM, f"worst {worst:.2f} km, others up to {others:.2f} km"
    assert round(100 * lost.mean(), 1) == 0.2, f"lost {100 * lost.mean():.2f}%"
    near = runs["final_position"][lost & ~catastrophe] / 1000
    assert (round(near.min(), 1), round(near.max(), 1)) == NEAR_MISS_FINAL_KM, f"near misses end {near.min():.2f}-{near.max():.2f} km off"
    # their time-RMS errors reach about 1.1 km
    near_rms = runs["time_rms_position"][lost & ~catastrophe]
    assert round(near_rms.max() / 1000, 1) == 1.1, f"near misses' time-RMS errors up to {near_rms.max():.0f} m"


@claim("nonlinear-filters/study-mean-behind")
def _() -> None:
    """Over the study's 4000 runs, the PF's mean position metric (with its one catastrophe) is above CUT6's and CUT8's, while its median is the smallest of the seven filters (pf-best-all)."""
    t = _pooled(False)
    assert t["pf"]["position"] > max(t["cut6"]["position"], t["cut8"]["position"]), \
        f"mean position PF {t['pf']['position']:.1f}, CUT6 {t['cut6']['position']:.1f}, CUT8 {t['cut8']['position']:.1f}"

@claim("nonlinear-filters/one-lost-run-moves-the-mean")
def _() -> None:
    """One lost run with an 11 km time-RMS position error (a lecture metric of 4.9 km) added to the PF's 400 shipped runs lifts its mean position metric from under 120 m to over 250 m (more than double), behind CUT4's, CUT6's and CUT8's means, and moves its median by under 1 m."""
    assert _lost_run()["time_rms_position"][0] == 1000.0 * LOST_RUN_KM == 11_000.0
    assert round(_lost_run()["metric"][0, 0] / 1000, 1) == 4.9, _lost_run()["metric"]
    before, after = (_tables(inject)[0] for inject in (False, True))
    assert before["pf"]["position"] < 120 and after["pf"]["position"] > 250, (before["pf"]["position"], after["pf"]["position"])
    assert after["pf"]["position"] > 2 * before["pf"]["position"], (before["pf"]["position"], after["pf"]["position"])
    assert all(after["pf"]["position"] > after[name]["position"] for name in ("cut4", "cut6", "cut8")), after["pf"]
    moved = abs(after["pf"]["median"]["position"] - before["pf"]["median"]["position"])
    assert moved < 1.0, f"the PF's median moved by {moved:.2f} m"


@claim("nonlinear-filters/cut8-velocity-gap")
def _() -> None:
    """CUT8's velocity metric is below 50 m/s and over 10 times smaller than CUT6's, in the table and in every batch."""
    for i, t in enumerate(_all_tables()):
        v8, v6 = t["cut8"]["velocity"], t["cut6"]["velocity"]
        assert v8 < 50 and 10 * v8 < v6, f"table {i}: velocity metric CUT8 {v8:.1f} m/s, CUT6 {v6:.1f} m/s"


@claim("nonlinear-filters/diverged-runs-make-the-mean")
def _() -> None:
    """CUT4's and CUT6's mean velocity metrics are more than 50 times their median velocity errors, in the 400-run table and over the 4000 study runs (seen 69-103 times)."""
    for label, t in (("shipped table", _tables(False)[0]), ("4000 study runs", _pooled(False))):
        for name in ("cut4", "cut6"):
            ratio = t[name]["velocity"] / t[name]["median"]["velocity"]
            assert ratio > 50, f"{label}: {name}'s mean velocity metric is {ratio:.0f} times its median"


@claim("nonlinear-filters/mean-ranks-cut8-ahead")
def _() -> None:
    """By the lecture's metric (a mean), CUT8's position error is below CUT6's in the 400-run table and over the 4000 study runs, while their medians are within 3% (position-ordering)."""
    for label, t in (("shipped table", _tables(False)[0]), ("4000 study runs", _pooled(False))):
        assert t["cut8"]["position"] < t["cut6"]["position"], f"{label}: mean position CUT8 {t['cut8']['position']:.1f}, CUT6 {t['cut6']['position']:.1f}"


@claim("nonlinear-filters/cut-matches-lecture")
def _() -> None:
    """CUT6's and CUT8's position metrics are within 20% of the lecture's (138.82 m and 135.89 m), in the table and every batch."""
    for t in _all_tables():
        for name in ("cut6", "cut8"):
            lecture = air_traffic.LECTURE_TABLE["position"][name]
            assert abs(t[name]["position"] / lecture - 1) < 0.2, f"{name}: {t[name]['position']:.1f} m vs {lecture} m"


@claim("nonlinear-filters/lost-runs")
def _() -> None:
    """Lost runs: CKF 40-60%, UKF about one in three (25-40%; seen 33.5% in the table, 34.8% over the 4000 study runs, 39.7% pooled over the batches), CUT4 1-8%, CUT6 under 2%, CUT8 under 1%: in the 400-run table, pooled over the 390 batch runs and over the 4000 study runs."""
    ranges = {"ckf": (0.40, 0.60), "ukf": (0.25, 0.40), "cut4": (0.01, 0.08), "cut6": (0.0, 0.02), "cut8": (0.0, 0.01)}
    for name, (low, high) in ranges.items():
        fractions = (*_lost_fraction(name), _pooled(False)[name]["lost_runs"] / 4000)
        assert all(low <= f <= high for f in fractions), f"{name}: lost fractions {fractions}, claimed {low}-{high}"


@claim("nonlinear-filters/ekf-loses-most")
def _() -> None:
    """The EKF loses more than nine runs in ten, in the 400-run table and pooled over the batches."""
    fractions = _lost_fraction("ekf")
    assert min(fractions) > 0.9, f"EKF lost fractions {fractions}"


@claim("nonlinear-filters/velocity-best-two")
def _() -> None:
    """The two smallest median velocity errors of the seven filters are the PF's and CUT8's: in the table, the study and every study batch, with and without one lost PF run added."""
    def check(t: dict) -> str | None:
        best = sorted(air_traffic.FILTERS, key=lambda name: t[name]["median"]["velocity"])[:2]
        return None if best == ["pf", "cut8"] else f"smallest median velocity errors {best}"

    _ranking_holds(check)


@claim("nonlinear-filters/orders-of-magnitude")
def _() -> None:
    """The seven filters' median velocity errors span more than two orders of magnitude: in the table, the study and every study batch, with and without one lost PF run added."""
    def check(t: dict) -> str | None:
        v = [t[name]["median"]["velocity"] for name in air_traffic.FILTERS]
        return None if max(v) > 100 * min(v) else f"median velocity errors {v}"

    _ranking_holds(check)


@claim("nonlinear-filters/initial-error-settles")
def _() -> None:
    """The expected initial position RMSE is sqrt(P0_xx + P0_yy) = sqrt(2) km; every filter's position RMSE_k is 1.3-1.7 km (1.5 km to 0.05) at t = 0 in the 400-run curves, and below 500 m at t = 10 s in those and in each PF batch."""
    assert np.isclose(np.sqrt(air_traffic.P0[0, 0] + air_traffic.P0[1, 1]), np.sqrt(2) * 1000.0)
    for name, curve in _curves()[0].items():
        assert 1300 < curve[0] < 1700 and abs(curve[0] - 1500) < 50, f"shipped curves, {name}: {curve[0]:.0f} m at t = 0"
    for i, curves in enumerate(_curves()):
        for name, curve in curves.items():
            assert curve[2] < 500, f"curves {i}, {name}: {curve[2]:.0f} m at t = 10 s"


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
    """The flight passes closest to the radar at t = 240 s (3.1 km, 25 s after the first turn ends), the flight without
    turns at t = 210 s (10 km); on both, the bearing changes fastest within 5 s of that sample, and the CKF's and UKF's
    shipped position RMSE_k curves depart (straight-curves-depart) within 45 s of it."""
    turn_ends = sum(duration for duration, _ in air_traffic.LEGS[:2])
    assert air_traffic.LEGS[1][1] != 0 and air_traffic.LEGS[2][1] == 0 and turn_ends == 215.0, air_traffic.LEGS
    assert _closest_approach(air_traffic.LEGS)[0] - turn_ends == 25.0
    shipped = _shipped()
    for legs, curves in ((air_traffic.LEGS, {n: c[:, 0] for n, c in shipped.rmse_curves.items()}),
                         (air_traffic.STRAIGHT_LEGS, shipped.straight_position_rmse)):
        closest = _closest_approach(legs)[0]
        for name in ("ckf", "ukf"):
            assert abs(_departure(curves[name]) - closest) <= 45.0, f"{name} departs at {_departure(curves[name])} s, closest at {closest} s"
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


@claim("nonlinear-filters/sweep-cut6-behind-cut4-at-ten")
def _() -> None:
    """At T = 10 s the shipped sweep's CUT6 loses and diverges about twice as many of its 200 runs as CUT4 (22% against
    11% lost, 30.5% against 16% diverged); a science review saw 22% against 14% and 37% against 13% over 150 runs."""
    shipped = _shipped()
    at = list(shipped.sweep_T).index(10.0)
    for what, fraction, cut6, cut4 in (("lost", shipped.sweep_lost, 0.22, 0.11), ("diverged", shipped.sweep_diverged, 0.31, 0.16)):
        assert abs(fraction["cut6"][at] - cut6) < 0.01 and abs(fraction["cut4"][at] - cut4) < 0.01, \
            f"{what} at T = 10 s: CUT6 {fraction['cut6'][at]:.3f}, CUT4 {fraction['cut4'][at]:.3f}"
        assert 1.5 < fraction["cut6"][at] / fraction["cut4"][at] < 2.5, f"{what}: CUT6 over CUT4 at T = 10 s"


@claim("nonlinear-filters/sweep-cut8-diverges-least")
def _() -> None:
    """At every interval T, CUT8 diverges in no more runs than any other Gaussian filter, and in under 10% of them:
    in the shipped sweep (200 runs per T; seen 0-5%) and in the independent one (20 runs per T)."""
    shipped = _shipped()
    for what, diverged in (("shipped sweep", shipped.sweep_diverged), ("independent sweep", _independent_sweep()[3])):
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
    """At T = 5 s and T = 10 s the PF has the smallest median position error of the seven filters, in the shipped sweep and an independent one, with and without one lost PF run added."""
    for inject in (False, True):
        for what, T, median in _median_sweeps(inject):
            for interval in (5.0, 10.0):
                i = list(T).index(interval)
                best = min(air_traffic.FILTERS, key=lambda name: median[name][i, 0])
                assert best == "pf", f"{what} (lost run added: {inject}), T = {interval:g} s: smallest median position is {best}'s"


@claim("nonlinear-filters/pf-falls-behind")
def _() -> None:
    """At T = 15 s CUT8 has the smallest median position error of the seven filters, and at T = 20 s the PF's is more than 10 times CUT8's (shipped and independent sweep, with and without one lost PF run added)."""
    for inject in (False, True):
        for what, T, median in _median_sweeps(inject):
            i15, i20 = list(T).index(15.0), list(T).index(20.0)
            best = min(air_traffic.FILTERS, key=lambda name: median[name][i15, 0])
            assert best == "cut8", f"{what}, T = 15 s: smallest median position is {best}'s"
            assert median["pf"][i20, 0] > 10 * median["cut8"][i20, 0], f"{what}, T = 20 s: PF {median['pf'][i20, 0]:.0f} m"


@claim("nonlinear-filters/errors-grow-with-interval")
def _() -> None:
    """Every filter but the EKF has a larger median position error at T = 20 s than at T = 5 s, and the EKF loses over 90% of the runs at every T (shipped and independent sweep)."""
    independent = _independent_sweep()
    for (what, T, median), lost in zip(_median_sweeps(False), (_shipped().sweep_lost, independent[2])):
        first, last = list(T).index(5.0), list(T).index(20.0)
        for name in air_traffic.FILTERS:
            if name != "ekf":
                assert median[name][last, 0] > median[name][first, 0], f"{what}: {name}"
        assert np.all(lost["ekf"] > 0.9), f"{what}: EKF lost fractions {lost['ekf']}"


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
    """At T = 20 s the PF loses more than 80% of the runs, and its median velocity error is within 25% of that of estimating zero velocity (120/sqrt(5) = 53.7 m/s): shipped and independent sweep."""
    shipped = _shipped()
    independent = _independent_sweep()
    for (what, T, median), lost_fraction in zip(_median_sweeps(False), (shipped.sweep_lost, independent[2])):
        i = list(T).index(20.0)
        assert lost_fraction["pf"][i] > 0.8, f"{what}: PF lost fraction at T = 20 s {lost_fraction['pf'][i]:.2f}"
        ratio = median["pf"][i, 1] / air_traffic.ZERO_VELOCITY_METRIC
        assert abs(ratio - 1) < 0.25, f"{what}: PF median velocity {median['pf'][i, 1]:.1f} m/s"


@functools.cache
def _many_particles() -> list[int]:
    """The PF's lost runs at T = 20 s with MANY_PARTICLES particles, out of MANY_PARTICLE_RUNS, on each of MANY_PARTICLE_SEEDS."""
    return [int(np.sum(air_traffic.lost_runs(ref.monte_carlo(MANY_PARTICLE_RUNS, seed, T=20.0, particles=MANY_PARTICLES,
                                                               filters=("pf",))["pf"])))
            for seed in MANY_PARTICLE_SEEDS]


@claim("nonlinear-filters/more-particles-help")
def _() -> None:
    """At T = 20 s, 20 000 particles lose half to two thirds of the runs (checked 25-75%, pooled over two seeds of 16
    runs; seen: 10 and 6 of 16, and 8 of 16 on seed 307; an independent review saw 32 of 48), where 5000 lose over 85%
    of the shipped sweep's 200. With a true rate of 58%, 32 runs fall outside 8-24 lost with probability about 1.4%."""
    shipped = _shipped()
    few = shipped.sweep_lost["pf"][list(shipped.sweep_T).index(20.0)]
    lost = _many_particles()
    many = sum(lost) / (MANY_PARTICLE_RUNS * len(MANY_PARTICLE_SEEDS))
    assert few > 0.85 and 0.25 <= many <= 0.75, f"PF lost at T = 20 s: {few:.0%} with {shipped.particles}, {lost} of {MANY_PARTICLE_RUNS} with 20 000"
