"""Castaway Bob: the three estimators over many seeded drifts, and the flow build time.

``python benchmarks/castaway_bob.py`` prints

1. the flow build (PhiFlow, seeded): its time, the shipped file's size, and whether the rebuild
   is byte-identical to the shipped file (skip with ``--no-build``);
2. the RMSE of the moving average, the rank-2 filter, the constant-velocity control and the rank-4 filter over ``--drifts`` seeded
   drifts (default 100) in the shipped current, and again in slack water (the same flow pattern
   at a tenth of the speed), with the spread over drifts and paired differences with 95 %
   intervals;
3. the rank-2 filter's RMSE as its random-walk step sigma_walk varies, in both currents, and on the
   slack-water tuning set (50 other drifts, seed 7) on which the notebook's slack-water step was chosen;
4. the time of one 50-drift comparison, the notebook's cost.

Nothing here is asserted: the numbers are for the lab's discussion and for the maintainers.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run as a script from anywhere
    sys.path.insert(0, str(ROOT))

from course import ocean  # noqa: E402
from solutions.castaway_bob import reference as ref  # noqa: E402
from solutions.castaway_bob import flow as castaway_bob_flow  # noqa: E402
from solutions.castaway_bob.claims import CONDITIONS, TUNING_SEED  # noqa: E402

SEED = 2024
SLACK_SIGMA_WALK = CONDITIONS["slack"][1]
"""The rank-2 filter's step in slack water, chosen on the tuning set (seed ``TUNING_SEED``)."""


def run_cv(flow: ocean.Flow):
    """The comparison's control: four states, no current map, its first velocity 0 +- the current's speed."""
    return ocean.constant_velocity_filter(ref.kalman_step, ref.transition_matrix, ref.observation_matrix,
                                          sigma_v0=flow.current)


def build_time() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        path = castaway_bob_flow.write_flow(tmp)[0]
        seconds = time.perf_counter() - start
        same = path.read_bytes() == ocean.DATA_FILE.read_bytes()
    print(f"flow build: {seconds:.0f} s (PhiFlow, {castaway_bob_flow.SPIN_UP_STEPS} + "
          f"{castaway_bob_flow.SNAPSHOT_EVERY * (castaway_bob_flow.N_SNAPSHOTS - 1)} steps on a "
          f"{castaway_bob_flow.CELLS[0]} x {castaway_bob_flow.CELLS[1]} grid); "
          f"rebuild byte-identical to the shipped file: {same}")


def table(flow: ocean.Flow, drifts: list[ocean.Drift], sigma_walk: float, title: str) -> None:
    result = ocean.compare(drifts, flow, ref.trailing_mean, ref.run_rank2, run_cv(flow), ref.run_rank4, ref.track_rmse,
                           ref.ellipse_area, sigma_walk=sigma_walk)
    raw = np.array([ref.track_rmse(d.fixes, d.position) for d in drifts])
    print(f"\n{title} (rank-2 sigma_walk = {sigma_walk:g} m)")
    print(ocean.format_comparison(result, raw))
    names = ocean.NAMES
    for a, b in ((names[1], names[0]), (names[2], names[1]), (names[3], names[2]), (names[3], names[0])):
        diff = result.rmse[a] - result.rmse[b]
        half = 1.96 * diff.std(ddof=1) / np.sqrt(len(diff))
        print(f"  {a} - {b}: {diff.mean():+6.1f} m +- {half:.1f} (95 %), {a} better on "
              f"{np.mean(diff < 0) * 100:.0f} % of drifts")


def sweep(flow: ocean.Flow, drifts: list[ocean.Drift], label: str) -> None:
    ma = np.mean([ref.track_rmse(ref.trailing_mean(d.fixes), d.position) for d in drifts])
    values = (5, 10, 15, 20, 30, 45, 60)
    rmse = [np.mean([ref.track_rmse(ref.run_rank2(d.fixes, sigma_walk=s)[0], d.position) for d in drifts])
            for s in values]
    cells = "".join(f"{r:>7.1f}" for r in rmse)
    print(f"{label:<26}{ma:>8.1f}{cells}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drifts", type=int, default=100)
    parser.add_argument("--no-build", action="store_true", help="skip the (minutes-long) flow build")
    args = parser.parse_args(argv)

    size = ocean.DATA_FILE.stat().st_size
    print(f"shipped flow: {ocean.DATA_FILE.name}, {size / 1e6:.2f} MB")
    if not args.no_build:
        build_time()

    flow = ocean.load()
    slack = flow.scaled(0.1)
    drifts = ocean.simulate_drifts(flow, np.random.default_rng(SEED), args.drifts)
    slack_drifts = ocean.simulate_drifts(slack, np.random.default_rng(SEED), args.drifts)
    table(flow, drifts, ocean.SIGMA_WALK, f"Shipped current (0.5 m/s), {args.drifts} drifts")
    table(slack, slack_drifts, SLACK_SIGMA_WALK, f"Slack water (0.05 m/s), {args.drifts} drifts")

    print("\nRank-2 RMSE (m) against sigma_walk (m per minute); MA = moving average of 3")
    print(f"{'':<26}{'MA':>8}" + "".join(f"{s:>7}" for s in (5, 10, 15, 20, 30, 45, 60)))
    sweep(flow, drifts, "shipped current")
    sweep(slack, slack_drifts, "slack water")
    sweep(slack, ocean.simulate_drifts(slack, np.random.default_rng(TUNING_SEED), 50), "slack tuning set (50)")

    start = time.perf_counter()
    notebook_drifts = ocean.simulate_drifts(flow, np.random.default_rng(1), 50)
    ocean.compare(notebook_drifts, flow, ref.trailing_mean, ref.run_rank2, run_cv(flow), ref.run_rank4, ref.track_rmse,
                  ref.ellipse_area)
    print(f"\none 50-drift simulation + comparison: {time.perf_counter() - start:.2f} s")


if __name__ == "__main__":
    main()
