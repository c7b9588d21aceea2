"""Given code for the reentry-pf lab: a falling object tracked by an altitude radar.

The state is ``x = [h, v, beta]``: altitude h [m] above the ground, *downward* speed v [m/s]
(v > 0 while the object falls, so dh/dt = -v) and ballistic coefficient beta [kg/(m s^2)].
A particle cloud is an array of shape (3, N), one column per particle; its weights have shape
(N,). Equation numbers refer to the handout (Calvetti and Somersalo, Bayesian Scientific
Computing, Day 5 exercise).

This module holds what the handout gives you: the constants, the shipped radar data, a
container for the filter's history, and the figures. The figures and the report *take your
results as arguments*; nothing here implements a blank.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

Vector = NDArray[np.float64]
Matrix = NDArray[np.float64]

# --- The model, equations (1) to (5) -----------------------------------------------------------
G: float = 9.81  # acceleration due to gravity [m/s^2]
GAMMA: float = 1.754  # air density at the ground, rho(0) [kg/m^3]
ETA: float = 1.39e-4  # inverse scale height of the atmosphere [1/m]

# --- The radar and the time grid ---------------------------------------------------------------
DT: float = 0.1  # time between radar readings, and the Forward Euler step [s]
N_STEPS: int = 300  # readings b_0 .. b_T with T = 300: half a minute of tracking
SIGMA: float = 500.0  # standard deviation of the radar's altitude noise [m]
X0_TRUE: Vector = np.array([61_000.0, 3_048.0, 19_161.0])  # h_0 [m], v_0 [m/s], beta_* [kg/(m s^2)]

# --- The particle filter -----------------------------------------------------------------------
N_PARTICLES: int = 5000
V_INIT: float = 3000.0  # prior mean of the speed [m/s]
BETA_INIT: float = 20_000.0  # prior mean of the ballistic coefficient [kg/(m s^2)]
PRIOR_STD: Vector = np.array([500.0, 200.0, 1500.0])  # prior standard deviations of h, v, beta
INNOVATION_STD: Vector = np.array([100.0, 100.0, 5.0])  # innovation standard deviations, D^(1/2)
RUN_SEED: int = 2029  # seed of the lab's filter run, np.random.default_rng(RUN_SEED)

STATE_NAMES: tuple[str, str, str] = ("h", "v", "beta")
STATE_LABELS: tuple[str, str, str] = ("altitude h [m]", "speed v [m/s]", r"ballistic coefficient $\beta$ [kg/(m s$^2$)]")

for _constant in (X0_TRUE, PRIOR_STD, INNOVATION_STD):
    _constant.setflags(write=False)

#: The data file shipped with the kit, built by the instructors' reference simulator from a seed.
DATA_FILE: Path = Path(__file__).resolve().parent / "data" / "falling_object_radar.csv"
CSV_HEADER: str = "t_s,h_true_m,v_true_m_per_s,beta_true_kg_per_m_s2,b_m"


def time_grid(n_steps: int = N_STEPS, dt: float = DT) -> Vector:
    """The reading times t_j = j dt, j = 0..n_steps [s], shape (n_steps + 1,)."""
    return dt * np.arange(n_steps + 1)


# =============================================================================================
# Data
# =============================================================================================
@dataclass(frozen=True)
class RadarData:
    """Half a minute of radar tracking: the truth and the altitude readings at times t.

    ``t`` [s] and ``b`` [m] have shape (T + 1,); ``x_true`` has shape (3, T + 1), rows h [m],
    v [m/s] and beta [kg/(m s^2)].
    """

    t: Vector
    x_true: Matrix
    b: Vector
    sigma: float = SIGMA

    def __post_init__(self) -> None:
        n = self.t.shape[0]
        if self.t.shape != (n,) or self.b.shape != (n,) or self.x_true.shape != (3, n):
            raise ValueError(
                f"RadarData needs t (n,), x_true (3, n) and b (n,); got {self.t.shape}, "
                f"{self.x_true.shape} and {self.b.shape}."
            )


def format_radar_csv(t: Vector, x_true: Matrix, b: Vector) -> str:
    """The kit's CSV text for radar data: one row per reading, fixed decimals.

    Fixed decimals (0.1 s, 1 micrometre, 1 micrometre per second) make the file independent
    of the last bits of floating point, so a rebuild reproduces it byte for byte.
    """
    lines = [CSV_HEADER]
    for j in range(t.shape[0]):
        h, v, beta = x_true[:, j]
        lines.append(f"{t[j]:.1f},{h:.6f},{v:.6f},{beta:.6f},{b[j]:.6f}")
    return "\n".join(lines) + "\n"


def load(path: str | Path | None = None) -> RadarData:
    """Load the shipped radar data (301 readings, t = 0, 0.1, ..., 30 s)."""
    table = np.loadtxt(DATA_FILE if path is None else path, delimiter=",", skiprows=1, ndmin=2)
    return RadarData(t=table[:, 0], x_true=table[:, 1:4].T.copy(), b=table[:, 4].copy())


# =============================================================================================
# The filter's history
# =============================================================================================
@dataclass
class FilterHistory:
    """What the particle filter reports at every reading time t_j, j = 0..T.

    Rows of every (3, T + 1) array are h [m], v [m/s] and beta [kg/(m s^2)]:

    - ``mean``: the weighted mean of the particles, sum_l w_l x_l;
    - ``median``: the median of the particle values;
    - ``lo50``, ``hi50`` and ``lo90``, ``hi90``: the 50% and 90% credibility intervals by the
      handout's sorted-sample rule;
    - ``ess`` (T + 1,): the effective sample size 1 / sum_l w_l^2 of the weights.

    ``FilterHistory.empty(n)`` makes one filled with NaN, for a run to fill in.
    """

    mean: Matrix
    median: Matrix
    lo50: Matrix
    hi50: Matrix
    lo90: Matrix
    hi90: Matrix
    ess: Vector
    n_particles: int = field(default=0)

    @classmethod
    def empty(cls, n_times: int, n_particles: int = 0) -> FilterHistory:
        """A history for ``n_times`` reading times, every entry NaN until the run fills it."""

        def nan(*shape: int) -> NDArray[np.float64]:
            return np.full(shape, np.nan)

        return cls(
            mean=nan(3, n_times),
            median=nan(3, n_times),
            lo50=nan(3, n_times),
            hi50=nan(3, n_times),
            lo90=nan(3, n_times),
            hi90=nan(3, n_times),
            ess=nan(n_times),
            n_particles=n_particles,
        )

    @property
    def n_times(self) -> int:
        return int(self.ess.shape[0])

    def missing(self) -> list[str]:
        """Names of the fields that still hold NaN (not filled in at every time)."""
        names = ("mean", "median", "lo50", "hi50", "lo90", "hi90", "ess")
        return [name for name in names if not np.all(np.isfinite(getattr(self, name)))]


def check_history(history: object, n_times: int, n_particles: int) -> None:
    """Visible check of a run's FilterHistory: its type, every entry filled, bands that nest
    (lo90 <= lo50 <= median <= hi50 <= hi90) and an ESS between 1 and N. Raises AssertionError
    with a message that says what to fix."""
    if not isinstance(history, FilterHistory):
        raise AssertionError(
            f"run_particle_filter should return a FilterHistory (FilterHistory.empty(len(b), N), filled in), "
            f"not {type(history).__name__}."
        )
    for name in ("mean", "median", "lo50", "hi50", "lo90", "hi90", "ess"):
        value = np.asarray(getattr(history, name))
        shape = (n_times,) if name == "ess" else (3, n_times)
        if value.shape != shape:
            raise AssertionError(f"history.{name} should have shape {shape}, one column per reading; it has {value.shape}.")
        if not np.all(np.isfinite(value)):
            missing = np.flatnonzero(~np.all(np.isfinite(value.reshape(-1, n_times)), axis=0))
            raise AssertionError(f"history.{name} is not filled in at the times j = {missing[:8].tolist()}: fill it at every t_j.")
    order = (history.lo90, history.lo50, history.median, history.hi50, history.hi90)
    labels = ("lo90", "lo50", "median", "hi50", "hi90")
    for k in range(4):
        if np.any(order[k] > order[k + 1]):
            raise AssertionError(
                f"history.{labels[k]} exceeds history.{labels[k + 1]} somewhere: the 90% band should contain the 50% "
                "band, which contains the median. Did you sort the samples, and use p = 50 and p = 90 the right way round?"
            )
    if np.any(history.ess < 1 - 1e-9) or np.any(history.ess > n_particles * (1 + 1e-9)):
        raise AssertionError(
            f"The effective sample size should lie between 1 and N = {n_particles}; it ranges from "
            f"{np.min(history.ess):.3g} to {np.max(history.ess):.3g}. ESS = 1 / sum_l w_l^2 with normalised weights."
        )


def _require_complete(history: FilterHistory, n_times: int) -> None:
    if not isinstance(history, FilterHistory):
        raise TypeError(f"Expected a FilterHistory (from run_particle_filter), got {type(history).__name__}.")
    if history.n_times != n_times:
        raise ValueError(f"The history covers {history.n_times} times, but the data has {n_times} readings.")
    missing = history.missing()
    if missing:
        raise ValueError(f"The history still has NaN entries in {', '.join(missing)}: fill them at every time t_j.")


# =============================================================================================
# Report and figures
# =============================================================================================
def coverage(data: RadarData, history: FilterHistory) -> dict[str, Vector]:
    """The fraction of reading times at which the truth lies inside each band.

    Returns ``{"50": (3,), "90": (3,)}``, one fraction per state variable (h, v, beta).
    """
    _require_complete(history, data.t.shape[0])
    x = data.x_true
    return {
        "50": np.mean((history.lo50 <= x) & (x <= history.hi50), axis=1),
        "90": np.mean((history.lo90 <= x) & (x <= history.hi90), axis=1),
    }


def format_report(data: RadarData, history: FilterHistory) -> str:
    """A table of the final estimates, their 90% intervals, errors, and band coverage."""
    _require_complete(history, data.t.shape[0])
    cover = coverage(data, history)
    rows = [
        f"{'t = ' + format(data.t[-1], '.1f') + ' s':<8}{'truth':>11}{'mean':>11}{'median':>11}"
        f"{'90% interval':>24}{'RMSE of mean':>14}{'in 50%':>8}{'in 90%':>8}",
    ]
    for i, name in enumerate(STATE_NAMES):
        rmse = float(np.sqrt(np.mean((history.mean[i] - data.x_true[i]) ** 2)))
        interval = f"[{history.lo90[i, -1]:.0f}, {history.hi90[i, -1]:.0f}]"
        rows.append(
            f"{name:<8}{data.x_true[i, -1]:>11.0f}{history.mean[i, -1]:>11.0f}{history.median[i, -1]:>11.0f}"
            f"{interval:>24}{rmse:>14.1f}{cover['50'][i]:>8.0%}{cover['90'][i]:>8.0%}"
        )
    rmse_radar = float(np.sqrt(np.mean((data.b - data.x_true[0]) ** 2)))
    rows.append(f"(the raw radar readings have an altitude RMSE of {rmse_radar:.1f} m)")
    return "\n".join(rows)


def print_report(data: RadarData, history: FilterHistory) -> None:
    """Print ``format_report``."""
    print(format_report(data, history))


def plot_tracking(data: RadarData, history: FilterHistory, title: str = "") -> NDArray[np.object_]:
    """The show and tell: h, v and beta against time with the truth, weighted mean, median and
    the 50% and 90% credibility bands.

    Altitude and speed change by tens of kilometres and kilometres per second, while the bands
    are a few hundred metres wide, so the top row shows the values and the bottom row shows
    the same curves minus the truth. Returns the 2 x 3 array of Axes.
    """
    import matplotlib.pyplot as plt

    _require_complete(history, data.t.shape[0])
    t = data.t
    fig, axes = plt.subplots(2, 3, figsize=(15, 7.5), sharex=True, layout="constrained")
    for i, (name, label) in enumerate(zip(STATE_NAMES, STATE_LABELS)):
        for row, offset in ((0, 0.0), (1, data.x_true[i])):
            ax = axes[row, i]
            ax.fill_between(t, history.lo90[i] - offset, history.hi90[i] - offset, color="C0", alpha=0.18, lw=0, label="90% band")
            ax.fill_between(t, history.lo50[i] - offset, history.hi50[i] - offset, color="C0", alpha=0.38, lw=0, label="50% band")
            if i == 0:
                ax.plot(t, data.b - offset, ".", color="0.55", ms=2.5, label="radar reading $b_j$")
            ax.plot(t, data.x_true[i] - offset, color="k", lw=1.6, label="truth")
            ax.plot(t, history.mean[i] - offset, color="C3", lw=1.3, label="weighted mean")
            ax.plot(t, history.median[i] - offset, color="C1", lw=1.1, ls="--", label="median")
            ax.grid(alpha=0.3)
        axes[0, i].set_title(f"{name}: estimate and truth")
        axes[0, i].set_ylabel(label)
        axes[1, i].set_title(f"{name} minus the truth")
        axes[1, i].set_ylabel(f"error in {label}")
        axes[1, i].set_xlabel("time t [s]")
    axes[1, 0].set_ylim(-4 * data.sigma, 4 * data.sigma)
    axes[0, 0].legend(loc="upper right", fontsize=8)
    axes[1, 2].legend(loc="upper right", fontsize=8)
    n = f", N = {history.n_particles} particles" if history.n_particles else ""
    fig.suptitle(title or f"Particle filter tracking of the falling object{n}")
    return axes


def plot_ess(data: RadarData, history: FilterHistory, ax: Axes | None = None) -> Axes:
    """The effective sample size 1 / sum w^2 of the filter's weights against time."""
    import matplotlib.pyplot as plt

    _require_complete(history, data.t.shape[0])
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 3.5), layout="constrained")
    ax.plot(data.t, history.ess, color="C2", lw=1.4, label="effective sample size")
    if history.n_particles:
        ax.axhline(history.n_particles, color="k", lw=0.8, ls=":", label=f"N = {history.n_particles}")
        ax.set_ylim(0, 1.05 * history.n_particles)
    else:
        ax.set_ylim(bottom=0)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("ESS = 1 / $\\sum_\\ell w_\\ell^2$ [particles]")
    ax.set_title("Effective sample size of the weights after each step")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left")
    return ax


def plot_band_widths(data: RadarData, histories: Mapping[str, FilterHistory], ax: Axes | None = None) -> Axes:
    """The width of the 90% credibility band of beta against time, one curve per run.

    ``histories`` maps a label (for example "N = 5000") to a run's FilterHistory. The prior's
    90% band, 2 x 1.645 x 1500 = 4935, is drawn for comparison.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(8, 3.8), layout="constrained")
    for label, history in histories.items():
        _require_complete(history, data.t.shape[0])
        ax.plot(data.t, history.hi90[2] - history.lo90[2], lw=1.4, label=label)
    prior = 2 * 1.6448536269514722 * PRIOR_STD[2]
    ax.axhline(prior, color="k", lw=0.8, ls=":", label=f"prior 90% band ({prior:.0f})")
    ax.set_ylim(bottom=0)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel(r"width of the 90% band of $\beta$ [kg/(m s$^2$)]")
    ax.set_title(r"How fast does the filter learn $\beta$? The 90% band for several N")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize=9)
    return ax
