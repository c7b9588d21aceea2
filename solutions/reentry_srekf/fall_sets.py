"""Whole sets of simulated falls at once, for the claims of part 9 (``solutions/reentry_srekf/claims.py``).

The claims about the NEES averaged over 40 falls are checked on the shipped falls and on fresh sets of 40
falls simulated from other seeds. ``course.starship.simulate_falls`` and ``filter_falls`` with the reference
take about 30 s of one core a set (a Python loop per fall, per step and per RK4 substep). This module does the
same arithmetic with every fall of every set as one row of an array, which takes a few seconds for several
sets together: the same draws from each seed as ``course.starship.simulate_falls``, the same RK4 steps, and the
reference's square-root time and measurement updates. ``claims.py`` checks on every run that it reproduces the
shipped falls (built by the reference's simulator) and the reference filter's run on them to within rounding
(measured: 2e-16 relative in the truth, 3e-12 in the NEES, 1e-14 in the standard deviations).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from course import starship
from course.starship import G, L, M, P0, R, RADAR_R1, RADAR_R2, SIGMA_RANGE, SQRT_Q, T0

Array = NDArray[np.float64]

_EXPONENT = G * M / (R * L)


def _density(h: Array) -> tuple[Array, Array]:
    """Air density rho [kg/m^3] and temperature T [K] at altitudes h [m], equations (5), (8) and (9)."""
    T = T0 - L * h
    return P0 * (1 - L * h / T0) ** _EXPONENT * M / (R * T), T


def _dynamics(X: Array) -> Array:
    """f(x) of equation (3) for each row of X, (B, 3) -> (B, 3)."""
    h, v, c = X[:, 0], X[:, 1], X[:, 2]
    rho, _ = _density(h)
    # (4) d = rho v^2 c / 2;  (3) f = [v, d - g, 0]
    return np.stack([v, 0.5 * rho * v**2 * c - G, np.zeros_like(h)], axis=1)


def _jacobian(X: Array) -> Array:
    """df/dx for each row of X, (B, 3) -> (B, 3, 3), as ``reference.ballistic_jacobian``."""
    h, v, c = X[:, 0], X[:, 1], X[:, 2]
    rho, T = _density(h)
    d = 0.5 * rho * v**2 * c
    J = np.zeros((X.shape[0], 3, 3))
    J[:, 0, 1] = 1.0
    J[:, 1, 0] = d * L * (1 - _EXPONENT) / T
    J[:, 1, 1] = rho * v * c
    J[:, 1, 2] = 0.5 * rho * v**2
    return J


def _rk4_step(X: Array, W: Array, dt: float) -> Array:
    """``course.starship.rk4_step`` for each row of X with its noise increment, the row of W."""
    k1 = _dynamics(X)
    k2 = _dynamics(X + (k1 * dt + W) / 2)
    k3 = _dynamics(X + (k2 * dt + W) / 2)
    k4 = _dynamics(X + k3 * dt + W)
    return X + dt * (k1 + 2 * k2 + 2 * k3 + k4) / 6 + W


def _rk4_step_with_jacobian(X: Array, dt: float) -> tuple[Array, Array]:
    """``course.starship.rk4_step_with_jacobian`` at w = 0 for each row of X: (B, 3) and J (B, 3, 6)."""
    dx = np.hstack([np.eye(3), np.zeros((3, 3))])
    dw = np.hstack([np.zeros((3, 3)), np.eye(3)])
    k1 = _dynamics(X)
    dk1 = _jacobian(X) @ dx
    X2 = X + k1 * dt / 2
    dk2 = _jacobian(X2) @ (dx + (dk1 * dt + dw) / 2)
    k2 = _dynamics(X2)
    X3 = X + k2 * dt / 2
    dk3 = _jacobian(X3) @ (dx + (dk2 * dt + dw) / 2)
    k3 = _dynamics(X3)
    X4 = X + k3 * dt
    dk4 = _jacobian(X4) @ (dx + dk3 * dt + dw)
    k4 = _dynamics(X4)
    return X + dt * (k1 + 2 * k2 + 2 * k3 + k4) / 6, dx + dt * (dk1 + 2 * dk2 + 2 * dk3 + dk4) / 6 + dw


def simulate_sets(seeds: Sequence[int]) -> starship.SimulatedFalls:
    """``course.starship.simulate_falls(seeds, ...)`` with the reference model, all falls at once."""
    N, substeps, dt = starship.N_ROWS, starship.SUBSTEPS, starship.DT
    B = len(seeds)
    process_noise, range_noise, e0 = np.empty((B, N - 1, substeps, 3)), np.empty((B, N)), np.empty((B, 3))
    for i, seed in enumerate(seeds):
        # the draws of simulate_fall, in its order, then the initial mean's
        rng = np.random.default_rng(seed)
        process_noise[i] = rng.standard_normal((N - 1, substeps, 3))
        range_noise[i] = rng.standard_normal(N)
        e0[i] = rng.standard_normal(3)
    h_sub = dt / substeps
    X = np.tile(starship.X0_TRUE, (B, 1))
    truth = np.empty((B, N, 3))
    truth[:, 0] = X
    for k in range(1, N):
        for j in range(substeps):
            # w = SQRT_Q^T e sqrt(dt / substeps), one row per fall
            X = _rk4_step(X, process_noise[:, k - 1, j] @ SQRT_Q * np.sqrt(h_sub), h_sub)
        truth[:, k] = X
    # (13) the true range, then range + N(0, SIGMA_RANGE^2)
    range_true = np.hypot(RADAR_R1, truth[..., 0] - RADAR_R2)
    return starship.SimulatedFalls(t=np.arange(N) * dt, truth=truth, range_true=range_true,
                                   range_meas=range_true + SIGMA_RANGE * range_noise,
                                   mu0=starship.X0_TRUE - e0 @ starship.S0)


def _filter(falls: starship.SimulatedFalls) -> starship.MonteCarloRun:
    """``course.starship.filter_falls`` with the reference's blanks, every fall at once."""
    B, N = falls.range_meas.shape
    mu, S = falls.mu0.copy(), np.tile(starship.S0, (B, 1, 1))
    mus, Ss = np.empty((B, N, 3)), np.empty((B, N, 3, 3))
    time = 0.0
    for k in range(N):
        dt = float(falls.t[k] - time)
        if dt > 0:
            mu, J = _rk4_step_with_jacobian(mu, dt)
            # S+ = R of the Q-less QR of blkdiag(S, S_Q) J^T
            S_z = np.zeros((B, 6, 6))
            S_z[:, :3, :3], S_z[:, 3:, 3:] = S, SQRT_Q * np.sqrt(dt)
            S = np.linalg.qr(S_z @ np.swapaxes(J, 1, 2), mode="r")
        time = float(falls.t[k])
        y_pred = np.hypot(RADAR_R1, mu[:, 0] - RADAR_R2)
        H_h = (mu[:, 0] - RADAR_R2) / y_pred
        # joint of [y; x]: the R of the QR of [S H^T  S; S_R  0] = [R1 R2; 0 R3]
        pre = np.zeros((B, 4, 4))
        pre[:, :3, 0] = S[:, :, 0] * H_h[:, None]
        pre[:, :3, 1:] = S
        pre[:, 3, 0] = SIGMA_RANGE
        joint = np.linalg.qr(pre, mode="r")
        # (31) mu+ = mu + R2^T R1^-T (y - h(mu)),  S+ = R3
        mu = mu + joint[:, 0, 1:] * ((falls.range_meas[:, k] - y_pred) / joint[:, 0, 0])[:, None]
        S = joint[:, 1:, 1:]
        mus[:, k], Ss[:, k] = mu, S
    # NEES = |S^-T e|^2, S^T lower triangular: forward substitution
    e = falls.truth - mus
    w0 = e[..., 0] / Ss[..., 0, 0]
    w1 = (e[..., 1] - Ss[..., 0, 1] * w0) / Ss[..., 1, 1]
    w2 = (e[..., 2] - Ss[..., 0, 2] * w0 - Ss[..., 1, 2] * w1) / Ss[..., 2, 2]
    std = np.sqrt(np.einsum("fkij,fkij->fkj", Ss, Ss))
    return starship.MonteCarloRun(t=falls.t.copy(), nees=w0**2 + w1**2 + w2**2, mu=mus, truth=falls.truth.copy(),
                                  std=std, mu0=falls.mu0.copy())


def filter_sets(sets: Sequence[starship.SimulatedFalls]) -> tuple[starship.MonteCarloRun, ...]:
    """Each set of falls filtered as ``course.starship.filter_falls`` does with the reference, all in one batch."""
    run = _filter(starship.SimulatedFalls(
        t=sets[0].t, truth=np.concatenate([s.truth for s in sets]), range_true=np.concatenate([s.range_true for s in sets]),
        range_meas=np.concatenate([s.range_meas for s in sets]), mu0=np.concatenate([s.mu0 for s in sets])))
    edges = np.cumsum([0] + [s.mu0.shape[0] for s in sets])
    return tuple(starship.MonteCarloRun(t=run.t, nees=run.nees[a:b], mu=run.mu[a:b], truth=run.truth[a:b],
                                        std=run.std[a:b], mu0=run.mu0[a:b]) for a, b in zip(edges[:-1], edges[1:]))
