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
import scipy.stats
from matplotlib.figure import Figure

from course.tables import cell

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
    # the noise-free part of x_{t+1} = x_t + h v_{t+1}, v_{t+1} = v_t + z with h = dt/60 hours: x_{t+1} = x_t + h v_t
    # and v_{t+1} = v_t; the noise Z = (h z, z) of process_noise adds the rest
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
    print(f"{'GPS only':<20}{cell(gps[0], 15)}{cell(gps[1], 16)}")
    print(f"{'Kalman filter':<20}{cell(kf[0], 15)}{cell(kf[1], 16)}")


def _clipped(ax, minute: np.ndarray, values: np.ndarray, limit: float, **style) -> None:
    """Plot points; those beyond +-limit are drawn as triangles on the panel's edge."""
    inside = np.abs(values) <= limit
    ax.plot(minute[inside], values[inside], "o", **style)
    for sign, marker in ((1, "^"), (-1, "v")):
        out = sign * values > limit
        ax.plot(minute[out], np.full(out.sum(), sign * limit), marker, **{**style, "label": None})


def plot_estimates(data: TrainData, x_a: np.ndarray, B_a: np.ndarray) -> Figure:
    """The handout's plotstuff.m: position and velocity against time, with a +-2 sigma band.

    x_a (T, 2) and B_a (T, 2, 2) are the filter's analyses at minutes 1..T. The two lower panels
    show the errors (estimate or fix minus truth), on a scale set by the filter's band: GPS errors
    beyond it are drawn as triangles on the panel's edge.
    """
    sd = np.sqrt(np.diagonal(B_a, axis1=1, axis2=2))
    fig, axes = plt.subplots(4, 1, figsize=(9, 11), sharex=True, layout="constrained")
    truth, gps = data.truth, data.gps
    units = ("mi", "mph")
    for k, name in enumerate(("position", "velocity")):
        ax = axes[k]
        ax.fill_between(data.minute, x_a[:, k] - 2 * sd[:, k], x_a[:, k] + 2 * sd[:, k], color="tab:blue",
                        alpha=0.25, label="Kalman filter ±2σ band")
        ax.plot(data.minute, truth[:, k], color="black", lw=2, label="truth")
        ax.plot(data.minute, gps[:, k], "o", ms=4, color="tab:orange", label="GPS fix (GPS error below)")
        ax.plot(data.minute, x_a[:, k], color="tab:blue", lw=1.5, label="Kalman filter estimate (error below)")
        ax.set_ylabel(f"{name} [{units[k]}]")
        ax = axes[k + 2]
        limit = max(3.0 * sd[:, k].max(), 1.3 * np.abs(x_a[:, k] - truth[:, k]).max())
        ax.fill_between(data.minute, -2 * sd[:, k], 2 * sd[:, k], color="tab:blue", alpha=0.25)
        _clipped(ax, data.minute, gps[:, k] - truth[:, k], limit, ms=4, color="tab:orange")
        ax.plot(data.minute, x_a[:, k] - truth[:, k], color="tab:blue", lw=1.5)
        ax.axhline(0.0, color="black", lw=1)
        ax.set_ylim(-1.05 * limit, 1.05 * limit)
        ax.set_ylabel(f"{name} error [{units[k]}]")
        ax.set_title(f"{name.capitalize()} errors (GPS errors beyond ±{limit:.1f} {units[k]} shown as ▲/▼ on the edge)",
                     fontsize="medium")
    axes[-1].set_xlabel("time [min]")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=4, fontsize="small")
    fig.suptitle("Tracking the train: truth, GPS and the Kalman filter")
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
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), layout="constrained")
    for k, (ax, name) in enumerate(zip(axes, ["position RMSE [mi]", "velocity RMSE [mph]"])):
        ax.semilogx(result.scales, result.rmse_scaled_Q[:, k], "o-", color="tab:blue", label="filter told Q × factor")
        ax.semilogx(result.scales, result.rmse_scaled_R[:, k], "s-", color="tab:purple", label="filter told R × factor")
        ax.axhline(result.rmse_gps[k], color="tab:orange", ls="--", label="GPS only")
        ax.axvline(1.0, color="grey", lw=1, ls=":", label="the true covariances")
        ax.set_ylim(0.0, None)
        ax.set_title(name.split(" RMSE")[0].capitalize())
        ax.set_xlabel("factor applied to the filter's covariance (1 = the true value)")
        ax.set_ylabel(name)
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=4, fontsize="small")
    fig.suptitle("What happens when the filter's covariances are wrong (mean RMSE over the simulated hours)")
    return fig


def white_noise_acceleration(q: float, dt_min: float = 1.0) -> np.ndarray:
    """Q (2 x 2) of the continuous white-noise acceleration model, for a step of dt_min minutes.

    The acceleration is white noise of spectral density q (mph^2 per hour); over a step of
    h = dt_min/60 hours the velocity variance grows by q h and the position, which integrates the
    velocity, by q h^3/3.
    """
    h = dt_min / MINUTES_PER_HOUR
    # Q = q [[h^3/3, h^2/2], [h^2/2, h]]
    return q * np.array([[h**3 / 3.0, h**2 / 2.0], [h**2 / 2.0, h]])


