"""The train lab's world: the train model, its GPS, the shipped data and the figures.

Units: time in minutes, position in miles (mi), velocity in miles per hour (mph). The state is
x = [position, velocity]. One model step is one minute, so a velocity in mph moves the train by
v/60 miles per step.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

MINUTES_PER_HOUR = 60.0
SIGMA_Z = 15.0
"""Standard deviation of the change in velocity over one minute, mph."""
SIGMA_GPS = np.array([10.0, 10.0])
"""Standard deviations of the GPS position (mi) and velocity (mph) errors."""
DATA_FILE = Path(__file__).parent / "data" / "train.csv"
CSV_HEADER = "minute,x_true_mi,v_true_mph,x_gps_mi,v_gps_mph"

RunFilter = Callable[..., tuple[np.ndarray, np.ndarray]]


def model_matrix(dt_min: float = 1.0) -> np.ndarray:
    """The train model's matrix A (2 x 2) for a step of ``dt_min`` minutes."""
    # x_{t+1} = x_t + (dt/60) v_t,  v_{t+1} = v_t
    return np.array([[1.0, dt_min / MINUTES_PER_HOUR], [0.0, 1.0]])


def gps_operator() -> np.ndarray:
    """The GPS observation operator H (2 x 2): it reports position and velocity directly."""
    return np.eye(2)


def gps_covariance() -> np.ndarray:
    """R (2 x 2), the GPS error covariance, in mi^2 and mph^2."""
    return np.diag(SIGMA_GPS**2)


def initial_belief() -> tuple[np.ndarray, np.ndarray]:
    """The belief at minute 0, before any GPS fix: mean (2,) and covariance (2, 2).

    The train leaves the station (0 mi, known to about 1 mi) at the rail company's advertised
    100 mph, which we trust only to +-15 mph.
    """
    return np.array([0.0, 100.0]), np.diag([1.0**2, SIGMA_Z**2])


def forward(
    x0: np.ndarray, n_steps: int, rng: np.random.Generator, sigma: float = SIGMA_Z, dt_min: float = 1.0
) -> np.ndarray:
    """Simulate the true train (the handout's forwardop.m).

    Returns the states at minutes 0..n_steps, shape (n_steps + 1, 2): position (mi) and
    velocity (mph).
    """
    h = dt_min / MINUTES_PER_HOUR
    z = rng.normal(0.0, sigma, size=n_steps)
    # v_{t+1} = v_t + z_t
    v = x0[1] + np.concatenate(([0.0], np.cumsum(z)))
    # x_{t+1} = x_t + h v_t + h z_t = x_t + h v_{t+1}
    x = x0[0] + h * np.concatenate(([0.0], np.cumsum(v[1:])))
    return np.column_stack((x, v))


def observe(states: np.ndarray, rng: np.random.Generator, sigma: np.ndarray = SIGMA_GPS) -> np.ndarray:
    """GPS fixes of the given states (the handout's obs.m): states (T, 2) plus N(0, sigma^2) noise."""
    return states + rng.normal(0.0, 1.0, size=states.shape) * sigma


@dataclass(frozen=True)
class TrainData:
    """One hour of the train: arrays of shape (T,) at minutes 1..T."""

    minute: np.ndarray
    x_true: np.ndarray
    v_true: np.ndarray
    x_gps: np.ndarray
    v_gps: np.ndarray

    @property
    def truth(self) -> np.ndarray:
        """True states, shape (T, 2)."""
        return np.column_stack((self.x_true, self.v_true))

    @property
    def gps(self) -> np.ndarray:
        """GPS fixes, shape (T, 2): the observations y."""
        return np.column_stack((self.x_gps, self.v_gps))


def simulate(n_minutes: int, rng: np.random.Generator) -> TrainData:
    """A fresh hour of truth and GPS from the true process.

    The train's state at minute 0 is drawn from the initial belief, so the filter's assumptions
    are exactly those of the simulation.
    """
    mean, cov = initial_belief()
    states = forward(rng.multivariate_normal(mean, cov), n_minutes, rng)[1:]
    fixes = observe(states, rng)
    return TrainData(np.arange(1, n_minutes + 1), states[:, 0], states[:, 1], fixes[:, 0], fixes[:, 1])


def write_csv(data: TrainData, path: Path) -> None:
    """Write the data in the kit's CSV format (one row per minute)."""
    table = np.column_stack((data.minute, data.x_true, data.v_true, data.x_gps, data.v_gps))
    np.savetxt(path, table, delimiter=",", header=CSV_HEADER, comments="", fmt=["%d"] + ["%.6f"] * 4)


def load(path: Path = DATA_FILE) -> TrainData:
    """Load the shipped hour of truth and GPS (60 rows, minutes 1..60)."""
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    return TrainData(table[:, 0].astype(int), table[:, 1], table[:, 2], table[:, 3], table[:, 4])


