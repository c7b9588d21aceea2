"""Time the nonlinear-filters reference: one run of each filter, and R runs of all seven at once.

Run from the repository root:  python -m benchmarks.nonlinear_filters [R]   (default R = 400)
Wall times on a shared machine vary; nothing here is asserted.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from course import air_traffic  # noqa: E402
from solutions.nonlinear_filters import reference as ref  # noqa: E402


def _time(runs: int, filters: tuple[str, ...]) -> tuple[float, float]:
    """Wall and CPU time [s] of a Monte Carlo of ``runs`` runs of ``filters``."""
    wall, cpu = time.perf_counter(), time.process_time()
    ref.monte_carlo(runs, seed=1, filters=filters)
    return time.perf_counter() - wall, time.process_time() - cpu


def main(runs: int = 400) -> dict[str, tuple[float, float]]:
    """Print and return (wall, CPU) times [s]: one run of each filter, then ``runs`` runs of every filter."""
    times = {name: _time(1, (name,)) for name in air_traffic.FILTERS}
    for name, (wall, cpu) in times.items():
        print(f"one run, {air_traffic.LABELS[name]:<10} wall {wall * 1e3:8.1f} ms   CPU {cpu * 1e3:8.1f} ms")
    times["all"] = _time(runs, air_traffic.FILTERS)
    wall, cpu = times["all"]
    print(f"{runs} runs of all seven filters (the PF with {ref.PARTICLES} particles): wall {wall:.1f} s, CPU {cpu:.1f} s")
    return times


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 400)
