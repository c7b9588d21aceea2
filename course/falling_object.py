"""Given code for the reentry-pf lab: a falling object tracked by an altitude radar.

The state is ``x = [h, v, beta]``: altitude h [m] above the ground, *downward* speed v [m/s]
(v > 0 while the object falls, so dh/dt = -v) and ballistic coefficient beta [kg/(m s^2)].
A particle cloud is an array of shape (3, N), one column per particle; its weights have shape
(N,). Equation numbers refer to the handout (Calvetti and Somersalo, Bayesian Scientific
Computing, Day 5 exercise).

This module holds what the handout gives you: the constants, the shipped radar data, a
container for the filter's history, and the figures. The figures and the report *take your
results as arguments*; nothing here implements a blank.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from course.tables import cell, number

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

Vector = NDArray[np.float64]
Matrix = NDArray[np.float64]

# --- The model, equations (1) to (5) -----------------------------------------------------------
G: float = 9.81  # acceleration due to gravity [m/s^2]
GAMMA: float = 1.754  # air density at the ground, rho(0) [kg/m^3]
ETA: float = 1.39e-4  # inverse scale height of the atmosphere [1/m]

# --- The radar and the time grid ---------------------------------------------------------------
DT: float = 0.1  # time between radar readings, and the Forward Euler step [s]
N_STEPS: int = 300  # readings b_0 .. b_T with T = 300: half a minute of tracking
SIGMA: float = 500.0  # standard deviation of the radar's altitude noise [m]
X0_TRUE: Vector = np.array([61_000.0, 3_048.0, 19_161.0])  # h_0 [m], v_0 [m/s], beta_* [kg/(m s^2)]

# --- The particle filter -----------------------------------------------------------------------
N_PARTICLES: int = 5000
V_INIT: float = 3000.0  # prior mean of the speed [m/s]
BETA_INIT: float = 20_000.0  # prior mean of the ballistic coefficient [kg/(m s^2)]
PRIOR_STD: Vector = np.array([500.0, 200.0, 1500.0])  # prior standard deviations of h, v, beta
INNOVATION_STD: Vector = np.array([100.0, 100.0, 5.0])  # innovation standard deviations, D^(1/2)
RUN_SEED: int = 2029  # seed of the lab's filter run, np.random.default_rng(RUN_SEED)

CHOSEN: tuple[float, float, float] = (10.0, 10.0, 50.0)  # the tuned artificial process noise of the lab's study
CHOSEN_STD: Vector = np.array(CHOSEN)


@dataclass(frozen=True)
class TuningSetting:
    """One setting of the tuning study: the filter ("auxiliary" = pf_step, "bootstrap"), N, and
    the standard deviations of the artificial process noise in h [m], v [m/s], beta [kg/(m s^2)]."""

    filter: str
    N: int
    innovation_std: tuple[float, float, float]

    @property
    def label(self) -> str:
        h, v, beta = self.innovation_std
        return f"{self.filter}, N = {self.N}, noise ({h:g}, {v:g}, {beta:g})"


HANDOUT_STD: tuple[float, float, float] = (100.0, 100.0, 5.0)
HANDOUT_SETTING = TuningSetting("auxiliary", N_PARTICLES, HANDOUT_STD)
"""The handout's setting: the auxiliary filter (pf_step), N = 5000, noise (100 m, 100 m/s, 5)."""
TUNED_SETTING = TuningSetting("auxiliary", 2000, CHOSEN)
"""The tuned setting: the auxiliary filter (pf_step), N = 2000, noise (10 m, 10 m/s, 50)."""
SETTING_NAMES: dict[TuningSetting, str] = {HANDOUT_SETTING: "the handout's setting", TUNED_SETTING: "the tuned setting"}
TUNING_SETTINGS: tuple[TuningSetting, ...] = (
    *(TuningSetting("auxiliary", 2000, (hv, hv, beta)) for beta in (5.0, 50.0) for hv in (3.0, 10.0, 30.0, 100.0)),
    TuningSetting("auxiliary", 500, HANDOUT_STD),
    TuningSetting("auxiliary", 5000, HANDOUT_STD),
    TuningSetting("auxiliary", 500, CHOSEN),
    TuningSetting("bootstrap", 2000, HANDOUT_STD),
    TuningSetting("bootstrap", 2000, CHOSEN),
    TuningSetting("auxiliary", 500, (10.0, 10.0, 5.0)),
)
"""The settings of the shipped tuning study (course/data/falling_object_tuning.csv)."""
TUNING_SEEDS: int = 50  # simulated half minutes per setting
SCORE_FROM: float = 20.0  # the study scores RMSE and coverage at the readings t_j >= SCORE_FROM [s]
WIDTH_EVERY: int = 10  # the study keeps the width of beta's 90% band at every 10th reading

STATE_NAMES: tuple[str, str, str] = ("h", "v", "beta")
STATE_LABELS: tuple[str, str, str] = ("altitude h [m]", "speed v [m/s]", r"ballistic coefficient $\beta$ [kg/(m s$^2$)]")

for _constant in (X0_TRUE, PRIOR_STD, INNOVATION_STD, CHOSEN_STD):
    _constant.setflags(write=False)

#: The data file shipped with the kit, built by the instructors' reference simulator from a seed.
DATA_FILE: Path = Path(__file__).resolve().parent / "data" / "falling_object_radar.csv"
CSV_HEADER: str = "t_s,h_true_m,v_true_m_per_s,beta_true_kg_per_m_s2,b_m"
#: The tuning study shipped with the kit (built by the instructors' data build, 50 seeds per setting).
TUNING_FILE: Path = DATA_FILE.parent / "falling_object_tuning.csv"


def time_grid(n_steps: int = N_STEPS, dt: float = DT) -> Vector:
    """The reading times t_j = j dt, j = 0..n_steps [s], shape (n_steps + 1,)."""
    return dt * np.arange(n_steps + 1)


