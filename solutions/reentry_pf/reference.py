"""Reference solution of the reentry-pf lab (Calvetti and Somersalo, Day 5 exercise).

Notation follows the handout: x = [h, v, beta] with h' = -v, v' = g - g rho(h) v^2 / (2 beta),
beta' = 0 (equation (5)); b_j = x_1(t_j) + eps_j the radar readings; a particle cloud is an
array of shape (3, N), one column per particle x^(l), with weights w of shape (N,). Each
function here is the model answer of one blank, and the lab's answer cell holds the same code.

Instructors: ``python -m solutions.reentry_pf.reference`` rebuilds the shipped data from DATA_SEED.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from course import falling_object
from course.falling_object import (
    BETA_INIT,
    DT,
    ETA,
    GAMMA,
    INNOVATION_STD,
    PRIOR_STD,
    SIGMA,
    V_INIT,
    FilterHistory,
    G,
    ResamplingHealth,
    credibility_interval,
)

DATA_SEED = 20191205
"""Seed of the shipped radar data (course/data/falling_object_radar.csv)."""


def tracking_dynamics(t: float, x: np.ndarray) -> np.ndarray:
    """The right-hand side f(x) of equation (5); t [s] is unused (the model is autonomous).

    x has shape (3,) for one state or (3, N) for a particle cloud; rows h [m], v [m/s] (down),
    beta [kg/(m s^2)]. Returns dx/dt of the same shape, in [m/s, m/s^2, kg/(m s^3)].
    """
    h, v, beta = np.asarray(x, dtype=float)
    # rho(h) = gamma exp(-eta h)   (4)
    rho = GAMMA * np.exp(-ETA * h)
    # dh/dt = -v   (1);   dv/dt = g - g rho(h) v^2 / (2 beta)   (2);   dbeta/dt = 0   (3)
    return np.stack([-v, G - G * rho * v**2 / (2 * beta), np.zeros_like(beta)])


def simulate_radar(
    x0: np.ndarray, t: np.ndarray, sigma: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Noiseless truth x_true (3, len(t)) at the times t [s], from x0 (3,), and altitude
    readings b (len(t),) [m] with noise of standard deviation sigma [m].

    Tolerances: rtol = 1e-10 makes the truth accurate to about 1e-5 m and 1e-5 m/s, eight
    orders of magnitude below the 500 m radar noise, so the truth is exact for every comparison
    in the lab (ode45's default rtol = 1e-3 would be off by about 20 m and 6 m/s). atol = 1e-8
    only matters for components near zero. The whole solve costs about 650 evaluations of f.
    """
    t = np.asarray(t, dtype=float)
    # x' = f(x), x(t_0) = x0, solved with RK45 (ode45) and reported at every t_j
    solution = solve_ivp(
        tracking_dynamics, (t[0], t[-1]), np.asarray(x0, dtype=float), method="RK45", t_eval=t, rtol=1e-10, atol=1e-8
    )
    if not solution.success:
        raise RuntimeError(f"solve_ivp failed: {solution.message}")
    x_true = solution.y
    # b_j = q^T x(t_j) + sigma e_j,  q = [1, 0, 0],  e ~ N(0, I) drawn in one call
    b = x_true[0] + sigma * rng.standard_normal(t.shape[0])
    return x_true, b


