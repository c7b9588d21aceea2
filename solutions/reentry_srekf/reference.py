"""Hidden reference for the reentry-srekf lab (MCHA4400 Lab 5, square-root EKF).

The reference for every blank, the truth simulator that generates the shipped data, and the
command line that runs the reference filter on a data file and prints the handout's report::

    python -m solutions.reentry_srekf.reference --data course/data/starship_reentry.csv
    python -m solutions.reentry_srekf.reference --write-data course/data

State x = [h, v, c]: altitude [m], velocity [m/s] (v < 0 when falling), ballistic coefficient
[m^2/kg]. Square roots are upper triangular with S^T S = P. Equation numbers are the handout's.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import block_diag, solve_triangular

from course import starship
from course.starship import G, L, M, P0, R, RADAR_R1, RADAR_R2, SIGMA_RANGE, SQRT_Q, T0
from solutions.shipped_npz import write_npz

Vector = NDArray[np.float64]
Matrix = NDArray[np.float64]


# =============================================================================================
# Blank 1: ballistic process model
# =============================================================================================
def ballistic_dynamics(x: ArrayLike) -> Vector:
    """Mean dynamics f(x) of x = [h, v, c], equation (3). Returns shape (3,): [m/s, m/s^2, m^2/kg/s]."""
    h, v, c = np.asarray(x, dtype=float)
    # (8) T = T0 - L h
    T = T0 - L * h
    # (9) p = p0 (1 - L h / T0)^(g M / (R L))
    p = P0 * (1 - L * h / T0) ** (G * M / (R * L))
    # (5) rho = p M / (R T)
    rho = p * M / (R * T)
    # (4) d = rho v^2 c / 2
    d = 0.5 * rho * v**2 * c
    # (3) f = [v, d - g, 0]
    return np.array([v, d - G, 0.0])


def ballistic_jacobian(x: ArrayLike) -> Matrix:
    """Jacobian df/dx of equation (3), shape (3, 3)."""
    h, v, c = np.asarray(x, dtype=float)
    T = T0 - L * h
    exponent = G * M / (R * L)
    # (10) d = (M p0 / (2 R)) (T0 - L h)^-1 (1 - L h / T0)^(g M / (R L)) v^2 c
    rho = P0 * (1 - L * h / T0) ** exponent * M / (R * T)
    d = 0.5 * rho * v**2 * c
    # d is proportional to T^(gM/(RL) - 1) with dT/dh = -L, so dd/dh = d L (1 - gM/(RL)) / T
    dd_dh = d * L * (1 - exponent) / T
    # dd/dv = rho v c, dd/dc = rho v^2 / 2
    dd_dv = rho * v * c
    dd_dc = 0.5 * rho * v**2
    return np.array(
        [
            [0.0, 1.0, 0.0],
            [dd_dh, dd_dv, dd_dc],
            [0.0, 0.0, 0.0],
        ]
    )


# =============================================================================================
# Blank 2: range measurement model
# =============================================================================================
def radar_predict(x: ArrayLike) -> Vector:
    """Predicted range [m] from the radar at (r1, r2), equation (13). Returns shape (1,)."""
    h = float(np.asarray(x, dtype=float)[0])
    # (13) h_rng = sqrt(r1^2 + (h - r2)^2)
    return np.array([np.hypot(RADAR_R1, h - RADAR_R2)])


def radar_jacobian(x: ArrayLike) -> Matrix:
    """Jacobian of equation (13) with respect to x = [h, v, c], shape (1, 3)."""
    h = float(np.asarray(x, dtype=float)[0])
    h_rng = np.hypot(RADAR_R1, h - RADAR_R2)
    # d h_rng / dh = (h - r2) / h_rng; the range does not depend on v or c
    return np.array([[(h - RADAR_R2) / h_rng, 0.0, 0.0]])


# =============================================================================================
# Blank 3: marginal of a Gaussian in square-root form
# =============================================================================================
def marginal(mu: ArrayLike, S: ArrayLike, idx: ArrayLike) -> tuple[Vector, Matrix]:
    """Marginal N^(1/2)(mu_I, S_I) of the entries ``idx`` (any order, contiguous or not), eq. (22).

    mu: (n,), S: (n, n) upper triangular, idx: (n_I,) integer indices.
    Returns mu_I (n_I,) and upper-triangular S_I (n_I, n_I) with S_I^T S_I = P[idx][:, idx].
    """
    mu, S = np.asarray(mu, dtype=float), np.asarray(S, dtype=float)
    idx = np.asarray(idx, dtype=int).reshape(-1)
    # (22) S_{:,I} = Q [R1; 0]  =>  S_I = R1 (Q-less QR)
    S_I = np.linalg.qr(S[:, idx], mode="r")
    return mu[idx], S_I


# =============================================================================================
# Blank 4: conditional of a Gaussian in square-root form
# =============================================================================================
def conditional(
    mu: ArrayLike, S: ArrayLike, idx_a: ArrayLike, idx_b: ArrayLike, x_b: ArrayLike
) -> tuple[Vector, Matrix]:
    """Conditional p(x_A | x_B = x_b) = N^(1/2)(mu_c, S_c), equations (29) to (31).

    mu: (n,), S: (n, n) upper triangular, idx_a: (n_A,), idx_b: (n_B,), x_b: (n_B,).
    Returns mu_c (n_A,) and upper-triangular S_c (n_A, n_A).
    """
    mu, S = np.asarray(mu, dtype=float), np.asarray(S, dtype=float)
    idx_a = np.asarray(idx_a, dtype=int).reshape(-1)
    idx_b = np.asarray(idx_b, dtype=int).reshape(-1)
    x_b = np.asarray(x_b, dtype=float).reshape(-1)
    n_b = idx_b.size
    # (29)-(30) [S_{:,B}  S_{:,A}] = Q [R1 R2; 0 R3], a Q-less QR of the permuted columns
    R_ba = np.linalg.qr(S[:, np.concatenate([idx_b, idx_a])], mode="r")
    R1, R2, R3 = R_ba[:n_b, :n_b], R_ba[:n_b, n_b:], R_ba[n_b:, n_b:]
    # (31) mu_{A|B} = mu_A + R2^T R1^-T (x_B - mu_B), with R1^-T applied by a triangular solve
    mu_c = mu[idx_a] + R2.T @ solve_triangular(R1, x_b - mu[idx_b], trans="T")
    # (31) S_{A|B} = R3
    return mu_c, R3


# =============================================================================================
# Blank 5: square-root time update
# =============================================================================================
def sqrt_time_update(
    mu: ArrayLike, S: ArrayLike, f_and_jacobian: Callable[[Vector], tuple[Vector, Matrix]], S_Q: ArrayLike
) -> tuple[Vector, Matrix]:
    """Predict N^(1/2)(mu, S) through a step x+ = F(x, w) linearised at (mu, 0).

    mu: (n,), S: (n, n) upper triangular, S_Q: (q, q) upper-triangular square root of the
    covariance of the step's noise w. f_and_jacobian(mu) returns (F(mu, 0), J) with
    J = dF/d[x; w] of shape (n, n + q). Returns mu+ (n,) and upper-triangular S+ (n, n).
    """
    mu, S, S_Q = (np.asarray(a, dtype=float) for a in (mu, S, S_Q))
    mu_next, J = f_and_jacobian(mu)
    # square root of cov([x; w]) = blkdiag(P, Q): S_z = blkdiag(S, S_Q)
    S_z = block_diag(S, S_Q)
    # P+ = J blkdiag(P, Q) J^T = (S_z J^T)^T (S_z J^T), so S+ is the R of a Q-less QR of S_z J^T
    S_next = np.linalg.qr(S_z @ J.T, mode="r")
    return mu_next, S_next


# =============================================================================================
# Blank 6: square-root measurement update
# =============================================================================================
def sqrt_measurement_update(
    mu: ArrayLike, S: ArrayLike, y: ArrayLike, h_and_jacobian: Callable[[Vector], tuple[Vector, Matrix]],
    S_R: ArrayLike,
) -> tuple[Vector, Matrix]:
    """Condition N^(1/2)(mu, S) on y = h(x) + e, e ~ N^(1/2)(0, S_R), linearised at mu.

    mu: (n,), S: (n, n) upper triangular, y: (m,), S_R: (m, m) upper triangular.
    h_and_jacobian(mu) returns (h(mu) (m,), H (m, n)). Returns mu+ (n,) and upper-triangular S+ (n, n).
    """
    mu, S, S_R = (np.asarray(a, dtype=float) for a in (mu, S, S_R))
    y = np.atleast_1d(np.asarray(y, dtype=float))
    m, n = y.size, mu.size
    y_pred, H = h_and_jacobian(mu)
    # joint of [y; x] = [H x + e; x] near mu: covariance [H P H^T + R, H P; P H^T, P], whose
    # square root is the R factor of the QR of [S H^T  S; S_R  0]
    S_joint = np.linalg.qr(np.block([[S @ H.T, S], [S_R, np.zeros((m, n))]]), mode="r")
    # p(x | y): the state (the tail) given the measurement (the head), with the joint mean [h(mu); mu]
    return conditional(np.concatenate([y_pred, mu]), S_joint, np.arange(m, m + n), np.arange(m), y)


# =============================================================================================
# Blank 7: the ballistic-coefficient subplot of Figure 2
# =============================================================================================
def plot_ballistic_coefficient(
    ax: Axes, t: ArrayLike, c_true: ArrayLike, c_mean: ArrayLike, c_std: ArrayLike
) -> Axes:
    """Draw truth, estimate and 99.7% region (mean +/- 3 std) of c [m^2/kg] against t [s]."""
    t, c_mean, c_std = (np.asarray(a, dtype=float) for a in (t, c_mean, c_std))
    ax.fill_between(
        t, c_mean - 3 * c_std, c_mean + 3 * c_std, color="C0", alpha=0.25, linewidth=0, label="99.7% region (±3σ)"
    )
    ax.plot(t, c_true, color="k", linewidth=1.5, label="truth")
    ax.plot(t, c_mean, color="C0", linewidth=1.5, linestyle="--", label="estimate")
    ax.set(title="Ballistic coefficient", xlabel="Time [s]", ylabel="c [m²/kg]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right")
    return ax


# =============================================================================================
# Reference filter, truth simulator and data build
# =============================================================================================
def run_reference(data: starship.ReentryData, mu0: Vector = starship.MU0) -> starship.FilterResult:
    """The course framework run with the reference blanks, from the initial mean ``mu0`` (3,)."""
    return starship.run_square_root_ekf(
        data, ballistic_dynamics, ballistic_jacobian, radar_predict, radar_jacobian, sqrt_time_update,
        sqrt_measurement_update, mu0=mu0,
    )


DATA_SEED: int = 20230503  #: seed of the shipped data file
X0_TRUE, N_ROWS, DT, SUBSTEPS = starship.X0_TRUE, starship.N_ROWS, starship.DT, starship.SUBSTEPS


def simulate_reentry(rng: np.random.Generator) -> tuple[Vector, Matrix, Vector, Vector]:
    """One fall of :func:`course.starship.simulate_fall` with the reference model.

    Returns t (N,) [s], truth (N, 3), range_true (N,) [m], range_meas (N,) [m].
    """
    data = starship.simulate_fall(rng, ballistic_dynamics, radar_predict)
    return data.t, data.truth, data.range_true, data.range_meas


def posterior_square_root(S: ArrayLike, H: ArrayLike, sigma: float, dtype: type = np.float32) -> Matrix:
    """The posterior square root alone, from one Q-less QR computed in ``dtype``.

    [S H^T, S; sigma I, 0] = Q [R1, R2; 0, R3] gives S+ = R3 with S+^T S+ = P+. S: (n, n) upper
    triangular, H: (m, n), sigma [m] the noise standard deviation. Returns S+ (n, n) as float64.
    Hidden, because it is the heart of sqrt_measurement_update; part 8 gets its float32 results as data.
    """
    S, H = np.asarray(S, dtype=dtype), np.asarray(H, dtype=dtype)
    m, n = H.shape
    pre_array = np.block([[S @ H.T, S], [dtype(sigma) * np.eye(m, dtype=dtype), np.zeros((m, n), dtype=dtype)]])
    return np.linalg.qr(pre_array, mode="r")[m:, m:].astype(float)


def float32_square_root_text() -> str:
    """The text of the shipped float32 square-root results of part 8, over starship.FIRST_UPDATE_SIGMA."""
    H = radar_jacobian(starship.MU0)
    covariances = [S.T @ S for S in (posterior_square_root(starship.S0, H, s) for s in starship.FIRST_UPDATE_SIGMA)]
    return starship.format_float32_square_root_csv(
        starship.FIRST_UPDATE_SIGMA, [P[0, 0] for P in covariances], [starship.is_positive_definite(P) for P in covariances]
    )


FALL_SEEDS: range = range(7100, 7140)
"""Seeds of the 40 shipped simulated falls (``course/data/starship_falls.npz``), one per fall."""


def simulated_falls(seeds: Sequence[int] = FALL_SEEDS) -> starship.SimulatedFalls:
    """The falls of :func:`course.starship.simulate_falls` with the reference model, one per seed."""
    return starship.simulate_falls(seeds, ballistic_dynamics, radar_predict)


def data_text(seed: int = DATA_SEED) -> str:
    """The shipped data file's text, built from ``seed``."""
    t, truth, range_true, range_meas = simulate_reentry(np.random.default_rng(seed))
    return starship.format_csv(t, truth, range_true, range_meas)


