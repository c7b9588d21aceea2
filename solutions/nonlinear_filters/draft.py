# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3 (ipykernel)
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Lab nonlinear-filters: sigma points, the conjugate unscented transform and the particle filter on a turning aircraft
#
# A radar at the origin measures the range and bearing of an aircraft every 5 seconds. The aircraft flies
# straight, turns left at 1 deg/s, flies straight, turns right sharply at 3 deg/s, and flies straight again.
# You will track it with seven filters and find that their errors differ by orders of magnitude, <!-- claim: nonlinear-filters/orders-of-magnitude -->
# for a reason you can read off a table of moments.
#
# The idea of the lab: a Gaussian filter (EKF, CKF, UKF, CUT) is a **rule for computing expectations**
# $E[g(x)]$, $x \sim N(m, P)$. A sigma-point filter replaces the integral by a weighted sum over a few points.
# How many moments of the Gaussian those points get right decides how well it copes with the model's very
# uncertain turn rate. The particle filter uses thousands of random points instead.
#
# **What you will do**
# 1. Derive the Kalman update as the minimum-variance linear estimator (its derivation by Bayes' rule is worked).
# 2. Build three point sets (cubature, unscented, CUT4) and measure how many moments each gets right.
# 3. Write one filter for every point set, an EKF update and a bootstrap particle filter step.
# 4. Compare all seven filters on the aircraft: a few runs live, and 400 runs computed for you.
#
# **What is graded, and about how long each part takes**
#
# | part | what you write | points | about |
# |---|---|---|---|
# | 1. The Kalman update, twice | derivation 2 (derivation 1 is worked) | 3 | 35 min |
# | 2, 3. Point sets and their moments | `cubature_points`, `unscented_points`, `cut4_points`, `moment_error`, Question 1 | 8 | 50 min |
# | 5–7. The filters | `sigma_point_predict`, `sigma_point_update`, `ekf_update`, `bootstrap_pf_step` | 10 | 1 h 10 min |
# | 8. Seven filters on the turning aircraft | Question 2 (three parts, a point each) | 3 | 45 min |
# | **all** | 8 functions, 3 written answers | **24** | **about 3 h 20 min** |
#
# Section 4 (the aircraft and the radar) has nothing to write: read it before section 5. Section 9,
# "Going further", is optional and not graded.
#
# **How this notebook works.** Each blank is one function in a cell that says `YOUR CODE HERE`. The read-only
# cell below it runs *visible checks* whose messages say what to fix. In grading, *hidden tests* compare your
# function with a reference on random inputs of several sizes, each blank on its own. Return new arrays and
# leave the ones you are given as they are; draw random numbers only from the `rng` you are given.
# Derivation 2 and the two questions are marked by hand; the code blanks by the hidden tests. The grey cells are
# locked: grading puts back their originals. Before you submit, press **Validate**: it lists each blank that is
# not written yet or fails its visible checks.
#
# *Credit.* This lab follows P. Singla's lecture "Applications to estimation & filtering" (P. Singla and
# M. Majji, AFRL workshop "New Advances in Uncertainty Analysis & Estimation", 2017). The conjugate unscented
# transform is by N. Adurthi, P. Singla and T. Singh (ACC 2012; J. Dyn. Sys. Meas. Control 2018), the cubature
# rule by I. Arasaratnam and S. Haykin (IEEE TAC 2009). The air-traffic set-up follows the authors' MATLAB code
# (github.com/nadurthi/air_traffic; CUT6 and CUT8 from github.com/nadurthi/CUTpoints). We take the 5000
# particles of the lecture's table and average over 400 runs. That code leaves its EKF switched off, so our EKF
# row has no published counterpart: expect it to diverge. <!-- claim: nonlinear-filters/ekf-loses-most -->
# The text and code here are our own, and so are any errors. Where the lecture has a slip, we say so in a quoted
# correction.

# %% nbgrader={"grade": false, "grade_id": "setup", "locked": true, "schema_version": 3, "solution": false, "task": false}
# Set-up: run this cell first.
# %xmode Minimal
# %matplotlib inline
import itertools

import numpy as np
import scipy.special
import matplotlib.pyplot as plt

from course import air_traffic, cut
from course.air_traffic import symmetric_sqrt, systematic_resample, wrap_angle
from course.checks import check_array, check_close, check_pair, check_symmetric, check_true, passed, require, validate


# %% [markdown]
# ## 1. The Kalman update, twice
#
# For a linear model $x_{k+1} = F x_k + v_k$, $y_{k+1} = H x_{k+1} + \omega_{k+1}$ with Gaussian noises
# $v_k \sim N(0, Q)$, $\omega_{k+1} \sim N(0, R)$, the prior $p(x_{k+1} \mid Y_k) = N(\hat x^-, P^-)$ stays
# Gaussian, with $\hat x^- = F \hat x_{k|k}$ and $P^- = F P_{k|k} F^T + Q$. The lecture then reaches the same
# measurement update by two routes.
#
# **Derivation 1 (Bayes' rule; worked for you, not graded).** The posterior
# $p(x \mid Y_{k+1}) \propto N(y; Hx, R)\, N(x; \hat x^-, P^-)$ is Gaussian with mean
# $\hat x^+ = \hat x^- + K(y - H\hat x^-)$ and covariance $P^+ = P^- - K H P^-$, where
# $K = P^- H^T (H P^- H^T + R)^{-1}$. Up to terms without $x$, minus twice the log of the product is
# $(y - Hx)^T R^{-1} (y - Hx) + (x - \hat x^-)^T (P^-)^{-1} (x - \hat x^-) = x^T A x - 2 b^T x + \text{const}$ with
# $A = (P^-)^{-1} + H^T R^{-1} H$ and $b = H^T R^{-1} y + (P^-)^{-1} \hat x^-$. Completing the square,
# $x^T A x - 2b^T x = (x - A^{-1}b)^T A (x - A^{-1} b) - b^T A^{-1} b$, so the posterior is Gaussian with
# covariance $A^{-1}$ and mean $A^{-1} b$. The matrix inversion lemma gives
# $A^{-1} = P^- - P^- H^T (H P^- H^T + R)^{-1} H P^- = P^- - K H P^-$. Then
# $A^{-1} b = (P^- - K H P^-)(H^T R^{-1} y + (P^-)^{-1}\hat x^-) = \hat x^- - K H \hat x^- + (P^- H^T - K H P^- H^T) R^{-1} y$,
# and $P^- H^T - K H P^- H^T = K (H P^- H^T + R) - K H P^- H^T = K R$, so the last term is $K y$:
# $\hat x^+ = \hat x^- + K (y - H \hat x^-)$.
# (Section 9 lists two slips of the lecture's version of this derivation.)

# %% [markdown]
# **Derivation 2 (minimum variance).** Now assume nothing about Gaussians. Look for an estimate of the form
# $\hat x^+ = \hat x^- + K(y - \hat y)$, with $\hat y = E[y]$, that minimises
# $\mathrm{tr}\, E[(x - \hat x^+)(x - \hat x^+)^T]$. With $P^- = E[(x - \hat x^-)(x - \hat x^-)^T]$, show that the
# best gain is $K = P_{xy} P_{yy}^{-1}$, where
# $P_{xy} = E[(x - \hat x^-)(y - \hat y)^T]$ and $P_{yy} = E[(y - \hat y)(y - \hat y)^T]$, that the posterior
# covariance is then $P^- - K P_{yy} K^T$, and that for the linear model above this is the Kalman filter
# ($P_{yy} = H P^- H^T + R$, $P_{xy} = P^- H^T$). This route is what every sigma-point filter below uses: it only
# needs the expectations $\hat y$, $P_{yy}$ and $P_{xy}$, whatever the model.

# %% [markdown] nbgrader={"grade": true, "grade_id": "derivation_min_variance", "locked": false, "points": 3, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** With $e = x - \hat x^-$ and $\nu = y - \hat y$, the error is $e - K\nu$ and
# $J(K) = \mathrm{tr}\,E[(e - K\nu)(e - K\nu)^T] = \mathrm{tr}(P^- - K P_{xy}^T - P_{xy} K^T + K P_{yy} K^T)$.
# Its derivative with respect to $K$ is $-2 P_{xy} + 2 K P_{yy}$ (using $\partial\,\mathrm{tr}(K B)/\partial K = B^T$
# and $\partial\,\mathrm{tr}(K C K^T)/\partial K = 2 K C$ for symmetric $C$). Setting it to zero gives
# $K = P_{xy} P_{yy}^{-1}$; $J$ is convex because $P_{yy}$ is positive definite, so this is the minimum. Substituting,
# $P^+ = P^- - K P_{xy}^T - P_{xy} K^T + K P_{yy} K^T = P^- - K P_{yy} K^T$ (since $P_{xy} = K P_{yy}$). For the
# linear model, $\nu = H e + \omega$ with $\omega$ independent of $e$, so $P_{yy} = H P^- H^T + R$ and
# $P_{xy} = E[e (He + \omega)^T] = P^- H^T$: the Kalman gain, and $K P_{yy} K^T = K H P^-$.
#
# **Rubric (3 points).** 1 point: expanding the trace of the error covariance in $K$. 1 point: the stationarity
# condition and $K = P_{xy} P_{yy}^{-1}$. 1 point: $P^+ = P^- - K P_{yy} K^T$ and the linear case's $P_{yy}$ and $P_{xy}$.
# ### END SOLUTION

# %% [markdown]
# ## 2. Point sets: rules for Gaussian expectations
#
# For $x \sim N(m, P)$ write $x = m + S z$ with $z \sim N(0, I)$ and $S$ the **symmetric** square root of $P$
# ($S = S^T$, $S S = P$). A *point set* is standard-normal points $z_i$ (the rows of `Z`, shape `(N, n)`) with
# weights $w_i$ (summing to 1) such that $E[g(z)] \approx \sum_i w_i\, g(z_i)$. A rule is *exact to degree d* when
# this holds for every polynomial of degree at most $d$.
#
# **Cubature (CKF).** The third-degree spherical-radial rule of Arasaratnam and Haykin: the $2n$ points
# $z = \pm\sqrt{n}\, e_i$ on the principal axes, each with weight $1/(2n)$.

