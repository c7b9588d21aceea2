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
# # Lab train-kf: catching the train with a Kalman filter
#
# You keep missing the train that runs through the woods near your home. An online feed gives the
# train's GPS position and speed every minute, but under the trees both readings are poor. In this lab you
# combine a simple model of how the train moves with those noisy readings, and you get an estimate that
# is better than either on its own: a **Kalman filter**.
#
# **What you will do**
# 1. Derive the Kalman gain by minimising a cost function, and the covariance of the result (two short written
#    derivations, 1 and 4(a); derivations 2 and 3 and part (b) of 4 are worked for you).
# 2. Write the two forms of the gain, then the filter one piece at a time: the process noise `Q`, the forecast
#    step, the analysis step, and the loop over one hour of GPS fixes.
# 3. Run it on an hour of data. Compare it with the raw GPS and with another model of the train's noise, and
#    see what happens when the filter's covariances are wrong.
# 4. Measure over many simulated hours whether the filter's uncertainty is honest: how often the truth is inside
#    its band, and the normalised estimation error squared (NEES).
#
# **What is graded, and about how long each part takes**
#
# | part | what you write | points | about |
# |---|---|---|---|
# | 2. The best compromise | derivation 1 | 2 | 25 min |
# | 3. The two forms of the gain | `gain_information_form`, `gain_covariance_form` | 2 | 20 min |
# | 4, 5. The process noise and the forecast | `process_noise`, `predict` | 2 | 15 min |
# | 6. The analysis step | `kupdate`, derivation 4(a) | 3 | 30 min |
# | 7. The filter | `run_filter` | 2 | 15 min |
# | 8. Tracking the train | one written answer | 2 | 20 min |
# | 9. Playing with the covariances | one written answer | 2 | 20 min |
# | 10. Is the filter honest? | `nees`, one written answer | 3 | 30 min |
# | **all** | 7 functions, 5 written answers | **18** | **about 3 h** |
#
# Add about 15 minutes to read this introduction and section 1. Written answers (derivations and questions) are
# marked by hand, the functions by hidden tests. The last section, "Going further", is not graded.
#
# **How this notebook works.** You write only in the cells marked `YOUR CODE HERE` and `YOUR ANSWER HERE`. The grey
# cells are locked: grading puts back their originals, so an edit there would be lost. Below each blank, *visible
# checks* try cases you can work out by hand, and their messages say what to fix. Grading adds *hidden tests* on
# random inputs of several sizes: make each function work for any state dimension `n` and observation dimension
# `m`, return new arrays and leave its arguments unchanged. Each function is graded on its own, so a mistake in
# one costs no points in the blanks that use it. Before you submit, press **Validate** in the toolbar: it runs the
# whole notebook and lists each blank that is not written yet or does not pass its visible checks.
#
# *Credit.* This lab follows the science of the handout "More Train Fun" from a data-assimilation
# module distributed on HUBzero with `KalmanTrain.zip` (MATLAB). The copy we worked from names no author
# or year. The text, code and data here are our own, and so are any errors. Where the handout has a typo,
# a one-line *Handout correction* says so where the equation comes, and we use the corrected form. You do
# not need the handout, and you may skip these boxes; section 11 explains each correction.

# %% nbgrader={"grade": false, "grade_id": "setup", "locked": true, "schema_version": 3, "solution": false, "task": false}
# Set-up: run this cell first.
# %xmode Minimal
# %matplotlib inline
import numpy as np
import scipy.linalg
import matplotlib.pyplot as plt

from course import train
from course.checks import check_array, check_close, check_pair, check_symmetric, passed, random_spd, require, validate

# %% [markdown]
# ## 1. The train and its GPS
#
# We track the state $\vec{x}_t = (x_t, v_t)$: position $x$ in **miles** along the line and velocity $v$
# in **miles per hour**, at steps of one **minute**, $t = 0, 1, \dots, 60$.
#
# We no longer believe the rail company's "100 mph, give or take 15". Instead the velocity wanders: each
# minute it changes by a random amount $z_t \sim N(0, \sigma^2)$ with $\sigma = 15$ mph. In one minute
# (1/60 of an hour) a train at $v$ mph covers $v/60$ miles. The true train moves as
#
# $$\vec{x}_{t+1} = A\,\vec{x}_t + Z_t, \qquad
#   A = \begin{bmatrix} 1 & 1/60 \\ 0 & 1 \end{bmatrix}, \qquad
#   Z_t = \begin{pmatrix} z_t/60 \\ z_t \end{pmatrix},$$
#
# that is, $v_{t+1} = v_t + z_t$ and $x_{t+1} = x_t + v_t/60 + z_t/60 = x_t + v_{t+1}/60$: in each minute the train
# moves at the minute's new speed.
#
# > **Handout correction.** The handout's position update multiplies position by velocity and does not fit its
# > own noise $Z$; we use $x_{t+1} = x_t + v_{t+1}/60$, which is what $A$ and $Z$ say.

# %% [markdown]
# The GPS reports both position and velocity, with independent errors of standard deviation 10 mi and
# 10 mph. So the observation operator is $H = I$ and the observation error covariance is
# $R = \mathrm{diag}(100\ \mathrm{mi}^2,\ 100\ \mathrm{mph}^2)$. The shipped data are one simulated hour
# of this process: the truth and the GPS fixes at minutes 1 to 60.
#
# **Where the filter starts.** At minute 0 the train leaves the station, so we know its position well: 0 mi,
# with a standard deviation of 1 mi. For its starting speed we do use the company's 100 mph, with a standard
# deviation of 15 mph. This belief is $\vec{x}_0 = (0, 100)$ with covariance $B_0 = \mathrm{diag}(1\ \mathrm{mi}^2,\ 225\ \mathrm{mph}^2)$
# (`train.initial_belief`), and the simulated trains draw their starting state from it.
#
# In the shipped hour the train keeps going forward, between about 80 and 155 mph. <!-- claim: train-kf/shipped-hour-forward -->
# `train.simulate` gives you others (section 11 says how restless this train can be).

# %% nbgrader={"grade": false, "grade_id": "load_data", "locked": true, "schema_version": 3, "solution": false, "task": false}
data = train.load()
A, H, R = train.model_matrix(), train.gps_operator(), train.gps_covariance()
x0, B0 = train.initial_belief()
print(f"{len(data.minute)} GPS fixes, minutes {data.minute[0]} to {data.minute[-1]}")
print("A =\n", A, "\nR =\n", R)
print("belief at minute 0: x0 =", x0, " B0 = diag", np.diag(B0))

# %% [markdown]
# ## 2. The best compromise between model and data
#
# Suppose the model forecasts $\vec{x}^f$ with error covariance $B$, and we observe the state directly as
# $\vec{x}^0$ with error covariance $R$. A natural estimate is the $\vec{x}$ that is closest to both, each
# distance weighted by how much we trust it:
#
# $$J(\vec{x}) = (\vec{x} - \vec{x}^f)^T B^{-1} (\vec{x} - \vec{x}^f) + (\vec{x} - \vec{x}^0)^T R^{-1} (\vec{x} - \vec{x}^0).$$

# %% [markdown]
# **Derivation 1 (2 points).** Show that the minimiser $\vec{x}^a$ of $J$ can be written as
# $\vec{x}^a = \vec{x}^f + K(\vec{x}^0 - \vec{x}^f)$ with $K = B(R + B)^{-1}$.
# Write your answer in the cell below. Plain-text algebra such as `inv(inv(B) + inv(R))` is as good as LaTeX: the
# steps earn the points, not the typesetting.
#
# *Hint.* For a symmetric matrix $M$, the gradient of $(\vec{x} - \vec{a})^T M (\vec{x} - \vec{a})$ is
# $2M(\vec{x} - \vec{a})$. Set the gradient of $J$ to zero. To make $\vec{x}^0 - \vec{x}^f$ appear, add and
# subtract $R^{-1}\vec{x}^f$. Last, write $(B^{-1} + R^{-1})^{-1} R^{-1}$ as one inverse with the rule
# $(XY)^{-1} = Y^{-1}X^{-1}$ (read $R^{-1}$ as the inverse of $R$: the product is $[R(B^{-1} + R^{-1})]^{-1}$), and
# take $B^{-1}$ out of the sum inside it as a factor on the right (write $I = BB^{-1}$). $J$ is a strictly convex
# quadratic, so its one stationary point is its minimum: you need not prove that.