def initial_cloud(b0: float, N: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The prior particle cloud x (3, N) around [b0, v_init, beta_init], and equal weights w (N,)."""
    mean = np.array([b0, V_INIT, BETA_INIT])
    # x^(l) = [h_init, v_init, beta_init] + C^(1/2) z^(l),  z^(l) ~ N(0, I_3),  C^(1/2) = diag(PRIOR_STD)
    x = mean[:, None] + PRIOR_STD[:, None] * rng.standard_normal((3, N))
    # w^(l) = 1 / N
    w = np.full(N, 1.0 / N)
    return x, w


def pf_step(
    x: np.ndarray,
    w: np.ndarray,
    b_next: float,
    rng: np.random.Generator,
    *,
    innovation_std: np.ndarray = INNOVATION_STD,
    info: dict | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """One step (a) to (d) of the auxiliary particle filter, from t_j to t_{j+1}.

    x (3, N) and w (N,) are the cloud and its normalised weights at t_j; b_next [m] is the
    reading b_{j+1}. innovation_std (3,) are the standard deviations D^(1/2) of the artificial
    process noise (the handout's "innovation") in h [m], v [m/s] and beta [kg/(m s^2)]; the
    default is the handout's (100, 100, 5). If ``info`` is a dict, the step stores in it the
    effective sample size of the fitness weights that drive the resampling ("ess") and the
    parents' indices k_l ("parents", (N,)). Returns the new cloud (3, N) and its normalised
    weights (N,). Weights are handled as logarithms, so a reading far from every particle
    underflows nothing.
    """
    N = x.shape[1]
    # (a) x^(l) = x^(l) + dt f(x^(l)): Forward Euler for every particle at once
    x_hat = x + DT * tracking_dynamics(0.0, x)
    # (b) log w^(l) = log w(l) - |x^_1(l) - b_{j+1}|^2 / (2 sigma^2)   (a zero weight gives -inf)
    with np.errstate(divide="ignore"):
        log_w_hat = np.log(w) - (x_hat[0] - b_next) ** 2 / (2 * SIGMA**2)
    # w^(l) = w^(l) / sum w^, computed as exp(log w^ - max log w^) / sum(...)
    w_hat = np.exp(log_w_hat - np.max(log_w_hat))
    w_hat /= np.sum(w_hat)
    # (c) k_l drawn with replacement with probabilities w^ (multinomial resampling): k_l is the
    #     first index whose cumulative weight exceeds u_l ~ U(0, 1). Sorting the u_l does not
    #     change the draw, and lets the search and the copy run through memory in order.
    cdf = np.cumsum(w_hat)
    cdf /= cdf[-1]
    k = np.searchsorted(cdf, np.sort(rng.random(N)), side="right")
    # x_new(l) = x^(k_l) + D^(1/2) z(l),  z(l) ~ N(0, I_3),  D^(1/2) = diag(innovation_std)
    x_new = x_hat[:, k] + np.asarray(innovation_std)[:, None] * rng.standard_normal((3, N))
    # (d) log w(l) = -(|x_new_1(l) - b_{j+1}|^2 - |x^_1(k_l) - b_{j+1}|^2) / (2 sigma^2),
    #     with x^_1(k_l) the propagated parent before the innovation
    log_w = -((x_new[0] - b_next) ** 2 - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2)
    # w(l) = w(l) / sum w
    w_new = np.exp(log_w - np.max(log_w))
    if info is not None:
        # diagnostics: ESS = 1 / sum w^2 of the resampling weights, and the parents k_l
        info["ess"] = 1.0 / np.sum(w_hat**2)
        info["parents"] = k
    return x_new, w_new / np.sum(w_new)


def run_particle_filter(
    b: np.ndarray,
    N: int,
    rng: np.random.Generator,
    *,
    step: Callable | None = None,
    innovation_std: np.ndarray = INNOVATION_STD,
) -> FilterHistory:
    """Run a particle filter with N particles over the readings b (T + 1,) [m].

    ``step`` is the filter step (default: pf_step, the auxiliary particle filter); it is called
    as step(x, w, b_j, rng, innovation_std=innovation_std, info=info). At every t_j the run
    records the weighted mean, the weighted median, the weighted 50% and 90% credibility
    intervals of h, v and beta, the effective sample size of the weights, and the health of
    the resampling: the ESS of the weights it used, its number of distinct parents, and the
    number of distinct particles of t_0 that still have descendants.
    """
    step = pf_step if step is None else step
    history = FilterHistory.empty(len(b), N)
    health = ResamplingHealth(N)
    # the prior cloud at t_0 is centred on the first reading, h_init = b_0
    x, w = initial_cloud(b[0], N, rng)
    info: dict = {}
    for j in range(len(b)):
        if j > 0:
            # one step from t_{j-1} to t_j, with the reading b_j
            x, w = step(x, w, b[j], rng, innovation_std=innovation_std, info=info)
        # weighted mean sum_l w(l) x(l)
        history.mean[:, j] = x @ w
        for i in range(3):
            # weighted median (p = 0) and the weighted 50% and 90% credibility intervals
            lo, hi = credibility_interval(x[i], w, np.array([0.0, 50.0, 90.0]))
            history.median[i, j], history.lo50[i, j], history.hi50[i, j] = lo[0], lo[1], hi[1]
            history.lo90[i, j], history.hi90[i, j] = lo[2], hi[2]
        # ESS = 1 / sum_l w(l)^2
        history.ess[j] = 1.0 / np.sum(w**2)
        health.record(history, j, info)
    return history


# --- Instructor: the shipped data -------------------------------------------------------------
def radar_data_text(seed: int = DATA_SEED) -> str:
    """The CSV text of the shipped radar data: the lab's case simulated from ``seed``."""
    t = falling_object.time_grid()
    x_true, b = simulate_radar(falling_object.X0_TRUE, t, SIGMA, np.random.default_rng(seed))
    return falling_object.format_radar_csv(t, x_true, b)


def tuning_runs(seeds: range = range(falling_object.TUNING_SEEDS)) -> list[dict]:
    """The tuning study: every setting of falling_object.TUNING_SETTINGS, filter and N, on ``seeds``.

    Seed s simulates fresh readings of the lab's truth (np.random.default_rng([s, 1])) and runs
    the filter with np.random.default_rng([s, 2]); every setting sees the same readings. One row
    per run: the setting, the RMSE of the weighted mean of h, v and beta over the readings
    t_j >= falling_object.SCORE_FROM (20 s: before, the readings have taught little about beta
    and even an exact posterior is mostly the prior), the fraction of those t_j at which the
    truth lies in the 50% and 90% bands, the width of the
    90% band of beta at every t_j, the number of roots left at the end, and the lower end of the
    90% interval of v at the end.
    """
    t = falling_object.time_grid()
    rows = []
    for seed in seeds:
        x_true, b = simulate_radar(falling_object.X0_TRUE, t, SIGMA, np.random.default_rng([seed, 1]))
        for setting in falling_object.TUNING_SETTINGS:
            step = None if setting.filter == "auxiliary" else functools.partial(falling_object.bootstrap_step, dynamics=tracking_dynamics)
            history = run_particle_filter(
                b, setting.N, np.random.default_rng([seed, 2]), step=step, innovation_std=np.array(setting.innovation_std)
            )
            j = t >= falling_object.SCORE_FROM - 1e-9
            x = x_true[:, j]
            rows.append({
                "setting": setting,
                "seed": seed,
                "rmse": np.sqrt(np.mean((history.mean[:, j] - x) ** 2, axis=1)),
                "cover50": np.mean((history.lo50[:, j] <= x) & (x <= history.hi50[:, j]), axis=1),
                "cover90": np.mean((history.lo90[:, j] <= x) & (x <= history.hi90[:, j]), axis=1),
                "width90_beta": history.hi90[2] - history.lo90[2],
                "roots": history.roots[-1],
                "lo90_v_end": history.lo90[1, -1],
            })
    return rows


def write_data(directory: str | Path | None = None, seed: int = DATA_SEED) -> list[Path]:
    """Build the shipped radar data from ``seed``, and the tuning study, into ``directory``
    (default course/data/)."""
    folder = falling_object.DATA_FILE.parent if directory is None else Path(directory)
    path = folder / falling_object.DATA_FILE.name
    path.write_text(radar_data_text(seed))
    tuning = folder / falling_object.TUNING_FILE.name
    tuning.write_text(falling_object.format_tuning_csv(tuning_runs()))
    return [path, tuning]


if __name__ == "__main__":  # pragma: no cover
    for written in write_data(sys.argv[1] if len(sys.argv) > 1 else None):
        print(f"wrote {written}")