# =============================================================================================
# Data
# =============================================================================================
@dataclass(frozen=True)
class RadarData:
    """Half a minute of radar tracking: the truth and the altitude readings at times t.

    ``t`` [s] and ``b`` [m] have shape (T + 1,); ``x_true`` has shape (3, T + 1), rows h [m],
    v [m/s] and beta [kg/(m s^2)].
    """

    t: Vector
    x_true: Matrix
    b: Vector
    sigma: float = SIGMA

    def __post_init__(self) -> None:
        n = self.t.shape[0]
        if self.t.shape != (n,) or self.b.shape != (n,) or self.x_true.shape != (3, n):
            raise ValueError(
                f"RadarData needs t (n,), x_true (3, n) and b (n,); got {self.t.shape}, "
                f"{self.x_true.shape} and {self.b.shape}."
            )


def format_radar_csv(t: Vector, x_true: Matrix, b: Vector) -> str:
    """The kit's CSV text for radar data: one row per reading, fixed decimals.

    Fixed decimals (0.1 s, 1 micrometre, 1 micrometre per second) make the file independent
    of the last bits of floating point, so a rebuild reproduces it byte for byte.
    """
    lines = [CSV_HEADER]
    for j in range(t.shape[0]):
        h, v, beta = x_true[:, j]
        lines.append(f"{t[j]:.1f},{h:.6f},{v:.6f},{beta:.6f},{b[j]:.6f}")
    return "\n".join(lines) + "\n"


def load(path: str | Path | None = None) -> RadarData:
    """Load the shipped radar data (301 readings, t = 0, 0.1, ..., 30 s)."""
    table = np.loadtxt(DATA_FILE if path is None else path, delimiter=",", skiprows=1, ndmin=2)
    return RadarData(t=table[:, 0], x_true=table[:, 1:4].T.copy(), b=table[:, 4].copy())


# --- The tuning study -------------------------------------------------------------------------
TUNING_COLUMNS: tuple[str, ...] = (
    "filter", "N", "std_h", "std_v", "std_beta", "seed",
    "rmse_h", "rmse_v", "rmse_beta", "cover50_h", "cover50_v", "cover50_beta", "cover90_h", "cover90_v", "cover90_beta",
    "roots_end", "lo90_v_end",
)


def format_tuning_csv(rows: list[dict]) -> str:
    """The kit's CSV text of the tuning study: one row per run (setting, seed), fixed decimals,
    then the width of beta's 90% band at every WIDTH_EVERY-th reading."""
    n_widths = rows[0]["width90_beta"][::WIDTH_EVERY].shape[0] if rows else 0
    lines = [",".join(TUNING_COLUMNS + tuple(f"width90_beta_{WIDTH_EVERY * i}" for i in range(n_widths)))]
    for row in rows:
        setting = row["setting"]
        fields = [setting.filter, str(setting.N), *(f"{value:g}" for value in setting.innovation_std), str(row["seed"])]
        fields += [f"{value:.3f}" for value in row["rmse"]]
        fields += [f"{value:.6f}" for value in (*row["cover50"], *row["cover90"])]
        fields += [f"{row['roots']:.0f}", f"{row['lo90_v_end']:.3f}"] + [f"{value:.3f}" for value in row["width90_beta"][::WIDTH_EVERY]]
        lines.append(",".join(fields))
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class TuningStudy:
    """The shipped tuning study: for every setting, its runs on TUNING_SEEDS simulated half minutes.

    ``runs[setting]`` maps a column name of TUNING_COLUMNS (from "rmse_h" on) to an array over the
    seeds, and "width90_beta" to an array (seeds, times) at the times ``width_times`` [s].
    """

    runs: dict[TuningSetting, dict[str, Vector]]
    width_times: Vector

    def summary(self, setting: TuningSetting) -> dict[str, Vector]:
        """Means over the seeds of RMSE (3,) [m, m/s, kg/(m s^2)], coverage of the 50% and 90% bands (3,)."""
        run = self.runs[setting]
        return {key: np.array([np.mean(run[f"{key}_{n}"]) for n in STATE_NAMES]) for key in ("rmse", "cover50", "cover90")}


def load_tuning(path: str | Path | None = None) -> TuningStudy:
    """Load the shipped tuning study."""
    lines = Path(TUNING_FILE if path is None else path).read_text().splitlines()
    header = lines[0].split(",")
    n_fixed = len(TUNING_COLUMNS)
    groups: dict[TuningSetting, list[list[str]]] = {}
    for line in lines[1:]:
        fields = line.split(",")
        setting = TuningSetting(fields[0], int(fields[1]), (float(fields[2]), float(fields[3]), float(fields[4])))
        groups.setdefault(setting, []).append(fields)
    runs = {}
    for setting, rows in groups.items():
        table = np.array([[float(v) for v in row[5:]] for row in rows])
        run = {name: table[:, i] for i, name in enumerate(TUNING_COLUMNS[5:])}
        run["width90_beta"] = table[:, n_fixed - 5:]
        runs[setting] = run
    width_times = DT * np.array([int(name.rsplit("_", 1)[1]) for name in header[n_fixed:]])
    return TuningStudy(runs, width_times)