# %% [markdown] nbgrader={"grade": true, "grade_id": "derivation_1", "locked": false, "points": 2, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** $J$ is a convex quadratic ($B^{-1}$ and $R^{-1}$ are symmetric positive definite), so
# its minimiser is where the gradient vanishes:
# $\nabla J = 2B^{-1}(\vec{x} - \vec{x}^f) + 2R^{-1}(\vec{x} - \vec{x}^0) = 0$.
# Hence $(B^{-1} + R^{-1})\vec{x}^a = B^{-1}\vec{x}^f + R^{-1}\vec{x}^0 = (B^{-1} + R^{-1})\vec{x}^f + R^{-1}(\vec{x}^0 - \vec{x}^f)$,
# so $\vec{x}^a = \vec{x}^f + (B^{-1} + R^{-1})^{-1} R^{-1} (\vec{x}^0 - \vec{x}^f)$.
# Finally $(B^{-1} + R^{-1})^{-1} R^{-1} = \left(R(B^{-1} + R^{-1})\right)^{-1} = (RB^{-1} + I)^{-1} = \left((R + B)B^{-1}\right)^{-1} = B(R + B)^{-1}$.
#
# **Rubric (2 points).** 1 point: the gradient of both quadratic terms, set to zero (a missing factor 2
# on both terms is fine). 1 point: the algebra from the stationarity condition to $K = B(R+B)^{-1}$,
# with inverses of products taken in the right order.
# ### END SOLUTION

# %% [markdown]
# Often we do not observe the state itself. An observation operator $H$ ($m \times n$) maps a state to what
# the instrument would read, $\vec{y} = H\vec{x}$ (a radar might see only the position, so $m = 1$). The
# cost becomes
#
# $$J(\vec{x}) = (\vec{x} - \vec{x}^f)^T B^{-1} (\vec{x} - \vec{x}^f) + (H\vec{x} - \vec{y}^0)^T R^{-1} (H\vec{x} - \vec{y}^0).$$
#
# **Derivation 2 (worked for you, not graded).** Its minimiser is $\vec{x}^a = \vec{x}^f + K(\vec{y}^0 - H\vec{x}^f)$
# with $K = (B^{-1} + H^T R^{-1} H)^{-1} (R^{-1} H)^T$. The steps are those of derivation 1, with $H$ in the second
# term. By the chain rule through $H$, the gradient of the second term is $2H^T R^{-1}(H\vec{x} - \vec{y}^0)$, so
# the minimiser solves
# $(B^{-1} + H^T R^{-1} H)\vec{x}^a = B^{-1}\vec{x}^f + H^T R^{-1}\vec{y}^0$. Adding and subtracting
# $H^T R^{-1} H \vec{x}^f$ on the right gives $(B^{-1} + H^T R^{-1} H)\vec{x}^f + H^T R^{-1}(\vec{y}^0 - H\vec{x}^f)$,
# hence $\vec{x}^a = \vec{x}^f + (B^{-1} + H^T R^{-1} H)^{-1} H^T R^{-1} (\vec{y}^0 - H\vec{x}^f)$. Last,
# $H^T R^{-1} = (R^{-1} H)^T$ because $R$ is symmetric. With $H = I$ this is derivation 1's gain before its last
# rearrangement.

# %% [markdown]
# **Derivation 3: the two forms of the gain agree** (worked for you, not graded). Section 3 uses a second form of the same
# gain, $K = B H^T (H B H^T + R)^{-1}$. To see that it equals derivation 2's, expand one product in two ways:
# $H^T R^{-1}(H B H^T + R) = H^T R^{-1} H B H^T + H^T = (H^T R^{-1} H + B^{-1})\,B H^T$. Multiply on the left by
# $(B^{-1} + H^T R^{-1} H)^{-1}$ and on the right by $(H B H^T + R)^{-1}$ (both matrices are symmetric positive
# definite, so both inverses exist): $(B^{-1} + H^T R^{-1} H)^{-1} H^T R^{-1} = B H^T (H B H^T + R)^{-1}$, and
# $H^T R^{-1} = (R^{-1} H)^T$ as $R$ is symmetric.

# %% [markdown]
# ## 3. The two forms of the gain, in code
#
# Write both forms as functions of `B` ($n \times n$), `H` ($m \times n$) and `R` ($m \times m$). Each returns
# `K`, an $n \times m$ array. Use `np.linalg.solve` (or `scipy.linalg.cho_solve`) rather than
# `np.linalg.inv` wherever you can: solving is cheaper and more accurate than forming an inverse. (The
# information form does need $B^{-1}$ itself.)
#
# *Hint.* `np.linalg.solve(S, C)` gives $S^{-1} C$, but the covariance form has $S^{-1}$ on the right:
# $K = B H^T S^{-1}$ with $S = H B H^T + R$. As $S$ and $B$ are symmetric, $K = (S^{-1} H B)^T$, which is
# `np.linalg.solve(S, H @ B).T`. (`np.linalg.inv` costs no points if your numbers are right: the hidden tests
# compare values.)

# %% nbgrader={"grade": false, "grade_id": "gain_information_form", "locked": false, "schema_version": 3, "solution": true, "task": false}
def gain_information_form(B, H, R):
    """K = (B^-1 + H^T R^-1 H)^-1 (R^-1 H)^T, shape (n, m)."""
    ### BEGIN SOLUTION
    n = B.shape[0]
    # B^-1, from a Cholesky factorisation of the SPD forecast covariance
    B_inv = scipy.linalg.cho_solve(scipy.linalg.cho_factor(B), np.eye(n))
    # (R^-1 H)^T = H^T R^-1, since R is symmetric
    RinvH = np.linalg.solve(R, H)
    # K = (B^-1 + H^T R^-1 H)^-1 (R^-1 H)^T
    return np.linalg.solve(B_inv + H.T @ RinvH, RinvH.T)
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_gain_information_form", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(gain_information_form)
# Visible checks. With H = I the gain is B (B + R)^-1 (derivation 1): for diagonal B = diag(4, 9) and
# R = diag(4, 1) it is diag(4/8, 9/10).
K = check_array(gain_information_form(np.diag([4.0, 9.0]), np.eye(2), np.diag([4.0, 1.0])), "K", (2, 2))
check_close(K, np.diag([0.5, 0.9]), "K for B = diag(4, 9), H = I, R = diag(4, 1)",
            "Compare with derivation 1. Did you invert B and R?")
# Observing only the position (H = [1, 0], m = 1) gives a 2 x 1 gain.
K = check_array(gain_information_form(np.diag([4.0, 9.0]), np.array([[1.0, 0.0]]), np.array([[4.0]])), "K", (2, 1),
                "K is n x m: here n = 2 states and m = 1 observation. Check your transposes.")
check_close(K, [[0.5], [0.0]], "K for B = diag(4, 9), H = [[1, 0]], R = [[4]]",
            "The position gain is B_xx / (B_xx + R) = 4/8, and velocity is uncorrelated with position here.")
# A full R: with H = I and B = I, K = (I + R)^-1 (derivation 1). For R = [[2, 1], [1, 2]], I + R = [[3, 1], [1, 3]],
# whose inverse is [[3, -1], [-1, 3]] / 8.
K = gain_information_form(np.eye(2), np.eye(2), np.array([[2.0, 1.0], [1.0, 2.0]]))
check_close(K, np.array([[3.0, -1.0], [-1.0, 3.0]]) / 8, "K for B = I, H = I, R = [[2, 1], [1, 2]]",
            "R is not diagonal here, so R^-1 is not the reciprocal of its diagonal: solve with the whole R.")
passed("gain_information_form")

# %% nbgrader={"grade": true, "grade_id": "test_gain_information_form", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of gain_information_form (1 point): random B, H, R of several sizes.
# Validate (and this cell) first checks that gain_information_form passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(gain_information_form)
### BEGIN HIDDEN TESTS
from solutions.train_kf.hidden_tests import check_gain_information_form
check_gain_information_form(gain_information_form)
### END HIDDEN TESTS

# %% nbgrader={"grade": false, "grade_id": "gain_covariance_form", "locked": false, "schema_version": 3, "solution": true, "task": false}
def gain_covariance_form(B, H, R):
    """K = B H^T (H B H^T + R)^-1, shape (n, m)."""
    ### BEGIN SOLUTION
    # S = H B H^T + R, the covariance of the innovation
    S = H @ B @ H.T + R
    # K = B H^T S^-1, so K^T = S^-1 H B (B and S are symmetric)
    return np.linalg.solve(S, H @ B).T
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_gain_covariance_form", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(gain_covariance_form)
# Visible checks: the same two hand-worked cases as for the information form.
K = check_array(gain_covariance_form(np.diag([4.0, 9.0]), np.eye(2), np.diag([4.0, 1.0])), "K", (2, 2))
check_close(K, np.diag([0.5, 0.9]), "K for B = diag(4, 9), H = I, R = diag(4, 1)",
            "With H = I this is B (B + R)^-1. Did you add R inside the inverse?")
K = check_array(gain_covariance_form(np.diag([4.0, 9.0]), np.array([[1.0, 0.0]]), np.array([[4.0]])), "K", (2, 1),
                "K is n x m: here n = 2 states and m = 1 observation. Check your transposes.")
