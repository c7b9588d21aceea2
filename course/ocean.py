"""The castaway-bob lab's world: the ocean flow, Bob's drift, the GPS, the comparison and the figures.

Units: SI inside (positions in m, velocities in m/s, times in s); the figures show km and
minutes. Positions are (x, y) with x pointing downstream and the island at the origin.

The flow is a vortex street behind an island of diameter 1 km in a 0.5 m/s current, computed
by a 2-D incompressible Navier-Stokes solver at Reynolds number 150 and shipped as velocity
snapshots every 6 minutes on a 200 m grid (``data/castaway_bob_flow.npz``; the instructors rebuild
it from a seed, bit for bit). ``load()`` returns it as a ``Flow``, a function
u(p, t) that interpolates the snapshots linearly in x, y and t with SciPy.

Bob (handout equations (1)-(4), with the issue's reading): his state is [x, y, wx, wy], where
w is his own velocity relative to the water. Each minute
    w[n+1] = alpha w[n] + F[n],   F[n] ~ N(0, sigma_F^2 I_2),
and his position follows dx/dt = u(x, t) + w[n] over the minute, integrated with RK4 substeps.
The GPS gives y[n] = [x, y] + N(0, sigma_GPS^2 I_2) once a minute.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Ellipse
from scipy.ndimage import map_coordinates

DATA_FILE = Path(__file__).parent / "data" / "castaway_bob_flow.npz"

DT = 60.0
"""Time between GPS fixes and model steps, s."""
ALPHA = 0.95
"""Damping of Bob's own velocity per minute (weak: alpha < 1)."""
SIGMA_F = 0.02
"""Standard deviation of the random force F per minute, m/s (each axis)."""
SIGMA_GPS = 50.0
"""Standard deviation of the GPS error, m (each axis): the handout's "50 m radius"."""
SIGMA_WALK = 30.0
"""Default random-walk step of the rank-2 filter, m per minute: 0.5 m/s current x 60 s."""
N_FIXES = 120
"""Fixes in a drift: two hours."""
SUBSTEPS = 3
"""RK4 substeps per minute in Bob's true drift."""
START_BOX = ((1500.0, 6000.0), (-1500.0, 1500.0))
"""Where Bob falls in: x and y ranges, m (behind the island, in its wake)."""

Estimator = Callable[..., tuple[np.ndarray, np.ndarray]]


# ----------------------------------------------------------------------------------------------
# The flow
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Flow:
    """The ocean current u(x, y, t) on a regular grid.

    x (nx,), y (ny,) [m] are the grid's cell centres, t (nt,) [s] the snapshot times, and
    velocity (nt, nx, ny, 2) [m/s] the current. Call it as ``flow(p, t)`` with positions p of
    shape (..., 2) [m] and a time t [s] (a float, or an array that broadcasts with p[..., 0]) to
    get the velocity (..., 2) [m/s], interpolated linearly in t, x and y with SciPy's
    ``map_coordinates``. Positions outside the grid see the velocity at its edge, and times are
    clipped to the shipped window.
    """

    x: np.ndarray
    y: np.ndarray
    t: np.ndarray
    velocity: np.ndarray
    island_center: np.ndarray
    island_radius: float
    reynolds: float
    current: float
    solver: str

    def __post_init__(self) -> None:
        for name in ("t", "x", "y"):
            steps = np.diff(getattr(self, name))
            if not np.allclose(steps, steps[0], rtol=1e-9, atol=0.0):
                raise ValueError(f"Flow.{name} must be evenly spaced")
        # one contiguous (nt, nx, ny) array per velocity component, for map_coordinates
        components = tuple(np.ascontiguousarray(self.velocity[..., c]) for c in range(2))
        object.__setattr__(self, "_components", components)

    def __call__(self, p: np.ndarray, t: float | np.ndarray) -> np.ndarray:
        p = np.asarray(p, dtype=float)
        # fractional grid indices of (t, x, y); linear interpolation between the 8 neighbours,
        # and the edge value outside the grid (mode="nearest")
        indices = np.stack(np.broadcast_arrays(
            (np.asarray(t, dtype=float) - self.t[0]) / (self.t[1] - self.t[0]),
            (p[..., 0] - self.x[0]) / (self.x[1] - self.x[0]),
            (p[..., 1] - self.y[0]) / (self.y[1] - self.y[0]),
        ))
        flat = indices.reshape(3, -1)
        u = [map_coordinates(c, flat, order=1, mode="nearest") for c in self._components]
        return np.stack(u, axis=-1).reshape(indices.shape[1:] + (2,))

    def scaled(self, factor: float) -> "Flow":
        """The same flow pattern with every velocity multiplied by ``factor`` (e.g. a weaker tide)."""
        return replace(self, velocity=factor * self.velocity, current=factor * self.current)

    @property
    def duration(self) -> float:
        """Length of the shipped window, s."""
        return float(self.t[-1] - self.t[0])

    def snapshot(self, t: float) -> np.ndarray:
        """The velocity on the whole grid at time t [s], shape (nx, ny, 2), linear in time."""
        k = int(np.clip(np.searchsorted(self.t, t) - 1, 0, len(self.t) - 2))
        s = float(np.clip((t - self.t[k]) / (self.t[k + 1] - self.t[k]), 0.0, 1.0))
        return (1.0 - s) * self.velocity[k] + s * self.velocity[k + 1]

    def vorticity(self, t: float) -> np.ndarray:
        """dv/dx - du/dy on the grid at time t [s], shape (nx, ny), in 1/s (centred differences)."""
        u = self.snapshot(t)
        return np.gradient(u[..., 1], self.x, axis=0) - np.gradient(u[..., 0], self.y, axis=1)

    def divergence(self, t: float) -> np.ndarray:
        """du/dx + dv/dy on the grid at time t [s], shape (nx, ny), in 1/s (centred differences)."""
        u = self.snapshot(t)
        return np.gradient(u[..., 0], self.x, axis=0) + np.gradient(u[..., 1], self.y, axis=1)


