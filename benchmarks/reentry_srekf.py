"""Time the reentry-srekf reference filter on the shipped data (500 steps), median of 5 runs.

Run from the repository root:  python -m benchmarks.reentry_srekf   (or python benchmarks/reentry_srekf.py)
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from course import starship  # noqa: E402
from solutions.reentry_srekf import reference as ref  # noqa: E402


def main(repeats: int = 5) -> float:
    """Print and return the median wall time [s] of one reference filter run."""
    data = starship.load()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        ref.run_reference(data)
        times.append(time.perf_counter() - start)
    median = statistics.median(times)
    print(f"reentry-srekf reference filter: {len(data)} steps, median of {repeats}: {median * 1e3:.1f} ms")
    return median


if __name__ == "__main__":
    main()