check_close(K, [[0.5], [0.0]], "K for B = diag(4, 9), H = [[1, 0]], R = [[4]]")
passed("gain_covariance_form")

# %% nbgrader={"grade": true, "grade_id": "test_gain_covariance_form", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of gain_covariance_form (1 point): random B, H, R of several sizes.
# Validate (and this cell) first checks that gain_covariance_form passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(gain_covariance_form)
### BEGIN HIDDEN TESTS
from solutions.train_kf.hidden_tests import check_gain_covariance_form
check_gain_covariance_form(gain_covariance_form)
### END HIDDEN TESTS

# %% [markdown]
# Section 2 showed that the two forms are the same matrix. Here is the numerical evidence, on random
# symmetric positive definite `B` and `R` of several sizes. (Which form is cheaper to compute? See section 11.)

# %% nbgrader={"grade": false, "grade_id": "gain_forms_agree", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(gain_information_form, gain_covariance_form)
rng = np.random.default_rng(3)
print(" n  m   max |K_information - K_covariance|")
for n, m in [(2, 2), (2, 1), (4, 3), (6, 2), (8, 8)]:
    B_rand, H_rand, R_rand = random_spd(rng, n), rng.standard_normal((m, n)), random_spd(rng, m)
    gap = np.max(np.abs(gain_information_form(B_rand, H_rand, R_rand) - gain_covariance_form(B_rand, H_rand, R_rand)))
    print(f"{n:2d} {m:2d}   {gap:.1e}")

# %% [markdown]
# ## 4. The process noise $Q$
#
# The forecast moves the estimate with $A$ and leaves out the noise $Z_t$. So each step adds the noise's
# covariance $Q = E[Z Z^T]$ to the forecast's uncertainty. Write `process_noise(sigma, dt_min)`, the $Q$ of one
# step of `dt_min` minutes:
#
# * the step is $h = $ `dt_min`$/60$ hours long;
# * once per step the velocity jumps by $z \sim N(0, \sigma^2)$; `sigma` (mph) is the size of one jump,
#   whatever the length of the step;
# * the position carries the jump for the whole step, so $Z = (h z, z)$.
#
# Work out $E[Z Z^T]$ from $E[z^2] = \sigma^2$. You should find
# $Q = \sigma^2 \begin{bmatrix} h^2 & h \\ h & 1 \end{bmatrix}$.
#
# > **Handout correction.** The handout's "$\sigma = 15/60$" is the position noise's standard deviation in miles;
# > the $\sigma$ in $Q$ is the velocity's, 15 mph.
#
# This $Q$ has **rank one**: it is $\sigma^2 \vec{g}\,\vec{g}^T$ with $\vec{g} = (h, 1)$, because one noise input $z$
# drives both the position and the velocity. Section 9 comes back to this.

# %% nbgrader={"grade": false, "grade_id": "process_noise", "locked": false, "schema_version": 3, "solution": true, "task": false}
def process_noise(sigma, dt_min=1.0):
    """Q (2 x 2) for velocity noise sigma (mph) per step of dt_min minutes."""
    ### BEGIN SOLUTION
    h = dt_min / 60.0
    # Z = (h z, z) with z ~ N(0, sigma^2), so Q = E[Z Z^T] = sigma^2 [[h^2, h], [h, 1]]
    return sigma**2 * np.array([[h * h, h], [h, 1.0]])
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_process_noise", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(process_noise)
# Visible checks with the train's numbers: sigma = 15 mph, one-minute steps.
Q = check_array(process_noise(15.0), "process_noise(15.0)", (2, 2))
check_symmetric(Q, "Q")
check_close(Q[1, 1], 225.0, "Q[1, 1], the variance of the velocity change",
            "It is sigma^2 = 15^2 mph^2: sigma is in mph already, so do not divide it by 60.")
check_close(Q[0, 0], 0.0625, "Q[0, 0], the variance of the position noise z/60",
            "The position noise is z h with the step h in hours: h = dt_min / 60 = 1/60, not the 1 minute of dt_min. "
            "Its standard deviation is 15/60 = 0.25 mi, its variance (sigma h)^2.")
check_close(Q[0, 1], 3.75, "Q[0, 1], the covariance of z/60 and z", "E[(z/60) z] = sigma^2/60.")
check_close(process_noise(15.0, dt_min=2.0)[0, 0], 0.25, "Q[0, 0] for two-minute steps",
            "With dt_min = 2, h = 2/60 hours, so the position noise is z h with variance (15/30)^2.")
passed("process_noise")

# %% nbgrader={"grade": true, "grade_id": "test_process_noise", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of process_noise (1 point): random sigma and step lengths.
# Validate (and this cell) first checks that process_noise passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(process_noise)
### BEGIN HIDDEN TESTS
from solutions.train_kf.hidden_tests import check_process_noise
check_process_noise(process_noise)
### END HIDDEN TESTS

# %% [markdown]
# ## 5. The forecast step
#
# Move the analysis at minute $t$ (the estimate after that minute's fix) and its covariance forward one step, to the
# forecast for minute $t+1$:
#
# $$\vec{x}^f_{t+1} = A\vec{x}^a_t, \qquad B^f_{t+1} = A B^a_t A^T + Q.$$
#
# The covariance grows: the old uncertainty is carried along by the model, and the model's own error $Q$
# is added on top. Write `predict(x, B, A, Q)` for any state dimension $n$ (`x` has shape `(n,)`) and
# return the pair `(x_f, B_f)`.
#
# > **Handout correction.** The handout carries the previous *forecast* error forward and mixes time indices; the
# > forecast starts from the previous analysis, so $A$ carries $B^a_t$ forward, and both equations above are for one step.

# %% nbgrader={"grade": false, "grade_id": "predict", "locked": false, "schema_version": 3, "solution": true, "task": false}
def predict(x, B, A, Q):
    """Forecast: x (n,), B (n, n) -> x_f (n,), B_f (n, n)."""
    ### BEGIN SOLUTION
    # x^f_{t+1} = A x^a_t
    x_f = A @ x
    # B^f_{t+1} = A B^a_t A^T + Q
    B_f = A @ B @ A.T + Q
    return x_f, B_f
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_predict", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(predict)
# Visible checks on a train at 10 mi doing 60 mph: in one minute it moves 1 mile.
x_f, B_f = check_pair(predict(np.array([10.0, 60.0]), np.eye(2), A, np.zeros((2, 2))), "predict", "x_f", "B_f")
check_close(check_array(x_f, "x_f", (2,)), [11.0, 60.0], "x_f = A x for x = [10 mi, 60 mph]",
            "Move the mean with the model too: at 60 mph the train covers 1 mi in the minute.")
# With B = 0 the forecast is as uncertain as the process noise alone: B_f is the Q that predict is given.
_, B_f_0 = predict(np.array([10.0, 60.0]), np.zeros((2, 2)), A, np.diag([0.5, 2.0]))
check_close(B_f_0, np.diag([0.5, 2.0]), "B_f for B = 0, Q = diag(0.5, 2)",
            "With B = 0, B_f is Q itself: add the Q that predict is given as its argument, once, and not a Q of your "
            "own such as process_noise(15.0) or the notebook's Q.")
check_close(check_array(B_f, "B_f", (2, 2)), [[1 + 1 / 3600, 1 / 60], [1 / 60, 1.0]], "B_f = A B A^T for B = I, Q = 0",
            "Check the order of the product: A @ B @ A.T.")
x_f, B_f = predict(np.array([10.0, 60.0]), np.eye(2), A, np.diag([0.5, 2.0]))
check_close(B_f, [[1.5 + 1 / 3600, 1 / 60], [1 / 60, 3.0]], "B_f for B = I, Q = diag(0.5, 2)", "Did you add Q?")
check_symmetric(B_f, "B_f")
passed("predict")

# %% nbgrader={"grade": true, "grade_id": "test_predict", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of predict (1 point): random x, B, A, Q with n = 1 to 5.
# Validate (and this cell) first checks that predict passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(predict)
### BEGIN HIDDEN TESTS
from solutions.train_kf.hidden_tests import check_predict
check_predict(predict)
### END HIDDEN TESTS

# %% [markdown]
# ## 6. The analysis step
#
# When a fix $\vec{y}^0$ arrives, blend it with the forecast:
#
# $$K = B H^T (H B H^T + R)^{-1}, \qquad \vec{x}^a = \vec{x}^f + K(\vec{y}^0 - H\vec{x}^f), \qquad B^a = B - K H B.$$
#
# Here $B$ is the forecast covariance $B^f$. The *innovation* $\vec{y}^0 - H\vec{x}^f$ is what the fix tells us that the forecast did not know.
#
# > **Handout correction.** The handout prints $+H\vec{x}^f$ in the innovation; that sign is a typo, and
# > derivation 2 gives the minus.
#
# Write `kupdate(x_f, B_f, y, H, R)` and return `(x_a, B_a)`. You may call your `gain_covariance_form`.