def load(path: Path = DATA_FILE) -> Flow:
    """Load the shipped flow (float16 on disk, float64 in memory)."""
    with np.load(path, allow_pickle=False) as data:
        return Flow(
            x=data["x_m"].astype(float),
            y=data["y_m"].astype(float),
            t=data["t_s"].astype(float),
            velocity=data["velocity_m_s"].astype(float),
            island_center=data["island_center_m"].astype(float),
            island_radius=float(data["island_radius_m"]),
            reynolds=float(data["reynolds"]),
            current=float(data["current_m_s"]),
            solver=str(data["solver"]),
        )


# ----------------------------------------------------------------------------------------------
# Bob's drift and the GPS
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Drift:
    """One drift of Bob: n fixes, one a minute.

    t (n,) [s] are the fix times in the flow's clock, truth (n, 4) Bob's true state
    [x, y, wx, wy] [m, m, m/s, m/s] at those times, and fixes (n, 2) [m] the GPS fixes y[n].
    """

    t: np.ndarray
    truth: np.ndarray
    fixes: np.ndarray

    @property
    def position(self) -> np.ndarray:
        """Bob's true position, shape (n, 2), m."""
        return self.truth[:, :2]


def drift_step(flow: Flow, p: np.ndarray, w: np.ndarray, t: float, dt: float = DT, substeps: int = SUBSTEPS) -> np.ndarray:
    """Bob's position after dt [s]: dx/dt = u(x, t) + w, with w held fixed, by RK4 substeps.

    p and w have shape (..., 2) [m, m/s]; returns the new positions (..., 2) [m].
    """
    h = dt / substeps
    for k in range(substeps):
        s = t + k * h
        k1 = flow(p, s) + w
        k2 = flow(p + 0.5 * h * k1, s + 0.5 * h) + w
        k3 = flow(p + 0.5 * h * k2, s + 0.5 * h) + w
        k4 = flow(p + h * k3, s + h) + w
        p = p + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return p


