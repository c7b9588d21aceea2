"""Checks of the results that the reentry-pf notebook states.

The tuning study (course/data/falling_object_tuning.csv, 50 simulated half minutes per setting)
is built by ``solutions.reentry_pf.reference.tuning_runs`` and rebuilt byte for byte by
``python -m autograder data --check``, so the checks that quote it read the shipped file rather
than rerun 700 filters. The yardstick (the linearised posterior sd of beta at the truth) and the
Van Trees bound are recomputed; the diagnostics of single runs are recomputed on 10 fresh seeds.

Issue 33: the RMSE and coverage of beta scatter by about +-25% from one batch of runs to the next,
so the claims about them state their spread over five batches of 10 study runs (``batches``), or
compare with the standard error of the mean, rather than a threshold inside that scatter.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.integrate import solve_ivp

from autograder.authoring.claims import claim, rate_at_least
from course import falling_object as fo
from solutions.reentry_pf import reference as ref

HANDOUT = {N: fo.TuningSetting("auxiliary", N, fo.HANDOUT_STD) for N in (500, 2000, 5000)}
HANDOUT_SETTING = fo.HANDOUT_SETTING  # the handout's setting: auxiliary, N = 5000, noise (100, 100, 5)
TUNED_SETTING = fo.TUNED_SETTING  # the tuned setting: auxiliary, N = 2000, noise (10, 10, 50)
assert HANDOUT_SETTING == HANDOUT[5000]
CHOSEN = {N: fo.TuningSetting("auxiliary", N, fo.CHOSEN) for N in (500, 2000)}
SMALL_BETA_NOISE = {N: fo.TuningSetting("auxiliary", N, (10.0, 10.0, 5.0)) for N in (500, 2000)}
BOOTSTRAP = {"handout": fo.TuningSetting("bootstrap", 2000, fo.HANDOUT_STD), "chosen": fo.TuningSetting("bootstrap", 2000, fo.CHOSEN)}


@functools.cache
def crb() -> np.ndarray:
    """The yardstick: beta's posterior sd for the model linearised at the truth, at every t_j."""
    return fo.beta_linearised_sd(ref.tracking_dynamics, fo.X0_TRUE, fo.time_grid())


def fisher_information(x0: np.ndarray) -> np.ndarray:
    """The readings' Fisher information about x0 at every t_j, (T + 1, 3, 3), without the prior's."""
    s = fo.state_sensitivities(ref.tracking_dynamics, x0, fo.time_grid())[:, 0, :].copy()
    s[0] = 0.0  # b_0 is in the prior
    return np.cumsum(s[:, :, None] * s[:, None, :], axis=0) / fo.SIGMA**2