def format_tuning_table(study: TuningStudy, settings: tuple[TuningSetting, ...] = TUNING_SETTINGS,
                        ideal: dict[str, Vector] | None = None) -> str:
    """A table of the study: RMSE of h, v, beta (beta's with +- two standard errors of its mean over the
    seeds, and its paired difference from the handout's setting, run by run, with +- two standard errors
    of that difference: every setting runs on the same readings and filter seeds) and the coverage of
    the 50% and 90% bands, per setting; the two named settings (SETTING_NAMES) marked. With ``ideal``
    (from ideal_scores) a last row with what an exact posterior would score."""
    rows = [f"{'setting':<42}{'RMSE h [m]':>11}{'v [m/s]':>8}{'beta':>6}{'+-2se':>7}{'diff':>7}{'+-2se':>7}"
            f"{'in 50%: h':>10}{'v':>5}{'beta':>6}{'in 90%: h':>10}{'v':>5}{'beta':>6}"]
    named = []
    baseline = study.runs[HANDOUT_SETTING]["rmse_beta"]
    for setting in settings:
        betas = study.runs[setting]["rmse_beta"]
        spread = f"+-{2 * np.std(betas, ddof=1) / np.sqrt(betas.shape[0]):.0f}"
        if setting == HANDOUT_SETTING:
            paired = f"{'--':>7}{'':>7}"
        else:
            diff = betas - baseline
            paired = f"{np.mean(diff):>+7.0f}{'+-' + format(2 * np.std(diff, ddof=1) / np.sqrt(diff.shape[0]), '.0f'):>7}"
        named.append((setting.label, study.summary(setting), spread, paired, SETTING_NAMES.get(setting, "")))
    if ideal is not None:
        named.append(("exact posterior (linearised)", ideal, "", f"{'':>14}", ""))
    for label, m, spread, paired, name in named:
        rows.append(f"{label:<42}" + f"{m['rmse'][0]:>11.0f}{m['rmse'][1]:>8.0f}{m['rmse'][2]:>6.0f}{spread:>7}" + paired
                    + f"{m['cover50'][0]:>10.0%}{m['cover50'][1]:>5.0%}{m['cover50'][2]:>6.0%}"
                    + f"{m['cover90'][0]:>10.0%}{m['cover90'][1]:>5.0%}{m['cover90'][2]:>6.0%}"
                    + (f"  <- {name}" if name else ""))
    n = len(next(iter(study.runs.values()))["rmse_h"])
    rows.append(f"(means over {n} simulated half minutes per setting; RMSE and coverage over t = {SCORE_FROM:g} s to 30 s.")
    rows.append(" beta +-2se: two standard errors of the mean RMSE of beta over the runs, not the scatter between runs.")
    rows.append(" diff +-2se: the mean, run by run, of beta's RMSE minus the handout's setting's on the same readings,")
    rows.append(" with two standard errors of that mean: a difference is shown when its range excludes 0.)")
    return "\n".join(rows)


# =============================================================================================
# Given parts: the bootstrap filter's step, and the yardstick of beta (its linearised posterior sd)
# =============================================================================================
Dynamics = Callable[[float, np.ndarray], np.ndarray]


def bootstrap_step(
    x: Matrix,
    w: Vector,
    b_next: float,
    rng: np.random.Generator,
    dynamics: Dynamics,
    *,
    innovation_std: Vector = INNOVATION_STD,
    info: dict | None = None,
) -> tuple[Matrix, Vector]:
    """One step of the bootstrap filter (Gordon, Salmond and Smith 1993), for comparison with pf_step.

    Resample the cloud x (3, N) with its weights w (N,), propagate the parents with Forward Euler of
    ``dynamics`` (your tracking_dynamics), add the artificial process noise D^(1/2) e with
    D^(1/2) = diag(innovation_std), and weigh the new particles by the likelihood of the reading
    b_next [m] alone. Unlike pf_step, the resampling does not look ahead at b_next. ``info``, if a
    dict, receives the ESS of the resampling weights ("ess") and the parents' indices ("parents").
    """
    N = x.shape[1]
    # parents k_l drawn with replacement with probabilities w (multinomial resampling)
    cdf = np.cumsum(w)
    k = np.searchsorted(cdf / cdf[-1], np.sort(rng.random(N)), side="right")
    # x_new(l) = x(k_l) + dt f(x(k_l)) + D^(1/2) e(l),  e(l) ~ N(0, I_3)
    parents = x[:, k]
    x_new = parents + DT * dynamics(0.0, parents) + np.asarray(innovation_std)[:, None] * rng.standard_normal((3, N))
    # w(l) proportional to exp(-|x_new_1(l) - b_{j+1}|^2 / (2 sigma^2)), in logarithms
    log_w = -((x_new[0] - b_next) ** 2) / (2 * SIGMA**2)
    w_new = np.exp(log_w - np.max(log_w))
    if info is not None:
        info["ess"] = 1.0 / np.sum(np.asarray(w) ** 2)
        info["parents"] = k
    return x_new, w_new / np.sum(w_new)


def scripted_step(parents: list) -> Callable[..., tuple[Matrix, Vector]]:
    """A step for following run_particle_filter by hand: it moves no particle and changes no weight, and
    its k-th call reports ``parents[k]`` as the resampled indices (info["parents"]) and N as the ESS."""
    script = iter(parents)

    def step(x: Matrix, w: Vector, b_next: float, rng: np.random.Generator, innovation_std: Vector | None = None,
             info: dict | None = None) -> tuple[Matrix, Vector]:
        if info is not None:
            info["parents"], info["ess"] = np.asarray(next(script)), float(x.shape[1])
        return x, w

    return step


def state_sensitivities(dynamics: Dynamics, x0: Vector, t: Vector) -> NDArray[np.float64]:
    """Phi_j = dx(t_j) / dx0 of the noise-free model x' = f(x) (``dynamics``) from x0, shape (len(t), 3, 3),
    by central differences of tight ODE solves."""
    from scipy.integrate import solve_ivp

    t = np.asarray(t, dtype=float)
    x0 = np.asarray(x0, dtype=float)
    step = np.array([1.0, 0.1, 1.0])  # difference steps in h0 [m], v0 [m/s], beta [kg/(m s^2)]

    def states(start: Vector) -> Matrix:
        return solve_ivp(dynamics, (t[0], t[-1]), start, method="DOP853", t_eval=t, rtol=1e-12, atol=1e-9).y

    # column i: (x(x0 + d e_i) - x(x0 - d e_i)) / (2 d)
    return np.stack([(states(x0 + d * e) - states(x0 - d * e)) / (2 * d) for d, e in zip(step, np.eye(3))], axis=-1).transpose(1, 0, 2)


def _information(phi: NDArray[np.float64], sigma: float, prior_std: Vector) -> NDArray[np.float64]:
    """J_j = C^-1 + sum_{i=1..j} s_i s_i^T / sigma^2 for every j, s_i = dh_i / dx0 (row 0 of Phi_i)."""
    S = phi[:, 0, :].copy()
    S[0] = 0.0  # b_0 is already in the prior (h_init = b_0)
    return np.diag(1.0 / np.asarray(prior_std) ** 2) + np.cumsum(S[:, :, None] * S[:, None, :], axis=0) / sigma**2