def print_model_comparison(data: TrainData, estimates: dict[str, np.ndarray]) -> None:
    """Print the RMSE over the hour of the GPS and of each named filter's estimates (T, 2)."""
    print(f"{'RMSE over the hour':<34}{'position [mi]':>15}{'velocity [mph]':>16}")
    for name, estimate in {"GPS only": data.gps, **estimates}.items():
        error = rmse(estimate, data.truth)
        print(f"{name:<34}{cell(error[0], 15, '.3f')}{cell(error[1], 16, '.3f')}")


@dataclass(frozen=True)
class ConsistencyResult:
    """The filter's errors against its own covariances over many simulated hours."""

    minute: np.ndarray
    """Minutes 1..T, shape (T,)."""
    inside: np.ndarray
    """Fraction of each hour in which the truth lies inside the +-2 sigma band, shape (n_hours, 2)."""
    nees: np.ndarray
    """NEES of each hour at each minute, shape (n_hours, T)."""


def consistency_experiment(
    run_filter: RunFilter, nees: Callable[[np.ndarray, np.ndarray], np.ndarray], Q: np.ndarray, n_hours: int,
    rng: np.random.Generator, n_minutes: int = 60,
) -> ConsistencyResult:
    """Run ``run_filter`` on ``n_hours`` simulated hours and measure its errors against its own B^a.

    ``nees(errors (T, n), covariances (T, n, n)) -> (T,)`` is your NEES function and Q your
    process noise for one-minute steps.
    """
    A, H, R = model_matrix(), gps_operator(), gps_covariance()
    x0, B0 = initial_belief()
    inside, values = np.empty((n_hours, 2)), np.empty((n_hours, n_minutes))
    for i in range(n_hours):
        data = simulate(n_minutes, rng)
        x_a, B_a = run_filter(data.gps, x0, B0, A, Q, H, R)
        errors = x_a - data.truth
        inside[i] = np.mean(np.abs(errors) <= 2.0 * np.sqrt(np.diagonal(B_a, axis1=1, axis2=2)), axis=0)
        values[i] = nees(errors, B_a)
    return ConsistencyResult(np.arange(1, n_minutes + 1), inside, values)


def nees_band(n_hours: int, dim: int = 2, level: float = 0.95) -> tuple[float, float]:
    """The central ``level`` interval of the NEES averaged over ``n_hours`` independent hours.

    For a consistent filter each hour's NEES at a given minute is chi-square with ``dim`` degrees of
    freedom, so the average over the hours is chi-square with n_hours * dim degrees, divided by n_hours.
    """
    tail = (1.0 - level) / 2.0
    return tuple(scipy.stats.chi2.ppf([tail, 1.0 - tail], n_hours * dim) / n_hours)


def plot_consistency(result: ConsistencyResult) -> Figure:
    """Left: how often the truth is inside the +-2 sigma band, per hour. Right: NEES against time."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), layout="constrained")
    ax = axes[0]
    # each fraction is a whole number of minutes over the hour: put the bin edges half-way between two counts
    n_minutes = result.nees.shape[1]
    bins = np.concatenate([[-0.5], np.arange(0.5, n_minutes + 1.0, n_minutes / 20.0)]) / n_minutes
    ax.hist([result.inside[:, 0], result.inside[:, 1]], bins=bins, color=["tab:blue", "tab:red"],
            label=[f"{name}: {result.inside[:, k].mean():.1%} over all hours"
                   for k, name in enumerate(("position", "velocity"))])
    ax.axvline(0.9545, color="black", ls="--", label="95.45%, a consistent filter's average")
    ax.set_xlabel("fraction of the hour with the truth inside ±2σ")
    ax.set_ylabel("number of hours")
    ax.set_title(f"Inside the ±2σ band, {len(result.inside)} simulated hours")
    ax.legend(loc="upper left", fontsize="small")
    ax = axes[1]
    n_hours = len(result.nees)
    low, high = nees_band(n_hours)
    ax.fill_between(result.minute, low, high, color="lightgrey", label=f"95% χ² band for the mean of {n_hours} hours")
    ax.plot(result.minute, result.nees.mean(axis=0), "o-", ms=3, color="tab:green", label="NEES, mean over the hours")
    ax.axhline(2.0, color="black", ls="--", label="2, the state dimension")
    ax.set_ylim(0.0, 2.0 * high)
    ax.set_xlabel("time [min]")
    ax.set_ylabel("NEES (dimensionless)")
    ax.set_title("Normalised estimation error squared")
    ax.legend(loc="lower center", ncols=2, fontsize="small")
    fig.suptitle("Is the filter's ±2σ band honest?")
    return fig
