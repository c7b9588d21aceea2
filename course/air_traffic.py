"""The air-traffic problem of the nonlinear-filters lab: an aircraft turning in front of a radar.

Units: metres (m), seconds (s), radians (rad). The state is x = [xi, eta, xi_dot, eta_dot, Omega]:
position (m), velocity (m/s) and turn rate (rad/s). A radar at the origin measures the range (m)
and the bearing atan2(eta, xi) (rad). The set-up follows the air-traffic example of Adurthi,
Singla and Singh (the coordinated-turn model of Bar-Shalom, Li and Kirubarajan).

Functions act on the last axis, so that one call moves every sigma point, particle or Monte Carlo
run at once: ``ct_step(X, T)`` takes X of shape (..., 5).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from course.tables import cell, number

DEG = np.pi / 180.0
T_RADAR = 5.0
"""The lecture's measurement interval, s."""
L1, L2 = 0.16, 0.01
"""Process-noise intensities of the coordinated-turn model: acceleration (m^2/s^3) and turn rate (rad^2/s^3)."""
R_RADAR = np.diag([100.0**2, (1.0 * DEG) ** 2])
"""Radar noise covariance: 100 m in range, 1 deg in bearing (the authors' code: diag((1e2)^2, (pi/180)^2))."""
X0_TRUE = np.array([25000.0, 10000.0, -120.0, 0.0, 0.0])
"""The aircraft at t = 0: 25 km east, 10 km north, flying west at 120 m/s, not turning."""
M0 = np.array([25000.0, 10000.0, -120.0, 0.0, 1e-6])
"""The centre of the filters' initial beliefs (each run draws its initial mean around it)."""
P0 = np.diag([1000.0**2, 1000.0**2, 100.0, 100.0, (1.0 * DEG) ** 2])
"""The filters' initial covariance."""
LEGS = ((125.0, 0.0), (90.0, 1.0 * DEG), (125.0, 0.0), (30.0, -3.0 * DEG), (125.0, 0.0))
"""The flight plan: (duration s, turn rate rad/s) of each leg, 495 s in all."""
STRAIGHT_LEGS = ((495.0, 0.0),)
"""The same flight without its turns: 495 s straight west."""
LOST_KM = 1.0
"""A run is lost when its position error at the last radar return exceeds this many km."""
DIVERGED_KMS = 1.0
"""A run has diverged when its velocity error exceeds this many km/s at any return: more than eight times the
aircraft's speed (120 m/s), a hundred times the initial velocity uncertainty (10 m/s), so no tracking filter's
error reaches it. The radar can keep a diverged run's position pinned while its velocity runs away."""
SPEED = 120.0
"""The aircraft's speed, m/s (constant: the coordinated-turn model keeps it)."""
FILTERS = ("pf", "ekf", "ckf", "ukf", "cut4", "cut6", "cut8")
LABELS = {"pf": "PF", "ekf": "EKF", "ckf": "CKF", "ukf": "UKF", "cut4": "CUT4", "cut6": "CUT6", "cut8": "CUT8"}
COLOURS = {"pf": "black", "ekf": "tab:brown", "ckf": "tab:red", "ukf": "tab:orange", "cut4": "tab:purple",
           "cut6": "tab:blue", "cut8": "tab:green"}