def beta_linearised_sd(dynamics: Dynamics, x0: Vector, t: Vector, sigma: float = SIGMA, prior_std: Vector = PRIOR_STD) -> Vector:
    """The lab's yardstick: the posterior standard deviation of beta [kg/(m s^2)] after the readings
    b_1..b_j, for the model linearised at x0, for every t_j (shape (len(t),)).

    The noise-free model x' = f(x) (``dynamics``) from x0 makes the altitudes h_j(x0) a function of the
    initial state; their sensitivities s_j = dh_j / dx0 give the Fisher information of the readings,
    J_j = C^-1 + sum_{i=1..j} s_i s_i^T / sigma^2, with the prior covariance C = diag(prior_std^2)
    standing for what is known at t_0. Evaluated along the true trajectory (x0 = the truth),
    sqrt([J_j^-1]_33) is the posterior sd of the model linearised there (a Laplace approximation). It is
    not a bound at that truth; the Van Trees bound, a floor for the error averaged over the prior,
    averages the readings' information over prior draws of x0 instead. It knows nothing of the
    filter's artificial process noise.
    """
    J = _information(state_sensitivities(dynamics, x0, t), sigma, prior_std)
    # [J^-1]_33 by solving J y = e_3
    return np.sqrt(np.linalg.solve(J, np.broadcast_to([0.0, 0.0, 1.0], (J.shape[0], 3))[..., None])[:, 2, 0])


def _mean_run_rmse(phi: NDArray[np.float64], J: NDArray[np.float64], prior_std: Vector, fixed: Vector, sigma: float,
                   scored: NDArray[np.bool_], draws: int = 4000) -> Vector:
    """The exact posterior's RMSE in the study's metric: the mean over ``draws`` simulated runs of each run's RMSE
    over the scored t_j (not the root of the mean squared error, which is larger). A run draws the readings'
    noise e_0..e_T; its x0 error after b_1..b_j is J_j^-1 (C^-1 d + sum_{i<=j} s_i e_i / sigma), with the
    prior's h offset d_h = sigma e_0 (h_init = b_0) and ``fixed`` the rest of C^-1 d. Seeded: the same on
    every call."""
    e = np.random.default_rng(0).standard_normal((draws, phi.shape[0]))
    S = phi[:, 0, :].copy()
    S[0] = 0.0
    # u_j = C^-1 d + sum_{i<=j} s_i e_i / sigma, with C^-1 d = fixed + [sigma e_0 / prior_std_h^2, 0, 0]
    u = np.cumsum(e[:, :, None] * S[None] / sigma, axis=1) + fixed
    u[:, :, 0] += sigma * e[:, :1] / np.asarray(prior_std)[0] ** 2
    error0 = np.linalg.solve(J[None, scored], u[:, scored, :, None])[..., 0]
    error = np.einsum("jab,njb->nja", phi[scored], error0)
    return np.mean(np.sqrt(np.mean(error**2, axis=1)), axis=0)


def ideal_scores(
    dynamics: Dynamics, x0: Vector, t: Vector, score_from: float = SCORE_FROM, sigma: float = SIGMA,
    prior_std: Vector = PRIOR_STD, prior_mean: tuple[float, float] = (V_INIT, BETA_INIT),
) -> dict[str, Vector]:
    """What an exact posterior would score in the tuning study: the RMSE (3,) of its mean in the table's metric
    (the mean over runs of each run's RMSE, "rmse"; the root of the mean squared error as "rms") and the
    expected coverage of its 50% and 90% bands (3,) for h, v, beta, over the readings t_j >= score_from.

    The posterior is the exact one of the noise-free model x' = f(x) (``dynamics``), linearised at the
    truth x0, with the lab's prior (h_init = b_0; v and beta at ``prior_mean``). Its error
    x0_hat - x0 = J^-1 (C^-1 d + sum_i s_i e_i / sigma) has the fixed part mu = J^-1 C^-1 d, with d the
    prior mean's offset from the truth, and a random part of covariance R = J^-1 (J - C_vb^-1) J^-1
    (C_vb^-1: the prior precision of v and beta, whose means are not random). At t_j the error is
    Phi_j times that, and the band mean +- z sd holds the truth with probability
    Phi((z sd - m) / s) - Phi((-z sd - m) / s). Means over the scored t_j, as in the study.
    """
    from scipy.stats import norm

    t = np.asarray(t, dtype=float)
    phi = state_sensitivities(dynamics, x0, t)
    J = _information(phi, sigma, prior_std)
    phi_all = phi
    prior_precision = np.diag(1.0 / np.asarray(prior_std) ** 2)
    d = np.array([0.0, prior_mean[0] - x0[1], prior_mean[1] - x0[2]])
    fixed_precision = np.diag([0.0, *np.diag(prior_precision)[1:]])
    # mu_j = J_j^-1 C^-1 d,  R_j = J_j^-1 (J_j - C_vb^-1) J_j^-1,  P_j = J_j^-1 (the posterior covariance of x0)
    P = np.linalg.inv(J)
    mu = P @ (prior_precision @ d)
    R = P @ (J - fixed_precision) @ P
    scored = t >= score_from - 1e-9
    phi, P, mu, R = phi[scored], P[scored], mu[scored], R[scored]
    # at t_j: mean error m = Phi mu, posterior variance Phi P Phi^T, random part's variance Phi R Phi^T
    m = np.einsum("jab,jb->ja", phi, mu)
    sd = np.sqrt(np.einsum("jab,jbc,jac->ja", phi, P, phi))
    s = np.sqrt(np.einsum("jab,jbc,jac->ja", phi, R, phi))
    # "rmse" in the table's metric (the mean of each run's RMSE); "rms": the root of the mean squared error
    scores = {"rmse": _mean_run_rmse(phi_all, J, prior_std, prior_precision @ d, sigma, scored),
              "rms": np.sqrt(np.mean(m**2 + s**2, axis=0))}
    for level in (50, 90):
        a = norm.ppf(0.5 + level / 200) * sd
        scores[f"cover{level}"] = np.mean(norm.cdf((a - m) / s) - norm.cdf((-a - m) / s), axis=0)
    return scores