def rmse(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Root-mean-square error over time of each state component: (T, n) arrays give (n,)."""
    return np.sqrt(np.mean((np.asarray(estimate) - truth) ** 2, axis=0))


def print_rmse_table(data: TrainData, x_a: np.ndarray) -> None:
    """Print the RMSE of the raw GPS fixes and of the filter's estimates."""
    gps, kf = rmse(data.gps, data.truth), rmse(x_a, data.truth)
    print(f"{'RMSE over the hour':<20}{'position [mi]':>15}{'velocity [mph]':>16}")
    print(f"{'GPS only':<20}{gps[0]:>15.2f}{gps[1]:>16.2f}")
    print(f"{'Kalman filter':<20}{kf[0]:>15.2f}{kf[1]:>16.2f}")


def plot_estimates(data: TrainData, x_a: np.ndarray, B_a: np.ndarray) -> Figure:
    """The handout's plotstuff.m: position and velocity against time, with a +-2 sigma band.

    x_a (T, 2) and B_a (T, 2, 2) are the filter's analyses at minutes 1..T. A third panel shows
    the position error, where the band is easier to see than on the 100-mile scale.
    """
    sd = np.sqrt(np.diagonal(B_a, axis1=1, axis2=2))
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True, constrained_layout=True)
    panels = [
        (axes[0], data.x_true, data.x_gps, x_a[:, 0], sd[:, 0], "position [mi]"),
        (axes[1], data.v_true, data.v_gps, x_a[:, 1], sd[:, 1], "velocity [mph]"),
    ]
    for ax, truth, gps, estimate, s, label in panels:
        ax.fill_between(data.minute, estimate - 2 * s, estimate + 2 * s, color="tab:blue", alpha=0.25,
                        label="Kalman filter ±2σ")
        ax.plot(data.minute, truth, color="black", lw=2, label="truth")
        ax.plot(data.minute, gps, "o", ms=4, color="tab:orange", label="GPS fix")
        ax.plot(data.minute, estimate, color="tab:blue", lw=1.5, label="Kalman filter estimate")
        ax.set_ylabel(label)
        ax.legend(loc="best", fontsize="small")
    ax = axes[2]
    ax.fill_between(data.minute, -2 * sd[:, 0], 2 * sd[:, 0], color="tab:blue", alpha=0.25, label="±2σ of the filter")
    ax.plot(data.minute, data.x_gps - data.x_true, "o", ms=4, color="tab:orange", label="GPS error")
    ax.plot(data.minute, x_a[:, 0] - data.x_true, color="tab:blue", lw=1.5, label="filter error")
    ax.axhline(0.0, color="black", lw=1)
    ax.set_ylabel("position error [mi]")
    ax.set_xlabel("time [min]")
    ax.legend(loc="best", fontsize="small", ncols=3)
    axes[0].set_title("Tracking the train: truth, GPS and the Kalman filter")
    return fig


@dataclass(frozen=True)
class ScalingResult:
    """Mean RMSE (over runs) of position and velocity, shape (len(scales), 2), for each experiment."""

    scales: np.ndarray
    rmse_scaled_Q: np.ndarray
    rmse_scaled_R: np.ndarray
    rmse_gps: np.ndarray


def covariance_scaling_experiment(
    run_filter: RunFilter,
    Q: np.ndarray,
    scales: np.ndarray,
    n_runs: int,
    rng: np.random.Generator,
    n_minutes: int = 60,
) -> ScalingResult:
    """Run ``run_filter`` on ``n_runs`` simulated hours with Q, and then R, multiplied by each scale.

    The data always come from the true process (sigma_z = 15 mph, GPS sigma = 10): only the
    filter's assumptions change. ``run_filter(y, x0, B0, A, Q, H, R)`` is your function and
    ``Q`` (2 x 2) your process noise for one-minute steps.
    """
    A, H, R = model_matrix(), gps_operator(), gps_covariance()
    x0, B0 = initial_belief()
    hours = [simulate(n_minutes, rng) for _ in range(n_runs)]
    errors = np.zeros((2, len(scales), 2))
    for i, scale in enumerate(scales):
        for data in hours:
            errors[0, i] += rmse(run_filter(data.gps, x0, B0, A, scale * Q, H, R)[0], data.truth)
            errors[1, i] += rmse(run_filter(data.gps, x0, B0, A, Q, H, scale * R)[0], data.truth)
    gps = np.mean([rmse(data.gps, data.truth) for data in hours], axis=0)
    return ScalingResult(np.asarray(scales), errors[0] / n_runs, errors[1] / n_runs, gps)


def plot_covariance_scaling(result: ScalingResult) -> Figure:
    """RMSE against the factor applied to Q or to R, one panel for position and one for velocity."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), constrained_layout=True)
    for k, (ax, unit) in enumerate(zip(axes, ["position RMSE [mi]", "velocity RMSE [mph]"])):
        ax.semilogx(result.scales, result.rmse_scaled_Q[:, k], "o-", label="filter with Q × factor")
        ax.semilogx(result.scales, result.rmse_scaled_R[:, k], "s-", label="filter with R × factor")
        ax.axhline(result.rmse_gps[k], color="tab:orange", ls="--", label="GPS only")
        ax.axvline(1.0, color="grey", lw=1, ls=":")
        ax.set_xlabel("factor applied to the filter's covariance (1 = the true value)")
        ax.set_ylabel(unit)
        ax.legend(fontsize="small")
    fig.suptitle("What happens when the filter's covariances are wrong")
    return fig
