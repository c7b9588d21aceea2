"""Helpers of the tests that prove the shipped data (course/data/) equal a rebuild, in part."""

import numpy as np


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal dtype, shape and bytes (unlike ==, this tells -0.0 from 0.0 and compares NaNs)."""
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