# %% nbgrader={"grade": false, "grade_id": "kupdate", "locked": false, "schema_version": 3, "solution": true, "task": false}
def kupdate(x_f, B_f, y, H, R):
    """Analysis: x_f (n,), B_f (n, n), y (m,) -> x_a (n,), B_a (n, n)."""
    ### BEGIN SOLUTION
    # K = B H^T (H B H^T + R)^-1
    K = gain_covariance_form(B_f, H, R)
    # x^a = x^f + K (y^0 - H x^f)   (the handout's "+ H x^f" is a typo)
    x_a = x_f + K @ (y - H @ x_f)
    # B^a = B - K H B
    B_a = B_f - K @ H @ B_f
    return x_a, B_a
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_kupdate", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(kupdate)
# Visible checks. Forecast [10 mi, 60 mph] with B = diag(4, 9); GPS with R = diag(4, 1), so K = diag(1/2, 9/10).
x_f, B_f, R_small = np.array([10.0, 60.0]), np.diag([4.0, 9.0]), np.diag([4.0, 1.0])
x_a, B_a = check_pair(kupdate(x_f, B_f, np.array([12.0, 70.0]), np.eye(2), R_small), "kupdate", "x_a", "B_a")
check_close(check_array(x_a, "x_a", (2,)), [11.0, 69.0], "x_a for the fix y = [12 mi, 70 mph]",
            "The estimate should move towards the fix: half-way in position, 9/10 of the way in velocity. "
            "Check the sign of the innovation y - H x_f.")
check_close(check_array(B_a, "B_a", (2, 2)), np.diag([2.0, 0.9]), "B_a = (I - K H) B",
            "The analysis is more certain than the forecast: 4 -> 2 and 9 -> 0.9.")
# A fix of the position only (m = 1) also sharpens the velocity when the two are correlated in B.
x_a, B_a = kupdate(x_f, np.array([[4.0, 2.0], [2.0, 9.0]]), np.array([12.0]), np.array([[1.0, 0.0]]), np.array([[4.0]]))
check_close(check_array(x_a, "x_a with a position-only fix", (2,),
                        "Here n = 2 states and m = 1 observation: H is 1 x 2, H B H^T + R is 1 x 1 and K is 2 x 1. "
                        "Check the order of each product and your transposes."),
            [11.0, 60.5], "x_a with H = [[1, 0]]",
            "K = B H^T / (H B H^T + R) = [4, 2]/8, times the innovation 12 - 10.")
check_symmetric(B_a, "B_a")
# A scalar state (n = 1): x_f = 10, B_f = 4 and a fix y = 12 with R = 4, so K = 4 / (4 + 4) = 1/2, x_a = 11, B_a = 2.
scalar = (np.array([10.0]), np.array([[4.0]]), np.array([12.0]), np.eye(1), np.array([[4.0]]))
result = kupdate(*scalar)  # n = 1 here: size every identity from the inputs, np.eye(len(x_f))
x_a, B_a = check_pair(result, "kupdate with a scalar state", "x_a", "B_a")
check_close(check_array(x_a, "x_a with a scalar state", (1,)), [11.0], "x_a for a scalar state (n = 1)",
            "K = 1/2 moves the estimate half-way to the fix.")
check_close(check_array(B_a, "B_a with a scalar state", (1, 1)), [[2.0]], "B_a for a scalar state (n = 1)",
            "kupdate must work for any n: size each matrix from the inputs (np.eye(len(x_f)), not np.eye(2)).")
passed("kupdate")

# %% nbgrader={"grade": true, "grade_id": "test_kupdate", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of kupdate (2 points): random states and observations with n = 1 to 5, m = 1 to 3.
# Validate (and this cell) first checks that kupdate passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(kupdate)
### BEGIN HIDDEN TESTS
from solutions.train_kf.hidden_tests import check_kupdate
check_kupdate(kupdate)
### END HIDDEN TESTS

# %% [markdown]
# **Derivation 4: the analysis covariance (1 point, for (a)).** `kupdate` uses $B^a = B - KHB$. Show that
#
# $$B^a = (B^{-1} + H^T R^{-1} H)^{-1} = (I - KH)\,B .$$
#
# Write $P = (B^{-1} + H^T R^{-1} H)^{-1}$, so that $K = P H^T R^{-1}$ (derivation 2).
#
# (a) Show that $(I - KH)B = P$. *Hint.* Put in $K = P H^T R^{-1}$, then take $P$ out on the left as a common
# factor: $B = P P^{-1} B$.
#
# (b) *Worked for you, not graded:* why $P$ is the covariance of the analysis error. Assume that the forecast error
# $\vec{x}^f - \vec{x}$ (covariance $B$) and the observation error $\vec{y}^0 - H\vec{x}$ (covariance $R$) have mean
# zero and are independent. The analysis error is
# $\vec{x}^a - \vec{x} = (I - KH)(\vec{x}^f - \vec{x}) + K(\vec{y}^0 - H\vec{x})$, and $\mathrm{Cov}(M\vec{e}) =
# M\,\mathrm{Cov}(\vec{e})\,M^T$ gives its covariance $(I - KH)B(I - KH)^T + KRK^T$ (the *Joseph form*). By (a),
# $I - KH = PB^{-1}$, and $K = PH^TR^{-1}$; as $B$, $R$ and $P$ are symmetric, $(I - KH)^T = B^{-1}P$ and
# $K^T = R^{-1}HP$, so it is $PB^{-1}BB^{-1}P + PH^TR^{-1}RR^{-1}HP = P(B^{-1} + H^TR^{-1}H)P = P$. (Another route: with Gaussian errors, $J$
# is $-2\log$ of the posterior density up to a constant, and its Hessian $2P^{-1}$ says that the posterior is
# Gaussian with covariance $P$.)

# %% [markdown] nbgrader={"grade": true, "grade_id": "derivation_4", "locked": false, "points": 1, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** (a) Write $P = (B^{-1} + H^T R^{-1} H)^{-1}$, so that $K = P H^T R^{-1}$. Then
# $(I - KH)B = B - P H^T R^{-1} H B = P\left[(B^{-1} + H^T R^{-1} H)B - H^T R^{-1} H B\right] = P\,[I] = P$.
#
# **Rubric (1 point).** Any correct derivation of $(I - KH)B = P$, from either form of $K$: factoring $P$ out on the
# left (the hint), the Woodbury identity (the matrix inversion lemma) applied to derivation 3's $K$, or checking that
# $P^{-1}(I - KH)B = I$ or $(I - KH)BP^{-1} = I$. Citing (b)'s Joseph-form
# computation does not earn it, as (b) uses (a). Nothing is needed for (b), which the text works.
# ### END SOLUTION

# %% [markdown]
# ## 7. The filter
#
# Put the pieces together. Start from the belief `x0`, `B0` at minute 0. For each fix `y[t]` (the rows of
# `y`, one per minute): forecast one step with `predict`, assimilate the fix with `kupdate`, store the
# analysis, and carry it on to the next step. Return two arrays: the analyses, shape `(T, n)`, and their
# covariances, shape `(T, n, n)`.

# %% nbgrader={"grade": false, "grade_id": "run_filter", "locked": false, "schema_version": 3, "solution": true, "task": false}
def run_filter(y, x0, B0, A, Q, H, R):
    """Kalman filter over the fixes y (T, m) from the belief x0 (n,), B0 (n, n).

    Returns the analyses x_a (T, n) and their covariances B_a (T, n, n).
    """
    ### BEGIN SOLUTION
    T, n = y.shape[0], x0.shape[0]
    xs, Bs = np.empty((T, n)), np.empty((T, n, n))
    x, B = x0, B0
    for t in range(T):
        # 1. forecast to the time of observation t, 2. assimilate it, 3. repeat
        x, B = predict(x, B, A, Q)
        x, B = kupdate(x, B, y[t], H, R)
        xs[t], Bs[t] = x, B
    return xs, Bs
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_run_filter", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(run_filter, predict, kupdate)
# Visible checks. With a constant state (A = 1, Q = 0) and H = 1, R = 1, a prior of 0 with variance 1
# followed by two fixes of 2 gives the running average: 1 after one fix, (0 + 2 + 2)/3 after two.
xs, Bs = check_pair(run_filter(np.array([[2.0], [2.0]]), np.zeros(1), np.eye(1), np.eye(1), np.zeros((1, 1)),
                               np.eye(1), np.eye(1)), "run_filter", "x_a", "B_a")
check_close(check_array(xs, "the estimates", (2, 1), "One row per fix, one column per state."), [[1.0], [4 / 3]],
            "the estimates of a constant from fixes [2, 2]",
            "Each step should start from the previous analysis, forecast, then assimilate the fix.")
check_close(check_array(Bs, "the covariances", (2, 1, 1)), [[[0.5]], [[1 / 3]]], "the variances after one and two fixes",
            "Store the analysis covariance (after kupdate), not the forecast.")
