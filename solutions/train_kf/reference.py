"""Reference solution of the train-kf lab (handout "More Train Fun").

Notation follows the handout: x^f and B are the forecast and its covariance, x^a and B^a the
analysis, y^0 the observation, H the observation operator, R the observation error covariance.
Each function here is the model answer of one blank, and the lab's answer cell holds the same
code (a test keeps the two identical).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.linalg

from course import train

DATA_SEED = 20261139
"""Seed of the shipped hour of train data (course/data/train.csv): the first seed from 20261121 on
whose train keeps its speed between 40 and 160 mph all hour. With sigma = 15 mph per minute the
speed wanders by about 15 sqrt(60) = 116 mph in an hour, and many hours have a train that reverses."""


def gain_information_form(B: np.ndarray, H: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Kalman gain K (n x m) in information form, from B (n x n), H (m x n), R (m x m)."""
    n = B.shape[0]
    # B^-1, from a Cholesky factorisation of the SPD forecast covariance
    B_inv = scipy.linalg.cho_solve(scipy.linalg.cho_factor(B), np.eye(n))
    # (R^-1 H)^T = H^T R^-1, since R is symmetric
    RinvH = np.linalg.solve(R, H)
    # K = (B^-1 + H^T R^-1 H)^-1 (R^-1 H)^T
    return np.linalg.solve(B_inv + H.T @ RinvH, RinvH.T)


def gain_covariance_form(B: np.ndarray, H: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Kalman gain K (n x m) in covariance form, from B (n x n), H (m x n), R (m x m)."""
    # S = H B H^T + R, the covariance of the innovation
    S = H @ B @ H.T + R
    # K = B H^T S^-1, so K^T = S^-1 H B (B and S are symmetric)
    return np.linalg.solve(S, H @ B).T


def process_noise(sigma: float, dt_min: float = 1.0) -> np.ndarray:
    """Q (2 x 2) for a velocity random walk with standard deviation sigma (mph) per step.

    The step is dt_min minutes, so h = dt_min/60 hours converts mph to miles per step.
    """
    h = dt_min / 60.0
    # Z = (h z, z) with z ~ N(0, sigma^2), so Q = E[Z Z^T] = sigma^2 [[h^2, h], [h, 1]]
    return sigma**2 * np.array([[h * h, h], [h, 1.0]])


def predict(x: np.ndarray, B: np.ndarray, A: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Forecast step (predict.m): x (n,), B (n x n) to x^f (n,), B^f (n x n)."""
    # x^f_{t+1} = A x^a_t
    x_f = A @ x
    # B^f_{t+1} = A B^a_t A^T + Q
    B_f = A @ B @ A.T + Q
    return x_f, B_f


def kupdate(
    x_f: np.ndarray, B_f: np.ndarray, y: np.ndarray, H: np.ndarray, R: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Analysis step (Kupdate.m): x^f (n,), B^f (n x n), y^0 (m,) to x^a (n,), B^a (n x n)."""
    # K = B H^T (H B H^T + R)^-1
    K = gain_covariance_form(B_f, H, R)
    # x^a = x^f + K (y^0 - H x^f)   (the handout's "+ H x^f" is a typo)
    x_a = x_f + K @ (y - H @ x_f)
    # B^a = B - K H B
    B_a = B_f - K @ H @ B_f
    return x_a, B_a


def run_filter(
    y: np.ndarray,
    x0: np.ndarray,
    B0: np.ndarray,
    A: np.ndarray,
    Q: np.ndarray,
    H: np.ndarray,
    R: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The sequential Kalman filter (Run.m).

    y (T, m) holds one observation per step; x0 (n,) and B0 (n x n) are the belief before the
    first step. Returns the analyses x^a (T, n) and B^a (T, n, n), one per observation.
    """
    T, n = y.shape[0], x0.shape[0]
    xs, Bs = np.empty((T, n)), np.empty((T, n, n))
    x, B = x0, B0
    for t in range(T):
        # 1. forecast to the time of observation t, 2. assimilate it, 3. repeat
        x, B = predict(x, B, A, Q)
        x, B = kupdate(x, B, y[t], H, R)
        xs[t], Bs[t] = x, B
    return xs, Bs


def nees(errors: np.ndarray, covariances: np.ndarray) -> np.ndarray:
    """NEES (T,) of errors (T, n) against covariances (T, n, n): e_t^T B_t^-1 e_t at each time."""
    # B_t^-1 e_t, one solve per time (np.linalg.solve works on stacks of matrices)
    scaled = np.linalg.solve(covariances, errors[:, :, None])[:, :, 0]
    # eps_t = e_t^T B_t^-1 e_t
    return np.sum(errors * scaled, axis=1)


def write_data(directory: Path) -> list[Path]:
    """Build the shipped hour of train data from DATA_SEED into ``directory``."""
    path = Path(directory) / train.DATA_FILE.name
    train.write_csv(train.simulate(60, np.random.default_rng(DATA_SEED)), path)
    return [path]
