"""Instructor-side build of the castaway-bob ocean flow: a vortex street behind an island.

The flow is a 2-D incompressible Navier-Stokes solution computed with PhiFlow (``phiflow`` on
PyPI, NumPy backend): a uniform current past a circular island at Reynolds number 150, where a
laminar Karman vortex street forms. It is computed in dimensionless units (island diameter D = 1,
current U = 1) and rescaled to the ocean:

    D = 1 km, U = 0.5 m/s, so a time unit D/U is 2000 s and the viscosity U D / Re = 3.3 m^2/s
    (a plausible horizontal eddy viscosity for the upper ocean; the molecular value, 1e-6 m^2/s,
    would give Re = 5e8, which no 2-D grid resolves).

Scheme per step (dt = 0.09 D/U = 3 min): MacCormack advection, explicit viscous diffusion, the
inflow forced to U on the first half diameter (a sponge), then a pressure projection with a
no-penetration island (PhiFlow's ``make_incompressible``, conjugate gradients). A seeded cross
current during the first 3 time units breaks the symmetry so that shedding starts early; the
seed sets its sign and size, and so the phase of the street. After a spin-up of 27 time units
(15 h at sea) the velocity is kept every 2 steps (6 min) for 5 h, averaged over 2 x 2 cells to
a 200 m grid, and written as float16 in m/s.

Only instructors need PhiFlow: students load the shipped ``course/data/castaway_bob_flow.npz``
with ``course.ocean.load``. The file is written with fixed zip timestamps so that a rebuild on the
same environment reproduces it byte for byte.

The build also writes the solver's whole state at two steps (CHECKPOINT_STEPS) as a record,
``solutions/records/castaway_bob_flow_checkpoints.records.npz``: a run restarted from a checkpoint
continues bit for bit, so that the lab's reference tests rebuild the start of the run from the seed
and the kept window from a checkpoint, instead of all 400 steps.

Run ``python -m solutions.castaway_bob.flow [DIR]`` to rebuild it and print the build time.
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import numpy as np

from solutions.shipped_npz import write_npz

FLOW_SEED = 5
"""Seed of the shipped flow: it sets the sign and size of the start-up cross current."""
FILE_NAME = "castaway_bob_flow.npz"

REYNOLDS = 150.0
"""Re = U D / nu of the simulated wake."""
ISLAND_DIAMETER_M = 1000.0
CURRENT_M_S = 0.5
TIME_UNIT_S = ISLAND_DIAMETER_M / CURRENT_M_S
"""D / U: one dimensionless time unit, 2000 s."""

DOMAIN = ((-5.0, 19.0), (-5.0, 5.0))
"""(x, y) extent in island diameters, the island centred at the origin."""
CELLS = (240, 100)
"""Solver grid: D / 10 = 100 m cells."""
DT = 0.09
"""Solver step in D / U (180 s)."""
SPIN_UP_STEPS = 300
"""Steps before the first kept snapshot (27 D / U, 15 h)."""
SNAPSHOT_EVERY = 2
"""Steps between kept snapshots (6 min)."""
N_SNAPSHOTS = 51
"""Kept snapshots: 0, 6, ..., 300 min."""
COARSEN = 2
"""Kept grid: 2 x 2 block means of the solver's cell-centred velocity (200 m)."""
KICK_DURATION = 3.0
"""Duration of the seeded start-up cross current, in D / U."""
SPONGE = 0.5
"""Width of the inflow strip forced to the current, in D."""
PRESSURE_TOLERANCE = 1e-5


def _kick(seed: int) -> float:
    """The start-up cross current (in U) for ``seed``: random sign, size in [0.3, 0.6]."""
    rng = np.random.default_rng(seed)
    return float(rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 0.6))


KICK_STEPS = int(np.ceil(KICK_DURATION / DT))
"""Solver steps with the start-up cross current (34): step n has it while n DT < KICK_DURATION."""
CHECKPOINT_STEPS = (KICK_STEPS, SPIN_UP_STEPS)
"""Steps whose whole solver state is shipped (CHECKPOINT_FILE_NAME) so that tests can rebuild parts of the run:
the state after the cross current, rebuilt from the seed, and the state at the first kept snapshot, from which
the kept 5 h are rebuilt."""
CHECKPOINT_FILE_NAME = "castaway_bob_flow_checkpoints.records.npz"
STATE_PARTS = ("velocity_x", "velocity_y", "pressure")
"""A solver state: the staggered velocity's x faces (241, 100) and y faces (240, 101), and the pressure
(240, 100) that warm-starts the next projection, all float32 in D / U units."""