# A moving state, A = [[1, 1], [0, 1]], Q = diag(0, 1), from x0 = [0, 1], B0 = I, with one fix of the position,
# y = 2 (H = [[1, 0]], R = 1). Forecast first: x_f = A x0 = [1, 1], B_f = A B0 A^T + Q = [[2, 1], [1, 2]]. Then the
# gain is [2, 1] / (2 + 1) and the innovation 2 - 1 = 1, so x_a = [5/3, 4/3] and B_a = [[2/3, 1/3], [1/3, 5/3]].
xs, Bs = run_filter(np.array([[2.0]]), np.array([0.0, 1.0]), np.eye(2), np.array([[1.0, 1.0], [0.0, 1.0]]),
                    np.diag([0.0, 1.0]), np.array([[1.0, 0.0]]), np.array([[1.0]]))
check_close(check_array(xs, "the estimates", (1, 2)), [[5 / 3, 4 / 3]], "the estimate after one fix of a moving state",
            "Forecast the belief x0, B0 to the time of the fix with predict first, then assimilate the fix with kupdate.")
check_close(check_array(Bs, "the covariances", (1, 2, 2)), [[[2 / 3, 1 / 3], [1 / 3, 5 / 3]]],
            "the covariance after one fix of a moving state", "Store the analysis covariance B_a that kupdate returns.")
passed("run_filter")

# %% nbgrader={"grade": true, "grade_id": "test_run_filter", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of run_filter (2 points): random models and 1 to 60 observations, with the reference
# predict and kupdate, so that only your loop is graded here.
# Validate (and this cell) first checks that run_filter passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(run_filter)
### BEGIN HIDDEN TESTS
from solutions.train_kf.hidden_tests import check_run_filter
check_run_filter(run_filter)
### END HIDDEN TESTS

# %% [markdown]
# ## 8. Tracking the train
#
# Run your filter over the hour and compare it with the raw GPS. The table gives the root-mean-square
# error over the 60 minutes.

# %% nbgrader={"grade": false, "grade_id": "track_train", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
require(process_noise, predict, kupdate, run_filter)
x_a, B_a = run_filter(data.gps, x0, B0, A, process_noise(15.0), H, R)
train.print_rmse_table(data, x_a)

# %% [markdown]
# The figure shows the truth, the GPS fixes and your estimate with a band of $\pm 2$ standard deviations
# ($\pm 2\sqrt{B^a_{ii}}$). The two lower panels show the errors on the scale of the filter's band; GPS errors too
# large for that scale are drawn as triangles on the panel's edge. If the filter's covariances are honest, the
# truth lies inside the band about 95% of the time; section 10 measures it over many hours. <!-- claim: train-kf/coverage-about-95 -->

# %% nbgrader={"grade": false, "grade_id": "plot_train", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(run_filter)
fig = train.plot_estimates(data, x_a, B_a)
plt.show()

# %% [markdown]
# The filter improves the position far more than the velocity. <!-- claim: train-kf/shipped-hour-rmse --> This hour is a kind one:
# over many hours the median position RMSE is about 0.9 mi, and one hour in four is as low as this one. <!-- claim: train-kf/shipped-hour-typical -->
# To see why the position is so good, here is its standard deviation through the hour (1 mi at the start, $B_0$),
# and the gain and standard deviations at the end of the hour (not yet the steady state: the position's standard
# deviation is still growing). <!-- claim: train-kf/position-sd-grows -->

# %% nbgrader={"grade": false, "grade_id": "steady_gain", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
require(process_noise, predict, gain_covariance_form)
_, B_f = predict(x_a[-2], B_a[-2], A, process_noise(15.0))
print("analysis position sd at minutes 1, 10, 30, 60:", np.round(np.sqrt(B_a[[0, 9, 29, 59], 0, 0]), 2), "mi")
print("forecast sd:  position %.2f mi, velocity %.1f mph" % tuple(np.sqrt(np.diag(B_f))))
print("analysis sd:  position %.2f mi, velocity %.1f mph" % tuple(np.sqrt(np.diag(B_a[-1]))))
print("gain K (rows: position, velocity; columns: position fix, velocity fix):")
print(np.round(gain_covariance_form(B_f, H, R), 4))

# %% [markdown]
# **Question (2 points).** Why does the filter improve the position so much more than the velocity, compared with the GPS
# alone? Use the model and the printed gain. A paragraph is enough: 1 point for why the position is so good, 1 point for
# why the velocity is not much better than a fix.

# %% [markdown] nbgrader={"grade": true, "grade_id": "position_question", "locked": false, "points": 2, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** On the shipped hour the position RMSE falls from about 10 mi (GPS) to about 0.6 mi, the
# velocity RMSE only from about 11 to about 9 mph. <!-- claim: train-kf/shipped-hour-rmse --> The shipped hour is a
# kind one: over many hours the median position RMSE is about 0.9 mi and its root-mean-square 1.16 mi, and about one
# hour in four is as low as 0.64 mi. <!-- claim: train-kf/shipped-hour-typical --> Over many
# simulated hours it is the same story: in a typical hour the filter's position error is about a tenth of the
# GPS's, its velocity error about 0.85 of it. <!-- claim: train-kf/position-vs-velocity-over-hours -->
#
# Two things make the position so good: the start and the model. The filter starts knowing the position to
# 1 mi (the train leaves the station, $B_0$). Position is the integral of the velocity ($x_{t+1} = x_t + v_{t+1}/60$),
# so every velocity fix, integrated through $A$, tells the filter how far the train moved in that minute, to about
# $10/60$ mi. So the position uncertainty does not shrink during the hour, it grows, but only slowly: its standard
# deviation goes from 1 mi at the start to 1.01 mi after the first minute and 1.24 mi at minute 60 (1.29 mi in the
# long run). <!-- claim: train-kf/position-sd-grows --> At the end of the hour the position *forecast* is good to
# about 1.3 mi, against 10 mi for a position fix, so a position fix gets a gain of only about 0.015. <!-- claim: train-kf/steady-gain -->
# Without the station start the position fixes would need tens of minutes to bring the position in. Velocity fixes
# alone cannot: they say how far the train moved, not where it started (with them alone a 10-mi start stays at
# 10 mi all hour). With the velocity fixes pinning each minute's move, the filter averages the position fixes, about
# $10/\sqrt{n}$ mi after $n$ minutes: the same filter started with a position standard deviation of 10 mi still has
# 3 mi after ten minutes and 1.9 mi after thirty, and its root-mean-square position error over the hour, in
# expectation, is about 2.5 mi, a quarter of the GPS's rather than a tenth (1.16 mi with the station start). <!-- claim: train-kf/vague-start --> The velocity has no such
# help: it changes by 15 mph every minute, more than the 10 mph error of a fix, so the forecast velocity (standard
# deviation about 17 mph) is worse than a fix, the filter takes about three quarters of each velocity innovation, and its
# velocity is only a little better than the GPS's (about 8.7 mph against 10). <!-- claim: train-kf/steady-sd -->
#
# **Rubric (2 points).** 1 point: the position forecast is far better than a position fix, so the position fix
# gets a small gain, <!-- claim: train-kf/steady-gain --> because the model ties the position change to the
# velocity (the velocity fixes integrated through $A$), or because the filter starts knowing the position to 1 mi
# and the velocity fixes keep that uncertainty from growing much; either reason, or both, earns the point. Saying that
# the position uncertainty shrinks during the hour misreads the printed standard deviations (they grow from 1 to about
# 1.24 mi); <!-- claim: train-kf/position-sd-grows --> that slip costs the point only if it is the whole reason given. 1 point: the velocity changes by more each minute (15 mph) than a fix's
# error (10 mph), so the forecast velocity is poor, the velocity gain is large (about 0.75) and the estimate
# mostly follows the velocity fixes. <!-- claim: train-kf/steady-sd --> Words without the printed numbers earn full marks.
# ### END SOLUTION

# %% [markdown]
# ## 9. Playing with the covariances
#
# The filter trusts its model through $Q$ and the GPS through $R$. What if those numbers are wrong? Below,
# the data always come from the true process, but the filter is told $Q$ (or $R$) multiplied by a
# factor from 1/100 to 100. Each point is the mean over 20 simulated hours of each hour's RMSE, so it varies
# from one set of 20 hours to another. At factor 1, a few bad hours lift it above the typical hour's 0.9 mi of
# section 8. <!-- claim: train-kf/factor-one-above-typical -->
#
# The starting belief $B_0$ is not scaled, so a factor on $R$ also changes how much the filter trusts its start
# ($R \times c$ acts as $Q/c$ *and* $B_0/c$), <!-- claim: train-kf/r-scaling-equivalence --> which it remembers for much of the hour. <!-- claim: train-kf/vague-start -->