@functools.cache
def van_trees(seed: int, draws: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """The Van Trees bound of beta at every t_j from ``draws`` prior draws of x0 (the Fisher information
    averaged over them, plus the prior's), and the linearised posterior sd at 30 s of each draw."""
    rng = np.random.default_rng([seed, 55])
    mean = np.array([fo.load().b[0], fo.V_INIT, fo.BETA_INIT])
    prior_information = np.diag(1.0 / fo.PRIOR_STD**2)
    informations = [fisher_information(mean + fo.PRIOR_STD * rng.standard_normal(3)) for _ in range(draws)]
    at_draws = np.array([np.sqrt(np.linalg.inv(f[-1] + prior_information)[2, 2]) for f in informations])
    bound = np.sqrt(np.linalg.inv(np.mean(informations, axis=0) + prior_information)[:, 2, 2])
    return bound, at_draws


def batches(setting: fo.TuningSetting, column: str, size: int = 10) -> np.ndarray:
    """The mean of ``column`` over each batch of ``size`` consecutive study runs (5 batches of 10)."""
    return study().runs[setting][column].reshape(-1, size).mean(axis=1)


@functools.cache
def study() -> fo.TuningStudy:
    return fo.load_tuning()


@functools.cache
def handout_runs(seeds: range = range(1000, 1010), N: int = 2000) -> list[fo.FilterHistory]:
    """Runs of the handout's filter on fresh simulated readings (seeds outside the study's)."""
    t = fo.time_grid()
    runs = []
    for seed in seeds:
        _, b = ref.simulate_radar(fo.X0_TRUE, t, fo.SIGMA, np.random.default_rng([seed, 1]))
        runs.append(ref.run_particle_filter(b, N, np.random.default_rng([seed, 2])))
    return runs


@functools.cache
def ideal(score_from: float = fo.SCORE_FROM) -> dict[str, np.ndarray]:
    return fo.ideal_scores(ref.tracking_dynamics, fo.X0_TRUE, fo.time_grid(), score_from=score_from)


def prior_band() -> float:
    return 2 * fo.Z90 * fo.PRIOR_STD[2]


def mean(setting: fo.TuningSetting, column: str) -> float:
    return float(np.mean(study().runs[setting][column]))


@claim("reentry-pf/yardstick-insensitive")
def _() -> None:
    """The yardstick at 30 s changes by less than 3% when the truth's beta moves by +-400 or its v0 by +-50."""
    for shift in ([0.0, 0.0, 400.0], [0.0, 0.0, -400.0], [0.0, 50.0, 0.0], [0.0, -50.0, 0.0]):
        moved = fo.beta_linearised_sd(ref.tracking_dynamics, fo.X0_TRUE + np.array(shift), fo.time_grid())[-1]
        assert abs(moved / crb()[-1] - 1) < 0.03, (shift, moved, crb()[-1])


@claim("reentry-pf/yardstick-information")
def _() -> None:
    """At t = 30 s the information about beta (readings plus prior) is over 50 times the prior's: a yardstick of about 200."""
    ratio = (fo.PRIOR_STD[2] / crb()[-1]) ** 2
    assert ratio > 50 and 180 < crb()[-1] < 212, f"information / prior information at 30 s is {ratio:.1f}, yardstick {crb()[-1]:.0f}"


@claim("reentry-pf/yardstick-near-van-trees")
def _() -> None:
    """The Van Trees bound (over each of two sets of 40 prior draws) is within 6% of the yardstick at 20 s and 30 s, and 200-220 at 30 s ("about 210")."""
    for seed in (0, 1):
        bound, _ = van_trees(seed)
        for t in (20, 30):
            j = round(t / fo.DT)
            assert abs(bound[j] / crb()[j] - 1) < 0.06, (seed, t, bound[j], crb()[j])
        assert 200 < bound[-1] < 220, (seed, bound[-1])


@claim("reentry-pf/yardstick-across-prior")
def _() -> None:
    """Over 80 prior draws of x0, the linearised posterior sd of beta at 30 s has its 10th percentile at 170-195 and its 90th at 235-265."""
    at_draws = np.concatenate([van_trees(seed)[1] for seed in (0, 1)])
    low, high = np.percentile(at_draws, [10, 90])
    assert 170 < low < 195 and 235 < high < 265, (low, high)


@claim("reentry-pf/information-arrives-late")
def _() -> None:
    """The yardstick is within 1% of the prior's 1500 at 10 s, above 80% of it at 15 s, and falls most between 15 s and 25 s."""
    bound = crb()
    j = lambda t: round(t / fo.DT)  # noqa: E731
    assert bound[j(10)] > 0.99 * 1500 and bound[j(15)] > 0.8 * 1500, (bound[j(10)], bound[j(15)])
    drops = {t: bound[j(t)] - bound[j(t + 5)] for t in (0, 5, 10, 15, 20, 25)}
    assert max(drops, key=drops.get) in (15, 20), drops


@claim("reentry-pf/handout-band-far-from-yardstick")
def _() -> None:
    """Handout's noise, N = 2000 and 5000: beta's 90% band at 30 s is over 1.5 times the yardstick in every study run, and in
    the median run 4 to 8 times it (about 6 for N = 5000, 5 for N = 2000), also against the Van Trees bound."""
    for reference in (crb()[-1], van_trees(0)[0][-1], van_trees(1)[0][-1]):
        band = 2 * fo.Z90 * reference
        medians = {}
        for N in (2000, 5000):
            ratio = study().runs[HANDOUT[N]]["width90_beta"][:, -1] / band
            assert ratio.min() > 1.5 and 4 < np.median(ratio) < 8, (N, ratio.min(), np.median(ratio))
            medians[N] = np.median(ratio)
        assert 5.5 <= medians[5000] < 7 and 4.5 <= medians[2000] < 6, medians


@claim("reentry-pf/handout-band-narrow-early")
def _() -> None:
    """The handout's setting (N = 5000): from 1 s to 13 s, before the readings hold information about beta, the median
    run's 90% band of beta is 90-100% of the yardstick's, and about a quarter of the study's runs (20-35%) fall below
    80% of it at some second."""
    widths = study().runs[HANDOUT_SETTING]["width90_beta"]
    ratio = (widths / (2 * fo.Z90 * crb()[:: fo.WIDTH_EVERY][: widths.shape[1]]))[:, 1:14]
    median = np.median(ratio, axis=0)
    dipped = np.mean(np.any(ratio < 0.8, axis=1))
    assert 0.88 <= median.min() and median.max() <= 1.01 and 0.2 <= dipped <= 0.35, (median, dipped)
    # the yardstick is still the prior's there: the narrowing is not information
    assert crb()[13 * round(1 / fo.DT)] > 0.95 * fo.PRIOR_STD[2], crb()[13 * round(1 / fo.DT)]


@claim("reentry-pf/handout-band-above-prior")
def _() -> None:
    """The handout's setting (N = 5000): at 30 s, 20-40% of the study's runs end with a 90% band of beta wider than the
    prior's, the widest below 1.7 times it (about 30%, up to 1.6 times)."""
    ratio = study().runs[HANDOUT_SETTING]["width90_beta"][:, -1] / prior_band()
    assert 0.2 <= np.mean(ratio > 1.0) <= 0.4 and 1.4 <= ratio.max() < 1.7, (np.mean(ratio > 1.0), ratio.max())


@claim("reentry-pf/ess-after-d-high")
def _() -> None:
    """The ESS after step (d) stays above 0.6 N at every step, in every one of 10 fresh runs (N = 2000)."""
    rate_at_least([np.min(h.ess[1:]) > 0.6 * h.n_particles for h in handout_runs()], 1.0,
                  "the ESS after (d) above 0.6 N throughout a run")


@claim("reentry-pf/fitness-ess")
def _() -> None:
    """The ESS of the fitness weights that drive the resampling drops below 0.35 N at some reading in at least 8 of
    10 fresh runs."""
    rate_at_least([np.min(h.ess_resample[1:]) < 0.35 * h.n_particles for h in handout_runs()], 0.8,
                  "the ESS of the fitness weights below 0.35 N at some reading")


EQUAL_WEIGHTS_KEPT = 1 - np.exp(-1)  # distinct fraction that multinomial resampling keeps from equal weights


def drift_roots(N: int, n: int) -> float:
    """Roots left after n multinomial resamplings of N equally weighted particles: 2N / (n + 2)."""
    return 2 * N / (n + 2)


@claim("reentry-pf/parents-fraction")
def _() -> None:
    """Handout's setting, N = 2000: in each of 10 fresh runs the median over the steps of the distinct-parent fraction
    lies between 0.55 and 0.632 (1 - 1/e, the equal-weights value), and no step keeps more than 70%."""
    fractions = np.array([h.parents[1:] / h.n_particles for h in handout_runs()])
    medians = np.median(fractions, axis=1)
    rate_at_least(list((0.55 < medians) & (medians < EQUAL_WEIGHTS_KEPT)), 1.0,
                  "a run's median distinct-parent fraction between 0.55 and 1 - 1/e")
    assert fractions.max() < 0.7, fractions.max()


@claim("reentry-pf/equal-weights-drift")
def _() -> None:
    """Multinomial resampling of N = 5000 equal weights, 300 times, on 5 seeds: the distinct-parent fraction is
    0.632 +- 0.005 at each step on average, and the roots left are within a factor 1.5 of 2N / (n + 2) = 33 on each
    seed (the spread of the root count at 33 is about +-17%, so a factor 1.5 is over 2 sigma each way)."""
    N, steps = 5000, 300
    for seed in range(5):
        rng = np.random.default_rng([seed, 77])
        root, kept = np.arange(N), []
        for _ in range(steps):
            k = np.searchsorted(np.arange(1, N + 1) / N, np.sort(rng.random(N)), side="right")
            kept.append(np.unique(k).size / N)
            root = root[k]
        roots = np.unique(root).size
        assert abs(np.mean(kept) - EQUAL_WEIGHTS_KEPT) < 0.005, np.mean(kept)
        assert drift_roots(N, steps) / 1.5 < roots < 1.5 * drift_roots(N, steps), (seed, roots)


@claim("reentry-pf/roots-collapse")
def _() -> None:
    """Handout's setting, N = 5000: fewer than 30 particles of t_0 have descendants at 30 s, in all 50 study runs, and
    the median run keeps more than a third of the 33 roots that equal weights would leave (2N / (n + 2))."""
    roots = study().runs[HANDOUT[5000]]["roots_end"]
    assert roots.max() < 30 and np.median(roots) > drift_roots(5000, 300) / 3, (roots.max(), np.median(roots))


@claim("reentry-pf/fewer-particles-narrower")
def _() -> None:
    """Handout's noise: beta's 90% band at 30 s is narrower with N = 500 than with 2000 and 5000 (medians, in each batch of 10), narrower than the yardstick in some N = 500 runs, and below 0.8 of the prior's at 10 s."""
    medians = [np.median(study().runs[HANDOUT[N]]["width90_beta"][:, -1]) for N in (500, 2000, 5000)]
    assert [round(m, -1) for m in medians] == [1600, 3550, 4190], medians
    per_batch = [np.median(study().runs[HANDOUT[N]]["width90_beta"][:, -1].reshape(-1, 10), axis=1) for N in (500, 2000, 5000)]
    assert np.all(per_batch[0] < np.minimum(per_batch[1], per_batch[2])), per_batch
    assert study().runs[HANDOUT[500]]["width90_beta"][:, -1].min() < 2 * fo.Z90 * crb()[-1]
    at_10 = int(np.flatnonzero(np.isclose(study().width_times, 10.0))[0])
    early = np.median(study().runs[HANDOUT[500]]["width90_beta"][:, at_10]) / prior_band()
    assert early < 0.8 and crb()[round(10 / fo.DT)] > 0.99 * fo.PRIOR_STD[2], (early, crb()[round(10 / fo.DT)])


@claim("reentry-pf/handout-band-near-prior")
def _() -> None:
    """The handout's setting: the median width of beta's 90% band at 30 s is 0.8-0.9 of the prior's (4935), 77-98% per batch of 10."""
    widths = study().runs[HANDOUT[5000]]["width90_beta"][:, -1]
    ratio = np.median(widths) / prior_band()
    per_batch = np.median(widths.reshape(-1, 10), axis=1) / prior_band()
    assert 0.8 < ratio < 0.9 and round(100 * per_batch.min()) == 77 and round(100 * per_batch.max()) == 98, (ratio, per_batch)


@claim("reentry-pf/handout-v-too-wide")
def _() -> None:
    """The handout's setting: the truth of v is in the 50% band over 90% of the time, in the study and in each batch of 10 runs."""
    assert mean(HANDOUT_SETTING, "cover50_v") > 0.9 and batches(HANDOUT_SETTING, "cover50_v").min() > 0.9


@claim("reentry-pf/handout-v-upward")
def _() -> None:
    """The handout's setting (and its noise with N = 2000): the 90% interval of v at 30 s reaches below 0 in all 50 study runs."""
    for N in (2000, 5000):
        assert np.all(study().runs[HANDOUT[N]]["lo90_v_end"] < 0), N


@claim("reentry-pf/tuned-rmse-hv")
def _() -> None:
    """Tuned over handout's setting, RMSE over t >= 20 s: h 0.42-0.5 (0.4-0.52 per batch of 10), v 0.12-0.18 (0.1-0.21); the table's 86, 188, 14, 92."""
    for n, (low, high), (batch_low, batch_high) in (("h", (0.42, 0.5), (0.4, 0.52)), ("v", (0.12, 0.18), (0.1, 0.21))):
        ratio = mean(TUNED_SETTING, f"rmse_{n}") / mean(HANDOUT_SETTING, f"rmse_{n}")
        per_batch = batches(TUNED_SETTING, f"rmse_{n}") / batches(HANDOUT_SETTING, f"rmse_{n}")
        assert low < ratio < high and batch_low < per_batch.min() and per_batch.max() < batch_high, (n, ratio, per_batch)
    table = [round(mean(s, f"rmse_{n}")) for n in ("h", "v") for s in (TUNED_SETTING, HANDOUT_SETTING)]
    assert table == [86, 188, 14, 92], table


def two_se(setting: fo.TuningSetting, column: str) -> float:
    """Two standard errors of the mean of ``column`` over the study's runs, as the table prints it for beta's RMSE."""
    runs = study().runs[setting][column]
    return float(2 * np.std(runs, ddof=1) / np.sqrt(runs.shape[0]))


def paired_beta(setting: fo.TuningSetting) -> tuple[float, float]:
    """The table's diff column: the mean over the study's runs of beta's RMSE minus the handout's setting's on the
    same run (same readings, same filter seeds), and two standard errors of that mean."""
    diff = study().runs[setting]["rmse_beta"] - study().runs[HANDOUT_SETTING]["rmse_beta"]
    return float(np.mean(diff)), float(2 * np.std(diff, ddof=1) / np.sqrt(diff.shape[0]))


@claim("reentry-pf/tuned-rmse-beta")
def _() -> None:
    """Beta's RMSE, tuned against handout's setting: 508 against 678 (0.7-0.8), the rows' +-2 se 94 and 109 (their ranges
    overlap), the paired difference -171 +- 165 (just over 2 se from 0), both above the exact posterior's 289."""
    tuned, handout = mean(TUNED_SETTING, "rmse_beta"), mean(HANDOUT_SETTING, "rmse_beta")
    assert 0.7 < tuned / handout < 0.8 and (round(tuned), round(handout)) == (508, 678), (tuned, handout)
    spreads = two_se(TUNED_SETTING, "rmse_beta"), two_se(HANDOUT_SETTING, "rmse_beta")
    assert (round(spreads[0]), round(spreads[1])) == (94, 109) and tuned + spreads[0] > handout - spreads[1], spreads
    diff, se2 = paired_beta(TUNED_SETTING)
    assert (round(diff), round(se2)) == (-171, 165) and se2 < -diff < 1.1 * se2, (diff, se2)
    assert round(ideal()["rmse"][2]) == 289 and ideal()["rmse"][2] < tuned, ideal()["rmse"]


@claim("reentry-pf/tuned-beta-fresh")
def _() -> None:
    """On 50 fresh runs (seeds 1000-1049, outside the study's; readings and filter seeds as the study draws them), the tuned
    setting's mean RMSE of beta over t >= 20 s is 0.6-0.8 of the handout's setting's, and the paired difference is more than
    2 standard errors from 0; a 95% bootstrap interval of the ratio (5000 resamples of the 50 runs) runs from 0.5-0.6 to
    0.75-0.85 (0.54 to 0.82 measured). A science review found 0.79 (0.71-0.89) over 200 other fresh runs."""
    t = fo.time_grid()
    scored = t >= fo.SCORE_FROM - 1e-9
    rmse = {TUNED_SETTING: [], HANDOUT_SETTING: []}
    for seed in range(1000, 1050):
        x_true, b = ref.simulate_radar(fo.X0_TRUE, t, fo.SIGMA, np.random.default_rng([seed, 1]))
        for setting in rmse:
            run = ref.run_particle_filter(b, setting.N, np.random.default_rng([seed, 2]), innovation_std=np.array(setting.innovation_std))
            rmse[setting].append(np.sqrt(np.mean((run.mean[2, scored] - x_true[2, scored]) ** 2)))
    tuned, handout = np.array(rmse[TUNED_SETTING]), np.array(rmse[HANDOUT_SETTING])
    diff = tuned - handout
    assert 0.6 < tuned.mean() / handout.mean() < 0.8, (tuned.mean(), handout.mean())
    assert -diff.mean() > 2 * np.std(diff, ddof=1) / np.sqrt(diff.size), (diff.mean(), np.std(diff, ddof=1))
    # the ratio of the means over resampled sets of the 50 runs (pairs kept together)
    resampled = np.random.default_rng(0).integers(0, tuned.size, size=(5000, tuned.size))
    low, high = np.percentile(tuned[resampled].mean(axis=1) / handout[resampled].mean(axis=1), [2.5, 97.5])
    assert 0.5 <= low <= 0.6 and 0.75 <= high <= 0.85, (low, high)


@claim("reentry-pf/ideal-metric")
def _() -> None:
    """The exact posterior's beta error over t >= 20 s: the root of its mean squared error is 323, the table's mean of each
    run's RMSE 289."""
    assert round(ideal()["rms"][2]) == 323 and round(ideal()["rmse"][2]) == 289, ideal()


@claim("reentry-pf/shipped-tuned-band")
def _() -> None:
    """On the shipped readings (RUN_SEED, the reference pf_step), the tuned setting's 90% band of beta at 30 s is wider than
    the handout's setting's, by less than 15%."""
    data = fo.load()
    widths = []
    for setting in (TUNED_SETTING, HANDOUT_SETTING):
        run = ref.run_particle_filter(data.b, setting.N, np.random.default_rng(fo.RUN_SEED), innovation_std=np.array(setting.innovation_std))
        widths.append(run.hi90[2, -1] - run.lo90[2, -1])
    assert 1.0 < widths[0] / widths[1] < 1.15, widths


@claim("reentry-pf/tuned-band-narrower")
def _() -> None:
    """Study runs: the tuned setting's 90% band of beta at 30 s is wider than the handout's setting's in fewer than a quarter
    of the runs; the median of the ratio is 0.55-0.65."""
    ratio = study().runs[TUNED_SETTING]["width90_beta"][:, -1] / study().runs[HANDOUT_SETTING]["width90_beta"][:, -1]
    assert np.mean(ratio > 1) < 0.25 and 0.55 < np.median(ratio) < 0.65, (np.mean(ratio > 1), np.median(ratio))


@claim("reentry-pf/systematic-still-wide")
def _() -> None:
    """Handout's noise, N = 5000, 5 fresh readings: a pf_step that resamples systematically (the catalogued alternative) keeps
    over 3 times the roots of the reference's multinomial pf_step at 30 s, and its median 90% band of beta at 30 s is over
    0.8 of the prior's."""
    from solutions.reentry_pf.alternatives import ALTERNATIVES

    names = {"np": np, "DT": fo.DT, "SIGMA": fo.SIGMA, "INNOVATION_STD": fo.INNOVATION_STD, "tracking_dynamics": ref.tracking_dynamics}
    exec(next(a for a in ALTERNATIVES if a.slug == "systematic").code, names)  # noqa: S102 (our own catalogue)
    t = fo.time_grid()
    bands = []
    for seed in range(1000, 1005):
        _, b = ref.simulate_radar(fo.X0_TRUE, t, fo.SIGMA, np.random.default_rng([seed, 1]))
        systematic = ref.run_particle_filter(b, 5000, np.random.default_rng([seed, 2]), step=names["pf_step"])
        multinomial = ref.run_particle_filter(b, 5000, np.random.default_rng([seed, 2]))
        assert systematic.roots[-1] > 3 * multinomial.roots[-1], (seed, systematic.roots[-1], multinomial.roots[-1])
        bands.append((systematic.hi90[2, -1] - systematic.lo90[2, -1]) / prior_band())
    assert np.median(bands) > 0.8, bands


@claim("reentry-pf/beta-rmse-spread")
def _() -> None:
    """The handout's setting: the 10th percentile of one run's beta RMSE is 120-180, the 90th 1100-1300."""
    low, high = np.percentile(study().runs[HANDOUT_SETTING]["rmse_beta"], [10, 90])
    assert 120 < low < 180 and 1100 < high < 1300, (low, high)


@claim("reentry-pf/tuned-coverage")
def _() -> None:
    """Tuned setting, over t >= 20 s: 90% bands 96/100/97%, 50% bands h 55%, v 93%, beta 68% (55-76% per batch of 10); exact posterior 50-53%."""
    c90 = [mean(TUNED_SETTING, f"cover90_{n}") for n in fo.STATE_NAMES]
    c50 = [mean(TUNED_SETTING, f"cover50_{n}") for n in fo.STATE_NAMES]
    assert min(c90) >= 0.9 and 0.45 <= c50[0] <= 0.6 and c50[1] > 0.85 and 0.6 < c50[2] < 0.75, (c50, c90)
    assert [round(100 * c) for c in c90 + c50] == [96, 100, 97, 55, 93, 68], (c90, c50)
    per_batch = batches(TUNED_SETTING, "cover50_beta")
    assert 0.5 < per_batch.min() and per_batch.max() < 0.8 and round(100 * per_batch.min()) == 55 and round(100 * per_batch.max()) == 76, per_batch
    assert np.all((0.5 <= ideal()["cover50"]) & (ideal()["cover50"] <= 0.53)), ideal()["cover50"]
    assert np.all(ideal()["cover50"] < min(c50[1:])), ideal()["cover50"]
    # no band over-confident: each at least the exact posterior's; its 90% bands score 90-91%, its 50% band of h 51%
    assert np.all(np.array(c50) >= ideal()["cover50"]) and np.all(np.array(c90) >= ideal()["cover90"]), (c50, c90)
    assert [round(100 * c) for c in ideal()["cover90"]] in ([90, 90, 91], [90, 91, 91], [91, 91, 91], [90, 90, 90]), ideal()["cover90"]
    assert round(100 * ideal()["cover50"][0]) == 51, ideal()["cover50"]


@claim("reentry-pf/small-noise-overconfident")
def _() -> None:
    """N = 2000: with noise (3, 3, 5) and (3, 3, 50) the 90% band of h holds the truth less than 80% of the time."""
    for beta in (5.0, 50.0):
        setting = fo.TuningSetting("auxiliary", 2000, (3.0, 3.0, beta))
        assert mean(setting, "cover90_h") < 0.8, (beta, mean(setting, "cover90_h"))


@claim("reentry-pf/tuned-needs-particles")
def _() -> None:
    """Tuned noise: with N = 500 beta's 90% band holds the truth less than 80% of the time, in each batch of 10 (over 90% with N = 2000)."""
    assert batches(CHOSEN[500], "cover90_beta").max() < 0.8, batches(CHOSEN[500], "cover90_beta")
    assert mean(CHOSEN[500], "cover90_beta") < 0.8 < 0.9 < mean(CHOSEN[2000], "cover90_beta")


@claim("reentry-pf/bootstrap-similar")
def _() -> None:
    """N = 2000, handout's and tuned noise: bootstrap RMSE of h, v within 10% of the auxiliary's, their coverage within 7
    points; for beta (RMSE, 50% and 90% coverage) the paired difference, bootstrap minus auxiliary run by run on the
    study's 50 runs, is within two standard errors of 0."""
    for name, aux in (("handout", HANDOUT[2000]), ("chosen", CHOSEN[2000])):
        boot = BOOTSTRAP[name]
        for n in ("h", "v"):
            ratio = mean(boot, f"rmse_{n}") / mean(aux, f"rmse_{n}")
            assert 0.9 < ratio < 1.1, (name, n, ratio)
        for column in (f"cover{p}_{n}" for p in (50, 90) for n in ("h", "v")):
            assert abs(mean(boot, column) - mean(aux, column)) < 0.07, (name, column)
        # beta: the paired difference over the same runs, against its two standard errors
        for column in ("rmse_beta", "cover50_beta", "cover90_beta"):
            diff = study().runs[boot][column] - study().runs[aux][column]
            assert abs(diff.mean()) < 2 * np.std(diff, ddof=1) / np.sqrt(diff.size), (name, column, diff.mean())


@claim("reentry-pf/solver-tolerances")
def _() -> None:
    """Section 2, from the lab's start: with rtol=1e-10, atol=1e-8 the truth's altitude is right to under 0.01 mm
    (against DOP853 at rtol=1e-13), with the defaults about 20 m off; about 650 evaluations of f against 75."""
    t = fo.time_grid()
    span = (t[0], t[-1])
    exact = solve_ivp(ref.tracking_dynamics, span, fo.X0_TRUE, method="DOP853", t_eval=t, rtol=1e-13, atol=1e-12).y[0]
    default = solve_ivp(ref.tracking_dynamics, span, fo.X0_TRUE, t_eval=t)
    tight = solve_ivp(ref.tracking_dynamics, span, fo.X0_TRUE, t_eval=t, rtol=1e-10, atol=1e-8)
    default_error, tight_error = np.abs(default.y[0] - exact).max(), np.abs(tight.y[0] - exact).max()
    assert 15.0 < default_error < 22.0 and 1e-6 < tight_error < 1e-5, (default_error, tight_error)
    assert 550 < tight.nfev < 750 and 60 < default.nfev < 90, (tight.nfev, default.nfev)


@claim("reentry-pf/euler-error-small")
def _() -> None:
    """One Forward Euler step from the true state misses the true trajectory by less than 2 m in h and 1 m/s in v."""
    t = fo.time_grid()
    x, _ = ref.simulate_radar(fo.X0_TRUE, t, fo.SIGMA, np.random.default_rng(0))
    miss = np.abs(x[:, :-1] + fo.DT * ref.tracking_dynamics(0.0, x[:, :-1]) - x[:, 1:]).max(axis=1)
    assert miss[0] < 2.0 and miss[1] < 1.0, miss


@claim("reentry-pf/fitness-ess-typical")
def _() -> None:
    """The median over a run of the fitness weights' ESS is above 0.8 N, in each of 10 fresh runs (N = 2000)."""
    rate_at_least([np.median(h.ess_resample[1:]) > 0.8 * h.n_particles for h in handout_runs()], 1.0,
                  "the median ESS of the fitness weights above 0.8 N")


@claim("reentry-pf/ideal-whole-run")
def _() -> None:
    """Scored over the whole run (t_1..t_T) at the lab's truth, an exact posterior's beta bands would hold the truth 70-75% (50% band) and 95-97% (90%)."""
    whole = ideal(fo.DT)
    assert 0.70 < whole["cover50"][2] < 0.75 and 0.95 < whole["cover90"][2] < 0.97, whole
    assert abs((fo.BETA_INIT - fo.X0_TRUE[2]) / fo.PRIOR_STD[2] - 0.56) < 0.005


@claim("reentry-pf/ideal-scored")
def _() -> None:
    """Scored over t >= 20 s, an exact posterior's 50% bands of h, v and beta score 50-53% and its 90% bands 90-92%."""
    late = ideal()
    assert np.all((0.5 <= late["cover50"]) & (late["cover50"] <= 0.53)), late
    assert np.all((0.9 <= late["cover90"]) & (late["cover90"] <= 0.92)), late


@claim("reentry-pf/tuned-band-width")
def _() -> None:
    """Tuned setting: beta's 90% band at 30 s is 3 to 5 times the yardstick in the median study run, and in the median run of each batch of 10."""
    yardstick = 2 * fo.Z90 * crb()[-1]
    ratio = study().runs[TUNED_SETTING]["width90_beta"][:, -1] / yardstick
    assert 3 < np.median(ratio) < 5, np.median(ratio)
    per_batch = np.median(ratio.reshape(-1, 10), axis=1)
    assert 3 < per_batch.min() and per_batch.max() < 5, per_batch


@claim("reentry-pf/beta-noise-robust")
def _() -> None:
    """Noise (10, 10, 5) against the tuned (10, 10, 50), over t >= 20 s: RMSE of h, v within 5% at N = 2000; beta's 90% coverage (mean, batch range) 83 (75-93) against 97 (93-100), at N = 500 17 (10-32) against 69 (60-73)."""
    for n in ("h", "v"):
        assert abs(mean(SMALL_BETA_NOISE[2000], f"rmse_{n}") / mean(CHOSEN[2000], f"rmse_{n}") - 1) < 0.05, n
    # the means over the 50 runs and the range of the means of five batches of 10, in percent, as stated
    stated = {SMALL_BETA_NOISE[2000]: (83, 75, 93), TUNED_SETTING: (97, 93, 100), SMALL_BETA_NOISE[500]: (17, 10, 32),
              CHOSEN[500]: (69, 60, 73)}
    for setting, numbers in stated.items():
        per_batch = batches(setting, "cover90_beta")
        found = (round(100 * mean(setting, "cover90_beta")), round(100 * per_batch.min()), round(100 * per_batch.max()))
        assert found == numbers, (setting.label, found, numbers)


@claim("reentry-pf/tuned-band-widens-early")
def _() -> None:
    """Tuned setting, N = 2000: in 30% to 70% of the study runs beta's 90% band is wider than the prior's at some
    whole second between 10 s and 18 s."""
    times = (study().width_times >= 10 - 1e-9) & (study().width_times <= 18 + 1e-9)
    wider = np.mean(study().runs[TUNED_SETTING]["width90_beta"][:, times].max(axis=1) > prior_band())
    assert 0.3 <= wider <= 0.7, wider