def simulate_wake(
    seed: int = FLOW_SEED, n_snapshots: int = N_SNAPSHOTS, spin_up_steps: int = SPIN_UP_STEPS
) -> dict[str, np.ndarray]:
    """Run the solver and return the kept flow in ocean units (shorter runs are for tests).

    Returns arrays x (nx,) and y (ny,) [m] of cell centres, t (nt,) [s] from the first kept
    snapshot, and velocity (nt, nx, ny, 2) [m/s] as float32, with nx, ny = 120, 50.
    """
    snapshots, _ = run_solver(seed, n_snapshots=n_snapshots, spin_up_steps=spin_up_steps)
    return kept_flow(snapshots)


def run_solver(
    seed: int = FLOW_SEED, start: dict[str, np.ndarray] | None = None, stop: int | None = None,
    checkpoint_steps: tuple[int, ...] = (), n_snapshots: int = N_SNAPSHOTS, spin_up_steps: int = SPIN_UP_STEPS,
) -> tuple[list[np.ndarray], dict[int, dict[str, np.ndarray]]]:
    """Run the solver's steps from step 0 (or from the checkpoint ``start``, a state with its "step", as
    ``shipped_checkpoint`` returns it) up to step ``stop`` (default: the last kept snapshot).

    Returns the kept snapshots among those steps (coarsened, float32, in U) and, for each step of
    ``checkpoint_steps`` reached, the solver state before that step (STATE_PARTS). A run restarted from
    a checkpoint continues the uninterrupted run bit for bit.
    """
    with warnings.catch_warnings():
        # PhiFlow warns (DeprecationWarning, RuntimeWarning) on import about experimental parts
        # we do not use, and about jit being unavailable on NumPy; none affects the result.
        warnings.simplefilter("ignore")
        from phi import flow as pf

        return _simulate(pf, seed, start, stop, checkpoint_steps, n_snapshots, spin_up_steps)