# %% nbgrader={"grade": false, "grade_id": "cubature_points", "locked": false, "schema_version": 3, "solution": true, "task": false}
def cubature_points(n):
    """The third-degree spherical-radial rule: Z (2n, n), w (2n,)."""
    ### BEGIN SOLUTION
    # z = +-sqrt(n) e_i, each with weight 1/(2n)
    Z = np.sqrt(n) * np.vstack((np.eye(n), -np.eye(n)))
    w = np.full(2 * n, 1.0 / (2 * n))
    return Z, w
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_cubature_points", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(cubature_points)
# Visible checks. For n = 2 the rule is the four points (+-sqrt 2, 0), (0, +-sqrt 2), each with weight 1/4.
Z, w = check_pair(cubature_points(2), "cubature_points(2)", "Z", "w")
Z = check_array(Z, "Z for n = 2", (4, 2), "One row per point (2n of them), one column per state.")
w = check_array(w, "w for n = 2", (4,))
check_close(w.sum(), 1.0, "the sum of the weights", "The weights of a rule for a probability sum to 1.")
check_close(np.sort(np.abs(Z).max(axis=1)), np.full(4, np.sqrt(2)), "the distance of each point from the origin",
            "The points are +-sqrt(n) e_i: a distance of sqrt(2) for n = 2.")
check_close(w @ Z, [0.0, 0.0], "the rule's mean, sum_i w_i z_i", "Use both +e_i and -e_i.")
check_close(Z.T @ (w[:, None] * Z), np.eye(2), "the rule's covariance, sum_i w_i z_i z_i^T",
            "A rule for N(0, I) must give covariance I.")
passed("cubature_points")

# %% nbgrader={"grade": true, "grade_id": "test_cubature_points", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of cubature_points (1 point): n = 1 to 6, compared with the reference as sets of points.
# Validate (and this cell) first checks that cubature_points passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(cubature_points)
### BEGIN HIDDEN TESTS
from solutions.nonlinear_filters.hidden_tests import check_cubature_points
check_cubature_points(cubature_points)
### END HIDDEN TESTS

# %% [markdown]
# **Unscented (UKF).** Julier and Uhlmann's $2n + 1$ points: the centre $z_0 = 0$ with weight $\kappa/(n+\kappa)$,
# and $z = \pm\sqrt{n + \kappa}\, e_i$ with weight $1/(2(n + \kappa))$ each. The lecture's filter uses $\kappa = 1$.

# %% nbgrader={"grade": false, "grade_id": "unscented_points", "locked": false, "schema_version": 3, "solution": true, "task": false}
def unscented_points(n, kappa=1.0):
    """The unscented transform's 2n + 1 points: Z (2n + 1, n), w (2n + 1,)."""
    ### BEGIN SOLUTION
    # z_0 = 0 with weight kappa/(n + kappa); z = +-sqrt(n + kappa) e_i with weight 1/(2(n + kappa))
    scale = np.sqrt(n + kappa)
    Z = np.vstack((np.zeros((1, n)), scale * np.eye(n), -scale * np.eye(n)))
    w = np.concatenate(([kappa / (n + kappa)], np.full(2 * n, 0.5 / (n + kappa))))
    return Z, w
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_unscented_points", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(unscented_points)
# Visible checks. For n = 2, kappa = 1: the centre with weight 1/3 and four points at distance sqrt(3), weight 1/6.
Z, w = check_pair(unscented_points(2, 1.0), "unscented_points(2, 1.0)", "Z", "w")
Z = check_array(Z, "Z for n = 2", (5, 2), "2n + 1 points: the centre and two on each axis.")
w = check_array(w, "w for n = 2", (5,))
check_close(w.sum(), 1.0, "the sum of the weights",
            "The weights of a rule for a probability sum to 1: the centre's weight and the 2n equal weights of the "
            "other points together.")
centre = np.all(Z == 0, axis=1)
check_close(centre.sum(), 1, "the number of points at the centre", "One point is z_0 = 0.")
check_close(w[centre], [1 / 3], "the centre's weight for kappa = 1, n = 2", "It is kappa/(n + kappa).")
check_close(np.sort(np.abs(Z[~centre]).max(axis=1)), np.full(4, np.sqrt(3)), "the distance of the other points",
            "They are at +-sqrt(n + kappa) e_i.")
check_close(Z.T @ (w[:, None] * Z), np.eye(2), "the rule's covariance, sum_i w_i z_i z_i^T")
# For n = 1, kappa = 2: the centre with weight kappa/(n + kappa) = 2/3 and two points at +-sqrt(3), weight 1/6 each.
Z, w = check_pair(unscented_points(1, 2.0), "unscented_points(1, 2.0)", "Z", "w")
Z = check_array(Z, "Z for n = 1, kappa = 2", (3, 1), "2n + 1 points: the centre and one on each side.")
w = check_array(w, "w for n = 1, kappa = 2", (3,))
centre = Z[:, 0] == 0
check_close(centre.sum(), 1, "the number of points at the centre for n = 1, kappa = 2", "One point is z_0 = 0.")
check_close(w[centre], [2 / 3], "the centre's weight for kappa = 2, n = 1",
            "It is kappa/(n + kappa), which equals 1/(n + kappa) only for kappa = 1.")
check_close(np.sort(Z[~centre, 0]), [-np.sqrt(3), np.sqrt(3)], "the points off the centre for kappa = 2, n = 1",
            "They are at +-sqrt(n + kappa) e_i.")
check_close(w[~centre], [1 / 6, 1 / 6], "the weights of the points off the centre for kappa = 2, n = 1",
            "Each is 1/(2(n + kappa)).")
passed("unscented_points")

# %% nbgrader={"grade": true, "grade_id": "test_unscented_points", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of unscented_points (1 point): n = 1 to 6 with several kappa, and the default kappa.
# Validate (and this cell) first checks that unscented_points passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(unscented_points)
### BEGIN HIDDEN TESTS
from solutions.nonlinear_filters.hidden_tests import check_unscented_points
check_unscented_points(unscented_points)
### END HIDDEN TESTS

# %% [markdown]
# **The conjugate unscented transform, CUT4.** Adurthi, Singla and Singh add points on the *conjugate axes*,
# the $2^n$ diagonal directions $(\pm 1, \dots, \pm 1)$. CUT4 for $n \ge 3$ uses $2n + 2^n$ points: the principal
# axes $\pm r_1 e_i$, each with weight $w_1$, and the conjugate axes $r_2 (\pm 1, \dots, \pm 1)$, each with weight
# $w_2$. By symmetry every odd moment vanishes. Requiring the even moments up to degree 4 to be those of
# $N(0, I)$ gives, for coordinate 1 (and 2),
#
# $$E[z_1^2]:\ 2 w_1 r_1^2 + 2^n w_2 r_2^2 = 1, \qquad E[z_1^4]:\ 2 w_1 r_1^4 + 2^n w_2 r_2^4 = 3, \qquad
#   E[z_1^2 z_2^2]:\ 2^n w_2 r_2^4 = 1,$$
#
# and the weights sum to one, $2n w_1 + 2^n w_2 = 1$. Solve them (start from the last one): you should find
# $r_1^2 = (n+2)/2$, $r_2^2 = (n+2)/(n-2)$, $w_1 = 4/(n+2)^2$ and $w_2 = (n-2)^2 / (2^n (n+2)^2)$. Then write
# `cut4_points(n)`. (`itertools.product((1.0, -1.0), repeat=n)` lists the sign patterns.)

# %% nbgrader={"grade": false, "grade_id": "cut4_points", "locked": false, "schema_version": 3, "solution": true, "task": false}
def cut4_points(n):
    """The fourth-order conjugate unscented transform (n >= 3): Z (2n + 2^n, n), w (2n + 2^n,)."""
    ### BEGIN SOLUTION
    # principal axes +-r1 e_i with r1^2 = (n + 2)/2, weight w1 = 4/(n + 2)^2
    r1 = np.sqrt((n + 2) / 2)
    # conjugate axes r2 (+-1, ..., +-1) with r2^2 = (n + 2)/(n - 2), weight w2 = (n - 2)^2/(2^n (n + 2)^2)
    r2 = np.sqrt((n + 2) / (n - 2))
    signs = np.array(list(itertools.product((1.0, -1.0), repeat=n)))
    Z = np.vstack((r1 * np.eye(n), -r1 * np.eye(n), r2 * signs))
    w = np.concatenate((np.full(2 * n, 4 / (n + 2) ** 2), np.full(2**n, (n - 2) ** 2 / (2**n * (n + 2) ** 2))))
    return Z, w
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_cut4_points", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(cut4_points)
# Visible checks for n = 3: 6 axis points with weight 4/25 and 8 conjugate points with weight 1/200.
Z, w = check_pair(cut4_points(3), "cut4_points(3)", "Z", "w")
Z = check_array(Z, "Z for n = 3", (14, 3), "2n principal-axis points and 2^n conjugate-axis points.")
w = check_array(w, "w for n = 3", (14,))
check_close(w.sum(), 1.0, "the sum of the weights", "2n w1 + 2^n w2 = 1.")
check_close(np.sort(w), [1 / 200] * 8 + [4 / 25] * 6, "the weights for n = 3", "w1 = 4/(n+2)^2, w2 = (n-2)^2/(2^n (n+2)^2).")
check_close(w @ Z[:, 0] ** 4, 3.0, "the rule's E[z_1^4]", "Check the radii: r1^2 = (n+2)/2, r2^2 = (n+2)/(n-2).")
check_close(w @ (Z[:, 0] ** 2 * Z[:, 1] ** 2), 1.0, "the rule's E[z_1^2 z_2^2]",
            "Only the conjugate points contribute: 2^n w2 r2^4 = 1. Did you scale them by r2?")
passed("cut4_points")

# %% nbgrader={"grade": true, "grade_id": "test_cut4_points", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of cut4_points (2 points): n = 3 to 6, compared with the reference as sets of points.
# Validate (and this cell) first checks that cut4_points passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(cut4_points)
### BEGIN HIDDEN TESTS
from solutions.nonlinear_filters.hidden_tests import check_cut4_points
check_cut4_points(cut4_points)
### END HIDDEN TESTS