def write_data(directory: str | Path, seed: int = DATA_SEED) -> list[Path]:
    """Build the shipped data files (``starship_reentry.csv`` from ``seed``, the float32
    square-root results of part 8, and the simulated falls of part 9) into ``directory``."""
    path = Path(directory) / starship.DATA_FILE.name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data_text(seed).encode("ascii"))
    float32_path = Path(directory) / starship.FLOAT32_SQUARE_ROOT_FILE.name
    float32_path.write_bytes(float32_square_root_text().encode("ascii"))
    falls, falls_path = simulated_falls(), Path(directory) / starship.FALLS_FILE.name
    write_npz(falls_path, {name: getattr(falls, name) for name in starship.FALL_ARRAYS})
    return [path, float32_path, falls_path]


def main(argv: Sequence[str] | None = None) -> None:
    """Command line: run the reference filter on a data file and print the report."""
    parser = argparse.ArgumentParser(prog="python -m solutions.reentry_srekf.reference", description=__doc__.splitlines()[0])
    parser.add_argument("--data", help="data file in the handout's CSV format (default: the shipped file)")
    parser.add_argument("--write-data", metavar="DIR", help="rebuild the data file from the seed into DIR and exit")
    args = parser.parse_args(argv)
    if args.write_data:
        for path in write_data(args.write_data):
            print(f"Wrote {path}")
        return
    data = starship.load(args.data)
    starship.print_report(data, run_reference(data))


if __name__ == "__main__":
    main()
