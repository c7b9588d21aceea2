"""Performance study of the reentry-pf particle filter: ``python benchmarks/reentry_pf.py``.

Three implementations of the same step (a)-(d), timed in the same run on the shipped data:

- ``reference``: ``solutions.reentry_pf.reference.pf_step`` (log-weights, inverse-CDF resampling at sorted
  uniforms, so the search and the copy run through memory in order);
- ``plain``: straightforward vectorised NumPy, the way the handout reads (weights as
  probabilities, ``rng.choice(N, N, p=w)``);
- ``loop``: the same algorithm particle by particle in plain Python (``math``, ``bisect``).

It prints (1) a whole filter run, N = 5000 and 300 steps, for each, with the ratios, and
(2) the time of one step as N grows from 10^3 to 10^6. Nothing here is asserted: timings depend
on the machine. tests/ checks that ``plain`` and ``loop`` pass the same statistical checks as
the reference, so they are the same algorithm.

Options: ``--repeats R`` (median of R, default 3), ``--quick`` (fewer sizes, for a smoke test).
"""

from __future__ import annotations

import argparse
import bisect
import math
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run as a script from anywhere
    sys.path.insert(0, str(ROOT))

from course import falling_object  # noqa: E402
from course.falling_object import DT, ETA, GAMMA, INNOVATION_STD, SIGMA, G  # noqa: E402
from solutions.reentry_pf import reference as reentry_pf  # noqa: E402

Step = Callable[[np.ndarray, np.ndarray, float, np.random.Generator], tuple[np.ndarray, np.ndarray]]


def plain_pf_step(x: np.ndarray, w: np.ndarray, b_next: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Step (a)-(d) in plain vectorised NumPy, weights as probabilities (no logarithms)."""
    N = x.shape[1]
    x_hat = x + DT * reentry_pf.tracking_dynamics(0.0, x)
    w_hat = w * np.exp(-((x_hat[0] - b_next) ** 2) / (2 * SIGMA**2))
    w_hat = w_hat / w_hat.sum()
    k = rng.choice(N, size=N, p=w_hat)
    x_new = x_hat[:, k] + INNOVATION_STD[:, None] * rng.standard_normal((3, N))
    w_new = np.exp(-((x_new[0] - b_next) ** 2 - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2))
    return x_new, w_new / w_new.sum()


def loop_pf_step(x: np.ndarray, w: np.ndarray, b_next: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Step (a)-(d) particle by particle in plain Python, with log-weights like the reference."""
    N = x.shape[1]
    h, v, beta = x.tolist()
    weights = w.tolist()
    two_s2 = 2 * SIGMA**2
    h_hat, v_hat, log_w_hat = [0.0] * N, [0.0] * N, [0.0] * N
    for i in range(N):  # (a) Forward Euler and (b) log fitness
        rho = GAMMA * math.exp(-ETA * h[i])
        h_hat[i] = h[i] - DT * v[i]
        v_hat[i] = v[i] + DT * (G - G * rho * v[i] ** 2 / (2 * beta[i]))
        log_w_hat[i] = (math.log(weights[i]) if weights[i] > 0 else -math.inf) - (h_hat[i] - b_next) ** 2 / two_s2
    top = max(log_w_hat)
    cdf, total = [0.0] * N, 0.0
    for i in range(N):
        total += math.exp(log_w_hat[i] - top)
        cdf[i] = total
    noise = rng.standard_normal((3, N)).tolist()
    uniforms = rng.random(N).tolist()
    x_new = [[0.0] * N for _ in range(3)]
    log_w = [0.0] * N
    for ell in range(N):  # (c) resample by bisection in the cumulative weights, add the innovation
        k = min(bisect.bisect_right(cdf, uniforms[ell] * total), N - 1)
        x_new[0][ell] = h_hat[k] + INNOVATION_STD[0] * noise[0][ell]
        x_new[1][ell] = v_hat[k] + INNOVATION_STD[1] * noise[1][ell]
        x_new[2][ell] = beta[k] + INNOVATION_STD[2] * noise[2][ell]
        # (d) against the parent's candidate
        log_w[ell] = -((x_new[0][ell] - b_next) ** 2 - (h_hat[k] - b_next) ** 2) / two_s2
    top = max(log_w)
    new_weights = [math.exp(value - top) for value in log_w]
    total = sum(new_weights)
    return np.array(x_new), np.array([value / total for value in new_weights])


IMPLEMENTATIONS: dict[str, Step] = {"reference": reentry_pf.pf_step, "plain": plain_pf_step, "loop": loop_pf_step}


def run_filter(step: Step, b: np.ndarray, N: int, seed: int) -> float:
    """The whole filter over b with N particles; returns the final posterior mean of beta."""
    rng = np.random.default_rng(seed)
    x, w = reentry_pf.initial_cloud(b[0], N, rng)
    for j in range(1, b.shape[0]):
        x, w = step(x, w, b[j], rng)
    return float(x[2] @ w)


def median_time(func: Callable[[], object], repeats: int) -> float:
    """The median of ``repeats`` wall-clock timings of func() [s]."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def whole_run_table(b: np.ndarray, N: int, repeats: int) -> dict[str, float]:
    """Seconds for a whole run of each implementation (loop: one repeat, it is slow)."""
    return {
        name: median_time(lambda step=step: run_filter(step, b, N, seed=1), 1 if name == "loop" else repeats)
        for name, step in IMPLEMENTATIONS.items()
    }


def step_time(step: Step, N: int, repeats: int) -> float:
    """Seconds for one step with N particles, on a prior cloud and the second reading."""
    b = falling_object.load().b
    rng = np.random.default_rng(2)
    x, w = reentry_pf.initial_cloud(b[0], N, rng)
    return median_time(lambda: step(x, w, b[1], rng), repeats)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="small sizes only (smoke test)")
    args = parser.parse_args(argv)
    b = falling_object.load().b
    steps = b.shape[0] - 1
    N = 500 if args.quick else falling_object.N_PARTICLES

    print(f"1. Whole filter run: N = {N}, {steps} steps, median of {args.repeats} (loop: 1)")
    runs = whole_run_table(b, N, args.repeats)
    print(f"{'implementation':<16}{'time [s]':>10}{'per step [ms]':>15}{'vs reference':>14}")
    for name, seconds in runs.items():
        print(f"{name:<16}{seconds:>10.3f}{1e3 * seconds / steps:>15.3f}{seconds / runs['reference']:>13.2f}x")
    print(f"reference / plain = {runs['reference'] / runs['plain']:.2f} (target: at most 1.5)")
    print(f"loop / reference  = {runs['loop'] / runs['reference']:.0f}")

    sizes = [10**3, 10**4] if args.quick else [10**3, 10**4, 10**5, 10**6]
    loop_limit = 10**4 if args.quick else 10**5
    print(f"\n2. One step against N, median of {args.repeats} (loop only up to N = {loop_limit:.0e})")
    print(f"{'N':>9}{'reference [ms]':>16}{'ns/particle':>13}{'plain [ms]':>12}{'ref/plain':>11}{'loop [ms]':>12}")
    for n in sizes:
        ref = step_time(reentry_pf.pf_step, n, args.repeats)
        plain = step_time(plain_pf_step, n, args.repeats)
        loop = f"{1e3 * step_time(loop_pf_step, n, 1):>12.1f}" if n <= loop_limit else f"{'-':>12}"
        print(f"{n:>9}{1e3 * ref:>16.3f}{1e9 * ref / n:>13.0f}{1e3 * plain:>12.3f}{ref / plain:>11.2f}{loop}")


if __name__ == "__main__":
    main()