# %% [markdown]
# **CUT6 and CUT8** for the five states of the aircraft are given in `course.cut`: `cut.cut6_points()` (83 points)
# and `cut.cut8_points()` (355 points). They add more families of symmetric points (plane diagonals
# $(\pm1, \pm1, 0, 0, 0)$, three-dimensional diagonals, a second conjugate axis, and points like $(\pm3, \pm1, \dots, \pm1)$),
# and `course.cut` solves the moment equations up to degree 6 and 8 for their radii and weights, the same way you
# did for CUT4 but with a numerical solver. The solved rules agree with the authors' published radii and weights. <!-- claim: nonlinear-filters/cut-matches-published -->

# %% [markdown]
# ## 3. How many moments does a rule get right?
#
# Write `moment_error(Z, w, degree)`: the largest error, over all monomials $z^a = z_1^{a_1} \cdots z_n^{a_n}$ of
# exactly that degree ($a_1 + \dots + a_n = $ `degree` $\ge 1$), between the rule's moment $\sum_i w_i z_i^a$ and the
# standard normal's, $E[z^a] = \prod_k (a_k - 1)!!$ if every $a_k$ is even and $0$ otherwise (with $(-1)!! = 1$ and
# $(2h-1)!! = (2h)!/(2^h h!)$). Return a float. `itertools.combinations_with_replacement(range(n), degree)` lists
# every monomial of a degree once, as the coordinates it multiplies. Do not use
# `itertools.product(range(n), repeat=degree)`: it lists each monomial many times over (390,625 tuples for CUT8
# at degree 8 instead of 495), and the table below and the hidden tests then run out of time.

# %% nbgrader={"grade": false, "grade_id": "moment_error", "locked": false, "schema_version": 3, "solution": true, "task": false}
def moment_error(Z, w, degree):
    """The largest |sum_i w_i z_i^a - E[z^a]| over the monomials z^a of this degree (>= 1), z ~ N(0, I)."""
    ### BEGIN SOLUTION
    n = Z.shape[1]
    # each monomial of this degree as the coordinates it multiplies, i_1 <= i_2 <= ... <= i_degree
    index = np.array(list(itertools.combinations_with_replacement(range(n), degree)), dtype=int).reshape(-1, degree)
    # the rule's moments: sum_i w_i prod_j Z[i, index_j]
    rule = w @ np.prod(Z[:, index], axis=2)
    # the exponent a_k of each coordinate; E[z^a] = prod_k (a_k - 1)!!, zero if any a_k is odd
    powers = np.stack([np.sum(index == k, axis=1) for k in range(n)], axis=1)
    half = powers // 2
    # (2h - 1)!! = (2h)! / (2^h h!)
    double_factorial = scipy.special.factorial(2 * half) / (2.0**half * scipy.special.factorial(half))
    exact = np.prod(np.where(powers % 2 == 0, double_factorial, 0.0), axis=1)
    return float(np.max(np.abs(rule - exact)))
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_moment_error", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(moment_error)
# Visible checks. The two points +-1 with weights 1/2 (n = 1) get E[z^2] = 1 right, E[z^4] = 1 instead of 3.
Z1, w1 = np.array([[1.0], [-1.0]]), np.array([0.5, 0.5])
check_close(moment_error(Z1, w1, 2), 0.0, "moment_error of the points +-1 at degree 2")
check_close(moment_error(Z1, w1, 3), 0.0, "moment_error of the points +-1 at degree 3", "Odd moments of N(0, 1) are 0.")
check_close(moment_error(Z1, w1, 4), 2.0, "moment_error of the points +-1 at degree 4", "E[z^4] = 3!! = 3, the rule gives 1.")
# For two dimensions, the points (1, 1) and (-1, -1) with weights 1/2: E[z1 z2] is 1 instead of 0.
Z2, w2 = np.array([[1.0, 1.0], [-1.0, -1.0]]), np.array([0.5, 0.5])
check_close(moment_error(Z2, w2, 2), 1.0, "moment_error of (1, 1), (-1, -1) at degree 2",
            "The cross moment z1 z2 counts: its exact value is 0, the rule gives 1.")
check_close(moment_error(Z2, w2, 4), 2.0, "moment_error of (1, 1), (-1, -1) at degree 4",
            "E[z1^4] = 3 (rule 1), E[z1^2 z2^2] = 1 (rule 1), E[z1^3 z2] = 0 (rule 1).")
# Only the monomials of exactly this degree count: at degree 5 every moment of N(0, 1) is odd and zero, and so is the
# rule's, although the rule is wrong at degree 4.
check_close(moment_error(Z1, w1, 5), 0.0, "moment_error of the points +-1 at degree 5",
            "Take the largest error over the monomials of exactly this degree, not of this degree or less.")
# Unequal weights: the three points 0, +-sqrt(3) with weights 2/3, 1/6, 1/6 get E[z^2] = 1 and E[z^4] = 3 right, and
# E[z^6] = 2 * 27 / 6 = 9 instead of 5!! = 15.
Z3, w3 = np.array([[0.0], [np.sqrt(3)], [-np.sqrt(3)]]), np.array([2 / 3, 1 / 6, 1 / 6])
check_close(moment_error(Z3, w3, 2), 0.0, "moment_error of the points 0, +-sqrt(3) at degree 2",
            "Weight each point's monomial with its w_i: the rule's moment is sum_i w_i z_i^a.")
check_close(moment_error(Z3, w3, 6), 6.0, "moment_error of the points 0, +-sqrt(3) at degree 6", "E[z^6] = 5!! = 15.")
passed("moment_error")

# %% nbgrader={"grade": true, "grade_id": "test_moment_error", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of moment_error (2 points): random rules with n = 1 to 6 and degrees 1 to 8.
# Validate (and this cell) first checks that moment_error passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(moment_error)
### BEGIN HIDDEN TESTS
from solutions.nonlinear_filters.hidden_tests import check_moment_error
check_moment_error(moment_error)
### END HIDDEN TESTS

# %% [markdown]
# Here is the moment table of the five rules for the aircraft's five states: the largest moment error at each
# degree. A zero (to rounding, printed as `0`) means the rule is exact at that degree.

# %% nbgrader={"grade": false, "grade_id": "moment_table", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
require(cubature_points, unscented_points, cut4_points, moment_error)
rules = {"CKF": cubature_points(5), "UKF": unscented_points(5, 1.0), "CUT4": cut4_points(5),
         "CUT6": cut.cut6_points(), "CUT8": cut.cut8_points()}
degrees = range(1, 11)
print(f"{'rule':<6}{'points':>7}  " + "".join(f"{'d=' + str(d):>9}" for d in degrees) + "   exact to")
for name, (Z, w) in rules.items():
    errors = [moment_error(Z, w, d) for d in degrees]
    exact_to = next(d for d in degrees if errors[d - 1] > 1e-9) - 1
    print(f"{name:<6}{len(w):>7}  " + "".join(f"{(e if e > 1e-9 else 0):>9.3g}" for e in errors) + f"   {exact_to:>8}")

# %% [markdown]
# **Question 1.** Read the table. To which degree is each rule exact, and why are all the odd-degree errors zero?
# Which moments does the UKF get wrong first, and how does its error at degree 4 compare with the CKF's? (The
# table shows only the largest error at each degree: to name the moments, work out by hand what the CKF's and the
# UKF's points give for $E[z_1^4]$ and for $E[z_1^2 z_2^2]$.)

# %% [markdown] nbgrader={"grade": true, "grade_id": "moment_question", "locked": false, "points": 2, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** The CKF and the UKF are exact to degree 3, CUT4 to degree 5, CUT6 to 7 and CUT8 to 9. <!-- claim: nonlinear-filters/exactness-degrees -->
# The odd degrees vanish for every rule because each point set
# is symmetric under flipping the sign of any coordinate: with $z_i$, the rule also holds the point with one
# coordinate negated and the same weight, so the weighted sum of a monomial with an odd power cancels, as the
# Gaussian's odd moments do. So a rule that matches the even moments up to degree $2k$ is exact to degree
# $2k + 1$. At degree 4 the CKF and the UKF both miss $E[z_1^2 z_2^2] = 1$ (no point has two nonzero
# coordinates, so they give 0) and $E[z_1^4] = 3$ (the CKF gives $n = 5$, the UKF $n + \kappa = 6$), so their
# degree-4 errors are 2 and 3. <!-- claim: nonlinear-filters/degree-four-errors --> The conjugate axes are what
# fix the cross moments.
#
# **Rubric (2 points).** 1 point: the exactness degrees read from the table (3, 3, 5, 7, 9) and the symmetry
# argument for odd degrees. 1 point: the UKF and CKF first miss the degree-4 moments (naming the cross
# moment $E[z_1^2 z_2^2]$ and $E[z_1^4]$ is best; "the degree-4 moments" with the right reason also earns the
# point), with the errors 2 (CKF) and 3 (UKF) read from the table.
# ### END SOLUTION

# %% [markdown]
# ## 4. The aircraft and the radar
#
# The state is $x = [\xi, \eta, \dot\xi, \dot\eta, \Omega]$: position (m), velocity (m/s) and turn rate
# (rad/s). Between radar returns, $T = 5$ s apart, the aircraft follows the coordinated-turn model: the exact
# motion at constant speed and constant turn rate $\Omega$ (`air_traffic.ct_step`, which takes the limit
# $\Omega \to 0$ for straight flight). The process noise is
# $Q = L_1 \begin{bmatrix} T^3/3 & T^2/2 \\ T^2/2 & T \end{bmatrix}$ for each axis and $T L_2$ for $\Omega$,
# with $L_1 = 0.16$, $L_2 = 0.01$.
#
# Look at the last diagonal entry of $Q$ printed below: `Q[4, 4]` $= T L_2 = 0.05\ (\mathrm{rad/s})^2$, a turn-rate
# standard deviation of 0.22 rad/s (12.8°/s) added at every step, more than four times the sharpest true turn
# (3°/s). <!-- claim: nonlinear-filters/turn-noise-size -->
# The true flight has no random turn rate; this noise is the filters' cautious model, and it is what strains the
# Gaussian filters below.
#
# The radar at the origin measures the range $\sqrt{\xi^2 + \eta^2}$ and the bearing $\operatorname{atan2}(\eta, \xi)$,
# with $R = \mathrm{diag}((100\ \mathrm{m})^2, (1°)^2)$. A difference of bearings is wrapped to $(-\pi, \pi]$
# (`wrap_angle`).
#
# The true flight starts at (25 km, 10 km) heading west at 120 m/s: 125 s straight, 90 s turning left at 1°/s,
# 125 s straight, 30 s turning right at 3°/s, 125 s straight, sampled every 5 s (100 samples; the filters start
# at $t = 0$ and update on the 99 returns after it). In each Monte Carlo run every filter starts from the same
# mean, drawn from $N([25000, 10000, -120, 0, 10^{-6}], P_0)$ with $P_0 = \mathrm{diag}(1000^2, 1000^2, 100, 100, (1°)^2)$,
# and sees the same radar returns.