# =============================================================================================
# Weighted credibility intervals
# =============================================================================================
def credibility_interval(samples: Vector, weights: Vector, p: float | Vector) -> tuple[Vector, Vector]:
    """The central p% credibility interval [lo, hi] of weighted samples, p in percent.

    samples (N,) and weights (N,) (non-negative, not all zero, not necessarily normalised) describe one
    variable of the cloud; p is a number or an array of numbers in [0, 100], and lo, hi have its shape.
    The interval runs between the weighted quantiles of orders (1 - p/100)/2 and (1 + p/100)/2, where
    the quantile of order a is the smallest sample whose cumulative weight, in sorted order, reaches a.
    p = 0 gives the weighted median twice.
    """
    order = np.argsort(samples)
    s = samples[order]
    # F_i = sum of the weights of the i smallest samples, normalised so that F_N = 1
    cdf = np.cumsum(weights[order])
    cdf = cdf / cdf[-1]
    # orders of the lower and upper quantiles: (1 -+ p/100) / 2
    a_lo, a_hi = 0.5 - np.asarray(p) / 200, 0.5 + np.asarray(p) / 200
    # q(a) = s_i with the smallest i such that F_i >= a (clamped to the last sample)
    last = s.shape[0] - 1
    return s[np.minimum(np.searchsorted(cdf, a_lo), last)], s[np.minimum(np.searchsorted(cdf, a_hi), last)]


# =============================================================================================
# The filter's history
# =============================================================================================
HISTORY_FIELDS: tuple[str, ...] = ("mean", "median", "lo50", "hi50", "lo90", "hi90", "ess", "ess_resample", "parents", "roots")
"""The fields of a FilterHistory that a run fills in."""


@dataclass
class FilterHistory:
    """What the particle filter reports at every reading time t_j, j = 0..T.

    Rows of every (3, T + 1) array are h [m], v [m/s] and beta [kg/(m s^2)]:

    - ``mean``: the weighted mean of the particles, sum_l w_l x_l;
    - ``median``: the weighted median of the particle values;
    - ``lo50``, ``hi50`` and ``lo90``, ``hi90``: the weighted 50% and 90% credibility intervals;
    - ``ess`` (T + 1,): the effective sample size 1 / sum_l w_l^2 of the weights after the step;
    - ``ess_resample`` (T + 1,): the effective sample size of the weights the step resampled with
      (the fitness weights of the auxiliary filter, the previous weights of the bootstrap filter);
    - ``parents`` (T + 1,): the number of distinct parents the resampling drew;
    - ``roots`` (T + 1,): the number of particles of t_0 that still have descendants.

    At t_0 nothing has been resampled: ``ess_resample``, ``parents`` and ``roots`` are N there.

    ``FilterHistory.empty(n)`` makes one filled with NaN, for a run to fill in.
    """

    mean: Matrix
    median: Matrix
    lo50: Matrix
    hi50: Matrix
    lo90: Matrix
    hi90: Matrix
    ess: Vector
    ess_resample: Vector
    parents: Vector
    roots: Vector
    n_particles: int = field(default=0)

    @classmethod
    def empty(cls, n_times: int, n_particles: int = 0) -> FilterHistory:
        """A history for ``n_times`` reading times, every entry NaN until the run fills it."""

        def nan(*shape: int) -> NDArray[np.float64]:
            return np.full(shape, np.nan)

        return cls(
            mean=nan(3, n_times),
            median=nan(3, n_times),
            lo50=nan(3, n_times),
            hi50=nan(3, n_times),
            lo90=nan(3, n_times),
            hi90=nan(3, n_times),
            ess=nan(n_times),
            ess_resample=nan(n_times),
            parents=nan(n_times),
            roots=nan(n_times),
            n_particles=n_particles,
        )

    @property
    def n_times(self) -> int:
        return int(self.ess.shape[0])

    def missing(self) -> list[str]:
        """Names of the fields that still hold NaN (not filled in at every time)."""
        return [name for name in HISTORY_FIELDS if not np.all(np.isfinite(getattr(self, name)))]


class HelperMisused(ValueError):
    """A given helper was called in a way that cannot give the right numbers; the message says how to call it."""


class RecordedOutOfOrder(HelperMisused):
    """ResamplingHealth.record was not called once at every t_j, in order (made afresh inside the loop, twice, ...)."""


class InfoNotFilled(HelperMisused):
    """ResamplingHealth.record got a dict that the step to t_j did not fill (called before the step, or another dict)."""


class ResamplingHealth:
    """Follows the resampling of one particle-filter run and records its health in a FilterHistory.

    Make one per run, before the loop, ``health = ResamplingHealth(N)``, and call ``health.record(history, j,
    info)`` once at every reading time t_j, in order, after the step to t_j (at t_0 there is no step, and
    ``info`` is not read; you may also fill t_0 yourself and start at j = 1). It fills
    ``history.ess_resample[j]`` with ``info["ess"]``, ``history.parents[j]`` with the number of distinct
    indices in ``info["parents"]``, and ``history.roots[j]`` with the number of particles of t_0 that still
    have descendants in the cloud at t_j. At t_0 all three are N. A call that cannot give the right numbers
    (twice for one t_j, a time skipped, a dict that the step did not fill, the wrong N) raises HelperMisused,
    saying why.
    """

    def __init__(self, n_particles: int) -> None:
        # root[l]: the particle of t_0 that particle l descends from
        self.root = np.arange(n_particles)
        self.last_j: int | None = None

    def record(self, history: FilterHistory, j: int, info: Mapping | None = None) -> None:
        """Record the resampling of the step to t_j (j > 0) in ``history``, or N three times at j = 0."""
        n = self.root.size
        if self.last_j is not None and j == self.last_j:
            raise RecordedOutOfOrder(f"health.record(history, {j}, info) was called twice for t_{j}: call it once at "
                                     "every t_j, after the step to t_j.")
        if j == 0:
            if self.last_j is not None:
                raise RecordedOutOfOrder("health.record(history, 0, ...) came after later times: make one "
                                         "ResamplingHealth(N) per run, before the loop, and record t_0 first.")
            history.ess_resample[0] = history.parents[0] = history.roots[0] = n
            self.last_j = 0
            return
        if (self.last_j is None and j > 1) or (self.last_j is not None and j != self.last_j + 1):
            seen = "nothing yet" if self.last_j is None else f"t_{self.last_j} last"
            raise RecordedOutOfOrder(
                f"health.record(history, {j}, info) on a ResamplingHealth that has recorded {seen}: make one "
                "ResamplingHealth(N) before the loop (not inside it), and call record once at every t_j, in order."
            )
        if not isinstance(info, Mapping) or "parents" not in info or "ess" not in info:
            raise InfoNotFilled(
                f"health.record(history, {j}, info) got a dict without info['ess'] and info['parents']: pass this same "
                f"dict to the step as info=info (not a new one), and call record after the step to t_{j}."
            )
        parents = np.asarray(info["parents"])
        if parents.shape != (n,):
            raise HelperMisused(
                f"info['parents'] has shape {parents.shape}, but this ResamplingHealth was made for {n} particles: "
                "make it with the run's N, ResamplingHealth(N). (If N is right, the step should store one parent "
                "index per particle.)"
            )
        # particle l's new parent is k_l, and its root is that parent's root
        self.root = self.root[parents]
        self.last_j = j
        history.ess_resample[j] = info["ess"]
        history.parents[j] = np.unique(parents).size
        history.roots[j] = np.unique(self.root).size


