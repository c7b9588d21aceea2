"""Check helpers for the visible tests in the lab notebooks.

Each helper raises ``AssertionError`` with a message that says what was expected, what your
function gave, and, where we can guess it, what to look at. They check properties; they never
compute a blank's answer.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

NOT_WRITTEN = "Not written yet: replace this line with your code."
"""The message of the stub that stands in a blank until you write it."""


class NotWrittenYet(Exception):
    """A cell needs a blank that still holds its stub."""


def require(*functions: Callable) -> None:
    """Stop a cell early, with a clear message, if a blank it needs is not written yet."""
    missing = [f.__name__ for f in functions if NOT_WRITTEN in getattr(getattr(f, "__code__", None), "co_consts", ())]
    if missing:
        names = [f"{name}()" for name in missing]
        listed = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
        it, its, cell = ("it", "its", "cell") if len(names) == 1 else ("them", "their", "cells")
        raise NotWrittenYet(
            f"This cell needs {listed}, which you have not written yet. Write {it} in {its} {cell} above "
            f"(replace the line that raises NotImplementedError), run {it}, then run this cell again."
        )


def check_array(value: Any, name: str, shape: tuple[int, ...], hint: str = "") -> np.ndarray:
    """Check that ``value`` is a finite NumPy array of the given shape, and return it as one."""
    if isinstance(value, tuple):
        raise AssertionError(
            f"{name} should be one array of shape {shape}, but it is a tuple of {len(value)} items. "
            f"{hint}".strip()
        )
    array = np.asarray(value, dtype=float)
    if array.shape != shape:
        raise AssertionError(
            f"{name} should have shape {shape}, but it has shape {array.shape}. {hint}".strip()
        )
    if not np.all(np.isfinite(array)):
        raise AssertionError(f"{name} contains NaN or infinite entries: {array}. {hint}".strip())
    return array


def check_pair(value: Any, name: str, first: str, second: str) -> tuple[Any, Any]:
    """Check that a function returned a pair, such as ``(x_f, B_f)``, and unpack it."""
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise AssertionError(
            f"{name} should return two things, ({first}, {second}), for example "
            f"`return {first}, {second}`. It returned {type(value).__name__}."
        )
    return value[0], value[1]


def check_close(
    actual: Any,
    expected: Any,
    name: str,
    hint: str = "",
    *,
    rtol: float = 1e-7,
    atol: float = 1e-9,
    show_expected: bool = True,
) -> None:
    """Check that ``actual`` equals ``expected`` to within ``rtol`` and ``atol``.

    With ``show_expected=False`` the message gives only the size of the error, not the
    expected numbers.
    """
    actual = np.asarray(actual, dtype=float)
    expected = np.asarray(expected, dtype=float)
    if actual.shape != expected.shape:
        raise AssertionError(
            f"{name} should have shape {expected.shape}, but it has shape {actual.shape}. {hint}".strip()
        )
    if np.allclose(actual, expected, rtol=rtol, atol=atol):
        return
    error = np.max(np.abs(actual - expected))
    if show_expected:
        detail = f"expected\n{np.array2string(expected, precision=6)}\nbut got\n{np.array2string(actual, precision=6)}"
    else:
        detail = f"the largest difference from the reference is {error:.3g}"
    raise AssertionError(f"{name} is not right: {detail}. {hint}".strip())


def check_symmetric(matrix: Any, name: str, hint: str = "") -> None:
    """Check that a covariance matrix is symmetric, to rounding error."""
    matrix = np.asarray(matrix, dtype=float)
    scale = max(1.0, float(np.max(np.abs(matrix))))
    asymmetry = float(np.max(np.abs(matrix - matrix.T)))
    if asymmetry > 1e-9 * scale:
        raise AssertionError(
            f"{name} should be symmetric, like every covariance matrix, but {name} - {name}.T "
            f"has an entry of size {asymmetry:.3g}. {hint}".strip()
        )


def random_spd(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random symmetric positive definite n x n matrix with a modest condition number."""
    factor = rng.standard_normal((n, n))
    return factor @ factor.T + n * np.eye(n)


def passed(name: str) -> None:
    """Report that a blank passed its visible checks."""
    print(f"{name}: all visible checks passed. Hidden tests on random cases run when you are graded.")
