"""The sixth- and eighth-order conjugate unscented transforms (CUT6, CUT8) for five states.

Adurthi, Singla and Singh build their point sets from *families*: every point that a generator
vector reaches by permuting its coordinates and flipping their signs, scaled by one radius r and
given one weight w. The families they use for n = 5 (the air-traffic state) are

| rule | family (generator, before scaling)          | points |
|------|---------------------------------------------|--------|
| both | the centre (0, ..., 0)                      | 1      |
| both | principal axes (1, 0, 0, 0, 0)              | 2n     |
| both | conjugate axes (1, 1, 1, 1, 1)              | 2^n    |
| both | plane diagonals (1, 1, 0, 0, 0)             | 2n(n-1)|
| CUT8 | a second, differently scaled conjugate axis | 2^n    |
| CUT8 | 3-subspace diagonals (1, 1, 1, 0, 0), r = 2 | 4n(n-1)(n-2)/3 |
| CUT8 | space multisectors (h, 1, 1, 1, 1), h = 3   | n 2^n  |

so CUT6 has 83 points and CUT8 355. The radii and weights are what makes every moment of the
standard normal up to degree 6 (CUT6) or 8 (CUT8) exact; we solve those moment equations here
rather than typing in the published numbers. Odd moments vanish by the symmetry of each family,
so the rules are exact to degree 7 and 9. (The published construction fixes h = 3 and the
3-subspace radius 2; the starting guesses below are the published values rounded to one or two
figures, and the solver converges to the published rule.)

Points are standard-normal (the mean 0, covariance I): map them with x = m + S z, S a square root
of the covariance.
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
from scipy import optimize

N_STATES = 5
CUT8_MULTISECTOR_H = 3.0
"""The published h of CUT8's space multisectors (h, 1, 1, 1, 1)."""
CUT8_SUBSPACE_RADIUS = 2.0
"""The published radius of CUT8's 3-subspace diagonals (1, 1, 1, 0, 0)."""


def family(generator: tuple[float, ...]) -> np.ndarray:
    """Every distinct point reached from ``generator`` by coordinate permutations and sign flips, (M, n)."""
    points = set()
    for perm in set(itertools.permutations(generator)):
        nonzero = [i for i, v in enumerate(perm) if v != 0]
        for signs in itertools.product((1.0, -1.0), repeat=len(nonzero)):
            point = list(perm)
            for i, s in zip(nonzero, signs):
                point[i] = s * point[i]
            points.add(tuple(point))
    return np.array(sorted(points), dtype=float)


def even_moment_classes(max_degree: int, n: int) -> list[tuple[int, ...]]:
    """Half-exponents (a_1 >= a_2 >= ...) of the monomials z_1^(2 a_1) z_2^(2 a_2) ... of degree <= max_degree.

    By the symmetry of the families, one monomial stands for every permutation of its exponents.
    """
    classes: list[tuple[int, ...]] = []

    def split(rest: int, largest: int, parts: tuple[int, ...]) -> None:
        if rest == 0:
            if len(parts) <= n:
                classes.append(parts)
            return
        for part in range(min(rest, largest), 0, -1):
            split(rest - part, part, parts + (part,))

    for half in range(1, max_degree // 2 + 1):
        split(half, half, ())
    return classes


def gaussian_even_moment(half_exponents: tuple[int, ...]) -> float:
    """E[z_1^(2 a_1) z_2^(2 a_2) ...] for independent standard normals: the product of (2a - 1)!!."""
    return float(np.prod([np.prod(np.arange(2 * a - 1, 0, -2)) for a in half_exponents]))


def _moment_sums(families: list[np.ndarray], classes: list[tuple[int, ...]]) -> np.ndarray:
    """sums[c, f]: the sum over family f's unscaled points of the monomial of class c, shape (C, F)."""
    return np.array([[np.sum(np.prod(points[:, : len(c)] ** (2 * np.array(c)), axis=1)) for points in families]
                     for c in classes])


def solve_rule(generators: list[tuple[float, ...]], fixed_radii: dict[int, float], guess_radii: dict[int, float],
               guess_weights: list[float], max_degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Radii and weights (one each per family) that make every even moment up to max_degree exact.

    ``fixed_radii`` holds the radii the construction fixes, ``guess_radii`` starting values of the
    others (family index -> radius). The centre takes the weight left over.
    """
    families = [family(g) for g in generators]
    n = len(generators[0])
    classes = even_moment_classes(max_degree, n)
    sums = _moment_sums(families, classes)
    degree = np.array([2 * sum(c) for c in classes])[:, None]
    target = np.array([gaussian_even_moment(c) for c in classes])
    free = sorted(guess_radii)

    def radii_of(x: np.ndarray) -> np.ndarray:
        radii = np.empty(len(families))
        for index, value in fixed_radii.items():
            radii[index] = value
        radii[free] = x[: len(free)]
        return radii

    def residual(x: np.ndarray) -> np.ndarray:
        # sum over families of w_f r_f^degree (sum of the monomial over the family) = E[monomial]
        return np.sum(sums * x[len(free):] * radii_of(x) ** degree, axis=1) - target

    x0 = np.concatenate(([guess_radii[i] for i in free], guess_weights))
    if len(x0) != len(classes):
        raise ValueError(f"{len(x0)} unknowns for {len(classes)} moment equations")
    solution = optimize.root(residual, x0, method="hybr", options={"xtol": 1e-15}).x
    if np.max(np.abs(residual(solution))) > 1e-12:
        raise RuntimeError("the CUT moment equations were not solved from the starting guess")
    radii, weights = radii_of(solution), solution[len(free):]
    points = np.vstack([np.zeros((1, n))] + [r * f for r, f in zip(radii, families)])
    all_weights = np.concatenate([[1.0 - sum(w * len(f) for w, f in zip(weights, families))]]
                                 + [np.full(len(f), w) for w, f in zip(weights, families)])
    if np.any(all_weights < 0):
        raise RuntimeError("the solved CUT rule has a negative weight")
    return points, all_weights


@functools.cache
def _cut6() -> tuple[np.ndarray, np.ndarray]:
    generators = [(1, 0, 0, 0, 0), (1, 1, 1, 1, 1), (1, 1, 0, 0, 0)]
    return solve_rule(generators, {}, {0: 2.0, 1: 1.0, 2: 3.0}, [0.03, 0.01, 0.001], max_degree=6)


@functools.cache
def _cut8() -> tuple[np.ndarray, np.ndarray]:
    h = CUT8_MULTISECTOR_H
    generators = [(1, 0, 0, 0, 0), (1, 1, 1, 1, 1), (1, 1, 1, 1, 1), (1, 1, 0, 0, 0), (1, 1, 1, 0, 0), (h, 1, 1, 1, 1)]
    return solve_rule(generators, {4: CUT8_SUBSPACE_RADIUS}, {0: 2.3, 1: 0.84, 2: 1.4, 3: 1.8, 5: 1.1},
                      [0.01, 0.015, 0.001, 0.005, 0.0006, 0.0001], max_degree=8)


def cut6_points() -> tuple[np.ndarray, np.ndarray]:
    """CUT6 for n = 5: standard-normal points Z (83, 5) and weights w (83,), exact to degree 7."""
    Z, w = _cut6()
    return Z.copy(), w.copy()


def cut8_points() -> tuple[np.ndarray, np.ndarray]:
    """CUT8 for n = 5: standard-normal points Z (355, 5) and weights w (355,), exact to degree 9."""
    Z, w = _cut8()
    return Z.copy(), w.copy()