# %% nbgrader={"grade": false, "grade_id": "covariance_scaling", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(process_noise, predict, kupdate, run_filter)
factors = np.logspace(-2, 2, 9)
scaling = train.covariance_scaling_experiment(run_filter, process_noise(15.0), factors, n_runs=20,
                                              rng=np.random.default_rng(60))
fig = train.plot_covariance_scaling(scaling)
plt.show()


# %% [markdown]
# **Before the question: $Q$ has rank one.** Section 4 found $Q = \sigma^2 \vec{g}\,\vec{g}^T$ with $\vec{g} = (h, 1)$.
# Think of the state as a point in the (position, velocity) plane.
#
# * Each minute the noise moves the train only along $\vec{g}$: a speed change $z$ always comes with the
#   position change $h z$. So the band that $Q$ adds to the forecast is a thin one along $\vec{g}$. A factor on $Q$
#   makes it longer or shorter; it never turns it.
# * Across $\vec{g}$ the model adds no uncertainty, whatever the factor: the true train always has
#   $x_{t+1} - h\,v_{t+1} = x_t$, and the forecast says the same of its own estimate. <!-- claim: train-kf/q-rank-one -->
#   So each velocity fix also tells the filter the distance covered in its minute, whatever the factor.
#
# So a factor on $Q$ changes how far the fixes move the estimate along $\vec{g}$, never the model's link between the
# new position, the old one and the new speed. This explains the position curve for $Q$; the question below does not
# grade the explanation.

# %% [markdown]
# **Question (2 points, 1 per panel).** Describe the figure panel by panel: for the position and for the velocity,
# where is each curve lowest (or is it flat?), and how does its RMSE compare with the GPS's when the filter's $Q$, or its $R$, is too
# small or too large? A correct description of both curves of a panel earns its point. *Not graded, to think
# about:* the two ways the velocity goes wrong, and why the position curve for $Q$ looks so different from the one
# for $R$ (the note above).

# %% [markdown] nbgrader={"grade": true, "grade_id": "covariance_question", "locked": false, "points": 2, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** With the true $Q$, $R$ and starting belief the filter is the optimal (minimum mean-square
# error) estimator for these data, so the *expected squared error* of every curve of both panels is lowest at
# factor 1. <!-- claim: train-kf/optimal-at-1 --> The figure shows something else, a mean over 20 hours of each hour's
# RMSE, which scatters from one set of 20 hours to another.
# *Velocity (right panel).* Both curves are lowest at factor 1, the true covariances. <!-- claim: train-kf/velocity-minimum-at-1 -->
# With $Q$ too small the filter over-trusts its
# constant-velocity model: the gain is small, the estimate ignores the velocity fixes and lags behind the real
# changes of speed, and at $Q/100$ its error is roughly twice the GPS's or more. <!-- claim: train-kf/velocity-q-small -->
# With $Q$ too large the filter follows every noisy fix, and its error rises towards the GPS's from below (at
# $Q \times 100$ it is within 1% of it). <!-- claim: train-kf/velocity-q-large --> The $R$ curve is the mirror
# image: a large $R$ ignores the GPS, a small $R$ copies it. <!-- claim: train-kf/velocity-r-mirror -->
#
# *Position (left panel).* Every point lies well below the GPS line: in a typical figure (a set of 20 hours) the
# highest is about a quarter of the GPS error. <!-- claim: train-kf/position-below-gps --> The curve for $Q$ is nearly flat: from $Q/10$
# to $Q \times 100$ the position RMSE changes by only a few percent (less than 5% in almost every set of 20
# hours, though a single hour can move more), and
# at $Q/100$ it rises only a little. Its expected
# value varies by less than 0.3% from $Q/10$ to $Q \times 100$, far less than the scatter of a mean over 20 hours,
# so the figure cannot show where its minimum lies (for the expected squared error, at 1). <!-- claim: train-kf/q-scaling-position-flat -->
# $Q = \sigma^2 \begin{bmatrix} h^2 & h \\ h & 1 \end{bmatrix}$ has
# rank one (the note before the question): whatever the factor, it adds no uncertainty across $\vec{g} = (h, 1)$
# and says that the position's noise is exactly $h$ times the velocity's, so the
# filter builds its position from the velocity fixes integrated through $A$ (section 8), however much it trusts
# the model's velocity. The curve for $R$ is a shallow U, lowest near factor 1 and higher at both ends. <!-- claim: train-kf/r-scaling-position-u -->
# Scaling $R$ is not the mirror of scaling $Q$ here: multiplying
# $R$ by $c$ gives exactly the filter with $Q$ *and* $B_0$ divided by $c$, so it also changes how much the filter
# trusts its initial belief against the fixes. <!-- claim: train-kf/r-scaling-equivalence -->
# On the figure, the $R$ curve's position ends are about 2.4 mi at $R/100$ and 2.1 mi at $R \times 100$, against
# 1.3 mi at 1. <!-- claim: train-kf/r-scaling-shipped-figure --> Which end is higher varies with the 20 hours: the
# small-$R$ end is the higher in 3 to 4 sets of 20 hours in 10, as here; averaged over many sets the three points are
# about 2.2, 2.3 and 1.05 mi. <!-- claim: train-kf/r-scaling-end-order -->
# Over many hours, the root of the expected squared position error (written "expected error" below) is 2.32 mi
# with $R/100$ and 2.74 mi with $R \times 100$, against 1.16 mi with the true covariances. The small-$R$ end is
# a filter that distrusts its good start: $B_0 \times 100$ alone gives the same 2.32 mi. The large-$R$ end comes
# from the combination: $B_0/100$ alone gives 1.22 mi and $Q/100$ alone 1.25 mi. The filter ignores the position
# fixes while its velocity lags behind the real speed (the velocity panel), so the position, built from that
# velocity, drifts away and no fix pulls it back; a few hours drift far, which makes the expected error at
# $R \times 100$ large. <!-- claim: train-kf/r-scaling-ends -->
# Much of the gap between the two curves comes from the start of the run, and a longer run shrinks it: over 600
# minutes the expected error with $R \times 100$ is 1.76 mi against 1.51 mi for $Q/100$, and $R/100$ 1.43 mi against 1.27 mi for
# $Q \times 100$. <!-- claim: train-kf/r-scaling-long-run -->
#
# **Rubric (2 points).** 1 point: the velocity panel read correctly: both curves lowest at 1; <!-- claim: train-kf/velocity-minimum-at-1 -->
# $Q$ too small lags behind the speed changes with an error well
# above the GPS's; <!-- claim: train-kf/velocity-q-small --> $Q$ too large follows the fixes, its error approaching
# the GPS's from below; <!-- claim: train-kf/velocity-q-large --> $R$ mirrors $Q$. <!-- claim: train-kf/velocity-r-mirror --> 1 point: the position panel read correctly: far below the
# GPS everywhere, <!-- claim: train-kf/position-below-gps --> the $Q$ curve flat (naming its lowest plotted point
# too is fine, as long as the curve is called flat), <!-- claim: train-kf/q-scaling-position-flat -->
# the $R$ curve lowest near 1 and rising at both ends. <!-- claim: train-kf/r-scaling-position-u -->
# Either order of the $R$ curve's two ends is right when it is read correctly from the student's figure: over many
# sets of 20 hours the small-$R$ end is the higher in 3 to 4 sets in 10. <!-- claim: train-kf/r-scaling-end-order -->
# A correct description
# of each panel earns both points without the explanations. For the position curve for $Q$, "flat" and "lowest
# expected squared error at 1, since the true covariances give the optimal filter" are both correct readings. <!-- claim: train-kf/optimal-at-1 -->
# The explanations are not graded. For the instructor, these are correct ones for why the position curves for $Q$
# and $R$ differ: the starting belief $B_0$ held fixed while $R$ is scaled (a factor on $R$ also changes the trust
# in the start, which matters for most of a one-hour run); or the rank one of $Q$ (a factor on $Q$ adds no
# uncertainty across $\vec{g}$, so the position keeps coming from the velocity fixes integrated through $A$); or both.
# An answer that says the position error approaches the GPS's when $Q$ is large
# misreads the position panel and does not earn its point.
# ### END SOLUTION

