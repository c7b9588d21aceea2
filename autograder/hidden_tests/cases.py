"""Where the hidden tests draw their random cases from: a seed that the grading kernel never sees.

Every hidden test draws its cases from ``rng(stream)``, a NumPy Generator seeded with the pair
(submission seed, ``stream``); each check uses streams of its own (its old fixed seed, 1104 for
train-kf's ``predict``). The grader sets the submission seed for the time it grades one submission
(``seeded``): an HMAC of the submission's content under the course's secret (``seed_for``), so that
the same file regraded gets the same cases and the same score, a changed file gets new ones, and
nothing a submission learns about its cases (by printing what its function was called with) says
anything about another submission's. When nothing sets it (a source notebook run by hand, nbval,
the tests), the seed is ``DEFAULT_SEED`` and the cases are the same on every run.

Every check must hold for every seed: a correct answer passes whatever the seed, and a stochastic
check's stated false-fail probability is over the seeds (tests/test_case_seeds.py).
"""

from __future__ import annotations

import contextlib
import hashlib
import hmac
from collections.abc import Iterator

import numpy as np

DEFAULT_SEED = 0
"""The submission seed when the grader has set none."""

_seed = DEFAULT_SEED


def rng(*stream: int) -> np.random.Generator:
    """A Generator for one stream of cases (non-negative ints), seeded with a SHA-256 digest of the current
    submission seed and the stream. Not with the pair itself: the state of a generator that a hidden test gives a
    student's function can be inverted to the words it was seeded with (an adversarial review of issue 30 recovered
    the submission seed from ``default_rng([seed, *stream])``; tests/seed_inversion.py), and a digest's words tell
    nothing of the seed."""
    digest = hashlib.sha256(repr((_seed, tuple(int(s) for s in stream))).encode()).digest()
    return np.random.default_rng(int.from_bytes(digest, "big"))


def current_seed() -> int:
    """The submission seed the cases are drawn with now."""
    return _seed


@contextlib.contextmanager
def seeded(seed: int) -> Iterator[None]:
    """Draw every hidden test's cases with submission seed ``seed`` (an int in [0, 2^64)) inside the block."""
    global _seed
    if not 0 <= seed < 2**64:
        raise ValueError(f"a submission seed is an int in [0, 2^64), not {seed}")
    before, _seed = _seed, int(seed)
    try:
        yield
    finally:
        _seed = before


def seed_for(secret: bytes, content: bytes) -> int:
    """The submission seed of a submission whose content is ``content``: the first 8 bytes of
    HMAC-SHA256(secret, content). Without the secret it cannot be predicted or recomputed."""
    return int.from_bytes(hmac.new(secret, content, hashlib.sha256).digest()[:8], "big")
