"""What one call of a student's function costs when the hidden test runs in the grader's process
(autograder/pipeline/check_runner.py) and the function in a sandboxed grading kernel.

Starts one kernel as grading does (SandboxedKernelManager, the kernel's server sent as source),
defines an identity function and one that calls a served blank, and times, for arguments of several
sizes: a call from the grader into the kernel and back, and a call that also calls the grader back
once (a blank that uses another blank's reference, which the grader first runs on the same
arguments to know which calls it serves). Prints the median of each over REPEATS calls.

    .venv/bin/python benchmarks/hidden_test_calls.py
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from autograder.pipeline import hidden_blocks, kernel_code, kernel_connection  # noqa: E402
from autograder.pipeline.student_function import StudentFunction  # noqa: E402
from autograder.kernel.manager import SandboxedKernelManager  # noqa: E402

REPEATS = 200
SIZES = {"3 x 3": (3, 3), "3 x 1,000": (3, 1_000), "3 x 10,000 (a particle cloud)": (3, 10_000)}
DEFINITIONS = "def echo(x):\n    return x\n\ndef uses_other(x):\n    return other(x)\n"


def other(x):
    """The reference's version of the served blank."""
    return x


def uses_other(x):
    """The reference's version of the blank under test: it calls the served blank once."""
    return other(x)


def _median_ms(call, argument, repeats: int = REPEATS) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call(argument)
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times)


def main() -> None:
    import asyncio

    async def start():
        km = SandboxedKernelManager(kernel_name="python3")
        await km.start_kernel(cwd=None, extra_arguments=["--HistoryManager.hist_file=:memory:", "--IPKernelApp.log_level=ERROR"])
        kc = km.client()
        kc.start_channels()
        await kc.wait_for_ready(timeout=120)
        return km, kc

    loop = asyncio.new_event_loop()
    km, kc = loop.run_until_complete(start())

    def run(code: str) -> str:
        return kc.execute(code, silent=True, store_history=False)

    def reply(msg_id: str) -> dict:
        while True:
            message = loop.run_until_complete(kc.get_shell_msg(timeout=120))
            if message["parent_header"].get("msg_id") == msg_id:
                return message["content"]

    assert reply(run(kernel_code.kernel_setup_code()))["status"] == "ok"
    assert reply(run(DEFINITIONS))["status"] == "ok"
    rows = []
    for name in ("echo", "uses_other"):
        listener = kernel_connection.Listener(km.private_folder)
        msg_id = run(kernel_code.serve_code(listener.path, hidden_blocks.HiddenTest("benchmark", f"check_{name}", name)))
        peer, why_not = kernel_connection.connect(listener, time.monotonic() + 60, lambda: False)
        assert peer is not None, why_not
        # the grader serves ``other`` to the calls that the reference's own version makes (served_calls.py)
        student = StudentFunction(peer, name, frozenset({"other"}), {"other": other}, reference=uses_other)
        for label, shape in SIZES.items():
            rows.append((name, label, _median_ms(student, np.ones(shape))))
        kernel_connection.stop(peer)
        listener.close()
        assert reply(msg_id)["status"] == "ok"
    loop.run_until_complete(km.shutdown_kernel(now=True))
    kc.stop_channels()
    print(f"Median time per call over {REPEATS} calls, grader -> sandboxed kernel -> grader:")
    print(f"{'function':<12} {'argument':<32} {'per call [ms]':>14}")
    for name, label, remote in rows:
        what = "identity" if name == "echo" else "+1 callback"
        print(f"{what:<12} {label:<32} {remote:>14.3f}")


if __name__ == "__main__":
    main()
