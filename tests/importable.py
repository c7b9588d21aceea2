"""Which packages a Python interpreter can import, probed as a kernel started elsewhere would be:
in another folder, without the grader's PYTHONPATH."""

from __future__ import annotations

import ast
import os
import subprocess
from pathlib import Path

PACKAGES = ("solutions", "autograder", "course")


def importable(python: Path | str, cwd: Path) -> dict[str, bool]:
    """For each of PACKAGES, whether ``python`` run in ``cwd`` without PYTHONPATH finds it."""
    env = {name: value for name, value in os.environ.items() if name != "PYTHONPATH"}
    probe = f"import importlib.util as u; print([u.find_spec(m) is not None for m in {PACKAGES!r}])"
    out = subprocess.run([str(python), "-c", probe], cwd=cwd, env=env, capture_output=True, text=True, check=True)
    return dict(zip(PACKAGES, ast.literal_eval(out.stdout)))