def simulate_drifts(
    flow: Flow,
    rng: np.random.Generator,
    n_drifts: int,
    n_fixes: int = N_FIXES,
    dt: float = DT,
    alpha: float = ALPHA,
    sigma_F: float = SIGMA_F,
    sigma_gps: float = SIGMA_GPS,
) -> list[Drift]:
    """Simulate ``n_drifts`` independent drifts of Bob (all at once, vectorised) and their GPS fixes.

    Each drift starts at a random time in the flow's window and a random point of START_BOX,
    with w drawn from its stationary law N(0, sigma_F^2 / (1 - alpha^2) I_2).
    """
    (x0, x1), (y0, y1) = START_BOX
    latest_start = flow.t[-1] - (n_fixes - 1) * dt
    if latest_start < flow.t[0]:
        raise ValueError(f"{n_fixes} fixes {dt:g} s apart do not fit in the flow's {flow.duration / 3600:g} h window")
    t0 = dt * rng.integers(0, int((latest_start - flow.t[0]) // dt) + 1, size=n_drifts) + flow.t[0]
    p = np.column_stack((rng.uniform(x0, x1, n_drifts), rng.uniform(y0, y1, n_drifts)))
    w = rng.normal(0.0, sigma_F / np.sqrt(1.0 - alpha**2), size=(n_drifts, 2))
    states = np.empty((n_fixes, n_drifts, 4))
    for n in range(n_fixes):
        states[n] = np.column_stack((p, w))
        if n + 1 < n_fixes:
            # dx/dt = u(x, t) + w[n] over the minute;  w[n+1] = alpha w[n] + F[n]   (2)-(4)
            p = drift_step(flow, p, w, t0 + n * dt, dt)
            w = alpha * w + rng.normal(0.0, sigma_F, size=(n_drifts, 2))
    # y[n] = H x[n] + n_y,  n_y ~ N(0, sigma_GPS^2 I_2)   (5)
    fixes = states[..., :2] + rng.normal(0.0, sigma_gps, size=(n_fixes, n_drifts, 2))
    times = t0[None, :] + dt * np.arange(n_fixes)[:, None]
    return [Drift(times[:, k].copy(), states[:, k].copy(), fixes[:, k].copy()) for k in range(n_drifts)]


def simulate_drift(flow: Flow, rng: np.random.Generator, **options) -> Drift:
    """One drift of Bob; the options are those of ``simulate_drifts``."""
    return simulate_drifts(flow, rng, 1, **options)[0]


# ----------------------------------------------------------------------------------------------
# Running and comparing the estimators (they are passed in: these functions write none of them)
# ----------------------------------------------------------------------------------------------

Tracks = dict[str, tuple[np.ndarray, np.ndarray | None]]
"""Estimator name -> (estimated positions (n, 2) [m], position covariances (n, 2, 2) [m^2] or None)."""

NAMES = ("moving average", "rank-2 KF", "CV control", "rank-4 KF")
"""The estimators compared: the trailing mean of 3 fixes, the rank-2 random-walk filter, the
constant-velocity control (4 states, no current map) and the rank-4 filter (4 states, the current known)."""
NO_MAP = "rank-4, no map"
"""The ablation scored beside them: the rank-4 filter told the sea is still (its damped-velocity model
alpha, sigma_F kept, the current map removed). It is not one of NAMES: it is not counted in "best on"."""


def still_water(p: np.ndarray, t: float | np.ndarray) -> np.ndarray:
    """A current of 0 m/s everywhere: the flow given to the rank-4 filter for the NO_MAP ablation."""
    return np.zeros(np.shape(p))


def constant_velocity_filter(
    kalman_step: Callable[..., tuple[np.ndarray, np.ndarray]],
    transition_matrix: Callable[[float, float], np.ndarray],
    observation_matrix: Callable[[], np.ndarray],
    sigma_v0: float,
    sigma_v: float = SIGMA_F,
    sigma_gps: float = SIGMA_GPS,
    dt: float = DT,
) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The control of the comparison: the rank-4 filter's four states without the current map.

    The state [x, y, vx, vy] holds Bob's velocity over the ground, which the filter must learn from
    the fixes: A = transition_matrix(dt, 1) (alpha = 1, no damping), the velocity a random walk of
    sigma_v [m/s] per step, Q = diag(0, 0, sigma_v^2, sigma_v^2), no input. It starts from the first
    fix with velocity 0 +- sigma_v0 [m/s]: pass the speed of the current Bob drifts in (flow.current),
    the size of the velocity it has to learn. Built from the given blanks; returns run(y (n, 2) [m]) ->
    estimates (n, 4), covariances (n, 4, 4).
    """
    # x[k+1] = A(dt, alpha = 1) x[k] + [0, 0, e_x, e_y],  e ~ N(0, sigma_v^2 I_2);  y[k] = H x[k] + n_y
    A, H = transition_matrix(dt, 1.0), observation_matrix()
    Q = np.diag([0.0, 0.0, sigma_v**2, sigma_v**2])
    R = sigma_gps**2 * np.eye(2)

    def run(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = len(y)
        xs, Ps = np.empty((n, 4)), np.empty((n, 4, 4))
        xs[0] = [y[0][0], y[0][1], 0.0, 0.0]
        Ps[0] = np.diag([sigma_gps**2, sigma_gps**2, sigma_v0**2, sigma_v0**2])
        for k in range(1, n):
            xs[k], Ps[k] = kalman_step(xs[k - 1], Ps[k - 1], y[k], A, H, Q, R)
        return xs, Ps

    return run


def run_estimators(
    drift: Drift,
    flow: Flow,
    trailing_mean: Callable[[np.ndarray], np.ndarray],
    run_rank2: Estimator,
    run_cv: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    run_rank4: Estimator,
    sigma_walk: float = SIGMA_WALK,
) -> Tracks:
    """Run the four estimators of ``NAMES`` on one drift; returns their position tracks and covariances."""
    rank2, P2 = run_rank2(drift.fixes, sigma_walk=sigma_walk)
    cv, Pcv = run_cv(drift.fixes)
    rank4, P4 = run_rank4(drift.fixes, flow, drift.t)
    return {
        NAMES[0]: (np.asarray(trailing_mean(drift.fixes)), None),
        NAMES[1]: (np.asarray(rank2)[:, :2], np.asarray(P2)[:, :2, :2]),
        NAMES[2]: (np.asarray(cv)[:, :2], np.asarray(Pcv)[:, :2, :2]),
        NAMES[3]: (np.asarray(rank4)[:, :2], np.asarray(P4)[:, :2, :2]),
    }


@dataclass(frozen=True)
class Comparison:
    """Per-drift scores: rmse[name] (n_drifts,) [m]; for the filters, area[name] (n_drifts,) [m^2],
    the mean 2-sigma ellipse area over the drift's fixes, and inside[name] (n_drifts,), the
    fraction of fixes whose 2-sigma ellipse holds Bob (1 - exp(-2) = 86.5 % for honest ellipses)."""

    rmse: dict[str, np.ndarray]
    area: dict[str, np.ndarray]
    inside: dict[str, np.ndarray]
    n_fixes: int


def compare(
    drifts: list[Drift],
    flow: Flow,
    trailing_mean: Callable[[np.ndarray], np.ndarray],
    run_rank2: Estimator,
    run_cv: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    run_rank4: Estimator,
    track_rmse: Callable[[np.ndarray, np.ndarray], float],
    ellipse_area: Callable[..., np.ndarray],
    sigma_walk: float = SIGMA_WALK,
) -> Comparison:
    """Score the four estimators on every drift with the given RMSE and ellipse-area functions, and
    the NO_MAP ablation (run_rank4 in still water) by its RMSE only."""
    rmse: dict[str, list[float]] = {name: [] for name in NAMES + (NO_MAP,)}
    area: dict[str, list[float]] = {name: [] for name in NAMES[1:]}
    inside: dict[str, list[float]] = {name: [] for name in NAMES[1:]}
    for drift in drifts:
        tracks = run_estimators(drift, flow, trailing_mean, run_rank2, run_cv, run_rank4, sigma_walk)
        for name, (estimate, P) in tracks.items():
            rmse[name].append(float(track_rmse(estimate, drift.position)))
            if P is not None:
                area[name].append(float(np.mean(ellipse_area(P))))
                # Bob is inside the 2-sigma ellipse when e^T P^-1 e <= 4, e = estimate - truth
                e = np.asarray(estimate) - drift.position
                mahalanobis2 = np.einsum("ni,ni->n", e, np.linalg.solve(P, e[..., None])[..., 0])
                inside[name].append(float(np.mean(mahalanobis2 <= 4.0)))
        rmse[NO_MAP].append(float(track_rmse(np.asarray(run_rank4(drift.fixes, still_water, drift.t)[0])[:, :2],
                                             drift.position)))
    as_arrays = lambda scores: {k: np.array(v) for k, v in scores.items()}  # noqa: E731
    return Comparison(as_arrays(rmse), as_arrays(area), as_arrays(inside), len(drifts[0].t))


def format_comparison(result: Comparison, raw_gps: np.ndarray | None = None) -> str:
    """The comparison as a table: the RMSE's mean, standard deviation and median over the drifts,
    on how many drifts each estimator was best, and the filters' mean 2-sigma area and coverage."""
    n = len(next(iter(result.rmse.values())))
    stacked = np.column_stack([result.rmse[name] for name in NAMES])
    wins = np.bincount(np.argmin(stacked, axis=1), minlength=len(NAMES))
    lines = [
        f"{n} drifts of {result.n_fixes} fixes. RMSE = root mean square position error over a drift.",
        f"{'estimator':<16}{'RMSE mean':>11}{'sd':>8}{'median':>9}{'best on':>9}{'2-sigma area':>15}"
        f"{'Bob inside':>12}",
    ]
    if raw_gps is not None:
        lines.append(f"{'raw GPS':<16}{np.mean(raw_gps):>9.1f} m{np.std(raw_gps):>8.1f}{np.median(raw_gps):>9.1f}"
                     f"{'':>9}{'':>15}")
    for k, name in enumerate(NAMES):
        r = result.rmse[name]
        area = f"{np.mean(result.area[name]) / 1e4:>12.2f} ha" if name in result.area else ""
        inside = f"{np.mean(result.inside[name]) * 100:>11.1f}%" if name in result.inside else ""
        lines.append(f"{name:<16}{np.mean(r):>9.1f} m{np.std(r):>8.1f}{np.median(r):>9.1f}{wins[k]:>9d}{area:>15}"
                     f"{inside:>12}")
    if NO_MAP in result.rmse:
        r = result.rmse[NO_MAP]
        lines.append(f"{NO_MAP:<16}{np.mean(r):>9.1f} m{np.std(r):>8.1f}{np.median(r):>9.1f}{'-':>9}"
                     f"   (ablation: the rank-4 filter told the sea is still)")
    return "\n".join(lines)


# ----------------------------------------------------------------------------------------------
# The optimal gain: a numerical check that (18) minimises the trace of (13)
# ----------------------------------------------------------------------------------------------


def _random_problem(rng: np.random.Generator, n: int, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    F, G = rng.standard_normal((n, n)), rng.standard_normal((m, m))
    return F @ F.T + n * np.eye(n), rng.standard_normal((m, n)), G @ G.T + m * np.eye(m)


def gain_trace_experiment(
    kalman_gain: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    joseph_covariance: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    rng: np.random.Generator,
    n_problems: int = 200,
    n_perturbations: int = 20,
) -> np.ndarray:
    """tr P^(K + E) - tr P^(K) for random problems (P, H, R) and random perturbations E of the gain.

    K = kalman_gain(P, H, R) and P^ = joseph_covariance(P, K, H, R). Problems have n in 2..6
    states and m in 1..n observations; E has entries of size 0.001 to 1 times the size of K's.
    Returns the differences, shape (n_problems, n_perturbations): all >= 0 if K minimises (14).
    """
    out = np.empty((n_problems, n_perturbations))
    for i in range(n_problems):
        n = int(rng.integers(2, 7))
        P, H, R = _random_problem(rng, n, int(rng.integers(1, n + 1)))
        K = kalman_gain(P, H, R)
        best = np.trace(joseph_covariance(P, K, H, R))
        size = np.abs(K).max() * 10.0 ** rng.uniform(-3, 0, n_perturbations)
        for j in range(n_perturbations):
            E = size[j] * rng.standard_normal(K.shape)
            out[i, j] = np.trace(joseph_covariance(P, K + E, H, R)) - best
    return out


def plot_gain_trace(
    kalman_gain: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    joseph_covariance: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    rng: np.random.Generator,
    n_problems: int = 6,
    ax: Axes | None = None,
) -> Axes:
    """tr P^(K + s E) against s along a random direction E, for a few random 4-state problems.

    Each curve is a parabola whose minimum sits at s = 0 if K = kalman_gain(P, H, R) is optimal.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(6.5, 3.8))
    s = np.linspace(-1.0, 1.0, 81)
    for i in range(n_problems):
        P, H, R = _random_problem(rng, 4, 2)
        K = kalman_gain(P, H, R)
        E = rng.standard_normal(K.shape)
        E *= np.abs(K).max() / np.abs(E).max()
        best = np.trace(joseph_covariance(P, K, H, R))
        trace = [np.trace(joseph_covariance(P, K + si * E, H, R)) / best for si in s]
        ax.plot(s, trace, lw=1.3, label=f"problem {i + 1}")
    ax.axvline(0.0, color="black", lw=0.8, ls="--")
    ax.set_xlabel("s: gain used = K + s E  (E a random direction)")
    ax.set_ylabel("tr P^ / tr P^(K)")
    ax.set_title("The trace of the Joseph covariance (13) around the gain (18)")
    ax.legend(fontsize=8, ncol=2)
    return ax


@dataclass(frozen=True)
class RoundingResult:
    """Per precision ratio (n_ratios,): the fraction of problems whose updated covariance has a
    negative eigenvalue, and the median of max|P - P^T| / max|P|, for the short form (I - K H) P
    and for the Joseph form (13), both with the same rounded gain."""

    ratios: np.ndarray
    short_indefinite: np.ndarray
    joseph_indefinite: np.ndarray
    short_asymmetry: np.ndarray
    joseph_asymmetry: np.ndarray


def rounding_experiment(
    kalman_gain: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    joseph_covariance: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    rng: np.random.Generator,
    ratios: tuple[float, ...] = (1e-2, 1e-4, 1e-6, 1e-8),
    n_problems: int = 300,
) -> RoundingResult:
    """The short form and the Joseph form (13) of the update when the gain carries rounding errors.

    Each problem is a random 4-state prior P [m^2, typical variance 10^4 m^2] seen through Bob's H,
    with fixes of variance R = ratio * tr(P) / 4 * I_2. K = kalman_gain(P, H, R) is rounded to
    single precision (a relative error of about 6e-8, as if the filter ran in float32), and both
    updates are computed in double precision from that same gain.
    """
    H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
    stats = np.empty((4, len(ratios)))
    for i, ratio in enumerate(ratios):
        neg_short, neg_joseph, asym_short, asym_joseph = [], [], [], []
        for _ in range(n_problems):
            F = rng.standard_normal((4, 4))
            P = 1e4 * (F @ F.T + 0.1 * np.eye(4))
            R = ratio * np.trace(P) / 4.0 * np.eye(2)
            K = kalman_gain(P, H, R).astype(np.float32).astype(float)
            for P_new, neg, asym in (((np.eye(4) - K @ H) @ P, neg_short, asym_short),
                                     (joseph_covariance(P, K, H, R), neg_joseph, asym_joseph)):
                asym.append(np.abs(P_new - P_new.T).max() / np.abs(P_new).max())
                neg.append(np.linalg.eigvalsh(0.5 * (P_new + P_new.T)).min() < 0.0)
        stats[:, i] = np.mean(neg_short), np.mean(neg_joseph), np.median(asym_short), np.median(asym_joseph)
    return RoundingResult(np.array(ratios), *stats)


def format_rounding(result: RoundingResult) -> str:
    """The rounding experiment as a table, one row per precision ratio."""
    lines = [f"{'R / prior variance':>19}{'negative eigenvalue':>22}{'':>10}{'median asymmetry':>20}",
             f"{'':>19}{'short':>11}{'Joseph':>11}{'':>10}{'short':>10}{'Joseph':>10}"]
    for k, ratio in enumerate(result.ratios):
        lines.append(f"{ratio:>19.0e}{result.short_indefinite[k]:>10.0%} {result.joseph_indefinite[k]:>10.0%}"
                     f"{'':>10}{result.short_asymmetry[k]:>10.0e}{result.joseph_asymmetry[k]:>10.0e}")
    return "\n".join(lines)


# ----------------------------------------------------------------------------------------------
# Figures
# ----------------------------------------------------------------------------------------------

COLOURS = {"truth": "black", "gps": "tab:gray", NAMES[0]: "tab:orange", NAMES[1]: "tab:blue", NAMES[2]: "tab:green",
           NAMES[3]: "tab:red"}


def plot_flow(flow: Flow, t: float, ax: Axes | None = None, extent: tuple[float, float, float, float] | None = None,
              background: str = "vorticity", colorbar: bool = True, density: float = 1.6) -> Axes:
    """The current at time t [s]: vorticity (or speed) as colours, streamlines, and the island.

    ``background`` is "vorticity" (red: anticlockwise eddies, blue: clockwise) or "speed".
    ``extent`` = (x0, x1, y0, y1) in km zooms in; the default shows the whole grid.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(11, 4.6))
    u = flow.snapshot(t)
    xk, yk = flow.x / 1e3, flow.y / 1e3
    if background == "vorticity":
        scale = 2.0 * flow.current / (2.0 * flow.island_radius)  # 2 U / D, in 1/s
        colours = ax.pcolormesh(xk, yk, flow.vorticity(t).T * 1e3, cmap="RdBu_r", vmin=-scale * 1e3, vmax=scale * 1e3,
                                shading="gouraud")
        label = "vorticity (10$^{-3}$ s$^{-1}$)"
    else:
        colours = ax.pcolormesh(xk, yk, np.hypot(u[..., 0], u[..., 1]).T, cmap="viridis", vmin=0.0,
                                vmax=1.4 * flow.current, shading="gouraud")
        label = "current speed (m/s)"
    ax.streamplot(xk, yk, u[..., 0].T, u[..., 1].T, color="0.35", density=(density, density * 0.5), linewidth=0.5,
                  arrowsize=0.6)
    ax.add_patch(Circle(tuple(flow.island_center / 1e3), flow.island_radius / 1e3, fc="sandybrown", ec="saddlebrown",
                        zorder=3))
    if colorbar:
        ax.figure.colorbar(colours, ax=ax, label=label, shrink=0.8, pad=0.01)
    x0, x1, y0, y1 = extent if extent is not None else (xk[0], xk[-1], yk[0], yk[-1])
    _map_axes(ax, (x0, x1, y0, y1), f"The current behind the island at t = {t / 60:.0f} min")
    return ax


def _map_axes(ax: Axes, extent: tuple[float, float, float, float], title: str) -> None:
    """Limits (km), equal aspect, axis labels and title of a map of the sea."""
    x0, x1, y0, y1 = extent
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x, downstream (km)")
    ax.set_ylabel("y (km)")
    ax.set_title(title)


def _ellipse(ax: Axes, centre: np.ndarray, P: np.ndarray, colour: str, n_sigma: float = 2.0, label: str | None = None) -> None:
    values, vectors = np.linalg.eigh(P)
    angle = np.degrees(np.arctan2(vectors[1, 1], vectors[0, 1]))
    width, height = 2 * n_sigma * np.sqrt(np.maximum(values[::-1], 0.0))
    ax.add_patch(Ellipse(tuple(centre), width, height, angle=angle, fill=False, ec=colour, lw=1.2, label=label, zorder=5))


def plot_tracks(
    flow: Flow,
    drift: Drift,
    tracks: Tracks,
    zoom: tuple[int, int] = (40, 56),
    ellipses_every: int = 5,
    margin_km: float = 1.0,
) -> Figure:
    """Bob's true track, the GPS fixes and each estimator's track, over the current at mid-drift.

    Left: the whole drift. Right: the fixes zoom[0] to zoom[1] - 1, where the filters' 2-sigma
    ellipses (position block of P, to scale) are drawn every ``ellipses_every`` fixes.
    """
    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 5.6), width_ratios=(1.25, 1.0))
    t_mid = float(drift.t[len(drift.t) // 2])
    pos = drift.position / 1e3
    fixes = drift.fixes / 1e3
    extent = (pos[:, 0].min() - margin_km, pos[:, 0].max() + margin_km,
              pos[:, 1].min() - margin_km, pos[:, 1].max() + margin_km)
    plot_flow(flow, t_mid, ax=left, extent=extent, colorbar=True, density=3.0)
    left.plot(*fixes.T, ".", color=COLOURS["gps"], ms=3, label="GPS fixes")
    left.plot(*pos.T, "-", color=COLOURS["truth"], lw=2.0, label="Bob (truth)")
    left.plot(*pos[0], "o", color=COLOURS["truth"], ms=6)
    for name, (estimate, _) in tracks.items():
        left.plot(*np.asarray(estimate).T / 1e3, "-", color=COLOURS.get(name), lw=1.0, label=name)
    a, b = zoom
    box = pos[a:b]
    pad = 0.12
    zx0, zx1, zy0, zy1 = box[:, 0].min() - pad, box[:, 0].max() + pad, box[:, 1].min() - pad, box[:, 1].max() + pad
    left.add_patch(plt.Rectangle((zx0, zy0), zx1 - zx0, zy1 - zy0, fill=False, ec="black", lw=1.0, ls="--", zorder=6))
    left.set_title(f"Bob's {len(drift.t)}-minute drift (dot: start), current at mid-drift", fontsize=11)
    left.legend(loc="best", fontsize=8, framealpha=0.9)

    right.plot(*fixes[a:b].T, "o", color=COLOURS["gps"], ms=4, label="GPS fixes")
    right.plot(*pos[a:b].T, "-o", color=COLOURS["truth"], lw=2.0, ms=3, label="Bob (truth)")
    for name, (estimate, P) in tracks.items():
        colour = COLOURS.get(name)
        est = np.asarray(estimate)[a:b] / 1e3
        right.plot(*est.T, "-", marker=".", color=colour, lw=1.2, label=name)
        if P is not None:
            for j, n in enumerate(range(a, min(b, len(estimate)), ellipses_every)):
                _ellipse(right, np.asarray(estimate)[n] / 1e3, np.asarray(P)[n] / 1e6, colour,
                         label=f"{name}, 2-sigma ellipse" if j == 0 else None)
    _map_axes(right, (zx0, zx1, zy0, zy1), f"Zoom: minutes {a} to {b - 1} (dashed box on the left)")
    right.legend(loc="best", fontsize=7, framealpha=0.9)
    fig.tight_layout()
    return fig


def plot_errors(drift: Drift, tracks: Tracks, ax: Axes | None = None) -> Axes:
    """Position error |estimate - truth| [m] against time [min] for each estimator and the raw GPS."""
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 3.8))
    minutes = (drift.t - drift.t[0]) / 60.0
    ax.plot(minutes, np.linalg.norm(drift.fixes - drift.position, axis=1), ".", color=COLOURS["gps"], ms=3, label="raw GPS")
    for name, (estimate, _) in tracks.items():
        error = np.linalg.norm(np.asarray(estimate) - drift.position, axis=1)
        ax.plot(minutes, error, "-", color=COLOURS.get(name), lw=1.3, label=name)
    ax.set_xlabel("time since Bob fell in (min)")
    ax.set_ylabel("position error (m)")
    ax.set_title("How far each estimate is from Bob")
    ax.set_ylim(bottom=0.0)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    return ax