LECTURE_TABLE = {
    "position": {"pf": 115.47, "ckf": 989.15, "ukf": 685.90, "cut4": 245.30, "cut6": 138.82, "cut8": 135.89},
    "velocity": {"pf": 24.16, "ckf": 17330.23, "ukf": 12849.90, "cut4": 6127.86, "cut6": 2153.53, "cut8": 34.73},
    "turn_rate": {"pf": 0.0393, "ckf": 2.873, "ukf": 2.396, "cut4": 1.329, "cut6": 0.636, "cut8": 0.090},
}
"""The lecture's table for T = 5 s (its 'RMSE' is sqrt(mean over time of RMSE_k^2 / 5))."""
DATA_FILE = Path(__file__).parent / "data" / "nonlinear_filters_air_traffic.json"


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angles wrapped to (-pi, pi], rad."""
    return np.pi - np.mod(np.pi - a, 2.0 * np.pi)


def _turn_terms(omega: np.ndarray, T: float) -> tuple[np.ndarray, np.ndarray]:
    """sin(Omega T)/Omega and (1 - cos(Omega T))/Omega, with their limits T and 0 as Omega -> 0."""
    wt = omega * T
    small = np.abs(wt) < 1e-4
    safe = np.where(small, 1.0, omega)
    # Taylor series: sin(wT)/w = T (1 - (wT)^2/6), (1 - cos wT)/w = T wT/2 (1 - (wT)^2/12)
    s = np.where(small, T * (1.0 - wt**2 / 6.0), np.sin(wt) / safe)
    c = np.where(small, T * wt / 2.0 * (1.0 - wt**2 / 12.0), (1.0 - np.cos(wt)) / safe)
    return s, c


def ct_step(X: np.ndarray, T: float = T_RADAR) -> np.ndarray:
    """The coordinated-turn model's exact step over T seconds: X (..., 5) to the states T s later."""
    xi, eta, vxi, veta, omega = np.moveaxis(X, -1, 0)
    s, c = _turn_terms(omega, T)
    cos, sin = np.cos(omega * T), np.sin(omega * T)
    return np.stack((xi + s * vxi - c * veta,
                     eta + c * vxi + s * veta,
                     cos * vxi - sin * veta,
                     sin * vxi + cos * veta,
                     omega), axis=-1)


def ct_jacobian(m: np.ndarray, T: float = T_RADAR) -> np.ndarray:
    """The Jacobian of ct_step at m (..., 5), shape (..., 5, 5)."""
    _, _, vxi, veta, omega = np.moveaxis(m, -1, 0)
    s, c = _turn_terms(omega, T)
    wt = omega * T
    cos, sin = np.cos(wt), np.sin(wt)
    small = np.abs(wt) < 1e-4
    safe = np.where(small, 1.0, omega)
    # d/dOmega of s and c, with their series near Omega = 0
    ds = np.where(small, -T**2 * wt / 3.0, (T * cos - s) / safe)
    dc = np.where(small, T**2 * (0.5 - wt**2 / 8.0), (T * sin - c) / safe)
    F = np.zeros(m.shape[:-1] + (5, 5))
    F[..., 0, 0] = F[..., 1, 1] = F[..., 4, 4] = 1.0
    F[..., 0, 2], F[..., 0, 3], F[..., 0, 4] = s, -c, ds * vxi - dc * veta
    F[..., 1, 2], F[..., 1, 3], F[..., 1, 4] = c, s, dc * vxi + ds * veta
    F[..., 2, 2], F[..., 2, 3], F[..., 2, 4] = cos, -sin, -T * (sin * vxi + cos * veta)
    F[..., 3, 2], F[..., 3, 3], F[..., 3, 4] = sin, cos, T * (cos * vxi - sin * veta)
    return F


def ct_process_noise(T: float = T_RADAR, turn_noise: float = L2) -> np.ndarray:
    """Q (5 x 5): L1 [[T^3/3, T^2/2], [T^2/2, T]] for each axis, and T L2 for the turn rate (L2 = turn_noise)."""
    block = L1 * np.array([[T**3 / 3.0, T**2 / 2.0], [T**2 / 2.0, T]])
    Q = np.zeros((5, 5))
    Q[np.ix_([0, 2], [0, 2])] = block
    Q[np.ix_([1, 3], [1, 3])] = block
    Q[4, 4] = T * turn_noise
    return Q


def radar(X: np.ndarray) -> np.ndarray:
    """Range (m) and bearing atan2(eta, xi) (rad) of states X (..., 5) seen from the origin: (..., 2)."""
    return np.stack((np.hypot(X[..., 0], X[..., 1]), np.arctan2(X[..., 1], X[..., 0])), axis=-1)