def history_is_per_variable(name: str) -> bool:
    """Whether a FilterHistory field has one row per state variable, (3, T + 1), or is (T + 1,)."""
    return name in ("mean", "median", "lo50", "hi50", "lo90", "hi90")


def check_history(history: object, n_times: int, n_particles: int) -> None:
    """Visible check of a run's FilterHistory: its type, every entry filled, bands that nest
    (lo90 <= lo50 <= median <= hi50 <= hi90) and an ESS between 1 and N. Raises AssertionError
    with a message that says what to fix."""
    if not isinstance(history, FilterHistory):
        raise AssertionError(
            f"run_particle_filter should return a FilterHistory (FilterHistory.empty(len(b), N), filled in), "
            f"not {type(history).__name__}."
        )
    for name in HISTORY_FIELDS:
        value = np.asarray(getattr(history, name))
        shape = (3, n_times) if history_is_per_variable(name) else (n_times,)
        if value.shape != shape:
            raise AssertionError(f"history.{name} should have shape {shape}, one column per reading; it has {value.shape}.")
        if not np.all(np.isfinite(value)):
            missing = np.flatnonzero(~np.all(np.isfinite(value.reshape(-1, n_times)), axis=0))
            at_start = " (at t_0, call health.record(history, 0, info) too)" if (
                name in ("ess_resample", "parents", "roots") and missing[0] == 0) else ""
            raise AssertionError(f"history.{name} is not filled in at the times j = {missing[:8].tolist()}: fill it at "
                                 f"every t_j{at_start}.")
    order = (history.lo90, history.lo50, history.median, history.hi50, history.hi90)
    labels = ("lo90", "lo50", "median", "hi50", "hi90")
    for k in range(4):
        if np.any(order[k] > order[k + 1]):
            raise AssertionError(
                f"history.{labels[k]} exceeds history.{labels[k + 1]} somewhere: the 90% band should contain the 50% "
                "band, which contains the median. Did you sort the samples, and use p = 50 and p = 90 the right way round?"
            )
    for name in ("ess", "ess_resample", "parents", "roots"):
        value = getattr(history, name)
        if np.any(value < 1 - 1e-9) or np.any(value > n_particles * (1 + 1e-9)):
            raise AssertionError(
                f"history.{name} should lie between 1 and N = {n_particles}; it ranges from {np.min(value):.3g} to "
                f"{np.max(value):.3g}. ESS = 1 / sum_l w_l^2 with normalised weights; parents and roots count distinct indices. "
                "(If that is what you record, check that initial_cloud and the step return weights that sum to 1.)"
            )
    if np.any(np.diff(history.roots) > 0):
        raise AssertionError(
            "history.roots grows somewhere: a particle of t_0 that has lost all its descendants cannot get them back. "
            "Call health.record(history, j, info) exactly once at every t_j, after the step to t_j."
        )


def _require_complete(history: FilterHistory, n_times: int) -> None:
    if not isinstance(history, FilterHistory):
        raise TypeError(f"Expected a FilterHistory (from run_particle_filter), got {type(history).__name__}.")
    if history.n_times != n_times:
        raise ValueError(f"The history covers {history.n_times} times, but the data has {n_times} readings.")
    missing = history.missing()
    if missing:
        raise ValueError(f"The history still has NaN entries in {', '.join(missing)}: fill them at every time t_j.")


# =============================================================================================
# Report and figures
# =============================================================================================
def coverage(data: RadarData, history: FilterHistory) -> dict[str, Vector]:
    """The fraction of the reading times t_1..t_T at which the truth lies inside each band (t_0, where
    the cloud is the prior, is left out, as in the tuning study).

    Returns ``{"50": (3,), "90": (3,)}``, one fraction per state variable (h, v, beta).
    """
    _require_complete(history, data.t.shape[0])
    x, j = data.x_true[:, 1:], slice(1, None)
    return {
        "50": np.mean((history.lo50[:, j] <= x) & (x <= history.hi50[:, j]), axis=1),
        "90": np.mean((history.lo90[:, j] <= x) & (x <= history.hi90[:, j]), axis=1),
    }