PAIRS = ((NAMES[1], NAMES[2], "tab:purple"), (NAMES[2], NAMES[3], "tab:brown"), (NO_MAP, NAMES[3], "tab:olive"))
"""The paired differences of plot_comparison: (first, second, colour); above 0 the second is better."""


def plot_comparison(results: dict[str, Comparison]) -> Figure:
    """Left: each estimator's RMSE [m] on every drift (dots) and its mean (bar), per current.
    Then, one panel per current: the paired per-drift differences of RMSE [m] of PAIRS (dots),
    their mean (bar), and the share of drifts on which the second of a pair is better.

    ``results`` maps a current's label to its ``Comparison``; drifts are jittered sideways.
    """
    fig, axes = plt.subplots(1, 1 + len(results), figsize=(15, 4.6), width_ratios=(1.4,) + (1.0,) * len(results))
    ax = axes[0]
    rng = np.random.default_rng(0)  # the sideways jitter only
    width = 0.8 / len(NAMES)
    for g, (label, result) in enumerate(results.items()):
        for k, name in enumerate(NAMES):
            centre = g + (k - (len(NAMES) - 1) / 2) * width
            r = result.rmse[name]
            ax.plot(centre + rng.uniform(-0.3, 0.3, len(r)) * width, r, ".", color=COLOURS[name], ms=3, alpha=0.6)
            ax.hlines(np.mean(r), centre - 0.45 * width, centre + 0.45 * width, color=COLOURS[name], lw=2.5,
                      label=name if g == 0 else None)
    ax.set_xticks(range(len(results)), list(results))
    ax.set_xlabel("current")
    ax.set_ylabel("RMSE over a drift (m)")
    ax.set_ylim(bottom=0.0)
    ax.set_title("Every drift's RMSE (dots) and the mean (bar)", fontsize=11)
    ax.legend(loc="lower center", ncol=2, fontsize=8)

    for diff, (label, result) in zip(axes[1:], results.items()):
        ticks = []
        for k, (first, second, colour) in enumerate(PAIRS):
            d = result.rmse[first] - result.rmse[second]
            diff.plot(k + rng.uniform(-0.25, 0.25, len(d)), d, ".", color=colour, ms=3, alpha=0.6)
            diff.hlines(np.mean(d), k - 0.35, k + 0.35, color=colour, lw=2.5)
            ticks.append(f"{first}\n- {second}\n(> 0 on {np.mean(d > 0):.0%})")
        diff.axhline(0.0, color="black", lw=0.8)
        diff.set_xticks(range(len(PAIRS)), ticks, fontsize=7)
        diff.set_ylabel("difference of RMSE on a drift (m)")
        diff.set_title(f"{label}: paired differences\n(above 0: the second is better)", fontsize=10)
    fig.tight_layout()
    return fig
