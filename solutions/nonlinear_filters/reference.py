"""Reference solution of the nonlinear-filters lab (P. Singla, 'Uncertainty Analysis & Estimation',
filtering under the Bayesian framework; the air-traffic example of Adurthi, Singla and Singh).

A Gaussian filter is a rule for computing expectations E[g(x)] with x ~ N(m, P): it maps
standard-normal points Z with weights w to x_i = m + S z_i (S S = P) and sums w_i g(x_i). The
blanks build the point sets (cubature, unscented, CUT4), measure how many moments they get
right, and write one filter for every point set, an EKF update and a bootstrap particle filter.

The filter steps work for one run (m of shape (n,), P (n, n)) and, unchanged, for a stack of
runs (m (R, n), P (R, n, n)): the Monte Carlo below moves every run at once.

Run ``python -m solutions.nonlinear_filters.reference air-traffic --runs R --seed S --json`` for the
lecture's table from R runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import sys
from pathlib import Path
from typing import Callable

import numpy as np
import scipy.special

from course import air_traffic, cut
from course.air_traffic import symmetric_sqrt, systematic_resample, wrap_angle
from solutions.shipped_npz import write_npz

DATA_SEED = 20261122
"""Seed of the shipped Monte Carlo table (course/data/nonlinear_filters_air_traffic.json)."""
DATA_RUNS = 400
SWEEP_T = (5.0, 10.0, 15.0, 20.0)
SWEEP_RUNS = 200
PARTICLES = 5000


def cubature_points(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The third-degree spherical-radial cubature rule: Z (2n, n), w (2n,)."""
    # z = +-sqrt(n) e_i, each with weight 1/(2n)
    Z = np.sqrt(n) * np.vstack((np.eye(n), -np.eye(n)))
    w = np.full(2 * n, 1.0 / (2 * n))
    return Z, w