def format_report(data: RadarData, history: FilterHistory) -> str:
    """A table of the final estimates and their 90% intervals, at the last reading, and the scores of the
    whole run: the RMSE of the weighted mean over t_0..t_T and the band coverage over t_1..t_T (the tuning
    study scores only t >= SCORE_FROM; the headings and the last lines say which window is which)."""
    _require_complete(history, data.t.shape[0])
    cover = coverage(data, history)
    whole = f"{data.t[0]:g}-{data.t[-1]:g} s"
    rows = [
        f"{'':<8}{'at the last reading, t = ' + format(data.t[-1], '.1f') + ' s':^57}{'whole run, t = ' + whole:^30}",
        f"{'':<8}{'truth':>11}{'mean':>11}{'median':>11}"
        f"{'90% interval':>24}{'RMSE of mean':>14}{'in 50%':>8}{'in 90%':>8}",
    ]
    for i, name in enumerate(STATE_NAMES):
        rmse = float(np.sqrt(np.mean((history.mean[i] - data.x_true[i]) ** 2)))
        interval = f"[{number(history.lo90[i, -1], '.0f', 9)}, {number(history.hi90[i, -1], '.0f', 9)}]"
        rows.append(
            f"{name:<8}{cell(data.x_true[i, -1], 11, '.0f')}{cell(history.mean[i, -1], 11, '.0f')}"
            f"{cell(history.median[i, -1], 11, '.0f')}{interval:>24}{cell(rmse, 14, '.1f')}"
            f"{cell(cover['50'][i], 8, '.0%')}{cell(cover['90'][i], 8, '.0%')}"
        )
    rmse_radar = float(np.sqrt(np.mean((data.b - data.x_true[0]) ** 2)))
    rows.append(f"(RMSE and coverage over the whole run, t = {whole}; the study's table of section 8 scores only "
                f"t = {SCORE_FROM:g}-{data.t[-1]:g} s,")
    rows.append(f" so its numbers differ from these. The raw radar readings have an altitude RMSE of {rmse_radar:.1f} m.)")
    return "\n".join(row.rstrip() for row in rows)


def print_report(data: RadarData, history: FilterHistory) -> None:
    """Print ``format_report``."""
    print(format_report(data, history))


def print_beta_band(data: RadarData, history: FilterHistory, yardstick: Vector, every: float = 5.0) -> None:
    """Print, every ``every`` seconds, the width of the run's 90% band of beta, the width of an exact
    posterior's 90% band (2 x 1.645 x the yardstick), the prior's (2 x 1.645 x 1500), the ratio of the
    run's band to the yardstick's, and the run's roots (particles of t_0 with descendants)."""
    _require_complete(history, data.t.shape[0])
    print("   t   90% band of beta:  this run   yardstick's   prior's   run / yardstick   roots")
    for t_j in np.arange(0.0, data.t[-1] - data.t[0] + 1e-9, every):
        j = int(round(t_j / DT))
        band, ideal = history.hi90[2, j] - history.lo90[2, j], 2 * Z90 * yardstick[j]
        print(f"{t_j:4.0f} s {band:22.0f} {ideal:13.0f} {2 * Z90 * PRIOR_STD[2]:9.0f} {band / ideal:17.1f} "
              f"{history.roots[j]:7.0f}")


def plot_tracking(data: RadarData, history: FilterHistory, title: str = "", yardstick: Vector | None = None) -> NDArray[np.object_]:
    """The show and tell: h, v and beta against time with the truth, weighted mean, weighted
    median and the 50% and 90% credibility bands. With ``yardstick`` (the linearised posterior sd of
    beta at every t_j, from beta_linearised_sd), the beta panels also show the truth +- 1.645
    yardstick: a curve of the width of an exact posterior's 90% band (an ideal band is centred on its estimate, not on the truth, so
    only the widths compare).

    Altitude and speed change by tens of kilometres and kilometres per second, while the bands
    are a few hundred metres wide, so the top row shows the values and the bottom row shows
    the same curves minus the truth. Returns the 2 x 3 array of Axes.
    """
    import matplotlib.pyplot as plt

    _require_complete(history, data.t.shape[0])
    t = data.t
    fig, axes = plt.subplots(2, 3, figsize=(15, 7.5), sharex=True, layout="constrained")
    for i, (name, label) in enumerate(zip(STATE_NAMES, STATE_LABELS)):
        for row, offset in ((0, 0.0), (1, data.x_true[i])):
            ax = axes[row, i]
            ax.fill_between(t, history.lo90[i] - offset, history.hi90[i] - offset, color="C0", alpha=0.18, lw=0, label="90% band")
            ax.fill_between(t, history.lo50[i] - offset, history.hi50[i] - offset, color="C0", alpha=0.38, lw=0, label="50% band")
            if i == 0:
                ax.plot(t, data.b - offset, ".", color="0.55", ms=2.5, label="radar reading $b_j$")
            ax.plot(t, data.x_true[i] - offset, color="k", lw=1.6, label="truth")
            ax.plot(t, history.mean[i] - offset, color="C3", lw=1.3, label="weighted mean")
            ax.plot(t, history.median[i] - offset, color="C1", lw=1.1, ls="--", label="weighted median")
            ax.grid(alpha=0.3)
        if i == 2 and yardstick is not None:
            for row, offset in ((0, 0.0), (1, data.x_true[2])):
                for sign in (-1, 1):
                    axes[row, 2].plot(t, data.x_true[2] - offset + sign * Z90 * yardstick, color="C4", lw=1.4, ls=":",
                                      label=r"truth $\pm$ 1.645 $\times$ yardstick (linearised posterior sd)" if sign < 0 else None)
        axes[0, i].set_title(f"{name}: estimate and truth")
        axes[0, i].set_ylabel(label)
        axes[1, i].set_title(f"{name} minus the truth")
        axes[1, i].set_ylabel(f"error in {label}")
        axes[1, i].set_xlabel("time t [s]")
    axes[1, 0].set_ylim(-4 * data.sigma, 4 * data.sigma)
    axes[0, 0].legend(loc="upper right", fontsize=8)
    axes[1, 2].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    n = f", N = {history.n_particles} particles" if history.n_particles else ""
    fig.suptitle(title or f"Particle filter tracking of the falling object{n}")
    return axes