# %% nbgrader={"grade": false, "grade_id": "flight", "locked": true, "schema_version": 3, "solution": false, "task": false}
sc = air_traffic.scenario(5.0)
m0, y = air_traffic.simulate_runs(sc, 4, np.random.default_rng(2017))
print(f"{len(sc.times)} samples, t = {sc.times[0]:g} to {sc.times[-1]:g} s ({len(sc.times) - 1} radar updates after t = 0);"
      f" Q and R for T = {sc.T:g} s:")
print(np.round(sc.Q, 4), "\n", np.round(sc.R, 6))
fig = air_traffic.plot_flight(sc, y[0])
plt.show()


# %% [markdown]
# ## 5. One filter for every point set
#
# With the minimum-variance update of derivation 2, a Gaussian filter needs only expectations, and a point set
# computes them. With $x_i = m + S z_i$ ($S$ = `symmetric_sqrt(P)`):
#
# * **predict:** $m^- = \sum_i w_i f(x_i)$, $\ P^- = \sum_i w_i (f(x_i) - m^-)(f(x_i) - m^-)^T + Q$;
# * **update:** with $x_i = m^- + S^- z_i$, $\hat y = \sum_i w_i h(x_i)$,
#   $P_{yy} = \sum_i w_i (h(x_i) - \hat y)(h(x_i) - \hat y)^T + R$, $P_{xy} = \sum_i w_i (x_i - m^-)(h(x_i) - \hat y)^T$,
#   $K = P_{xy} P_{yy}^{-1}$, $m^+ = m^- + K(y - \hat y)$, $P^+ = P^- - K P_{yy} K^T$.
#
# `f` and `h` act on the last axis: `f(X)` maps all the points `X` (shape `(N, n)`) at once. Measurement components
# listed in `angles` are angles. Work with differences from the measurement, wrapped: $E_i = $ `wrap`$(h(x_i) - y)$
# in the angle components; then $\hat y = y + \sum_i w_i E_i$, the innovation is $y - \hat y = -\sum_i w_i E_i$, and
# $h(x_i) - \hat y = E_i - \sum_j w_j E_j$. Use `np.linalg.solve` for the gain, not an inverse, and return
# symmetric covariances. Your functions need to work for one run (`m` of shape `(n,)`); the model answers also
# accept a stack of runs (`m` of shape `(R, n)`), which the Monte Carlo uses, but you need not.

# %% nbgrader={"grade": false, "grade_id": "sigma_point_predict", "locked": false, "schema_version": 3, "solution": true, "task": false}
def sigma_point_predict(m, P, f, Z, w, Q):
    """Time step with the point set (Z, w): m (n,), P (n, n) -> m_{k+1|k} (n,), P_{k+1|k} (n, n)."""
    ### BEGIN SOLUTION
    # x_i = m + S z_i with S the symmetric square root of P
    X = m[..., None, :] + Z @ symmetric_sqrt(P)
    Y = f(X)
    # m_{k+1|k} = sum_i w_i f(x_i)
    m_new = w @ Y
    # P_{k+1|k} = sum_i w_i (f(x_i) - m)(f(x_i) - m)^T + Q
    D = Y - m_new[..., None, :]
    P_new = (w[:, None] * D).swapaxes(-1, -2) @ D + Q
    return m_new, 0.5 * (P_new + P_new.swapaxes(-1, -2))
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_sigma_point_predict", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(sigma_point_predict)
# Visible checks. A linear f(x) = A x gives the Kalman filter's A m and A P A^T + Q with any rule exact to degree 2.
A, Q = np.array([[1.0, 2.0], [0.0, 1.0]]), np.diag([0.5, 0.25])
m_check, P_check = np.array([1.0, -1.0]), np.array([[4.0, 1.0], [1.0, 2.0]])
Z, w = np.sqrt(2) * np.vstack((np.eye(2), -np.eye(2))), np.full(4, 0.25)
m_new, P_new = check_pair(sigma_point_predict(m_check, P_check, lambda X: X @ A.T, Z, w, Q), "sigma_point_predict", "m", "P")
check_close(check_array(m_new, "m", (2,), "Z and f(X) hold one point per row, w one weight per point: the mean is "
                        "sum_i w_i f(x_i), a sum over the rows."),
            A @ m_check, "the predicted mean for f(x) = A x", "It is sum_i w_i f(x_i).")
check_close(check_array(P_new, "P", (2, 2)), A @ P_check @ A.T + Q, "the predicted covariance for f(x) = A x",
            "sum_i w_i (f(x_i) - m)(f(x_i) - m)^T + Q, with x_i = m + S z_i and S = symmetric_sqrt(P).")
check_symmetric(P_new, "P")
# f(x) = x_1^2 with x_1 ~ N(1, 4): E[x_1^2] = 1 + 4 = 5. A rule exact to degree 2 gets the mean right.
m_sq, _ = sigma_point_predict(m_check, P_check, lambda X: X[..., :1] ** 2, Z, w, np.zeros((1, 1)))
check_close(m_sq, [5.0], "the predicted mean of x_1^2", "The mean is the weighted average of f over the points.")
# A non-diagonal P = [[5, 4], [4, 5]], whose symmetric square root is S = [[2, 1], [1, 2]], m = 0, and f(x) = x_1^4.
# The cubature points m + S z_i are +-sqrt(2) (2, 1) and +-sqrt(2) (1, 2), so the rule's mean of x_1^4 is
# (2 (2 sqrt 2)^4 + 2 (sqrt 2)^4) / 4 = (128 + 8) / 4 = 34. (A Cholesky factor of P gives an equally valid rule with
# other points, and 50.)
m_4, _ = sigma_point_predict(np.zeros(2), np.array([[5.0, 4.0], [4.0, 5.0]]), lambda X: X[..., :1] ** 4, Z, w,
                             np.zeros((1, 1)))
check_close(m_4, [34.0], "the predicted mean of x_1^4 with P = [[5, 4], [4, 5]]",
            "Place the points with S = symmetric_sqrt(P): x_i = m + S z_i. A Cholesky factor L (L L^T = P) gives "
            "another valid rule of the same degree, but other points and other numbers; this lab, like the authors' "
            "sqrtm, fixes the symmetric root so that answers can be compared.")
passed("sigma_point_predict")

# %% nbgrader={"grade": true, "grade_id": "test_sigma_point_predict", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of sigma_point_predict (2 points): n = 1 to 6, four point sets, random nonlinear f.
# Validate (and this cell) first checks that sigma_point_predict passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(sigma_point_predict)
### BEGIN HIDDEN TESTS
from solutions.nonlinear_filters.hidden_tests import check_sigma_point_predict
check_sigma_point_predict(sigma_point_predict)
### END HIDDEN TESTS

# %% nbgrader={"grade": false, "grade_id": "sigma_point_update", "locked": false, "schema_version": 3, "solution": true, "task": false}
def sigma_point_update(m, P, y, h, R, Z, w, angles=()):
    """Measurement update with the point set (Z, w): m (n,), P (n, n), y (p,) -> m, P after y.

    The components of y listed in angles are angles: their differences are wrapped to (-pi, pi].
    """
    ### BEGIN SOLUTION
    DX = Z @ symmetric_sqrt(P)
    # each point's predicted measurement, as a difference from y (angles wrapped)
    E = h(m[..., None, :] + DX) - y[..., None, :]
    E[..., list(angles)] = wrap_angle(E[..., list(angles)])
    # y_hat = y + sum_i w_i (h(x_i) - y), so the innovation y - y_hat is -sum_i w_i E_i
    e_bar = w @ E
    DY = E - e_bar[..., None, :]
    # P_yy = sum_i w_i (h_i - y_hat)(h_i - y_hat)^T + R,  P_xy = sum_i w_i (x_i - m)(h_i - y_hat)^T
    P_yy = (w[:, None] * DY).swapaxes(-1, -2) @ DY + R
    P_xy = (w[:, None] * DX).swapaxes(-1, -2) @ DY
    # K = P_xy P_yy^-1, from the symmetric P_yy: K^T = P_yy^-1 P_xy^T
    K = np.linalg.solve(P_yy, P_xy.swapaxes(-1, -2)).swapaxes(-1, -2)
    # m_{k+1|k+1} = m + K (y - y_hat),  P_{k+1|k+1} = P - K P_yy K^T
    m_new = m - (K @ e_bar[..., None])[..., 0]
    P_new = P - K @ P_yy @ K.swapaxes(-1, -2)
    return m_new, 0.5 * (P_new + P_new.swapaxes(-1, -2))
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_sigma_point_update", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(sigma_point_update)
# Visible checks. Observing x_1 directly (h(x) = x_1, R = 4) from m = 0, P = diag(4, 9): K = (1/2, 0),
# so y = 2 moves the mean to (1, 0) and halves the variance of x_1.
Z, w = np.sqrt(2) * np.vstack((np.eye(2), -np.eye(2))), np.full(4, 0.25)
m_new, P_new = check_pair(sigma_point_update(np.zeros(2), np.diag([4.0, 9.0]), np.array([2.0]), lambda X: X[..., :1],
                                             np.array([[4.0]]), Z, w), "sigma_point_update", "m", "P")
m_new = check_array(m_new, "m", (2,), "Here n = 2 states and p = 1 measurement: P_yy is p x p, P_xy is n x p, and "
                    "K = P_xy P_yy^-1 is n x p. Check your transposes.")
# the covariance first: a P_yy without R, or with differences from y instead of y_hat, gives a wrong gain K, and
# then a wrong mean as well; with the covariance right, a wrong mean points at the innovation
check_close(check_array(P_new, "P", (2, 2)), np.diag([2.0, 9.0]), "the updated covariance for h(x) = x_1",
            "P - K P_yy K^T with P_yy = sum_i w_i (h(x_i) - y_hat)(h(x_i) - y_hat)^T + R. Did you add R to P_yy, "
            "and take the differences from y_hat (not from y)?")
