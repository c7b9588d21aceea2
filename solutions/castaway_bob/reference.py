"""Reference solution of the castaway-bob lab (handout "Saving Castaway Bob", T. Cooper, MIT 2024).

Notation follows the handout: the state is x = [x, y, wx, wy] (1) with Bob's own velocity w
relative to the water, A of (4), H of (6), K_v = R the GPS covariance, P the covariance,
K the Kalman gain (18), and (13) the Joseph form of the updated covariance. Units are SI:
positions in m, velocities in m/s, times in s; one step is one GPS fix, dt = 60 s. The defaults
of the filters are Bob's parameters in ``course.ocean`` (a test keeps them equal).

Each function here is the model answer of one blank, and the lab's answer cell holds the same
code (a test keeps the two identical). Bob's true drift needs no blank, so it lives in
``course.ocean``. The flow is built by ``solutions.castaway_bob.flow`` (PhiFlow, instructors only),
which this module imports only inside ``write_data``.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Callable

import numpy as np

# Bob's parameters, which the notebook's set-up imports too: a catalogued mistake that uses one of them in place of
# an argument (run_rank2 with SIGMA_GPS) runs here, where the diagnosis and the tests define it, as in a notebook.
from course.ocean import ALPHA, SIGMA_F, SIGMA_GPS  # noqa: F401


def transition_matrix(dt: float, alpha: float) -> np.ndarray:
    """A (4 x 4) of (4) for the state [x, y, wx, wy]: a step of dt [s], damping alpha per step."""
    # x[n+1] = x[n] + dt wx[n],  y[n+1] = y[n] + dt wy[n],  w[n+1] = alpha w[n]   (4)
    return np.array([
        [1.0, 0.0, dt, 0.0],
        [0.0, 1.0, 0.0, dt],
        [0.0, 0.0, alpha, 0.0],
        [0.0, 0.0, 0.0, alpha],
    ])


def observation_matrix() -> np.ndarray:
    """H (2 x 4) of (6): the GPS sees the position [x, y] of the state [x, y, wx, wy]."""
    # y[n] = H x[n] + n_y   (5), (6)
    return np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])


def trailing_mean(y: np.ndarray, order: int = 3) -> np.ndarray:
    """Figure 1's estimator: the trailing mean of the last `order` fixes, the current one included.

    The handout calls it a "fixed-lag mean"; it is a causal moving average, not a fixed-lag smoother.

    y (n, 2) [m] -> estimates (n, 2) [m]; the first fixes average the fixes there are so far.
    """
    y = np.asarray(y, dtype=float)
    estimates = np.empty_like(y)
    for n in range(len(y)):
        # x^[n] = (y[n-order+1] + ... + y[n]) / order, and no fix from after n
        window = y[max(0, n - order + 1): n + 1]
        estimates[n] = window.mean(axis=0)
    return estimates


def kalman_gain(P: np.ndarray, H: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Kalman gain K (n x m) of (18) from P (n x n), H (m x n) and R = K_v (m x m)."""
    # S = H P H^T + K_v, the covariance of the innovation
    S = H @ P @ H.T + R
    # K = P H^T S^-1   (18), so K^T = S^-1 H P (P and S are symmetric)
    return np.linalg.solve(S, H @ P).T