def plot_health(data: RadarData, histories: Mapping[str, FilterHistory]) -> NDArray[np.object_]:
    """The health of the resampling, one curve per run: the effective sample size of the weights
    each step resampled with, the number of distinct parents each resampling drew, and the number
    of particles of t_0 that still have descendants (log scale). Returns the 3 Axes."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4), layout="constrained")
    for (label, history), colour in zip(histories.items(), ("C0", "C3", "C2", "C1")):
        _require_complete(history, data.t.shape[0])
        axes[0].plot(data.t[1:], history.ess_resample[1:], color=colour, lw=1.2, label=label)
        axes[1].plot(data.t[1:], history.parents[1:], color=colour, lw=1.2, label=label)
        axes[2].semilogy(data.t, history.roots, color=colour, lw=1.4, label=label)
    titles = ("ESS of the weights used to resample", "Distinct parents drawn by each resampling",
              "Particles of $t_0$ with descendants left")
    ylabels = ("ESS before resampling [particles]", "distinct parents [particles]", "surviving ancestors [particles]")
    for ax, title, ylabel in zip(axes, titles, ylabels):
        ax.set_title(title)
        ax.set_xlabel("time t [s]")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    for ax in axes[:2]:
        ax.set_ylim(0, 1.05 * max(h.n_particles for h in histories.values()))
    # the no-information baseline: multinomial resampling with equal weights keeps 1 - 1/e of N as
    # distinct parents per step, and n such steps leave about 2N / (n + 2) roots (pure genetic drift).
    # Both assume multinomial resampling: systematic resampling of equal weights keeps every particle.
    for N in sorted({h.n_particles for h in histories.values()}):
        n = np.arange(data.t.shape[0])
        axes[1].axhline((1 - np.exp(-1)) * N, color="0.3", lw=1.0, ls="--",
                        label=f"multinomial resampling of equal weights: (1 - 1/e) N = {(1 - np.exp(-1)) * N:.0f}")
        axes[2].semilogy(data.t, 2 * N / (n + 2), color="0.3", lw=1.0, ls="--", label="multinomial, equal weights: 2N / (n + 2) roots after n steps")
    # one legend below the panels, so that it covers no curve: the runs, then each baseline once
    labelled = {label: handle for ax in axes for handle, label in zip(*ax.get_legend_handles_labels())}
    fig.legend(labelled.values(), labelled.keys(), loc="outside lower center", ncol=len(labelled), fontsize=9)
    fig.suptitle("Health of the particle filter: resampling weights, parents and ancestry")
    return axes


Z90: float = 1.6448536269514722
"""The 95% point of the standard normal: a Gaussian's 90% band is the mean +- Z90 standard deviations."""


def plot_band_widths(study: TuningStudy, settings: list[TuningSetting], t: Vector, yardstick: Vector, ax: Axes | None = None) -> Axes:
    """The width of beta's 90% band against time over the study's seeds, one colour per setting:
    the median over the seeds and the band from the 10th to the 90th percentile. The width of an exact
    posterior's band, 2 x 1.645 x yardstick (the linearised posterior sd at the times t), and the prior's
    90% band are drawn for comparison."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(9, 4.2), layout="constrained")
    for setting, colour in zip(sorted(settings, key=lambda s: s.N), ("C0", "C1", "C2", "C3", "C5")):
        widths = study.runs[setting]["width90_beta"]
        low, mid, high = np.percentile(widths, [10, 50, 90], axis=0)
        ax.fill_between(study.width_times, low, high, color=colour, alpha=0.2, lw=0)
        ax.plot(study.width_times, mid, color=colour, lw=1.6, label=f"{setting.label}: median, 10-90% of {widths.shape[0]} seeds")
    ax.plot(t, 2 * Z90 * yardstick, color="C4", lw=1.6, ls=":", label=r"2 $\times$ 1.645 $\times$ yardstick (linearised posterior sd)")
    prior = 2 * Z90 * PRIOR_STD[2]
    ax.axhline(prior, color="k", lw=0.8, ls="--", label=f"prior 90% band ({prior:.0f})")
    ax.set_ylim(bottom=0)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel(r"width of the 90% band of $\beta$ [kg/(m s$^2$)]")
    ax.set_title(r"How fast does the filter learn $\beta$? Width of the 90% band over many seeds")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=8)  # below the axes: covers no band
    return ax


def plot_tuning(study: TuningStudy, settings: tuple[TuningSetting, ...] = TUNING_SETTINGS,
                ideal: dict[str, Vector] | None = None) -> NDArray[np.object_]:
    """Calibration of every setting: for h, v and beta, the fraction of the scored time (t >= SCORE_FROM)
    the truth lies in the 50% band (open circles) and the 90% band (squares), mean over the seeds with
    +- 2 standard errors. Left of the dotted line at 50% or 90%, the bands are too narrow
    (over-confident); right of it, too wide (under-confident). With ``ideal`` (from ideal_scores), a
    green line marks what an exact posterior would score. Returns the 3 Axes."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 0.42 * len(settings) + 1.8), sharey=True, layout="constrained")
    rows = np.arange(len(settings))[::-1]
    for i, (ax, name) in enumerate(zip(axes, STATE_NAMES)):
        for level, marker in (("50", "o"), ("90", "s")):
            runs = [study.runs[s][f"cover{level}_{name}"] for s in settings]
            mean = np.array([np.mean(r) for r in runs])
            error = np.array([2 * np.std(r, ddof=1) / np.sqrt(r.shape[0]) for r in runs])
            ax.errorbar(mean, rows, xerr=error, fmt=marker, mfc="white" if level == "50" else "C0", color="C0", ms=6,
                        label=f"truth in the {level}% band")
            ax.axvline(int(level) / 100, color="k", lw=0.9, ls=":")
            if ideal is not None:
                ax.axvline(ideal[f"cover{level}"][i], color="C2", lw=1.2, alpha=0.8,
                           label="exact posterior, expected" if level == "90" else None)
        ax.set_xlim(0, 1.02)
        ax.set_xlabel(f"fraction of t = {SCORE_FROM:g}-30 s the truth of {name} is inside")
        ax.set_title(f"{name}: coverage of the bands")
        ax.grid(alpha=0.3, axis="x")
    axes[0].set_yticks(rows, [s.label + (f" ({SETTING_NAMES[s][4:]})" if s in SETTING_NAMES else "") for s in settings], fontsize=8)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=9)
    fig.suptitle("Which settings are over-confident (left of the dotted lines) or under-confident (right)?")
    return axes
