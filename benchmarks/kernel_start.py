"""What the sandbox costs a grading kernel: start times, plain and sandboxed.

    python benchmarks/kernel_start.py [--runs 10]

Starts the python3 kernel ``runs`` times with each manager, in turn (so that the machine's load
falls on all alike): jupyter_client's AsyncKernelManager as nbclient uses it (TCP on loopback), the
same over Unix sockets (ipc), and autograder.kernel.sandbox's SandboxedKernelManager (ipc, launcher,
Landlock, network namespace). For each it prints the median seconds from starting the kernel to
its first reply, and to the end of a first cell that imports NumPy and SciPy and saves a Matplotlib
figure (the sandboxed kernel gets its font list from the sandbox's cache, made once beforehand).
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import tempfile
import time
from pathlib import Path

from jupyter_client.manager import AsyncKernelManager

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from autograder.kernel.manager import SandboxedKernelManager  # noqa: E402
from autograder.kernel.sandbox import status  # noqa: E402

FIRST_CELL = """
import numpy, scipy.linalg, matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
fig, ax = plt.subplots()
ax.plot([0, 1], [1, 0])
ax.set_title("a figure")
fig.savefig("figure.png")
"""

KERNEL_ARGUMENTS = ["--HistoryManager.hist_file=:memory:", "--IPKernelApp.log_level=ERROR"]
"""As nbgrader_config.py starts grading kernels."""

MANAGERS = {
    "plain (tcp)": lambda folder: AsyncKernelManager(kernel_name="python3"),
    "plain (ipc)": lambda folder: AsyncKernelManager(kernel_name="python3", transport="ipc", ip=str(folder / "ipc")),
    "sandboxed (ipc)": lambda folder: SandboxedKernelManager(kernel_name="python3"),
}
"""Each makes a kernel manager, given the kernel's working folder."""


async def one_start(make, folder: Path) -> tuple[float, float]:
    """Seconds from starting a kernel to its first reply, and to the end of FIRST_CELL."""
    km = make(folder)
    start = time.perf_counter()
    await km.start_kernel(cwd=str(folder), extra_arguments=KERNEL_ARGUMENTS)
    kc = km.client()
    kc.start_channels()
    try:
        await kc.wait_for_ready(timeout=180)
        ready = time.perf_counter() - start
        reply = await kc.execute_interactive(FIRST_CELL, timeout=180, output_hook=lambda msg: None)
        assert reply["content"]["status"] == "ok", reply["content"]
        first_cell = time.perf_counter() - start
    finally:
        kc.stop_channels()
        await km.shutdown_kernel(now=True)
    return ready, first_cell


async def main(runs: int) -> None:
    """Time ``runs`` starts of each manager and print the medians."""
    print(f"sandbox: {status().summary}")
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in MANAGERS}
    with tempfile.TemporaryDirectory(prefix="kit-bench-") as tmp:
        # a working folder for each kernel, as grading gives each submission its own: run by root, a sandboxed
        # kernel's folder becomes its own user's, and the next kernel could not replace the figure it saved
        folders = (Path(tempfile.mkdtemp(dir=tmp)) for _ in iter(int, 1))
        await one_start(MANAGERS["sandboxed (ipc)"], next(folders))  # makes the sandbox's font cache
        for _ in range(runs):
            for name, make in MANAGERS.items():
                times[name].append(await one_start(make, next(folders)))
    print(f"median of {runs} starts      to first reply   to end of first cell (NumPy, SciPy, a figure)")
    for name, pairs in times.items():
        ready = statistics.median(r for r, _ in pairs)
        cell = statistics.median(c for _, c in pairs)
        print(f"{name:<26}{ready:>10.2f} s{cell:>18.2f} s")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10, help="starts of each manager (default 10)")
    asyncio.run(main(parser.parse_args().runs))