check_close(m_new, [1.0, 0.0], "the updated mean for h(x) = x_1",
            "m + K (y - y_hat) with K = P_xy P_yy^-1. Check the sign of the innovation.")
# A nonlinear h(x) = x_1^3 with the non-diagonal P = [[5, 4], [4, 5]] (symmetric square root [[2, 1], [1, 2]]), m = 0,
# R = 40, y = 30. The cubature points are +-sqrt(2) (2, 1), +-sqrt(2) (1, 2), with h = +-16 sqrt 2, +-2 sqrt 2:
# y_hat = 0, P_yy = (2 * 512 + 2 * 8) / 4 + 40 = 300, P_xy = (34, 20), so m+ = (34, 20) / 300 * 30 = (3.4, 2.0).
m_new, _ = sigma_point_update(np.zeros(2), np.array([[5.0, 4.0], [4.0, 5.0]]), np.array([30.0]),
                              lambda X: X[..., :1] ** 3, np.array([[40.0]]), Z, w)
check_close(m_new, [3.4, 2.0], "the updated mean for h(x) = x_1^3 with P = [[5, 4], [4, 5]]",
            "Place the points with S = symmetric_sqrt(P): x_i = m + S z_i. A Cholesky factor L (L L^T = P) gives "
            "another valid rule of the same degree, but other points and other numbers; this lab, like the authors' "
            "sqrtm, fixes the symmetric root so that answers can be compared.")
# A bearing across the cut. The target is due west, 1 m north of the xi axis: its points' bearings are near +-pi,
# and the measurement is -pi + 0.01. Turned by 180 degrees, this is a target due east, 1 m south, measured at
# 0.01, where nothing needs wrapping. The two corrections must be each other's negatives, and with a bearing
# noise of 0.01 rad (10 m at 1 km) on a prior of 10 m, the update should halve the cross-range variance.
h_bearing = lambda X: np.arctan2(X[..., 1:2], X[..., 0:1])
m_west, P_west = sigma_point_update(np.array([-1000.0, 1.0]), np.diag([100.0, 100.0]), np.array([-np.pi + 0.01]),
                                    h_bearing, np.array([[1e-4]]), Z, w, (0,))
m_east, _ = sigma_point_update(np.array([1000.0, -1.0]), np.diag([100.0, 100.0]), np.array([0.01]), h_bearing,
                               np.array([[1e-4]]), Z, w, (0,))
wrap_hint = "Wrap the bearing differences E_i to (-pi, pi] with wrap_angle for the components listed in angles."
check_close(m_west - [-1000.0, 1.0], -(m_east - [1000.0, -1.0]),
            "the correction for a target due west (bearing -pi + 0.01), against minus the one due east (0.01)",
            wrap_hint, rtol=1e-6, atol=1e-6)
check_close(P_west[1, 1], 50.0, "the cross-range variance after a bearing near +-pi", wrap_hint, rtol=1e-3)
passed("sigma_point_update")

# %% nbgrader={"grade": true, "grade_id": "test_sigma_point_update", "locked": true, "points": 3, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of sigma_point_update (3 points): n = 1 to 6, p = 1 to 3, four point sets, random nonlinear h,
# and a radar-like h with bearings across +-pi.
# Validate (and this cell) first checks that sigma_point_update passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(sigma_point_update)
### BEGIN HIDDEN TESTS
from solutions.nonlinear_filters.hidden_tests import check_sigma_point_update
check_sigma_point_update(sigma_point_update)
### END HIDDEN TESTS

# %% [markdown]
# ## 6. The extended Kalman filter's update
#
# The EKF computes the same expectations by linearising: $\hat y = h(m)$, $H = \partial h/\partial x$ at $m$ (the
# given `air_traffic.radar_h_jacobian` for the radar), $S = H P H^T + R$, $K = P H^T S^{-1}$,
# $m^+ = m + K(y - h(m))$ (angle components of the innovation wrapped), and the covariance in Joseph form,
# $P^+ = (I - KH) P (I - KH)^T + K R K^T$. Its time step (`air_traffic.ekf_predict`, with the Jacobian of the
# coordinated-turn model) is given. Here `h(m)` takes one state `(n,)` and returns `(p,)`; `H_jacobian(m)` returns `(p, n)`.

# %% nbgrader={"grade": false, "grade_id": "ekf_update", "locked": false, "schema_version": 3, "solution": true, "task": false}
def ekf_update(m, P, y, h, H_jacobian, R, angles=()):
    """The EKF measurement update: m (n,), P (n, n), y (p,) -> m, P after y."""
    ### BEGIN SOLUTION
    # innovation y - h(m), angles wrapped
    e = y - h(m)
    e[..., list(angles)] = wrap_angle(e[..., list(angles)])
    H = H_jacobian(m)
    # S = H P H^T + R,  K = P H^T S^-1, so K^T = S^-1 H P
    S = H @ P @ H.swapaxes(-1, -2) + R
    K = np.linalg.solve(S, H @ P).swapaxes(-1, -2)
    m_new = m + (K @ e[..., None])[..., 0]
    # Joseph form: P = (I - K H) P (I - K H)^T + K R K^T
    A = np.eye(m.shape[-1]) - K @ H
    P_new = A @ P @ A.swapaxes(-1, -2) + K @ R @ K.swapaxes(-1, -2)
    return m_new, 0.5 * (P_new + P_new.swapaxes(-1, -2))
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_ekf_update", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(ekf_update)
# Visible checks: the same linear case as above (h(x) = x_1, so H = [1, 0]).
m_new, P_new = check_pair(ekf_update(np.zeros(2), np.diag([4.0, 9.0]), np.array([2.0]), lambda x: x[..., :1],
                                     lambda x: np.array([[1.0, 0.0]]), np.array([[4.0]])), "ekf_update", "m", "P")
check_close(check_array(m_new, "m", (2,), "Here n = 2 states and p = 1 measurement: H is p x n, S = H P H^T + R "
                        "is p x p and K = P H^T S^-1 is n x p. Check your transposes."),
            [1.0, 0.0], "the EKF's updated mean for h(x) = x_1",
            "The gain halves the distance to y = 2 in x_1 here, as P_11 = R = 4: did you add R to S = H P H^T + R?")
check_close(check_array(P_new, "P", (2, 2)), np.diag([2.0, 9.0]), "the EKF's updated covariance",
            "Joseph form: (I - K H) P (I - K H)^T + K R K^T.")
check_symmetric(P_new, "P")
# The radar, target due west just below the xi axis, bearing measured just above: the innovation is 0.01 rad.
m_west = np.array([-1000.0, -1.0, 0.0, 0.0, 0.0])
m_new, _ = ekf_update(m_west, np.diag([100.0, 100.0, 1.0, 1.0, 1e-4]), np.array([1000.0, np.pi - 0.009]),
                      air_traffic.radar, air_traffic.radar_h_jacobian, air_traffic.R_RADAR, (1,))
check_true(np.abs(m_new - m_west).max() < 30,
           "the correction for a bearing near +-pi moves the target by more than 30 m, where an innovation of 0.01 rad "
           "at 1 km should move it by a few metres",
           "Wrap the bearing innovation to (-pi, pi] with wrap_angle for the components listed in angles.")
# The angle elsewhere. A target at m = (xi, eta) = (-1000, 0), due west (bearing pi), P = 100 I (10 m), bearing noise
# 0.01 rad (10 m at 1 km). Measured at -pi + 0.01, the bearing innovation wraps to 0.01 rad, and the update takes half
# of it: 0.005 rad at 1000 m, 5 m south, so m = (-1000, -5). First the bearing alone (p = 1, angles=(0,)):
angle_hint = ("Wrap exactly the innovation components whose indices are listed in angles, wherever they are, and no "
              "other (a range difference of 10 m is not an angle).")
h_b = lambda x: np.arctan2(x[..., 1:2], x[..., 0:1])
H_b = lambda x: np.array([[-x[1], x[0]]]) / (x[0] ** 2 + x[1] ** 2)
m_new, _ = ekf_update(np.array([-1000.0, 0.0]), 100.0 * np.eye(2), np.array([-np.pi + 0.01]), h_b, H_b,
                      np.array([[1e-4]]), (0,))
check_close(m_new, [-1000.0, -5.0], "the updated mean for a bearing alone across +-pi (p = 1, angles=(0,))", angle_hint,
            rtol=0, atol=1e-3)
# Then the bearing first and the range second (p = 2, angles=(0,)), the range measured 10 m longer than predicted, with
# a range noise of 10 m: the update takes half of each, so m = (-1005, -5). A range innovation is not an angle.
h_br = lambda x: np.array([np.arctan2(x[1], x[0]), np.hypot(x[0], x[1])])
H_br = lambda x: np.array([[-x[1], x[0]] / (x[0] ** 2 + x[1] ** 2), [x[0], x[1]] / np.hypot(x[0], x[1])])
m_new, _ = ekf_update(np.array([-1000.0, 0.0]), 100.0 * np.eye(2), np.array([-np.pi + 0.01, 1010.0]), h_br, H_br,
                      np.diag([1e-4, 100.0]), (0,))
check_close(m_new, [-1005.0, -5.0], "the updated mean for (bearing, range) with angles=(0,), the bearing across +-pi",
            angle_hint, rtol=0, atol=1e-3)
passed("ekf_update")

# %% nbgrader={"grade": true, "grade_id": "test_ekf_update", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of ekf_update (2 points): n = 1 to 6, p = 1 to 3, random nonlinear h, and bearings across +-pi
# at any place in the measurement (angles).
# Validate (and this cell) first checks that ekf_update passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(ekf_update)
### BEGIN HIDDEN TESTS
from solutions.nonlinear_filters.hidden_tests import check_ekf_update
check_ekf_update(ekf_update)
### END HIDDEN TESTS