# %% [markdown]
# ## 10. Is the filter honest? Measuring consistency
#
# The band in section 8 is the filter's own statement of its error. A filter is *consistent* when its errors are
# as large as its covariance says, no larger and no smaller. Two measures, over many simulated hours (the
# simulation is exactly the filter's model, so a correct filter should pass both):
#
# * the fraction of each hour in which the truth lies inside the $\pm 2\sigma$ band: 95.45% on average for a
#   Gaussian error;
# * the **normalised estimation error squared** (NEES), with the error $\vec{e}_t = \vec{x}^a_t - \vec{x}_t$,
#   $$\epsilon_t = \vec{e}_t^{\,T} (B^a_t)^{-1} \vec{e}_t .$$
#   It weighs the position and velocity errors, and their correlation, by the filter's own covariance. For a
#   consistent filter $\epsilon_t$ is $\chi^2$ with $n = 2$ degrees of freedom (mean 2); averaged over $N$
#   independent hours it is $\chi^2_{2N}/N$, which gives the band in the figure below.
#
# Write `nees(errors, covariances)`: `errors` has shape `(T, n)`, `covariances` shape `(T, n, n)`, and the result
# is the NEES at each time, shape `(T,)`. Solve with $B^a_t$ rather than inverting it: `np.linalg.solve` works on stacks of matrices, and in NumPy 2
# its right-hand side must be a stack too. A `(T, n)` right-hand side is read as one matrix, so solve with
# `errors[..., None]`, shape `(T, n, 1)`, and take `[..., 0]` of the result.

# %% nbgrader={"grade": false, "grade_id": "nees", "locked": false, "schema_version": 3, "solution": true, "task": false}
def nees(errors, covariances):
    """NEES at each time, shape (T,), from errors (T, n) and covariances (T, n, n)."""
    ### BEGIN SOLUTION
    # B_t^-1 e_t, one solve per time (np.linalg.solve works on stacks of matrices)
    scaled = np.linalg.solve(covariances, errors[:, :, None])[:, :, 0]
    # eps_t = e_t^T B_t^-1 e_t
    return np.sum(errors * scaled, axis=1)
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_nees", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(nees)
# Visible checks. e = [4, 0] with B = diag(4, 1) gives 4^2/4 = 4. e = [1, 1] with B = [[2, 1], [1, 2]]:
# B^-1 = [[2, -1], [-1, 2]]/3, so e^T B^-1 e = 2/3 (the correlation matters: the diagonal alone would give 1).
errors = np.array([[4.0, 0.0], [1.0, 1.0]])
covariances = np.array([np.diag([4.0, 1.0]), [[2.0, 1.0], [1.0, 2.0]]])
value = check_array(nees(errors, covariances), "nees(errors, covariances)", (2,),
                    "One value per time: errors (T, n) and covariances (T, n, n) give shape (T,). In NumPy 2, "
                    "np.linalg.solve reads a (T, n) right-hand side as one matrix: solve with errors[..., None].")
check_close(value[0], 4.0, "the NEES of e = [4, 0] with B = diag(4, 1)",
            "It is e^T B^-1 e = 4^2/4 = 4, the squared distance itself: solve with B rather than multiply by it "
            "(that gives 64), and take no square root (that gives 2) and no mean over the n = 2 states (2 again).")
check_close(value[1], 2 / 3, "the NEES of e = [1, 1] with B = [[2, 1], [1, 2]]",
            "Use the whole covariance, off-diagonal terms included: solve B x = e, then take e . x.")
passed("nees")

# %% nbgrader={"grade": true, "grade_id": "test_nees", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of nees (1 point): random errors and covariances with n = 1 to 5 and 1 to 60 times.
# Validate (and this cell) first checks that nees passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(nees)
### BEGIN HIDDEN TESTS
from solutions.train_kf.hidden_tests import check_nees
check_nees(nees)
### END HIDDEN TESTS

# %% [markdown]
# Now run your filter on 200 fresh simulated hours and measure both. The left panel counts hours by the fraction
# of their minutes with the truth inside the band; the right panel shows, minute by minute, the NEES averaged
# over the hours, with the 95% $\chi^2$ band for that average.

# %% nbgrader={"grade": false, "grade_id": "consistency", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(process_noise, run_filter, nees)
consistency = train.consistency_experiment(run_filter, nees, process_noise(15.0), n_hours=200,
                                           rng=np.random.default_rng(10))
fig = train.plot_consistency(consistency)
plt.show()

# %% nbgrader={"grade": false, "grade_id": "consistency_summary", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
require(run_filter, nees)
inside, low, high = consistency.inside, *train.nees_band(len(consistency.nees))
mean_nees = consistency.nees.mean(axis=0)
print(f"truth inside ±2σ over all hours: position {inside[:, 0].mean():.3f}, velocity {inside[:, 1].mean():.3f}")
print(f"hours with the position inside the band all hour: {np.sum(inside[:, 0] == 1.0)} (of {len(inside)})")
print(f"hours with the truth inside for less than 3/4 of the hour: position {np.sum(inside[:, 0] < 0.75)},"
      f" velocity {np.sum(inside[:, 1] < 0.75)} (of {len(inside)})")
print(f"mean NEES over all hours and minutes: {consistency.nees.mean():.2f}")
print(f"minutes whose mean NEES is inside the 95% band [{low:.2f}, {high:.2f}]: "
      f"{np.sum((mean_nees >= low) & (mean_nees <= high))} of {len(mean_nees)}")

# %% [markdown]
# **Before the question: errors that last.** One hour's fraction is a steady measure only if its 60 minutes are
# nearly independent samples. An error that the filter corrects slowly lasts for many minutes: the errors of
# nearby minutes are then *correlated in time*, and a long run of them counts for little more than one sample.
# The gains printed in section 8 say how much of an error each fix removes.

# %% [markdown]
# **Question (2 points, 1 for each part).** What do the two panels say: is the filter consistent? Why is the per-hour fraction so much more
# spread out for the position than for the velocity?

# %% [markdown] nbgrader={"grade": true, "grade_id": "consistency_question", "locked": false, "points": 2, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** Over all the hours the truth is inside the band about 95% of the time, for the position and
# for the velocity, as a consistent filter should be. <!-- claim: train-kf/coverage-over-hours --> A single hour
# says much less about the position: its errors persist for many minutes. The position gain is only about 0.015
# (section 8), <!-- claim: train-kf/steady-gain --> and the position errors, each divided by the filter's standard
# deviation, are correlated by about 0.98 one minute apart, 0.85 ten minutes apart and still 0.6 thirty minutes apart. <!-- claim: train-kf/error-persistence -->
# So an hour's position errors are nearly one draw: as the printed counts
# show, in about three hours in four the position is inside the band all hour long, while in about 6% of hours
# the truth is outside for a quarter of the hour or more (the printed count out of 200 varies from set to set). <!-- claim: train-kf/coverage-per-hour-spread --> Velocity
# errors are renewed within a minute or two: three quarters of each innovation is taken, and their correlation is
# about 0.25 one minute apart and near zero (0.06) two minutes apart, <!-- claim: train-kf/error-persistence --> so
# the velocity fraction of almost every hour stays between 85% and 100%. <!-- claim: train-kf/coverage-per-hour-spread --> The NEES averaged over the hours scatters around 2 inside the
# 95% $\chi^2$ band at most minutes: a few minutes outside it are expected (about 1 in 20 on average), and its
# mean over all hours and minutes is close to 2: it varies by about ±0.08 (one standard deviation) from one set
# of 200 hours to another. <!-- claim: train-kf/nees-band -->
# So the filter is consistent: its band is honest on average, and one hour
# alone could neither confirm nor refute that.
#
# **Rubric (2 points).** 1 point: consistency read from the figure: about 95% inside over all hours, <!-- claim: train-kf/coverage-over-hours -->
# the NEES near 2 and mostly inside its band. <!-- claim: train-kf/nees-band -->
# 1 point: the wider spread of the position fraction <!-- claim: train-kf/coverage-per-hour-spread -->
# explained by its persistent (slowly corrected, correlated in time) errors, against the quickly renewed velocity
# errors: the small position gain of section 8, or "fewer independent samples per hour", or the same idea in other
# words, earns the point. The exact correlations are not needed.
# ### END SOLUTION

# %% [markdown]
# ## 11. Going further
#
# Nothing in this section is graded. It holds the details behind the main text, for when you want more.
#
# **Try it yourself.** Try an observation operator that sees only the position, `H = np.array([[1.0, 0.0]])`
# with `R = np.array([[100.0]])`, and give the filter the position column only, `hour.gps[:, :1]`: can it still
# estimate the speed? With `rng = np.random.default_rng(1)`, `hour = train.simulate(60, rng)` is a fresh hour, with
# its truth in `hour.truth`.


# %% [markdown]
# ### How restless is this train?
#
# A random walk with steps of 15 mph is a restless train. Over an hour its speed changes by an amount whose standard
# deviation is $15\sqrt{60} \approx 116$ mph (its typical size, the mean absolute change, is about 93 mph). <!-- claim: train-kf/speed-drift -->
# In about one simulated hour in three the train stops and reverses. <!-- claim: train-kf/speed-reverses -->
# We ship an hour in which it keeps going forward.