def unscented_points(n: int, kappa: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The unscented transform's 2n + 1 points: Z (2n + 1, n), w (2n + 1,)."""
    # z_0 = 0 with weight kappa/(n + kappa); z = +-sqrt(n + kappa) e_i with weight 1/(2(n + kappa))
    scale = np.sqrt(n + kappa)
    Z = np.vstack((np.zeros((1, n)), scale * np.eye(n), -scale * np.eye(n)))
    w = np.concatenate(([kappa / (n + kappa)], np.full(2 * n, 0.5 / (n + kappa))))
    return Z, w


def cut4_points(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The fourth-order conjugate unscented transform (n >= 3): Z (2n + 2^n, n), w (2n + 2^n,)."""
    # principal axes +-r1 e_i with r1^2 = (n + 2)/2, weight w1 = 4/(n + 2)^2
    r1 = np.sqrt((n + 2) / 2)
    # conjugate axes r2 (+-1, ..., +-1) with r2^2 = (n + 2)/(n - 2), weight w2 = (n - 2)^2/(2^n (n + 2)^2)
    r2 = np.sqrt((n + 2) / (n - 2))
    signs = np.array(list(itertools.product((1.0, -1.0), repeat=n)))
    Z = np.vstack((r1 * np.eye(n), -r1 * np.eye(n), r2 * signs))
    w = np.concatenate((np.full(2 * n, 4 / (n + 2) ** 2), np.full(2**n, (n - 2) ** 2 / (2**n * (n + 2) ** 2))))
    return Z, w


def moment_error(Z: np.ndarray, w: np.ndarray, degree: int) -> float:
    """The largest |sum_i w_i z_i^a - E[z^a]| over the monomials z^a of this degree (>= 1), z ~ N(0, I)."""
    n = Z.shape[1]
    # each monomial of this degree as the coordinates it multiplies, i_1 <= i_2 <= ... <= i_degree
    index = np.array(list(itertools.combinations_with_replacement(range(n), degree)), dtype=int).reshape(-1, degree)
    # the rule's moments: sum_i w_i prod_j Z[i, index_j]
    rule = w @ np.prod(Z[:, index], axis=2)
    # the exponent a_k of each coordinate; E[z^a] = prod_k (a_k - 1)!!, zero if any a_k is odd
    powers = np.stack([np.sum(index == k, axis=1) for k in range(n)], axis=1)
    half = powers // 2
    # (2h - 1)!! = (2h)! / (2^h h!)
    double_factorial = scipy.special.factorial(2 * half) / (2.0**half * scipy.special.factorial(half))
    exact = np.prod(np.where(powers % 2 == 0, double_factorial, 0.0), axis=1)
    return float(np.max(np.abs(rule - exact)))


def sigma_point_predict(m: np.ndarray, P: np.ndarray, f: Callable, Z: np.ndarray, w: np.ndarray,
                        Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Time step with the point set (Z, w): m (..., n), P (..., n, n) to m_{k+1|k}, P_{k+1|k}."""
    # x_i = m + S z_i with S the symmetric square root of P
    X = m[..., None, :] + Z @ symmetric_sqrt(P)
    Y = f(X)
    # m_{k+1|k} = sum_i w_i f(x_i)
    m_new = w @ Y
    # P_{k+1|k} = sum_i w_i (f(x_i) - m)(f(x_i) - m)^T + Q
    D = Y - m_new[..., None, :]
    P_new = (w[:, None] * D).swapaxes(-1, -2) @ D + Q
    return m_new, 0.5 * (P_new + P_new.swapaxes(-1, -2))


def sigma_point_update(m: np.ndarray, P: np.ndarray, y: np.ndarray, h: Callable, R: np.ndarray, Z: np.ndarray,
                       w: np.ndarray, angles: tuple[int, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
    """Measurement update with the point set (Z, w): m (..., n), P (..., n, n), y (..., p).

    The components of y listed in ``angles`` are angles: their differences are wrapped to (-pi, pi].
    """
    DX = Z @ symmetric_sqrt(P)
    # each point's predicted measurement, as a difference from y (angles wrapped)
    E = h(m[..., None, :] + DX) - y[..., None, :]
    E[..., list(angles)] = wrap_angle(E[..., list(angles)])
    # y_hat = y + sum_i w_i (h(x_i) - y), so the innovation y - y_hat is -sum_i w_i E_i
    e_bar = w @ E
    DY = E - e_bar[..., None, :]
    # P_yy = sum_i w_i (h_i - y_hat)(h_i - y_hat)^T + R,  P_xy = sum_i w_i (x_i - m)(h_i - y_hat)^T
    P_yy = (w[:, None] * DY).swapaxes(-1, -2) @ DY + R
    P_xy = (w[:, None] * DX).swapaxes(-1, -2) @ DY
    # K = P_xy P_yy^-1, from the symmetric P_yy: K^T = P_yy^-1 P_xy^T
    K = np.linalg.solve(P_yy, P_xy.swapaxes(-1, -2)).swapaxes(-1, -2)
    # m_{k+1|k+1} = m + K (y - y_hat),  P_{k+1|k+1} = P - K P_yy K^T
    m_new = m - (K @ e_bar[..., None])[..., 0]
    P_new = P - K @ P_yy @ K.swapaxes(-1, -2)
    return m_new, 0.5 * (P_new + P_new.swapaxes(-1, -2))


def ekf_update(m: np.ndarray, P: np.ndarray, y: np.ndarray, h: Callable, H_jacobian: Callable, R: np.ndarray,
               angles: tuple[int, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
    """The EKF measurement update: m (..., n), P (..., n, n), y (..., p); h and its Jacobian at m."""
    # innovation y - h(m), angles wrapped
    e = y - h(m)
    e[..., list(angles)] = wrap_angle(e[..., list(angles)])
    H = H_jacobian(m)
    # S = H P H^T + R,  K = P H^T S^-1, so K^T = S^-1 H P
    S = H @ P @ H.swapaxes(-1, -2) + R
    K = np.linalg.solve(S, H @ P).swapaxes(-1, -2)
    m_new = m + (K @ e[..., None])[..., 0]
    # Joseph form: P = (I - K H) P (I - K H)^T + K R K^T
    A = np.eye(m.shape[-1]) - K @ H
    P_new = A @ P @ A.swapaxes(-1, -2) + K @ R @ K.swapaxes(-1, -2)
    return m_new, 0.5 * (P_new + P_new.swapaxes(-1, -2))


def bootstrap_pf_step(X: np.ndarray, logw: np.ndarray, y: np.ndarray, rng: np.random.Generator, f: Callable,
                      h: Callable, Q: np.ndarray, R: np.ndarray, angles: tuple[int, ...] = (),
                      ess_fraction: float = 0.7) -> tuple[np.ndarray, np.ndarray]:
    """One bootstrap particle filter step: particles X (..., N, n), normalised log-weights logw (..., N), y (..., p).

    Propagate through f with process noise N(0, Q), weight by the likelihood of y, normalise, and
    resample (systematically) the runs whose effective sample size fell below ess_fraction N.
    """
    N = X.shape[-2]
    # x_k^i = f(x_{k-1}^i) + v^i,  v^i ~ N(0, Q)
    X = f(X) + rng.standard_normal(X.shape) @ np.linalg.cholesky(Q).T
    # log p(y | x^i) = -1/2 e^T R^-1 e + const, e = y - h(x^i) with angles wrapped
    E = y[..., None, :] - h(X)
    E[..., list(angles)] = wrap_angle(E[..., list(angles)])
    # e^T R^-1 e = |L^-1 e|^2 with R = L L^T
    whiten = np.linalg.solve(np.linalg.cholesky(R), np.eye(R.shape[0]))
    logw = logw - 0.5 * np.sum((E @ whiten.T) ** 2, axis=-1)
    # normalise: log w^i - log sum_j w^j
    logw = logw - scipy.special.logsumexp(logw, axis=-1, keepdims=True)
    # effective sample size 1 / sum_i (w^i)^2, one per run
    ess = 1.0 / np.sum(np.exp(2.0 * logw), axis=-1)
    resample = ess < ess_fraction * N
    parents = systematic_resample(np.exp(logw), rng)
    X = np.where(resample[..., None, None], np.take_along_axis(X, parents[..., None], axis=-2), X)
    logw = np.where(resample[..., None], -np.log(N), logw)
    return X, logw


# ------------------------------------------------------------------------------------------------
# The Monte Carlo comparison
# ------------------------------------------------------------------------------------------------


def point_sets() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The sigma-point filters' point sets for the five-state aircraft."""
    return {"ckf": cubature_points(5), "ukf": unscented_points(5, 1.0), "cut4": cut4_points(5),
            "cut6": cut.cut6_points(), "cut8": cut.cut8_points()}


def monte_carlo(runs: int, seed: int, T: float = air_traffic.T_RADAR, particles: int = PARTICLES,
                filters: tuple[str, ...] = air_traffic.FILTERS, legs: tuple[tuple[float, float], ...] = air_traffic.LEGS,
                turn_noise: float = air_traffic.L2, steps: int | None = None) -> dict[str, np.ndarray]:
    """Errors (runs, K, 3) of each filter over ``runs`` runs from ``seed``.

    Every filter in a run sees the same initial mean and radar data; the particle filter draws its
    particles and noise from a stream of its own. ``legs`` (the flight plan) and ``turn_noise`` (the
    filters' L2) change the set-up for experiments. With ``steps``, the filters stop after the first
    ``steps`` radar times (K = steps): the errors are then the first ``steps`` of the whole runs', bit for bit.
    """
    sc = air_traffic.scenario(T, legs, turn_noise)
    scenario_rng, particle_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
    m0, y = air_traffic.simulate_runs(sc, runs, scenario_rng)
    if steps is not None:
        sc, y = dataclasses.replace(sc, times=sc.times[:steps], truth=sc.truth[:steps]), y[:, :steps]
    sets = point_sets()
    estimates = {}
    for name in filters:
        if name == "pf":
            estimates[name] = air_traffic.run_bootstrap_pf(bootstrap_pf_step, sc, m0, y, particle_rng, particles)
        elif name == "ekf":
            estimates[name] = air_traffic.run_ekf(ekf_update, sc, m0, y)
        else:
            Z, w = sets[name]
            estimates[name] = air_traffic.run_sigma_point_filter(sigma_point_predict, sigma_point_update, Z, w, sc,
                                                                 m0, y)
    return {name: air_traffic.errors(est, sc) for name, est in estimates.items()}


def air_traffic_table(runs: int, seed: int, particles: int = PARTICLES) -> dict:
    """The lecture's table (and more) for T = 5 s, as the CLI prints it."""
    err = monte_carlo(runs, seed, particles=particles)
    return {"filters": {name: air_traffic.summarise(e) for name, e in err.items()}, "runs": runs, "seed": seed}


def _rounded(value):
    """Floats rounded to 6 significant figures, recursively, so the shipped file is stable and short."""
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_rounded(v) for v in value]
    if isinstance(value, float):
        return float(f"{value:.6g}")
    return value


@dataclasses.dataclass(frozen=True)
class Batch:
    """One Monte Carlo batch of the shipped results: ``runs`` runs from ``seed`` at radar interval T [s]."""

    name: str
    runs: int
    seed: int
    T: float = air_traffic.T_RADAR
    filters: tuple[str, ...] = air_traffic.FILTERS
    legs: tuple[tuple[float, float], ...] = air_traffic.LEGS

    def errors(self, filters: tuple[str, ...] | None = None, particles: int = PARTICLES,
               steps: int | None = None) -> dict[str, np.ndarray]:
        """monte_carlo of this batch, for ``filters`` (default all of the batch's)."""
        return monte_carlo(self.runs, self.seed, T=self.T, particles=particles, legs=self.legs,
                           filters=self.filters if filters is None else filters, steps=steps)


def batches(runs: int = DATA_RUNS, seed: int = DATA_SEED, sweep_runs: int = SWEEP_RUNS) -> tuple[Batch, ...]:
    """The batches of the shipped results: the T = 5 s table (``seed``), the sweep over T (seeds seed + 1, ...),
    and the CKF and UKF on the flight without turns (seed + 1 + len(SWEEP_T))."""
    return (
        Batch("table", runs, seed),
        *(Batch(f"sweep_T{T:g}", sweep_runs, seed + 1 + i, T=T) for i, T in enumerate(SWEEP_T)),
        Batch("straight", runs, seed + 1 + len(SWEEP_T), filters=("ckf", "ukf"), legs=air_traffic.STRAIGHT_LEGS),
    )


def results_from_errors(errors: dict[str, dict[str, np.ndarray]], runs: int = DATA_RUNS, seed: int = DATA_SEED,
                        sweep_runs: int = SWEEP_RUNS, particles: int = PARTICLES) -> dict:
    """Everything the notebook loads, from the errors (runs, K, 3) of each filter of each batch (by name): the
    T = 5 s table, RMSE_k curves, the CKF's and UKF's position RMSE_k on the flight without turns, and the
    sweep over T with its medians and its lost and diverged fractions."""
    err, straight = errors["table"], errors["straight"]
    sweep = {name: [] for name in air_traffic.FILTERS}
    sweep_lost = {name: [] for name in air_traffic.FILTERS}
    sweep_diverged = {name: [] for name in air_traffic.FILTERS}
    sweep_median = {name: [] for name in air_traffic.FILTERS}
    for T in SWEEP_T:
        for name, e in errors[f"sweep_T{T:g}"].items():
            sweep[name].append(air_traffic.lecture_metric(e).tolist())
            sweep_median[name].append(np.median(air_traffic.lecture_metric(e, axis=1), axis=0).tolist())
            sweep_lost[name].append(float(np.mean(air_traffic.lost_runs(e))))
            sweep_diverged[name].append(float(np.mean(air_traffic.diverged_runs(e))))
    return _rounded({
        "runs": runs, "seed": seed, "particles": particles,
        "filters": {name: air_traffic.summarise(e) for name, e in err.items()},
        "times": air_traffic.scenario().times.tolist(),
        "rmse_curves": {name: air_traffic.rmse_over_time(e).tolist() for name, e in err.items()},
        "straight_position_rmse": {name: air_traffic.rmse_over_time(e)[:, 0].tolist() for name, e in straight.items()},
        "sweep": {"T": list(SWEEP_T), "runs": sweep_runs, "filters": sweep, "lost_fraction": sweep_lost,
                  "diverged_fraction": sweep_diverged, "median": sweep_median},
    })


def results_text(results: dict) -> str:
    """The shipped JSON text of ``results``."""
    return json.dumps(results, indent=1) + "\n"


PF_ERRORS_FILE = "nonlinear_filters_pf_errors.records.npz"
"""The particle filter's errors (runs, K, 3) in every batch (by name), float64: what the shipped results
are computed from, shipped so that tests can check the results without rerunning the particle filter."""


def pf_records(errors: dict[str, dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """The particle filter's errors of each batch that runs it (batch name -> (runs, K, 3)), from the
    errors of every filter by batch: what PF_ERRORS_FILE holds."""
    return {name: by_filter["pf"] for name, by_filter in errors.items() if "pf" in by_filter}


def write_data(directory: Path) -> list[Path]:
    """Build the shipped Monte Carlo results from DATA_SEED, and the particle filter's errors, into ``directory``."""
    errors = {batch.name: batch.errors() for batch in batches()}
    path = Path(directory) / air_traffic.DATA_FILE.name
    path.write_text(results_text(results_from_errors(errors)))
    records = Path(directory) / PF_ERRORS_FILE
    write_npz(records, pf_records(errors))
    return [path, records]


# ------------------------------------------------------------------------------------------------
# The lost-run study: how often each filter loses a run, over thousands of runs
# ------------------------------------------------------------------------------------------------

LOST_STUDY_SEED = DATA_SEED + 1000
"""First seed of the lost-run study's batches (LOST_STUDY_SEED + b for batch b): distinct from the shipped
table's seeds (DATA_SEED to DATA_SEED + 5) and from the claim checks' (below 1000)."""
LOST_STUDY_BATCHES = 40
LOST_STUDY_RUNS = 100
"""The study: LOST_STUDY_BATCHES batches of LOST_STUDY_RUNS runs of every filter at T = 5 s (4000 runs)."""
LOST_STUDY_FILE = "nonlinear_filters_lost_runs.records.npz"
"""The study's per-run summary (per_run_summary of every filter, by ``<filter>/<quantity>``, batches in order)
and the seed of each run's batch: the PF takes about 0.2 s of CPU a run, so the study (about 15 min) is
shipped as a record, written by ``python -m solutions.nonlinear_filters.reference lost-study --out DIR``."""


def per_run_summary(err: np.ndarray) -> dict[str, np.ndarray]:
    """What the study keeps of each run, from the errors (runs, K, 3): the lecture's metric of the run (runs, 3),
    its time-RMS position error [m], its position error at the last radar return [m] (a run is lost if that is
    above LOST_KM) and its largest velocity error [m/s] (diverged above DIVERGED_KMS)."""
    return {"metric": air_traffic.lecture_metric(err, axis=1),
            "time_rms_position": np.sqrt(np.mean(err[:, :, 0] ** 2, axis=1)),
            "final_position": err[:, -1, 0].copy(),
            "peak_velocity": np.max(err[:, :, 1], axis=1)}


def lost_study_batch(batch: int, runs: int = LOST_STUDY_RUNS) -> dict[str, np.ndarray]:
    """The per-run summary of every filter (``<filter>/<quantity>``) on batch ``batch`` of the study (seed
    LOST_STUDY_SEED + batch), and the seed of each run (``seed``)."""
    err = monte_carlo(runs, LOST_STUDY_SEED + batch)
    summary = {f"{name}/{key}": value for name, e in err.items() for key, value in per_run_summary(e).items()}
    return {**summary, "seed": np.full(runs, LOST_STUDY_SEED + batch, dtype=np.int64)}


def lost_study_records(batches: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """The study's record from its batches in order: each array the batches' arrays end to end."""
    return {key: np.concatenate([b[key] for b in batches]) for key in batches[0]}


def write_lost_study(directory: Path, batches: int = LOST_STUDY_BATCHES) -> Path:
    """Run the lost-run study (``batches`` batches) and write its record into ``directory``."""
    path = Path(directory) / LOST_STUDY_FILE
    write_npz(path, lost_study_records([lost_study_batch(b) for b in range(batches)]))
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m solutions.nonlinear_filters.reference",
                                     description="The air-traffic comparison of the nonlinear-filters lab.")
    sub = parser.add_subparsers(dest="command", required=True)
    table = sub.add_parser("air-traffic", help="the lecture's table for T = 5 s from a Monte Carlo run")
    table.add_argument("--runs", type=int, default=DATA_RUNS)
    table.add_argument("--seed", type=int, default=DATA_SEED)
    table.add_argument("--particles", type=int, default=PARTICLES)
    table.add_argument("--json", action="store_true", help="print JSON on stdout")
    study = sub.add_parser("lost-study", help="the lost-run study over 4000 runs, written as a record (about 15 min)")
    study.add_argument("--out", type=Path, default=Path("solutions/records"))
    args = parser.parse_args(argv)
    if args.command == "lost-study":
        print(write_lost_study(args.out))
        return 0
    result = air_traffic_table(args.runs, args.seed, args.particles)
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        air_traffic.print_table(result["filters"], args.runs)
        air_traffic.print_robust_table(result["filters"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