# %% [markdown]
# ## 7. The bootstrap particle filter
#
# The particle filter carries $N$ samples $x^i$ with normalised weights $w^i$, kept as logarithms (`logw`), so that
# tiny likelihoods do not underflow. One step, vectorised over the particles (`X` has shape `(N, n)`):
#
# 1. propagate each particle through the model and add its own process noise: $x^i \leftarrow f(x^i) + v^i$,
#    $v^i \sim N(0, Q)$ (draw standard normals with `rng` and multiply by $L^T$, where $Q = L L^T$ is the Cholesky factor);
# 2. reweight: $\log w^i \leftarrow \log w^i - \frac12 e_i^T R^{-1} e_i$ with $e_i = y - h(x^i)$, angles wrapped;
# 3. normalise: subtract $\log \sum_j w^j$ (`scipy.special.logsumexp`);
# 4. if the effective sample size $1 / \sum_i (w^i)^2$ is below `ess_fraction` $\cdot N$, resample: take the parents
#    `systematic_resample(weights, rng)` (given; it needs normalised weights) and reset every log-weight to $-\log N$.
#
# Return the new `(X, logw)`.

# %% nbgrader={"grade": false, "grade_id": "bootstrap_pf_step", "locked": false, "schema_version": 3, "solution": true, "task": false}
def bootstrap_pf_step(X, logw, y, rng, f, h, Q, R, angles=(), ess_fraction=0.7):
    """One bootstrap PF step: particles X (N, n), normalised log-weights logw (N,), measurement y (p,)."""
    ### BEGIN SOLUTION
    N = X.shape[-2]
    # x_k^i = f(x_{k-1}^i) + v^i,  v^i ~ N(0, Q)
    X = f(X) + rng.standard_normal(X.shape) @ np.linalg.cholesky(Q).T
    # log p(y | x^i) = -1/2 e^T R^-1 e + const, e = y - h(x^i) with angles wrapped
    E = y[..., None, :] - h(X)
    E[..., list(angles)] = wrap_angle(E[..., list(angles)])
    # e^T R^-1 e = |L^-1 e|^2 with R = L L^T
    whiten = np.linalg.solve(np.linalg.cholesky(R), np.eye(R.shape[0]))
    logw = logw - 0.5 * np.sum((E @ whiten.T) ** 2, axis=-1)
    # normalise: log w^i - log sum_j w^j
    logw = logw - scipy.special.logsumexp(logw, axis=-1, keepdims=True)
    # effective sample size 1 / sum_i (w^i)^2, one per run
    ess = 1.0 / np.sum(np.exp(2.0 * logw), axis=-1)
    resample = ess < ess_fraction * N
    parents = systematic_resample(np.exp(logw), rng)
    X = np.where(resample[..., None, None], np.take_along_axis(X, parents[..., None], axis=-2), X)
    logw = np.where(resample[..., None], -np.log(N), logw)
    return X, logw
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_bootstrap_pf_step", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(bootstrap_pf_step)
# Visible checks on a scalar random walk observed directly, 2000 particles.
rng_check = np.random.default_rng(0)
X_check = rng_check.standard_normal((2000, 1))
logw_check = np.full(2000, -np.log(2000))
identity = lambda X: X
tiny_Q, R_check = np.array([[1e-20]]), np.array([[1.0]])
# (a) No resampling (ess_fraction = 0) and a negligible Q: the particles stay where they are and the weights
# become the normalised likelihood exp(-(y - x)^2 / 2).
X_new, logw_new = check_pair(bootstrap_pf_step(X_check, logw_check, np.array([0.5]), rng_check, identity, identity,
                                               tiny_Q, R_check, (), 0.0), "bootstrap_pf_step", "X", "logw")
check_close(check_array(X_new, "X", (2000, 1)), X_check, "the particles with Q ~ 0 and no resampling",
            "Propagate with f and add noise with covariance Q; resample only when the ESS is below ess_fraction * N.",
            atol=1e-6)
expected = -0.5 * (0.5 - X_check[:, 0]) ** 2
check_close(check_array(logw_new, "logw", (2000,)), expected - scipy.special.logsumexp(expected),
            "the log-weights after one measurement", "Add the log-likelihood, then normalise with logsumexp.")
# (b) A sharp measurement far in the tail: the ESS collapses, so the step resamples and resets the weights.
X_new, logw_new = bootstrap_pf_step(X_check, logw_check, np.array([2.5]), rng_check, identity, identity, tiny_Q,
                                    np.array([[0.01]]), (), 0.7)
check_close(logw_new, np.full(2000, -np.log(2000)), "the log-weights after resampling", "After resampling every log-weight is -log(N). If your step did not resample here, check the likelihood: it needs R^-1 (with R itself the weights stay too flat to fall below the threshold).")
check_close(np.mean(X_new), 2.5, "the mean of the resampled particles, near the measurement 2.5",
            "Resample with systematic_resample(np.exp(logw), rng) and index the particles with the parents.",
            rtol=0, atol=0.5)
# (c) A bearing across the cut: two particles at +3 rad and -3 rad, the bearing measured at pi. Both are pi - 3 = 0.14 rad
# from it once the residuals are wrapped, so they keep equal weights, log(1/2) each.
_, logw_cut = bootstrap_pf_step(np.array([[3.0], [-3.0]]), np.log([0.5, 0.5]), np.array([np.pi]), rng_check, identity,
                                identity, tiny_Q, R_check, (0,), 0.0)
check_close(logw_cut, np.log([0.5, 0.5]), "the log-weights of particles at +-3 rad for a bearing of pi",
            "Wrap the residuals y - h(x) to (-pi, pi] with wrap_angle for the components listed in angles.", atol=1e-6)
# (d) The process noise comes after the model: with f(x) = 2 x, Q = 1 and a flat likelihood (R = 1e12), x_new - f(x)
# has variance 1: the sample variance of 2000 particles is off by about 0.03, so it lies within 0.2 of 1. Noise added
# before f would be doubled by it: variance 4.
double = lambda X: 2 * X
X_new, _ = bootstrap_pf_step(X_check, logw_check, np.array([0.0]), rng_check, double, identity, np.eye(1),
                             np.array([[1e12]]), (), 0.0)
check_close(np.var(X_new - double(X_check)), 1.0, "the variance of x_new - f(x) for f(x) = 2 x, Q = 1",
            "Add the process noise after the model: x_new = f(x) + v with v ~ N(0, Q).", rtol=0, atol=0.2)
# (e) A 2-D noise with correlated components: Q = L L^T with L = [[2, 0], [1, 1]], Q = [[4, 2], [2, 2]]. With f(x) = x and
# a flat likelihood, the sample covariance of x_new - x over 20000 particles is Q to within about 0.1 (0.5 allowed).
# Rows of standard normals z times L (not L.T) would have the covariance L^T L = [[5, 1], [1, 1]] instead.
Q_2d = np.array([[4.0, 2.0], [2.0, 2.0]])
X_2d = np.zeros((20000, 2))
X_new, _ = bootstrap_pf_step(X_2d, np.full(20000, -np.log(20000)), np.zeros(2), rng_check, identity, identity, Q_2d,
                             np.diag([1e12, 1e12]), (), 0.0)
check_close(np.cov(X_new.T), Q_2d, "the sample covariance of x_new - f(x) for Q = [[4, 2], [2, 2]]",
            "Draw v ~ N(0, Q) as rows of standard normals times L.T, with L = np.linalg.cholesky(Q): rows z @ L have "
            "the covariance L^T L, not Q.", rtol=0, atol=0.5)
passed("bootstrap_pf_step")

# %% nbgrader={"grade": true, "grade_id": "test_bootstrap_pf_step", "locked": true, "points": 3, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of bootstrap_pf_step (3 points): exact checks of the weights (with bearings across +-pi), of when
# it resamples and of systematic resampling's offspring counts, and a chi-square test of the process noise
# (false-fail probability below 1e-6).
# Validate (and this cell) first checks that bootstrap_pf_step passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(bootstrap_pf_step)
### BEGIN HIDDEN TESTS
from solutions.nonlinear_filters.hidden_tests import check_bootstrap_pf_step
check_bootstrap_pf_step(bootstrap_pf_step)
### END HIDDEN TESTS

# %% [markdown]
# ## 8. Seven filters on the turning aircraft
#
# First a few runs live, with your functions (the four runs drawn above; the particle filter with 5000
# particles). A filter's error in one run is the lecture's metric of that run: at each radar time $k$ the position
# error $e_k = \sqrt{\Delta\xi^2 + \Delta\eta^2}$ (and likewise the velocity and the turn rate), then
# $\sqrt{\frac{1}{K}\sum_k e_k^2 / 5}$.

# %% nbgrader={"grade": false, "grade_id": "live_runs", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(cubature_points, unscented_points, cut4_points, sigma_point_predict, sigma_point_update, ekf_update,
        bootstrap_pf_step)
live_sets = {"ckf": cubature_points(5), "ukf": unscented_points(5, 1.0), "cut4": cut4_points(5),
             "cut6": cut.cut6_points(), "cut8": cut.cut8_points()}
live = {"pf": air_traffic.run_bootstrap_pf(bootstrap_pf_step, sc, m0, y, np.random.default_rng(5), 5000,
                                              vectorised=False),
        "ekf": air_traffic.run_ekf(ekf_update, sc, m0, y, vectorised=False)}
for name, (Z, w) in live_sets.items():
    live[name] = air_traffic.run_sigma_point_filter(sigma_point_predict, sigma_point_update, Z, w, sc, m0, y,
                                                    vectorised=False)
live_table = {name: air_traffic.summarise(air_traffic.errors(live[name], sc)) for name in air_traffic.FILTERS}
air_traffic.print_median_table(live_table, runs=len(m0))

# %% [markdown]
# **How we rank the filters.** Four runs are too few to rank seven filters. The tables below are the same
# comparison over 400 runs, computed with the reference solution (`air_traffic.load()`). A filter that loses
# the aircraft in a few runs has errors from two groups: the runs it tracks, and a few runs kilometres off. A
# mean mixes the two, and one bad run can outweigh hundreds of good ones. So we rank every filter by the
# **median** over the runs of each run's metric, the error of a typical run, and count the bad runs beside it.
#
# * A run is **lost** when its position error at the last radar return is above 1 km.
# * A run has **diverged** when its velocity error is above 1 km/s at some return, more than eight times the
#   aircraft's speed. A run can diverge without being lost: the radar measures the position, not the velocity.
#
# The second table is the lecture's own metric, a mean over all the runs, with the lecture's values in brackets.
#
# > **Handout correction.** The lecture calls its numbers "2-norms of RMSE". The authors' code computes
# > $\sqrt{\mathrm{mean}_k(\mathrm{RMSE}_k^2 / 5)}$, with $\mathrm{RMSE}_k$ over the runs, dividing by the state
# > dimension 5. Our second table prints that number.