# %% [markdown]
# ### Which form of the gain is cheaper?
#
# Which form is cheaper depends on what each has to invert (or factorise):
#
# * the **covariance form** solves with $S = HBH^T + R$: one $m \times m$ matrix;
# * the **information form** needs $B^{-1}$ ($n \times n$), $R^{-1}$ (a solve with the $m \times m$ matrix $R$),
#   and then a solve with $B^{-1} + H^T R^{-1} H$ ($n \times n$): two $n \times n$ factorisations and one $m \times m$.
#
# So the covariance form is the usual choice. The information form pays off when $R^{-1}$ is cheap (a diagonal
# $R$, independent sensors), $B^{-1}$ is already at hand (an *information filter* carries $B^{-1}$ rather than
# $B$), and there are many more observations than states ($m \gg n$): then it never touches an $m \times m$
# system at all.


# %% [markdown]
# ### The noise belongs to the step
#
# `process_noise` is a *velocity random walk*: once per step the velocity jumps by $z \sim N(0, \sigma^2)$, with
# $\sigma$ given **per step**, and the position carries the jump for the whole step ($x_{t+1} = x_t + h\,v_{t+1}$).
# So $Q_{vv} = \sigma^2$ whatever the step. With the same $\sigma$, one-minute steps let the velocity variance grow by
# $60\sigma^2$ per hour, and two-minute steps by only $30\sigma^2$. To keep the velocity's variance per hour with a
# different step, $\sigma$ must scale with $\sqrt{\texttt{dt\_min}}$. Even then the position noise depends on the
# step (two one-minute steps give a position variance of $5\sigma^2h^2$, one two-minute step $8\sigma^2h^2$), <!-- claim: train-kf/walk-step-dependence -->
# so the random walk describes a slightly different train at each step. The CWNA model below does not.

# %% [markdown]
# ### Where the continuous white-noise acceleration model comes from
#
# In the continuous white-noise acceleration (CWNA) model the acceleration $w(s)$ is white noise with spectral
# density $q$ (mph² per hour): $E[w(s)\,w(s')] = q\,\delta(s - s')$. Over a step of $h$ hours the velocity gains
# $\int_0^h w(s)\,ds$ and the position $\int_0^h (h - s)\,w(s)\,ds$. Their variances and covariance are
# $q\int_0^h ds = qh$, $q\int_0^h (h - s)^2 ds = qh^3/3$ and $q\int_0^h (h - s)\,ds = qh^2/2$, which is
#
# $$Q_{\mathrm{CWNA}} = q \begin{bmatrix} h^3/3 & h^2/2 \\ h^2/2 & h \end{bmatrix}.$$
#
# Here $q$ is per unit of time, so the same $q$ describes the same train for any step: two steps of $h$ give the
# $Q$ of one step of $2h$. <!-- claim: train-kf/cwna-steps-compose --> Compare the random walk at
# the same rate, $q = \sigma^2/h$: its position variance is $\sigma^2 h^2 = q h^3$, the CWNA model's $q h^3/3$, a third.
# Its covariance is half the random walk's. <!-- claim: train-kf/wna-vs-walk-q -->
# The position noise is smaller because the velocity changes gradually during the step instead of all at its start.
# This $Q$ has full rank, unlike the random walk's: the position's noise is strongly correlated with the velocity's
# (correlation $\sqrt{3}/2 \approx 0.87$), but not tied to it. <!-- claim: train-kf/cwna-correlation -->
# Do not confuse it with the *discrete* white-noise acceleration model of the same textbook, in which the
# acceleration $a$ is constant during each step, with variance $\sigma_a^2$. There the position gains $h^2 a/2$ and the velocity $h a$, so
# $Q = \sigma_a^2 \begin{bmatrix} h^4/4 & h^3/2 \\ h^3/2 & h^2 \end{bmatrix}$: one noise input again, and rank one. <!-- claim: train-kf/cwna-correlation -->

# %% [markdown]
# ### Two noise models on the shipped hour
#
# Tracking often uses the CWNA model above rather than the velocity random walk of `process_noise`. With
# $q = 225 \times 60$ mph²/h both add 225 mph² of velocity variance per minute. <!-- claim: train-kf/wna-vs-walk-q -->
# The cell below runs the filter with each on the shipped hour.

# %% nbgrader={"grade": false, "grade_id": "noise_models", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
require(process_noise, run_filter)
q = 15.0**2 * 60.0  # mph^2 per hour: 225 mph^2 of velocity variance per minute, as in the random walk
models = {"velocity random walk (process_noise)": process_noise(15.0),
          "CWNA (white-noise acceleration)": train.white_noise_acceleration(q)}
for name, Q_model in models.items():
    print(f"{name:<38} Q = {np.round(Q_model, 4).tolist()}")
train.print_model_comparison(data, {name: run_filter(data.gps, x0, B0, A, Q_model, H, R)[0]
                                    for name, Q_model in models.items()})

# %% [markdown]
# On the shipped hour the two filters are almost the same: about 0.64 and 0.67 mi in position, 9.28 and 9.26 mph
# in velocity. <!-- claim: train-kf/noise-models-shipped --> The CWNA model has a third of the random walk's position
# variance (0.0208 against 0.0625 mi²) and half its covariance (1.875 against 3.75 mi·mph). <!-- claim: train-kf/wna-vs-walk-q -->
# The data come from the random walk (`train.forward??` shows that each velocity jump is carried for the whole
# minute). The true states show it at once: in `data.truth`, $x_{t+1} - x_t - h\,v_{t+1}$ is zero to rounding, where
# CWNA would give it a standard deviation of about 0.14 mi. <!-- claim: train-kf/truth-identity -->
#
# The filters' errors on one hour cannot show it. Both filters see the same fixes, so the scale to judge their gap by
# is the gap's own spread from hour to hour: over many simulated hours the CWNA filter's position RMSE is on average
# 0.11 mi above the random walk's, with a standard deviation of 0.31 mi (from −0.39 to +0.65 mi in 90% of hours). <!-- claim: train-kf/noise-models-paired-gap -->
# The shipped hour's 0.03 mi is well inside that spread. The random-walk filter has the smaller position error in
# about 2 hours in 3, while the velocity errors agree to within 1%. <!-- claim: train-kf/noise-models-over-hours -->
# Averaged over 40 hours the gap shows: the random walk wins in about 49 sets of 50. <!-- claim: train-kf/noise-models-paired-gap -->
# To see it yourself, run both filters on a few dozen hours from `train.simulate` and compare
# `train.rmse(x_a, hour.truth)` of each.

# %% [markdown]
# ### Why the rank of $Q$ matters in section 9
#
# The flat position curve for $Q$ in section 9 comes from $Q$'s rank one. If the true train and the filter both used
# the full-rank CWNA $Q$ above, the curve would not be flat: the expected position error at $Q \times 100$ is about
# 47% above the one at 1, against less than 0.3% for the random walk. <!-- claim: train-kf/q-rank-matters --> A full-rank
# $Q$ adds uncertainty across $\vec{g}$, so a large factor makes the filter lean on the noisy position fixes.

# %% [markdown]
# ### Where this lab differs from the handout
#
# The handout "More Train Fun" has a few slips. The one-line corrections in the main text say what we changed;
# here is why.
#
# * **The position update (section 1).** The handout writes $x_{t+1} = \frac{v_t}{60} x_t + \frac{z}{60}$, which
#   multiplies position by velocity. Its first, noise-free form $x_{t+1} = x_t + v_t/60$ does not fit its own
#   $Z = (z/60, z)$ either: a position noise of $z/60$ means that the position moves with the new velocity,
#   $x_{t+1} = x_t + v_{t+1}/60$. That is the model of section 1, and it is what $A$ and $Z$ say.
# * **Which $\sigma$ (section 4).** The handout says the position noise $z/60$ has "$\sigma = 15/60$". That is its
#   standard deviation in miles. The $\sigma$ in $Q$ is the velocity noise, $\sigma = 15$ mph. With $h = 1/60$ our
#   $Q$ is the handout's $Q$ exactly.
# * **The forecast error (section 5).** The handout derives the forecast covariance from the error
#   $A(\vec{x}_{t-1} - \vec{x}^f_{t-1}) + Z$. The forecast starts from the previous *analysis*, so the error is
#   $A(\vec{x}_{t-1} - \vec{x}^a_{t-1}) + Z$, and the covariance carried forward is the analysis covariance $B^a_{t-1}$.
# * **The time indices (section 5).** The handout's forecast equations put $\vec{x}^f_{t+1} = A\vec{x}_t$ next to
#   $B_t = AB_{t-1}A^T + Q$, one step apart. Section 5 writes both for the same step, and the superscripts $f$ and
#   $a$ say which covariance is which.
# * **The sign of the innovation (section 6).** The handout prints $\vec{x}^a = \vec{x}^f + K(\vec{y}^0 + H\vec{x}^f)$.
#   With a plus, the estimate moves away from the observation. Derivation 2 gives the minus.
#
# The handout also states $B^a = B - KHB$ without a derivation; derivation 4 supplies one. Its MATLAB files
# `predict.m`, `Kupdate.m` and `Run.m` are our `predict`, `kupdate` and `run_filter`.