def _simulate(pf, seed: int, start: dict[str, np.ndarray] | None, stop: int | None, checkpoint_steps: tuple[int, ...],
              n_snapshots: int, spin_up_steps: int) -> tuple[list[np.ndarray], dict[int, dict[str, np.ndarray]]]:
    (x0, x1), (y0, y1) = DOMAIN
    nx, ny = CELLS
    bounds = pf.Box(x=(x0, x1), y=(y0, y1))
    grid = dict(x=nx, y=ny, bounds=bounds)
    nu = 1.0 / REYNOLDS
    kick = _kick(seed)

    island = pf.Obstacle(pf.Sphere(x=0.0, y=0.0, radius=0.5))
    # 1 on the inflow strip x < x0 + SPONGE, where the velocity is forced to the current
    strip = lambda pos: pf.math.where(pos.vector["x"] < x0 + SPONGE, 1.0, 0.0)  # noqa: E731
    sponge = pf.StaggeredGrid(lambda pos: pf.vec(x=strip(pos), y=strip(pos)), pf.ZERO_GRADIENT, **grid)
    velocity = pf.StaggeredGrid(pf.vec(x=1.0, y=0.0), pf.ZERO_GRADIENT, **grid)
    pressure = None
    first = 0
    if start is not None:
        faces = [pf.math.tensor(start[f"velocity_{axis}"], pf.math.spatial("x,y")) for axis in "xy"]
        velocity = velocity.with_values(pf.math.stack(faces, pf.math.dual(vector="x,y")))
        pressure = pf.CenteredGrid(0.0, pf.math.extrapolation.ZERO, **grid).with_values(
            pf.math.tensor(start["pressure"], pf.math.spatial("x,y")))
        first = int(start["step"])

    snapshots = []
    checkpoints = {}
    n_steps = spin_up_steps + SNAPSHOT_EVERY * (n_snapshots - 1)
    for step in range(first, (n_steps if stop is None else stop) + 1):
        if step in checkpoint_steps:
            checkpoints[step] = {
                "velocity_x": velocity.vector["x"].values.numpy("x,y"),
                "velocity_y": velocity.vector["y"].values.numpy("x,y"),
                "pressure": pressure.values.numpy("x,y"),
            }
        if step >= spin_up_steps and (step - spin_up_steps) % SNAPSHOT_EVERY == 0:
            centred = velocity.at_centers().values.numpy("x,y,vector")
            snapshots.append(centred.reshape(nx // COARSEN, COARSEN, ny // COARSEN, COARSEN, 2).mean(axis=(1, 3)))
        if step == n_steps or step == stop:
            break
        cross = kick if step * DT < KICK_DURATION else 0.0
        # du/dt + (u . grad) u = nu lap u - grad p, div u = 0   (handout (7), (8)), split in steps:
        velocity = pf.advect.mac_cormack(velocity, velocity, DT)
        velocity = pf.diffuse.explicit(velocity, nu, DT)
        velocity = velocity * (1 - sponge) + sponge * pf.vec(x=1.0, y=cross)
        # pressure projection: solve lap p = div u* (handout (9)) and subtract grad p
        velocity, pressure = pf.fluid.make_incompressible(
            velocity, island, pf.Solve("CG", PRESSURE_TOLERANCE, PRESSURE_TOLERANCE, x0=pressure)
        )
    return snapshots, checkpoints


def kept_flow(snapshots: list[np.ndarray]) -> dict[str, np.ndarray]:
    """The kept snapshots (run_solver's, in U) in ocean units: x (nx,), y (ny,) [m] of cell centres,
    t (nt,) [s] from the first, velocity (nt, nx, ny, 2) [m/s] float32."""
    (x0, x1), (y0, y1) = DOMAIN
    nx, ny = CELLS
    dx = (x1 - x0) / nx * COARSEN
    dy = (y1 - y0) / ny * COARSEN
    return {
        "x": (x0 + dx * (np.arange(nx // COARSEN) + 0.5)) * ISLAND_DIAMETER_M,
        "y": (y0 + dy * (np.arange(ny // COARSEN) + 0.5)) * ISLAND_DIAMETER_M,
        "t": np.arange(len(snapshots)) * SNAPSHOT_EVERY * DT * TIME_UNIT_S,
        "velocity": (np.stack(snapshots) * CURRENT_M_S).astype(np.float32),
    }


def flow_arrays(flow: dict[str, np.ndarray], seed: int = FLOW_SEED) -> dict[str, np.ndarray]:
    """Everything the shipped flow file holds: the kept flow (velocity as float16) and its metadata."""
    import phi

    return {
        "x_m": flow["x"],
        "y_m": flow["y"],
        "t_s": flow["t"],
        "velocity_m_s": flow["velocity"].astype(np.float16),
        "island_center_m": np.zeros(2),
        "island_radius_m": np.array(ISLAND_DIAMETER_M / 2),
        "current_m_s": np.array(CURRENT_M_S),
        "reynolds": np.array(REYNOLDS),
        "seed": np.array(seed),
        "solver": np.array(f"phiflow {phi.__version__}, MacCormack + explicit diffusion + CG projection"),
    }


def checkpoint_arrays(checkpoints: dict[int, dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Everything the shipped checkpoint file holds: each state part as "step<n>_<part>"."""
    return {f"step{step}_{part}": state[part] for step, state in sorted(checkpoints.items()) for part in STATE_PARTS}


def shipped_checkpoint(step: int, path: Path) -> dict[str, np.ndarray]:
    """The shipped solver state before ``step``, as ``run_solver(start=...)`` takes it."""
    with np.load(path) as archive:
        return {"step": np.array(step), **{part: archive[f"step{step}_{part}"] for part in STATE_PARTS}}


def write_flow(directory: str | Path, seed: int = FLOW_SEED) -> list[Path]:
    """Build the flow from ``seed`` and write ``castaway_bob_flow.npz`` and its checkpoints into ``directory``."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    snapshots, checkpoints = run_solver(seed, checkpoint_steps=CHECKPOINT_STEPS)
    write_npz(directory / FILE_NAME, flow_arrays(kept_flow(snapshots), seed))
    write_npz(directory / CHECKPOINT_FILE_NAME, checkpoint_arrays(checkpoints))
    return [directory / FILE_NAME, directory / CHECKPOINT_FILE_NAME]


if __name__ == "__main__":  # pragma: no cover
    target = sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "course" / "data"
    start = time.perf_counter()
    for written in write_flow(target):
        print(f"wrote {written} ({written.stat().st_size / 1e6:.2f} MB)")
    print(f"in {time.perf_counter() - start:.1f} s")