# %% nbgrader={"grade": false, "grade_id": "monte_carlo_table", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
shipped = air_traffic.load()
air_traffic.print_median_table(shipped.table, shipped.runs)
print()
air_traffic.print_table(shipped.table, shipped.runs)

# %% [markdown]
# **What the first table shows.** By the median, the particle filter has the smallest position, velocity and
# turn-rate errors of the seven filters. <!-- claim: nonlinear-filters/pf-best-all -->
# Its position error is 17% below CUT8's (10% to 25% in every batch of 100 runs), its velocity error is smaller,
# and its turn-rate error is about half of CUT8's. <!-- claim: nonlinear-filters/pf-ahead-of-cut8 -->
# The Gaussian filters line up by the degree of their rules: in position CUT6 and CUT8 are level, then come
# CUT4, the UKF, the CKF and the EKF. <!-- claim: nonlinear-filters/position-ordering -->
# CUT8 has the smallest velocity and turn-rate errors of the six Gaussian filters. <!-- claim: nonlinear-filters/cut8-best-gaussian -->
# The two smallest velocity errors are the particle filter's and CUT8's, the lecture's pair. <!-- claim: nonlinear-filters/velocity-best-two -->
# The particle filter pays for its lead with 5000 model evaluations per step, against 355 for CUT8.

# %% [markdown]
# **Lost and diverged runs.** The CKF loses between 40% and 60% of the runs, the UKF about one in three (25% to
# 40%), CUT4 between 1% and 8%, CUT6 under 2% and CUT8 under 1%. <!-- claim: nonlinear-filters/lost-runs -->
# The EKF loses more than nine runs in ten. <!-- claim: nonlinear-filters/ekf-loses-most -->
# Divergence is more common than loss: the CKF diverges in 65-90% of the runs, the UKF in 50-75%, CUT4 and CUT6
# in 3-12%, and CUT8 in none of the 400. <!-- claim: nonlinear-filters/diverged-runs -->
# In a diverged run every radar return pulls the position back to the aircraft, while the velocity and the turn
# rate, which the radar does not measure, run away. Compare the two tables: CUT4's and CUT6's few diverged runs
# make their mean velocity errors more than fifty times their medians. <!-- claim: nonlinear-filters/diverged-runs-make-the-mean -->

# %% [markdown]
# **How often does the particle filter lose a run?** Too rarely for 400 runs to tell, so we ran all seven
# filters on 4000 more runs (40 batches of 100, seeds of their own). The particle filter lost 7 of them, about
# 0.2%. Six were near misses, 1.1 to 2.1 km off at the end, with time-RMS errors up to about 1.1 km. One was a
# catastrophe: a time-RMS position error of 16.8 km, where no other run's time-RMS error was above 1.5 km.
# One catastrophe in 4000 runs puts the catastrophe rate at most at about 0.14%, one run in 700 (the upper end of
# its exact 95% interval). <!-- claim: nonlinear-filters/pf-lost-rate --> Seven is a small count, so other seeds
# can show a few more or fewer lost runs, and lost runs of other kinds.
#
# One such run is enough to upset a mean. Over the 4000 runs, the particle filter's mean position metric is
# above CUT6's and CUT8's, although its median is the smallest. <!-- claim: nonlinear-filters/study-mean-behind -->
# Add a run with an 11 km time-RMS position error (a metric of 4.9 km) to the 400 of the table: its mean rises from under 120 m to over 250 m, behind
# CUT4, CUT6 and CUT8, while its median moves by less than 1 m. <!-- claim: nonlinear-filters/one-lost-run-moves-the-mean -->
# That is why we rank by the median: every ranking of the particle filter above holds with such a run added.

# %% [markdown]
# **Longer intervals.** The last figure repeats the comparison when the radar reports every 5, 10, 15 or 20 s
# (200 fresh runs per interval, shipped with the table): the median errors, and the lost (solid) and diverged
# (dashed) runs. Points beyond the metric axes are drawn as triangles at the top.

# %% nbgrader={"grade": false, "grade_id": "error_against_interval", "locked": true, "schema_version": 3, "solution": false, "task": false}
fig = air_traffic.plot_rmse_against_interval(shipped.sweep_T, shipped.sweep_median, shipped.sweep_lost,
                                             shipped.sweep_diverged, shipped.sweep_runs,
                                             statistic="median of each run's metric")
plt.show()

# %% [markdown]
# The particle filter has the smallest median position error at T = 5 s and 10 s. <!-- claim: nonlinear-filters/pf-best-at-five-seconds -->
# It does not keep its lead: at T = 15 s CUT8 has the smallest, and at 20 s the particle filter's is more than ten
# times CUT8's. <!-- claim: nonlinear-filters/pf-falls-behind -->
# Do not read its velocity at 20 s as a success: it loses more than 80% of the runs there, and its median velocity
# error is close to that of the estimate "zero velocity" ($120/\sqrt 5 = 53.7$ m/s, the dashed line). <!-- claim: nonlinear-filters/pf-lost-at-long-intervals -->
# Over a longer interval the turn-rate noise spreads the particles over a wider arc, fewer of them land where
# the radar's likelihood is high, and the cloud loses the aircraft. CUT8's points stretch with the predicted
# covariance.

# %% [markdown]
# **Question 2** (3 points, one for each part). Connect the tables with your moment table, in a few sentences
# per part.
#
# * **(a)** Why do the CKF and the UKF lose the aircraft so often, and why, in the T = 5 s tables, does each extra
#   order of exactness (CUT4, CUT6, CUT8) help? Does the largest degree-4 moment error rank the CKF and the UKF?
# * **(b)** Why can a run's velocity error be huge while its position is tracked, and why is the median a better
#   summary than the mean for filters that lose or diverge in some runs?
# * **(c)** Why is the particle filter the best filter at T = 5 s, what does it pay for that, and why does it fall
#   behind CUT8 when the radar reports less often?

# %% [markdown] nbgrader={"grade": true, "grade_id": "comparison_question", "locked": false, "points": 3, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** Every Gaussian filter here computes the same expectations (the predicted mean and covariance,
# $\hat y$, $P_{yy}$, $P_{xy}$); they differ only in how exactly. The coordinated-turn step mixes the turn rate
# with the velocity through $\sin(\Omega T)/\Omega$ and $(1-\cos\Omega T)/\Omega$, and the filters' model gives
# the turn rate a large noise (`Q[4, 4]`: 0.22 rad/s per step), so the predicted covariance depends on fourth and
# higher moments of the prior. It is this noise, not the turns, that matters: without the turns the CKF and the
# UKF still lose a large fraction of the runs, and with a ten times smaller $L_2$ they lose none. <!-- claim: nonlinear-filters/straight-flight-still-lost --> <!-- claim: nonlinear-filters/small-turn-noise-no-loss -->
# The CKF and the UKF are exact only to
# degree 3 (their degree-4 errors are 2 and 3 in the moment table), so after a step their covariance is wrong in
# size and shape; the update then corrects in the wrong directions, the error outgrows the covariance, and the
# filter never recovers: the CKF loses 40-60% of the runs and the UKF about one in three. <!-- claim: nonlinear-filters/lost-runs --> The largest
# moment error does not rank these two: the UKF's is larger (3 against 2), yet it loses fewer runs than the CKF. <!-- claim: nonlinear-filters/ukf-ahead-of-ckf -->
# A single number per degree does not say which moments the model needs, nor where the
# points sit (the UKF keeps a centre point and spreads the others to $\sqrt 6$ instead of $\sqrt 5$).
# CUT4, CUT6 and CUT8 get the moments up to degree 5, 7 and 9 right. By the median, CUT4 beats the UKF and the CKF
# in position, and CUT6 and CUT8 are level ahead of CUT4. <!-- claim: nonlinear-filters/position-ordering -->
# Divergence tells them apart more sharply: CUT4 and CUT6 diverge in a few percent of the runs, CUT8 in none. <!-- claim: nonlinear-filters/diverged-runs -->
# Velocity is not measured. The radar pins the position to the aircraft at every return, but in a diverged run
# the velocity and turn-rate estimates run away to thousands of m/s while the position error stays under a
# kilometre: pooled over many runs, most of CUT4's and CUT6's diverged runs are not lost. <!-- claim: nonlinear-filters/diverged-but-pinned --> A few such runs
# make the whole mean: CUT6's mean velocity metric is more than ten times CUT8's, <!-- claim: nonlinear-filters/cut8-velocity-gap --> but
# without the diverged runs CUT4 and CUT6 are within a factor 1.5 of CUT8. <!-- claim: nonlinear-filters/velocity-without-diverged --> For
# a filter that loses or diverges in some runs the mean mixes two groups of runs, and one lost run can move it
# more than hundreds of good ones (a run with an 11 km time-RMS position error would more than double the particle filter's mean); <!-- claim: nonlinear-filters/one-lost-run-moves-the-mean -->
# the median describes a typical run. The particle filter assumes no Gaussian: its particles carry the curved,
# non-Gaussian predicted distribution that an uncertain turn rate produces through the step, so it needs no
# moments at all. At T = 5 s it has the smallest median position, velocity and turn-rate errors of all seven
# filters <!-- claim: nonlinear-filters/pf-best-all --> and rarely loses a run. <!-- claim: nonlinear-filters/pf-lost-rate -->
# It pays with 5000 model evaluations per step, against 355 for
# CUT8, and with its dependence on enough particles landing where the likelihood is high: when the radar reports
# less often, the turn-rate noise spreads the predicted particles wider, it loses most runs at T = 20 s, and
# from T = 15 s on CUT8 has the smaller median position error. <!-- claim: nonlinear-filters/pf-falls-behind --> <!-- claim: nonlinear-filters/pf-lost-at-long-intervals -->
#
# **Rubric (3 points).** (a) 1 point: links the ordering of the Gaussian filters in position to the degree of
# exactness (degree-4 errors of CKF and UKF; CUT4/6/8 exact to 5/7/9), through the predicted covariance after
# steps with a large turn-rate noise; the point is also earned by an answer that blames the turn-rate
# uncertainty without separating the noise from the turns, but not by one that blames the turns alone. Noting
# that the largest moment error does not rank the UKF and the CKF is expected for full marks on this point: an
# answer without it gets ½ point. An
# answer that reads CUT6 and CUT8 as level in position, or CUT8 as ahead by its velocity and its lack of
# diverged runs, reads the table correctly.
# (b) 1 point: the huge velocity errors come from diverged runs, in which the unmeasured velocity and turn rate run
# away while the radar keeps the position close (so they are often not lost); a few of them make the mean (CUT6
# against CUT8 in velocity), and the median describes a typical run because a few bad runs cannot move it.
# An answer that explains the velocity errors by lost runs alone gets half of this point. (c) 1 point: the particle
# filter is the best at T = 5 s (smallest median errors in all three quantities, rarely a lost run) because it
# represents the non-Gaussian predicted distribution directly; it costs thousands of points per step, and the
# sweep over T shows it losing most runs at long intervals, where its predicted particles spread too wide for
# 5000 of them. Full marks for any answer that reads the tables and the figures this way.
# ### END SOLUTION