def radar_h_jacobian(m: np.ndarray) -> np.ndarray:
    """The Jacobian of radar at m (..., 5), shape (..., 2, 5)."""
    xi, eta = m[..., 0], m[..., 1]
    r2 = xi**2 + eta**2
    r = np.sqrt(r2)
    H = np.zeros(m.shape[:-1] + (2, 5))
    H[..., 0, 0], H[..., 0, 1] = xi / r, eta / r
    H[..., 1, 0], H[..., 1, 1] = -eta / r2, xi / r2
    return H


RADAR_ANGLES = (1,)
"""Which radar components are angles (their residuals are wrapped)."""


def symmetric_sqrt(P: np.ndarray) -> np.ndarray:
    """The symmetric square root S = S^T with S S = P of covariances P (..., n, n)."""
    values, vectors = np.linalg.eigh(0.5 * (P + np.swapaxes(P, -1, -2)))
    return (vectors * np.sqrt(np.clip(values, 0.0, None))[..., None, :]) @ np.swapaxes(vectors, -1, -2)


def systematic_resample(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Systematic resampling: parent indices (..., N) for normalised weights (..., N).

    One uniform draw u per run; the j-th offspring takes the parent whose cumulative weight
    interval holds (u + j)/N. Each parent i gets floor(N w_i) or ceil(N w_i) offspring.
    """
    N = weights.shape[-1]
    batch = weights.shape[:-1]
    cumulative = np.cumsum(weights, axis=-1)
    cumulative[..., -1] = 1.0
    points = (rng.random(batch + (1,)) + np.arange(N)) / N
    # one sorted search over all runs: run r's cumulative weights, shifted by r, lie in [r, r + 1]
    shift = np.arange(int(np.prod(batch))).reshape(batch + (1,)).astype(float)
    index = np.searchsorted((cumulative + shift).ravel(), (points + shift).ravel(), side="right")
    return np.minimum(index.reshape(batch + (N,)) - N * shift.astype(int), N - 1)


def ekf_predict(m: np.ndarray, P: np.ndarray, T: float, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The EKF's time step through the coordinated-turn model: m (..., 5), P (..., 5, 5)."""
    F = ct_jacobian(m, T)
    # m_{k+1|k} = f(m_{k|k}),  P_{k+1|k} = F P F^T + Q
    P_new = F @ P @ np.swapaxes(F, -1, -2) + Q
    return ct_step(m, T), 0.5 * (P_new + np.swapaxes(P_new, -1, -2))


# ------------------------------------------------------------------------------------------------
# The truth and the radar data
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Scenario:
    """The flight sampled every T seconds: times (K,) s and true states (K, 5), Q and R for step T.

    ``turn_noise`` is the filters' turn-rate noise intensity L2 (rad^2/s^3) in Q.
    """

    T: float
    times: np.ndarray
    truth: np.ndarray
    turn_noise: float = L2

    @property
    def Q(self) -> np.ndarray:
        return ct_process_noise(self.T, self.turn_noise)

    @property
    def R(self) -> np.ndarray:
        return R_RADAR


def scenario(T: float = T_RADAR, legs: tuple[tuple[float, float], ...] = LEGS, turn_noise: float = L2) -> Scenario:
    """The noise-free flight plan ``legs`` (default LEGS), sampled every T s (T a whole number of seconds) from t = 0.

    ``turn_noise`` sets the filters' turn-rate noise intensity L2 in Q (default the lecture's 0.01 rad^2/s^3).

    The truth is built in one-second coordinated-turn steps (exact, since the model is the exact
    flow for a constant turn rate), with the turn rate of the leg that the next second belongs to.
    """
    if T != int(T) or T < 1:
        raise ValueError("T must be a whole number of seconds")
    rates = np.concatenate([np.full(int(duration), rate) for duration, rate in legs])
    states = [X0_TRUE.copy()]
    for rate in rates:
        current = states[-1].copy()
        current[4] = rate
        states[-1] = current
        states.append(ct_step(current, 1.0))
    states[-1][4] = 0.0
    states = np.array(states)
    times = np.arange(0, len(rates) + 1, int(T), dtype=float)
    return Scenario(float(T), times, states[times.astype(int)], float(turn_noise))


def simulate_runs(sc: Scenario, runs: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Each run's initial mean m0 (runs, 5), drawn from N(M0, P0), and radar data y (runs, K, 2)."""
    # P0 and R are diagonal, so their entrywise square roots are their square roots
    m0 = M0 + rng.standard_normal((runs, 5)) @ np.sqrt(P0)
    y = radar(sc.truth) + rng.standard_normal((runs, len(sc.times), 2)) @ np.sqrt(R_RADAR)
    y[..., 1] = wrap_angle(y[..., 1])
    return m0, y


# ------------------------------------------------------------------------------------------------
# Filters: frameworks that take your functions
# ------------------------------------------------------------------------------------------------

Predict = Callable[..., tuple[np.ndarray, np.ndarray]]
Update = Callable[..., tuple[np.ndarray, np.ndarray]]


def run_sigma_point_filter(predict: Predict, update: Update, Z: np.ndarray, w: np.ndarray, sc: Scenario,
                           m0: np.ndarray, y: np.ndarray, vectorised: bool = True) -> np.ndarray:
    """A sigma-point filter with the points Z (N, 5), weights w (N,): estimates (runs, K, 5).

    ``predict(m, P, f, Z, w, Q)`` and ``update(m, P, y, h, R, Z, w, angles)`` are your
    sigma_point_predict and sigma_point_update. With vectorised=False they see one run at a time.
    """
    f = lambda X: ct_step(X, sc.T)  # noqa: E731
    m, P = m0.copy(), np.broadcast_to(P0, m0.shape + (5,)).copy()
    estimates = np.empty(y.shape[:2] + (5,))
    estimates[:, 0] = m
    for k in range(1, len(sc.times)):
        if vectorised:
            m, P = predict(m, P, f, Z, w, sc.Q)
            m, P = update(m, P, y[:, k], radar, sc.R, Z, w, RADAR_ANGLES)
        else:
            pairs = [update(*predict(m[r], P[r], f, Z, w, sc.Q), y[r, k], radar, sc.R, Z, w, RADAR_ANGLES)
                     for r in range(len(m))]
            m, P = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
        estimates[:, k] = m
    return estimates


def run_ekf(update: Update, sc: Scenario, m0: np.ndarray, y: np.ndarray, vectorised: bool = True) -> np.ndarray:
    """The EKF (the given ekf_predict and your ``update(m, P, y, h, H_jacobian, R, angles)``): (runs, K, 5)."""
    m, P = m0.copy(), np.broadcast_to(P0, m0.shape + (5,)).copy()
    estimates = np.empty(y.shape[:2] + (5,))
    estimates[:, 0] = m
    for k in range(1, len(sc.times)):
        m, P = ekf_predict(m, P, sc.T, sc.Q)
        if vectorised:
            m, P = update(m, P, y[:, k], radar, radar_h_jacobian, sc.R, RADAR_ANGLES)
        else:
            pairs = [update(m[r], P[r], y[r, k], radar, radar_h_jacobian, sc.R, RADAR_ANGLES) for r in range(len(m))]
            m, P = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
        estimates[:, k] = m
    return estimates


def run_bootstrap_pf(step: Callable, sc: Scenario, m0: np.ndarray, y: np.ndarray, rng: np.random.Generator,
                        particles: int = 5000, vectorised: bool = True) -> np.ndarray:
    """The bootstrap particle filter with your ``step(X, logw, y, rng, f, h, Q, R, angles)``: weighted means (runs, K, 5).

    Each run starts from ``particles`` draws of N(m0, P0) with equal weights.
    """
    f = lambda X: ct_step(X, sc.T)  # noqa: E731
    runs = len(m0)
    X = m0[:, None, :] + rng.standard_normal((runs, particles, 5)) @ np.sqrt(P0)
    logw = np.full((runs, particles), -np.log(particles))
    estimates = np.empty(y.shape[:2] + (5,))
    estimates[:, 0] = m0
    for k in range(1, len(sc.times)):
        if vectorised:
            X, logw = step(X, logw, y[:, k], rng, f, radar, sc.Q, sc.R, RADAR_ANGLES)
        else:
            pairs = [step(X[r], logw[r], y[r, k], rng, f, radar, sc.Q, sc.R, RADAR_ANGLES) for r in range(runs)]
            X, logw = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
        # the estimate: the weighted mean of the particles
        estimates[:, k] = np.einsum("rn,rni->ri", np.exp(logw), X)
    return estimates


# ------------------------------------------------------------------------------------------------
# Errors and the lecture's table
# ------------------------------------------------------------------------------------------------

QUANTITIES = ("position", "velocity", "turn_rate")
UNITS = {"position": "m", "velocity": "m/s", "turn_rate": "rad/s"}


def errors(estimates: np.ndarray, sc: Scenario) -> np.ndarray:
    """Per run and time, the position error (m), velocity error (m/s) and turn-rate error (rad/s): (runs, K, 3)."""
    d = estimates - sc.truth
    return np.stack((np.hypot(d[..., 0], d[..., 1]), np.hypot(d[..., 2], d[..., 3]), np.abs(d[..., 4])), axis=-1)


def lecture_metric(err: np.ndarray, axis: int | tuple[int, ...] = (0, 1)) -> np.ndarray:
    """The lecture's 'RMSE': sqrt(mean over time of RMSE_k^2 / 5), RMSE_k over runs; err (runs, K, 3) gives (3,).

    The factor 1/5 (the state dimension) is in the authors' code; the slide calls the number a 2-norm.
    With axis=1 it is the same number for each run on its own, (runs, 3).
    """
    return np.sqrt(np.mean(err**2, axis=axis) / 5.0)


def rmse_over_time(err: np.ndarray) -> np.ndarray:
    """RMSE_k over runs at each time: err (runs, K, 3) gives (K, 3)."""
    return np.sqrt(np.mean(err**2, axis=0))


def lost_runs(err: np.ndarray) -> np.ndarray:
    """Which runs are lost: a position error above LOST_KM at the last radar return, (runs,) bool."""
    return err[:, -1, 0] > 1000.0 * LOST_KM


def diverged_runs(err: np.ndarray) -> np.ndarray:
    """Which runs have diverged: a velocity error above DIVERGED_KMS at any return, (runs,) bool."""
    return np.max(err[:, :, 1], axis=1) > 1000.0 * DIVERGED_KMS


def summarise(err: np.ndarray) -> dict:
    """The lecture's metric, the time-averaged RMSE, the metric without the lost (or the diverged) runs, the
    medians, and the counts of lost and diverged runs."""
    lost, diverged = lost_runs(err), diverged_runs(err)
    per_run = lecture_metric(err, axis=1)

    def named(values: np.ndarray) -> dict:
        return {q: float(v) for q, v in zip(QUANTITIES, values)}

    def without(drop: np.ndarray) -> dict:
        return named(lecture_metric(err[~drop]) if np.any(~drop) else np.full(3, np.nan))

    return {
        **named(lecture_metric(err)),
        "time_averaged_rmse": named(np.mean(rmse_over_time(err), axis=0)),
        "excluding_lost": without(lost),
        "excluding_diverged": without(diverged),
        "median": named(np.median(per_run, axis=0)),
        "lost_runs": int(np.sum(lost)),
        "diverged_runs": int(np.sum(diverged)),
    }


# ------------------------------------------------------------------------------------------------
# The shipped Monte Carlo table
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ShippedResults:
    """The reference's Monte Carlo results: the T = 5 s table, RMSE_k curves (and the CKF's and UKF's position
    RMSE_k (K,) on the flight without turns), and the sweep over T: the lecture's metric (``sweep``), the median
    over runs of each run's metric (``sweep_median``), both (len(T), 3) per filter, and the lost and diverged
    fractions."""

    runs: int
    seed: int
    particles: int
    table: dict
    times: np.ndarray
    rmse_curves: dict
    straight_position_rmse: dict
    sweep_T: np.ndarray
    sweep_runs: int
    sweep: dict
    sweep_lost: dict
    sweep_diverged: dict
    sweep_median: dict


def load(path: Path = DATA_FILE) -> ShippedResults:
    """Load the shipped Monte Carlo results (built by the instructors from seeded runs of the reference filters)."""
    raw = json.loads(Path(path).read_text())
    return ShippedResults(
        runs=raw["runs"], seed=raw["seed"], particles=raw["particles"], table=raw["filters"],
        times=np.array(raw["times"]), rmse_curves={k: np.array(v) for k, v in raw["rmse_curves"].items()},
        straight_position_rmse={k: np.array(v) for k, v in raw["straight_position_rmse"].items()},
        sweep_T=np.array(raw["sweep"]["T"]), sweep_runs=raw["sweep"]["runs"],
        sweep={k: np.array(v) for k, v in raw["sweep"]["filters"].items()},
        sweep_lost={k: np.array(v) for k, v in raw["sweep"]["lost_fraction"].items()},
        sweep_diverged={k: np.array(v) for k, v in raw["sweep"]["diverged_fraction"].items()},
        sweep_median={k: np.array(v) for k, v in raw["sweep"]["median"].items()},
    )


def print_table(table: dict, runs: int) -> None:
    """Print the lecture's metric (a mean over the runs) for every filter beside the lecture's, with the position
    metric without the lost runs and the counts of lost and diverged runs. The filters are ranked by
    print_median_table, not here."""
    print(f"The lecture's metric, sqrt(mean_k RMSE_k^2 / 5), a mean over {runs} runs (lecture's value in brackets)")
    print(f"{'filter':<10}{'position [m]':>24}{'velocity [m/s]':>26}{'turn rate [rad/s]':>24}{'pos w/o lost':>14}"
          f"{'lost':>6}{'diverged':>10}")
    for name in FILTERS:
        row = table[name]
        cells = []
        for q in QUANTITIES:
            lecture = LECTURE_TABLE[q].get(name)
            cells.append(f"{row[q]:.4g}" + (f" ({lecture:.4g})" if lecture is not None else " (-)"))
        print(f"{LABELS[name]:<10}{cells[0]:>24}{cells[1]:>26}{cells[2]:>24}"
              f"{cell(row['excluding_lost']['position'], 14, '.4g')}{row['lost_runs']:>6}{row['diverged_runs']:>10}")
    print(f"lost: position error above {LOST_KM:g} km at the last return; diverged: velocity error above "
          f"{DIVERGED_KMS:g} km/s at some return")


def print_median_table(table: dict, runs: int) -> None:
    """Print the ranking table: each filter's median over the runs of its runs' own metric (position, velocity,
    turn rate), the PF's median position as the unit, and the counts of lost and diverged runs."""
    print(f"Median over {runs} runs of each run's own metric, sqrt(mean_k e_k^2 / 5): the typical run")
    print(f"{'filter':<10}{'position [m]':>14}{'velocity [m/s]':>16}{'turn rate [rad/s]':>19}{'x PF (pos)':>12}"
          f"{'lost':>6}{'diverged':>10}")
    for name in FILTERS:
        row = table[name]["median"]
        factor = row["position"] / table["pf"]["median"]["position"]
        print(f"{LABELS[name]:<10}{cell(row['position'], 14, '.4g')}{cell(row['velocity'], 16, '.4g')}"
              f"{cell(row['turn_rate'], 19, '.4g')}{cell(factor, 12)}{table[name]['lost_runs']:>6}"
              f"{table[name]['diverged_runs']:>10}")
    print(f"lost: position error above {LOST_KM:g} km at the last return; diverged: velocity error above "
          f"{DIVERGED_KMS:g} km/s at some return")


def _or_dash(value: float) -> str:
    """A number to 4 significant figures, or '-' when it is undefined (every run was dropped)."""
    return "-" if np.isnan(value) else number(value, ".4g", 12)


def print_robust_table(table: dict) -> None:
    """Print the medians over runs, the metric without the lost and without the diverged runs ('-' where every
    run is dropped), and the time-averaged position RMSE, beside the lost and diverged counts."""
    print(f"{'filter':<10}{'median pos':>11}{'median vel':>11}{'pos w/o lost':>13}{'vel w/o lost':>13}"
          f"{'vel w/o div.':>13}{'time-avg pos':>13}{'lost':>6}{'diverged':>10}")
    print(f"{'':<10}{'[m]':>11}{'[m/s]':>11}{'[m]':>13}{'[m/s]':>13}{'[m/s]':>13}{'RMSE [m]':>13}")
    for name in FILTERS:
        row = table[name]
        print(f"{LABELS[name]:<10}{cell(row['median']['position'], 11, '.4g')}{cell(row['median']['velocity'], 11, '.4g')}"
              f"{cell(row['excluding_lost']['position'], 13, '.4g')}{cell(row['excluding_lost']['velocity'], 13, '.4g')}"
              f"{_or_dash(row['excluding_diverged']['velocity']):>13}{cell(row['time_averaged_rmse']['position'], 13, '.4g')}"
              f"{row['lost_runs']:>6}{row['diverged_runs']:>10}")


# ------------------------------------------------------------------------------------------------
# Figures
# ------------------------------------------------------------------------------------------------


def plot_flight(sc: Scenario, y: np.ndarray | None = None) -> Figure:
    """The true flight, the radar at the origin, and (optionally) one run's radar returns."""
    fig, ax = plt.subplots(figsize=(7, 6), constrained_layout=True)
    ax.plot(sc.truth[:, 0] / 1000, sc.truth[:, 1] / 1000, color="black", lw=2, label="true flight")
    ax.plot(sc.truth[0, 0] / 1000, sc.truth[0, 1] / 1000, "o", color="black", label="start (t = 0 s)")
    if y is not None:
        ax.plot(y[:, 0] * np.cos(y[:, 1]) / 1000, y[:, 0] * np.sin(y[:, 1]) / 1000, ".", color="tab:orange",
                label="radar returns (one run)")
    ax.plot(0, 0, "s", color="tab:green", ms=9, label="radar")
    ax.set_xlabel("xi, east [km]")
    ax.set_ylabel("eta, north [km]")
    ax.set_aspect("equal")
    ax.set_title(f"The aircraft's flight, sampled every {sc.T:g} s")
    ax.legend(loc="upper left", fontsize="small")
    return fig


def plot_position_error(times: np.ndarray, curves: dict, title: str, straight: dict | None = None) -> Figure:
    """RMSE_k of the position (over runs) against time, one line per filter, on a log scale.

    ``straight`` (optional): position RMSE_k (K,) of some filters on the flight without turns, drawn dashed in the
    filters' colours, with the times of closest approach to the radar of both flights marked.
    """
    fig, ax = plt.subplots(figsize=(9, 5), constrained_layout=True)
    for name in FILTERS:
        if name in curves:
            ax.semilogy(times, curves[name][:, 0], color=COLOURS[name], lw=2 if name in ("pf", "cut8") else 1.3,
                        label=LABELS[name])
    for start in np.cumsum([0.0] + [d for d, _ in LEGS])[1:-1]:
        ax.axvline(start, color="grey", lw=0.8, ls=":")
    xlabel = "time [s] (dotted lines: a turn starts or ends"
    if straight:
        for name, curve in straight.items():
            ax.semilogy(times, curve, color=COLOURS[name], lw=1.3, ls="--", label=f"{LABELS[name]}, no turns")
        for legs, marker in ((LEGS, "v"), (STRAIGHT_LEGS, "^")):
            truth = scenario(times[1] - times[0], legs).truth
            k = int(np.argmin(np.hypot(truth[:, 0], truth[:, 1])))
            ax.plot(times[k], 0.0, marker, color="grey", ms=10, transform=ax.get_xaxis_transform(), clip_on=False,
                    label=f"closest to the radar ({np.hypot(*truth[k, :2]) / 1000:.0f} km), "
                          + ("flight" if legs is LEGS else "no turns"))
        xlabel += "; dashed: the same filters on the flight without turns"
    ax.set_xlabel(xlabel + ")")
    ax.set_ylabel("position RMSE over runs [m]")
    ax.set_title(title)
    ax.legend(loc="upper left", ncols=4, fontsize="small")
    return fig


ZERO_VELOCITY_METRIC = SPEED / np.sqrt(5.0)
"""The lecture's velocity metric of the estimate 'zero velocity' (error = the speed at every return), m/s."""


def plot_rmse_against_interval(T: np.ndarray, sweep: dict, lost: dict, diverged: dict, runs: int,
                               statistic: str = "sqrt(mean_k RMSE_k^2 / 5)") -> Figure:
    """A metric for the position and the velocity, and the fractions of lost and diverged runs, against T.

    ``statistic`` names the metric on the axes: the lecture's by default; pass the sweep's medians and
    "median of each run's metric" to plot the typical run.

    ``sweep[name]`` is (len(T), 3), the metric per interval; ``lost[name]`` and ``diverged[name]`` (len(T),) the
    fractions of lost and of diverged runs.
    The metric axes stop at 1e5; a point beyond is drawn at the top as a triangle.
    """
    fig, axes = plt.subplots(1, 3, figsize=(15, 5), layout="constrained")
    for ax, (index, quantity, unit, top) in zip(axes, [(0, "position", "m", 1e5), (1, "velocity", "m/s", 1e5)]):
        for name in FILTERS:
            values = sweep[name][:, index]
            ax.semilogy(T, np.minimum(values, top), "o-", color=COLOURS[name], label=LABELS[name])
            off = values > top
            ax.plot(T[off], np.full(off.sum(), top), "^", color=COLOURS[name], ms=10)
        ax.set_ylim(top=top * 1.6)
        ax.set_xlabel("measurement interval T [s]")
        ax.set_ylabel(f"{quantity}: {statistic} [{unit}]")
        ax.set_title(f"{quantity} (triangle: off the scale, above $10^{{{np.log10(top):.0f}}}$ {unit})", fontsize="medium")
        ax.set_xticks(T)
    axes[1].axhline(ZERO_VELOCITY_METRIC, color="grey", ls="--", lw=1.2)
    axes[1].annotate(f"estimating zero velocity: {SPEED:g}/sqrt(5) = {ZERO_VELOCITY_METRIC:.1f} m/s",
                     (T[1], ZERO_VELOCITY_METRIC), xytext=(0, 5), textcoords="offset points", fontsize="small",
                     color="dimgrey")
    for name in FILTERS:
        axes[2].plot(T, 100 * lost[name], "o-", color=COLOURS[name], label=LABELS[name])
        axes[2].plot(T, 100 * diverged[name], "x--", color=COLOURS[name])
    axes[2].set_ylim(-3, 103)
    axes[2].set_xlabel("measurement interval T [s]")
    axes[2].set_ylabel("runs [%]")
    axes[2].set_title(f"solid: lost (position error > {LOST_KM:g} km at the end)\n"
                      f"dashed: diverged (velocity error > {DIVERGED_KMS:g} km/s at some return)", fontsize="medium")
    axes[2].set_xticks(T)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=len(labels), fontsize="small")
    fig.suptitle(f"Error, lost and diverged runs against the measurement interval ({runs} runs per T)")
    return fig