def joseph_covariance(P: np.ndarray, K: np.ndarray, H: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Updated covariance (n x n) in Joseph form (13), valid for any gain K (n x m)."""
    # I - K H
    I_KH = np.eye(P.shape[0]) - K @ H
    # P^ = (I - K H) P (I - K H)^T + K K_v K^T   (13)
    return I_KH @ P @ I_KH.T + K @ R @ K.T


def kalman_step(
    x: np.ndarray,
    P: np.ndarray,
    y: np.ndarray,
    A: np.ndarray,
    H: np.ndarray,
    Q: np.ndarray,
    R: np.ndarray,
    u: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """One predict and update: the estimate x (n,), P (n x n) at the last fix and the new fix
    y (m,) give the estimate at the new fix. u (n,) is an optional known input of the prediction."""
    # predict: x^-[n+1] = A x^[n] + u[n]   (10), with the known input u
    x_pred = A @ x if u is None else A @ x + u
    # P^-[n+1] = A P A^T + Q   (11)
    P_pred = A @ P @ A.T + Q
    # K = P^- H^T (H P^- H^T + K_v)^-1   (18)
    K = kalman_gain(P_pred, H, R)
    # x^ = x^- + K (y - H x^-)   (12)
    x_new = x_pred + K @ (y - H @ x_pred)
    # P^ = (I - K H) P^- (I - K H)^T + K K_v K^T   (13)
    P_new = joseph_covariance(P_pred, K, H, R)
    return x_new, P_new


def run_rank2(y: np.ndarray, sigma_walk: float = 30.0, sigma_gps: float = 50.0) -> tuple[np.ndarray, np.ndarray]:
    """Figure 2's rank-2 filter: state = position, a random walk of sigma_walk [m] per fix.

    y (n, 2) [m] -> estimates (n, 2) [m] and covariances (n, 2, 2) [m^2], one per fix.
    """
    n = len(y)
    # x[k+1] = x[k] + e[k], e ~ N(0, sigma_walk^2 I_2);  y[k] = x[k] + n_y, n_y ~ N(0, sigma_gps^2 I_2)
    A, H = np.eye(2), np.eye(2)
    Q, R = sigma_walk**2 * np.eye(2), sigma_gps**2 * np.eye(2)
    xs, Ps = np.empty((n, 2)), np.empty((n, 2, 2))
    # the first estimate is the first fix, as uncertain as the GPS
    xs[0], Ps[0] = y[0], R
    for k in range(1, n):
        xs[k], Ps[k] = kalman_step(xs[k - 1], Ps[k - 1], y[k], A, H, Q, R)
    return xs, Ps


def run_rank4(
    y: np.ndarray,
    flow: Callable[[np.ndarray, float], np.ndarray],
    t: np.ndarray,
    alpha: float = 0.95,
    sigma_F: float = 0.02,
    sigma_gps: float = 50.0,
    dt: float = 60.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Figure 3's rank-4 filter: state [x, y, wx, wy], the known current as input.

    y (n, 2) [m] fixes at times t (n,) [s]; flow(p, t) is the current [m/s] at p (2,) [m].
    Returns estimates (n, 4) and covariances (n, 4, 4), one per fix.
    """
    n = len(y)
    A, H = transition_matrix(dt, alpha), observation_matrix()
    # Q = diag(0, 0, sigma_F^2, sigma_F^2): F drives w only (the handout's sigma_F I_4 in (11) is a slip)
    Q = np.diag([0.0, 0.0, sigma_F**2, sigma_F**2])
    R = sigma_gps**2 * np.eye(2)
    xs, Ps = np.empty((n, 4)), np.empty((n, 4, 4))
    # first estimate: the first fix, and w = 0 with its stationary variance sigma_F^2 / (1 - alpha^2)
    var_w = sigma_F**2 / (1.0 - alpha**2)
    xs[0] = [y[0][0], y[0][1], 0.0, 0.0]
    Ps[0] = np.diag([sigma_gps**2, sigma_gps**2, var_w, var_w])
    for k in range(1, n):
        # x[k] = A x[k-1] + [dt u(x^[k-1], t[k-1]); 0, 0] + [0; 0; F]: the current, at the estimate
        u = np.concatenate((dt * flow(xs[k - 1, :2], t[k - 1]), [0.0, 0.0]))
        xs[k], Ps[k] = kalman_step(xs[k - 1], Ps[k - 1], y[k], A, H, Q, R, u=u)
    return xs, Ps


def track_rmse(estimates: np.ndarray, truth: np.ndarray) -> float:
    """Root mean square position error [m] of estimates (n, 2) [m] against the truth (n, 2) [m]."""
    error = np.asarray(estimates, dtype=float) - np.asarray(truth, dtype=float)
    # RMSE = sqrt( (1/n) sum_k |x^[k] - x[k]|^2 ), |.| the 2-D distance
    return float(np.sqrt(np.mean(np.sum(error**2, axis=-1))))


def ellipse_area(P: np.ndarray, n_sigma: float = 2.0) -> np.ndarray:
    """Area [m^2] of the n_sigma ellipse of each 2-D covariance in P (..., 2, 2) [m^2]: shape (...)."""
    # {d : d^T P^-1 d <= n_sigma^2} has semi-axes n_sigma sqrt(lambda_1), n_sigma sqrt(lambda_2),
    # so its area is pi n_sigma^2 sqrt(lambda_1 lambda_2) = pi n_sigma^2 sqrt(det P)
    return np.pi * n_sigma**2 * np.sqrt(np.linalg.det(P))


def write_data(directory: str | Path) -> list[Path]:
    """Build the shipped flow (castaway_bob_flow.npz, and the solver checkpoints that let tests rebuild parts
    of it) from its seed into ``directory`` (needs PhiFlow)."""
    from solutions.castaway_bob import flow

    return flow.write_flow(directory)


if __name__ == "__main__":  # pragma: no cover
    for written in write_data(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "course" / "data"):
        print(f"wrote {written}")