# %% [markdown]
# ## 9. Going further
#
# Nothing here is graded. It holds the checks behind the main text: more tables, the error over time, what
# breaks the CKF and the UKF, the lecture's own comparison, and the handout's slips.
#
# **More summaries of the 400 runs.** The table below gives, for each filter, the median, the lecture's metric
# without the lost runs and without the diverged runs, and the plain time-averaged RMSE of the position,
# $\mathrm{mean}_k \mathrm{RMSE}_k$.

# %% nbgrader={"grade": false, "grade_id": "robust_table", "locked": true, "schema_version": 3, "solution": false, "task": false}
air_traffic.print_robust_table(shipped.table)

# %% [markdown]
# A few diverged runs make the whole mean: CUT6's mean velocity metric is more than ten times CUT8's, <!-- claim: nonlinear-filters/cut8-velocity-gap -->
# but without their diverged runs CUT4 and CUT6 are below 50 m/s, within 1.5 times CUT8. <!-- claim: nonlinear-filters/velocity-without-diverged -->
# Compare the columns "vel w/o lost" and "vel w/o div.". Without their lost runs, CUT4's and CUT6's velocity
# metrics are still more than ten times those without their diverged runs. <!-- claim: nonlinear-filters/lost-criterion-misses-divergence -->
# The lost-run criterion looks only at the final position, and misses most of the divergence. Over the 400 runs,
# and pooled over 390 independent ones (a single batch of 50 need not show it), CUT4 and CUT6 diverge in at least
# twice as many runs as they lose, and most of their diverged runs end with the position within 1 km. <!-- claim: nonlinear-filters/diverged-but-pinned -->
#
# **The lecture's table.** By the lecture's metric (a mean), our CUT6 and CUT8 position numbers are within 20%
# of the lecture's. <!-- claim: nonlinear-filters/cut-matches-lecture -->
# Without its lost runs, our particle filter's mean is within 3% of the lecture's row in all three quantities,
# in the table and over the 4000 runs; one batch of 400 runs lands within about 5% in position (within 1% in
# velocity and 2% in turn rate). <!-- claim: nonlinear-filters/pf-near-lecture -->
# The mean ranks CUT8 ahead of CUT6 in position, as the lecture does, while the medians call them level: the
# mean weighs CUT6's few bad runs. <!-- claim: nonlinear-filters/mean-ranks-cut8-ahead -->
#
# **Why the CKF and the UKF fail.** The turn-rate noise in $Q$ adds 0.22 rad/s of uncertainty at every step,
# which over 5 s turns the velocity by about ±1.1 rad (one standard deviation). <!-- claim: nonlinear-filters/turn-noise-size -->
# The predicted position and velocity are spread along an arc, far from Gaussian. A rule exact only to degree
# 3 misjudges their covariance, the update trusts a wrong turn rate, and the velocity estimate spins away. The
# particle filter's cloud carries the arc through the step, and the radar update reweights it as it is.
#
# **The error over time.** The figure shows the position $\mathrm{RMSE}_k$ over the 400 runs against time.

# %% nbgrader={"grade": false, "grade_id": "error_over_time", "locked": true, "schema_version": 3, "solution": false, "task": false}
fig = air_traffic.plot_position_error(shipped.times, shipped.rmse_curves,
                                      f"Position RMSE over {shipped.runs} runs against time (T = 5 s)",
                                      straight=shipped.straight_position_rmse)
plt.show()

# %% [markdown]
# All filters start from the error of the initial mean (about 1.4 km: each position coordinate starts with a
# 1 km standard deviation, so the RMSE is $\sqrt 2 \times 1$ km; these 400 runs drew 1.5 km) and are below 500 m
# after two returns (t = 10 s). <!-- claim: nonlinear-filters/initial-error-settles -->
# The CKF's and the UKF's errors grow to more than three times their value at t = 125 s over the rest of the
# flight. <!-- claim: nonlinear-filters/ckf-ukf-error-grows -->
# This curve is a mean over the runs, so one lost run of the particle filter would lift its line too.
#
# The turns are not what breaks the CKF and the UKF. The dashed lines are the same two filters on the flight
# flown without its turns, 495 s straight west (400 other runs). With and without the turns their errors first
# exceed 1.5 times their value at t = 125 s at about 200 s in these curves, and then grow past three times it. <!-- claim: nonlinear-filters/straight-curves-depart -->
# On both flights this is within 45 s of the aircraft's closest approach to the radar, where its bearing changes
# fastest (the grey triangles: 3.1 km at t = 240 s, 25 s after the first turn ends; 10 km at t = 210 s without
# turns); <!-- claim: nonlinear-filters/closest-approach -->
# the timing alone does not make it the cause. Without its turns the CKF still loses 25-50% of the runs and the
# UKF 15-45%; the CKF diverges in more than half of them and the UKF in more than 40%. <!-- claim: nonlinear-filters/straight-flight-still-lost -->
# With a turn-rate noise ten times smaller ($L_2 = 10^{-3}$), no sigma-point filter loses or diverges in any of
# 50 runs, and all five reach the same position error to within 1.5%. <!-- claim: nonlinear-filters/small-turn-noise-no-loss -->
# The EKF is the exception: at $L_2 = 10^{-3}$ it still loses about three runs in four (in each of two batches of
# 50), and only with $L_2 = 10^{-5}$ does it keep the aircraft in every one of 2 × 50 runs. <!-- claim: nonlinear-filters/ekf-small-turn-noise -->
# Its Jacobians are right; the approximation is the linearisation itself. In the language of the moment table
# it is a rule exact only to degree 1. The true turns are gentle by comparison (at most 3°/s, 0.26 rad per step).
#
# **Longer intervals.** At every interval CUT8 diverges in no more runs than any other Gaussian filter, and in
# under 10%. <!-- claim: nonlinear-filters/sweep-cut8-diverges-least --> The degree of exactness is not the whole
# story, though: at T = 10 s the sweep's CUT6 loses and diverges about twice as many runs as CUT4 (22% against 11%
# lost, 31% against 16% diverged). <!-- claim: nonlinear-filters/sweep-cut6-behind-cut4-at-ten -->
# Every filter but the EKF has a larger median position error at T = 20 s than at T = 5 s; the EKF loses over 90%
# of the runs at every interval. <!-- claim: nonlinear-filters/errors-grow-with-interval -->
# More particles help the particle filter: at T = 20 s, 20 000 particles lose about half of 32 fresh runs (16 runs
# on each of two seeds), where 5000 lose over 85% of the sweep's 200. <!-- claim: nonlinear-filters/more-particles-help -->
#
# **Which turn-rate noise should a tracker assume?** The true flight turns at most at 3°/s, while the model's
# `Q[4, 4]` allows 12.8°/s per step. Try it with your own filters: `air_traffic.scenario(5.0, turn_noise=...)`
# builds the set-up with another $L_2$, and `air_traffic.scenario(5.0, legs=((495.0, 0.0),))` the flight without
# turns. How small can $L_2$ be before the filters lag behind the 3°/s turn? This lab makes no claim about the
# answer.
#
# **The Lorenz system.** The lecture also compares the filters on the Lorenz system with uncertain parameters. It
# does not say what is measured, so its table cannot be reproduced, and this lab makes no claim about it. The
# Lorenz state $[x, y, z, \sigma, \rho]$ is also five-dimensional, so `cut.cut8_points()` applies: pick a
# measurement (for example $x$ alone, with noise), integrate the dynamics over each interval with
# `scipy.integrate.solve_ivp`, and run your filters.
#
# **The handout's slips.** In section 1:
#
# > **Handout correction.** In the lecture's expansion of the exponent, the last term is written
# > $\hat x^T P^{-1} x_{k+1}$; it is $\hat x^T P^{-1} \hat x$ (it does not depend on $x_{k+1}$, which is why it
# > cancels in the normalisation). The posterior is also labelled $p(x_{k+1} \mid Y_k)$ on one slide where
# > $p(x_{k+1} \mid Y_{k+1})$ is meant.
#
# In section 4:
#
# > **Handout correction.** The lecture does not state $R$. The authors' code uses
# > $R = \mathrm{diag}((100\ \mathrm{m})^2, (1°)^2)$, a range variance of $10^4\ \mathrm{m}^2$ (a 100 m range noise).
#
# > **Handout correction.** The lecture's transition matrix orders the state as $[\xi, \dot\xi, \eta, \dot\eta, \Omega]$.
# > In our transcription of the handout its last row and its range are garbled; the turn rate is carried over,
# > $\Omega_{k} = \Omega_{k-1}$, so the last row is $(0, 0, 0, 0, 1)$, and the range is $\sqrt{\xi_k^2 + \eta_k^2}$.
# > The bearing, written $\tan^{-1}(\eta_k/\xi_k)$, must be the four-quadrant $\operatorname{atan2}(\eta_k, \xi_k)$
# > (the aircraft crosses into $\xi < 0$). A difference of bearings is an angle: we wrap it to $(-\pi, \pi]$
# > (`wrap_angle`), or a target near $\pm\pi$ would look $2\pi$ away from itself.
