"""Reference solution of the reentry-pf lab (Calvetti and Somersalo, Day 5 exercise).

Notation follows the handout: x = [h, v, beta] with h' = -v, v' = g - g rho(h) v^2 / (2 beta),
beta' = 0 (equation (5)); b_j = x_1(t_j) + eps_j the radar readings; a particle cloud is an
array of shape (3, N), one column per particle x^(l), with weights w of shape (N,). Each
function here is the model answer of one blank, and the lab's answer cell holds the same code.

Instructors: ``python -m solutions.reentry_pf`` rebuilds the shipped data from DATA_SEED.
"""

from __future__ import annotations

import sys
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
    # x^(l) = [h_init, v_init, beta_init] + C^(1/2) w^(l),  w^(l) ~ N(0, I_3),  C^(1/2) = diag(PRIOR_STD)
    x = mean[:, None] + PRIOR_STD[:, None] * rng.standard_normal((3, N))
    # w^(l) = 1 / N
    w = np.full(N, 1.0 / N)
    return x, w


def pf_step(x: np.ndarray, w: np.ndarray, b_next: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """One step (a) to (d) of the particle filter, from t_j to t_{j+1}.

    x (3, N) and w (N,) are the cloud and its normalised weights at t_j; b_next [m] is the
    reading b_{j+1}. Returns the new cloud (3, N) and its normalised weights (N,). Weights are
    handled as logarithms, so a reading far from every particle underflows nothing.
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
    # x_new(l) = x^(k_l) + D^(1/2) w(l),  w(l) ~ N(0, I_3),  D^(1/2) = diag(INNOVATION_STD)
    x_new = x_hat[:, k] + INNOVATION_STD[:, None] * rng.standard_normal((3, N))
    # (d) log w(l) = -(|x_new_1(l) - b_{j+1}|^2 - |x^_1(k_l) - b_{j+1}|^2) / (2 sigma^2),
    #     with x^_1(k_l) the propagated parent before the innovation
    log_w = -((x_new[0] - b_next) ** 2 - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2)
    # w(l) = w(l) / sum w
    w_new = np.exp(log_w - np.max(log_w))
    return x_new, w_new / np.sum(w_new)


def credibility_interval(samples: np.ndarray, p: float) -> tuple[np.ndarray, np.ndarray]:
    """The p% credibility interval [lo, hi] of the samples (N,), p in percent, by the handout's
    sorted-sample rule. (Written with ``...`` indexing, it also takes (k, N): one interval per row.)

    The handout's 1-based index i is Python's index i - 1 in the sorted samples. The rule is
    evaluated in floating point, as MATLAB evaluates it: where (1 -+ p/100)(N/2) is a half in exact
    arithmetic but lands just below it in floating point (N = 10, p = 90), it rounds down.
    """
    s = np.sort(samples, axis=-1)
    N = s.shape[-1]
    # i_min = [(1 - p/100)(N/2)],  i_max = [(1 + p/100)(N/2)],  [.] rounding halves away from
    # zero as MATLAB's round does (Python's round and np.round send halves to even)
    a_min, a_max = (1 - p / 100) * (N / 2), (1 + p / 100) * (N / 2)
    i_min = int(np.floor(a_min) + (a_min - np.floor(a_min) >= 0.5))
    i_max = int(np.floor(a_max) + (a_max - np.floor(a_max) >= 0.5))
    # clamp to the valid 1-based indices 1..N
    i_min, i_max = min(max(i_min, 1), N), min(max(i_max, 1), N)
    # [h_(i_min), h_(i_max)]: 1-based index i is Python's i - 1
    return s[..., i_min - 1], s[..., i_max - 1]


def run_particle_filter(b: np.ndarray, N: int, rng: np.random.Generator) -> FilterHistory:
    """Run the particle filter with N particles over the readings b (T + 1,) [m].

    At every t_j it records the weighted mean, the median, the 50% and 90% credibility
    intervals of h, v and beta, and the effective sample size, in a FilterHistory.
    """
    history = FilterHistory.empty(len(b), N)
    # the prior cloud at t_0 is centred on the first reading, h_init = b_0
    x, w = initial_cloud(b[0], N, rng)
    for j in range(len(b)):
        if j > 0:
            # steps (a)-(e) from t_{j-1} to t_j, with the reading b_j
            x, w = pf_step(x, w, b[j], rng)
        # weighted mean sum_l w(l) x(l)
        history.mean[:, j] = x @ w
        history.median[:, j] = np.median(x, axis=1)
        for i in range(3):
            # p% credibility intervals of h, v and beta by the sorted-sample rule
            history.lo50[i, j], history.hi50[i, j] = credibility_interval(x[i], 50)
            history.lo90[i, j], history.hi90[i, j] = credibility_interval(x[i], 90)
        # ESS = 1 / sum_l w(l)^2
        history.ess[j] = 1.0 / np.sum(w**2)
    return history


# --- Instructor: the shipped data -------------------------------------------------------------
def radar_data_text(seed: int = DATA_SEED) -> str:
    """The CSV text of the shipped radar data: the lab's case simulated from ``seed``."""
    t = falling_object.time_grid()
    x_true, b = simulate_radar(falling_object.X0_TRUE, t, SIGMA, np.random.default_rng(seed))
    return falling_object.format_radar_csv(t, x_true, b)


def write_data(directory: str | Path | None = None, seed: int = DATA_SEED) -> list[Path]:
    """Build the shipped radar data from ``seed`` into ``directory`` (default course/data/)."""
    folder = falling_object.DATA_FILE.parent if directory is None else Path(directory)
    path = folder / falling_object.DATA_FILE.name
    path.write_text(radar_data_text(seed))
    return [path]


if __name__ == "__main__":  # pragma: no cover
    for written in write_data(sys.argv[1] if len(sys.argv) > 1 else None):
        print(f"wrote {written}")
