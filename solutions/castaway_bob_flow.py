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

Run ``python -m solutions.castaway_bob_flow [DIR]`` to rebuild it and print the build time.
"""

from __future__ import annotations

import io
import sys
import time
import warnings
import zipfile
from pathlib import Path

import numpy as np

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


def simulate_wake(
    seed: int = FLOW_SEED, n_snapshots: int = N_SNAPSHOTS, spin_up_steps: int = SPIN_UP_STEPS
) -> dict[str, np.ndarray]:
    """Run the solver and return the kept flow in ocean units (shorter runs are for tests).

    Returns arrays x (nx,) and y (ny,) [m] of cell centres, t (nt,) [s] from the first kept
    snapshot, and velocity (nt, nx, ny, 2) [m/s] as float32, with nx, ny = 120, 50.
    """
    with warnings.catch_warnings():
        # PhiFlow warns (DeprecationWarning, RuntimeWarning) on import about experimental parts
        # we do not use, and about jit being unavailable on NumPy; none affects the result.
        warnings.simplefilter("ignore")
        from phi import flow as pf

        return _simulate(pf, seed, n_snapshots, spin_up_steps)


def _simulate(pf, seed: int, n_snapshots: int, spin_up_steps: int) -> dict[str, np.ndarray]:
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

    snapshots = []
    n_steps = spin_up_steps + SNAPSHOT_EVERY * (n_snapshots - 1)
    for step in range(n_steps + 1):
        if step >= spin_up_steps and (step - spin_up_steps) % SNAPSHOT_EVERY == 0:
            centred = velocity.at_centers().values.numpy("x,y,vector")
            snapshots.append(centred.reshape(nx // COARSEN, COARSEN, ny // COARSEN, COARSEN, 2).mean(axis=(1, 3)))
        if step == n_steps:
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

    dx = (x1 - x0) / nx * COARSEN
    dy = (y1 - y0) / ny * COARSEN
    return {
        "x": (x0 + dx * (np.arange(nx // COARSEN) + 0.5)) * ISLAND_DIAMETER_M,
        "y": (y0 + dy * (np.arange(ny // COARSEN) + 0.5)) * ISLAND_DIAMETER_M,
        "t": np.arange(n_snapshots) * SNAPSHOT_EVERY * DT * TIME_UNIT_S,
        "velocity": (np.stack(snapshots) * CURRENT_M_S).astype(np.float32),
    }


def flow_arrays(seed: int = FLOW_SEED, n_snapshots: int = N_SNAPSHOTS) -> dict[str, np.ndarray]:
    """Everything the shipped file holds: the kept flow (velocity as float16) and its metadata."""
    import phi

    flow = simulate_wake(seed, n_snapshots)
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


def write_npz(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """Write ``arrays`` as a compressed .npz that is a function of the arrays alone.

    ``np.savez_compressed`` stamps every member with the current time; here each member gets
    a fixed timestamp, so equal arrays give equal bytes.
    """
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, array in arrays.items():
            buffer = io.BytesIO()
            np.lib.format.write_array(buffer, np.asarray(array), allow_pickle=False)
            member = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            member.compress_type = zipfile.ZIP_DEFLATED
            member.external_attr = 0o644 << 16
            archive.writestr(member, buffer.getvalue(), compresslevel=9)


def write_flow(directory: str | Path, seed: int = FLOW_SEED) -> Path:
    """Build the flow from ``seed`` and write ``castaway_bob_flow.npz`` into ``directory``."""
    path = Path(directory) / FILE_NAME
    path.parent.mkdir(parents=True, exist_ok=True)
    write_npz(path, flow_arrays(seed))
    return path


if __name__ == "__main__":  # pragma: no cover
    target = sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent / "course" / "data"
    start = time.perf_counter()
    written = write_flow(target)
    print(f"wrote {written} ({written.stat().st_size / 1e6:.2f} MB) in {time.perf_counter() - start:.1f} s")
