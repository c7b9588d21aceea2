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
from solutions import nonlinear_filters as ref  # noqa: E402


def _time(runs: int, filters: tuple[str, ...]) -> float:
    start = time.perf_counter()
    ref.monte_carlo(runs, seed=1, filters=filters)
    return time.perf_counter() - start


def main(runs: int = 400) -> dict[str, float]:
    """Print and return wall times [s]: one run of each filter, then ``runs`` runs of every filter."""
    times = {name: _time(1, (name,)) for name in air_traffic.FILTERS}
    for name, seconds in times.items():
        print(f"one run, {air_traffic.LABELS[name]:<10}{seconds * 1e3:10.1f} ms")
    times["all"] = _time(runs, air_traffic.FILTERS)
    print(f"{runs} runs of all seven filters (the PF with {ref.PARTICLES} particles): {times['all']:.1f} s")
    return times


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 400)
