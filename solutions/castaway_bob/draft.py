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
# # Lab castaway-bob: saving Castaway Bob with Kalman filters
#
# Bob fell off a cruise ship near a small island. He can't swim, but his life jacket keeps him afloat, and
# his phone's SOS mode sends his GPS position once a minute. Each fix is off by about 50 m, and the rescue
# boat needs better than that. Meanwhile the current carries Bob through the eddies that the island sheds.
# In this lab you build the handout's three estimators of where Bob is, add a control that the handout
# lacks, and test the handout's claim about which is best.
#
# **What you will do**
# 1. Write Bob's state-space model: the matrices $A$ and $H$.
# 2. Write the simplest estimator: the mean of the last three fixes, a trailing moving average.
# 3. Write the Kalman gain and the Joseph form of the covariance update, and derive the gain.
# 4. Write one step of a Kalman filter with a known input.
# 5. Write two filters: a rank-2 filter that knows nothing about the sea, and a rank-4 filter that knows the
#    current. Like the handout, we call the length of a filter's state vector its **rank**: the rank-2 state is
#    Bob's position (x, y), the rank-4 state adds his own velocity. (It is not the rank of a matrix.)
# 6. Score them over many simulated drifts, with a control we give you, and decide whether the handout's
#    ranking holds.
#
# **What is graded, and about how long each part takes**
#
# | part | what you write | points | about |
# |---|---|---|---|
# | 1–2. Bob's ocean and his model | `transition_matrix`, `observation_matrix` | 2 | 20 min |
# | 3. A trailing moving average | `trailing_mean` | 2 | 15 min |
# | 4. The Kalman gain | `kalman_gain`, `joseph_covariance`, a derivation (written answer 1) | 7 | 50 min |
# | 5. One filter step | `kalman_step` | 3 | 20 min |
# | 6. Two Kalman filters | `run_rank2`, a derivation (written answer 2), `run_rank4` | 10 | 55 min |
# | 7. Which estimator is best? | `track_rmse`, `ellipse_area`, a discussion of the results (written answer 3) | 4 | 30 min |
# | **all** | 10 functions, 3 written answers | **28** | **about 3 h 10 min** |
#
# Hidden tests grade the code blanks; the written answers are marked by hand. Section 8, *Going further*,
# holds extra experiments and notes on the handout: read it if you like, nothing there is graded.
#
# **How this notebook works.** Each blank is one function in a cell that says `YOUR CODE HERE`. Below it, a
# read-only cell runs *visible checks* on cases you can work out by hand, and their messages say what to fix.
# When your work is graded, *hidden tests* compare your function with a reference on random inputs (other
# sizes, parameters and currents), so write general code, not code for Bob's numbers only. Each function is
# graded on its own: a mistake in one blank does not cost you the points of the blanks that use it. A graded
# function must return new arrays and leave the ones it is given as they are; the checks fail a function that
# writes into its arguments. Units are SI: metres, seconds, m/s. The figures show km and minutes.
#
# **Locked cells.** The grey cells (the set-up, the checks, the graded cells, the figures) are read-only. Grading
# puts back the original of each, so an edit there would be lost. Write only in the cells marked
# `YOUR CODE HERE` and `YOUR ANSWER HERE`. Before you submit, press **Validate** in the toolbar: it runs the
# notebook and lists each blank that is not written yet or does not pass its visible checks.
#
# *Credit.* This lab follows the handout "Saving Castaway Bob" by Thelonious Cooper (EECS, MIT, May 2024),
# which used the Julia fluid solver WaterLily.jl for the ocean. The text, code, flow and data here are our
# own, and so are any errors. Where the handout has a slip, we say so and use the corrected form.

# %% nbgrader={"grade": false, "grade_id": "setup", "locked": true, "schema_version": 3, "solution": false, "task": false}
# Set-up: run this cell first.
# %xmode Minimal
# %matplotlib inline
import numpy as np
import matplotlib.pyplot as plt

from course import ocean
from course.ocean import ALPHA, SIGMA_F, SIGMA_GPS
from course.checks import (check_array, check_close, check_pair, check_symmetric, check_true, passed, random_spd,
                           require, validate)

# %% [markdown]
# ## 1. Bob's ocean
#
# Bob drifts in the wake of an island 1 km across, in a 0.5 m/s current. Behind the island the flow
# breaks into a **Kármán vortex street**: eddies that the island sheds from alternate sides, which then
# drift downstream.
#
# We computed this flow with a Navier-Stokes solver in Python, [PhiFlow](https://github.com/tum-pbs/PhiFlow),
# in place of the handout's WaterLily.jl. A real island wake is far too turbulent for any grid, so we simulated
# a gentler wake and rescaled it to the ocean; Section 8 says how, and why that is a fair stand-in. The flow
# is shipped as velocity snapshots every 6 minutes on a 200 m grid, over a 5-hour window. `ocean.load()`
# interpolates them linearly in $x$, $y$ and $t$.

# %% nbgrader={"grade": false, "grade_id": "show_flow", "locked": true, "schema_version": 3, "solution": false, "task": false}
flow = ocean.load()
print(f"grid {len(flow.x)} x {len(flow.y)} points, {flow.x[1] - flow.x[0]:.0f} m apart; "
      f"{len(flow.t)} snapshots over {flow.duration / 3600:.0f} h; Re = {flow.reynolds:.0f}; {flow.solver}")
print(f"current far upstream: {np.round(flow(np.array([-4500.0, 0.0]), 0.0), 2)} m/s;  "
      f"fastest anywhere: {np.linalg.norm(flow.velocity, axis=-1).max():.2f} m/s")
fig, axes = plt.subplots(2, 1, figsize=(11, 8.6))
for ax, t in zip(axes, (0.0, 90 * 60.0)):
    ocean.plot_flow(flow, t, ax=ax)
fig.tight_layout()


# %% [markdown]
# Red eddies spin anticlockwise and blue ones clockwise. Between the two snapshots, 90 minutes apart, each
# eddy has moved about 2.4 km downstream, a little slower than the current, <!-- claim: castaway-bob/eddies-move-2-4-km --> and new
# eddies have formed behind the island. The grey lines are streamlines
# of the current at that instant. Bob does not follow them exactly, because the current changes while he
# drifts.

# %% [markdown]
# ## 2. Bob's model
#
# Bob's state (1) is his position and his own velocity relative to the water. Wind, waves and fish push
# him around:
#
# $$\vec{x} = \begin{bmatrix} x \\ y \\ w_x \\ w_y \end{bmatrix}, \qquad
#   \vec w[n+1] = \alpha\,\vec w[n] + \vec F[n], \quad \vec F[n] \sim \mathcal N(0, \sigma_F^2 I_2),$$
#
# with a weak damping $\alpha < 1$ and one step per GPS fix, $dt = 60$ s. Bob is a neutrally buoyant
# particle, so the water carries him. During the minute, his position follows
# $d\vec p/dt = \vec u(\vec p, t) + \vec w[n]$. Our simulator integrates this with Runge-Kutta substeps
# on the interpolated current. In still water ($\vec u = 0$) this is the handout's linear model (2)-(4),
# $\vec x[n+1] = A\vec x[n] + [0, 0, F_x, F_y]^T$, with
#
# $$A = \begin{bmatrix} 1 & 0 & dt & 0 \\ 0 & 1 & 0 & dt \\ 0 & 0 & \alpha & 0 \\ 0 & 0 & 0 & \alpha \end{bmatrix}. \tag{4}$$
#
# The GPS (5)-(6) sees only the position: $\vec y[n] = H\vec x[n] + \vec n_y$ with $\vec n_y \sim \mathcal N(0, R)$,
# where $R = \sigma_{GPS}^2 I_2$ and $\sigma_{GPS} = 50$ m.
#
# > **Handout corrections.** (i) The force enters only the velocity rows of (2). Its covariance is therefore
# > $Q = \mathrm{diag}(0, 0, \sigma_F^2, \sigma_F^2)$, not the $\sigma_F \mathbb{I}_4$ that (11) adds to all four states.
# > (ii) In (3) and (5), $\mathcal N(0, \sigma I)$ should read $\mathcal N(0, \sigma^2 I)$, if $\sigma$ is a standard deviation.
# > (iii) We read the "50 m radius" of the GPS as $\sigma_{GPS} = 50$ m on each axis. A raw fix is then off
# > by $50\sqrt 2 \approx 71$ m RMS. <!-- claim: castaway-bob/raw-gps-71-m -->
#
# Bob's parameters here are $\alpha = 0.95$ per minute and $\sigma_F = 0.02$ m/s. His own velocity therefore wanders
# with a standard deviation of $\sigma_F/\sqrt{1-\alpha^2} \approx 6$ cm/s <!-- claim: castaway-bob/own-velocity-spread --> and a memory of about 20 minutes.
#
# Write $A$ and $H$. Return NumPy arrays of floats.

# %% nbgrader={"grade": false, "grade_id": "transition_matrix", "locked": false, "schema_version": 3, "solution": true, "task": false}
def transition_matrix(dt, alpha):
    """A (4 x 4) of (4): a step of dt [s], damping alpha per step."""
    ### BEGIN SOLUTION
    return np.array([
        [1.0, 0.0, dt, 0.0],
        [0.0, 1.0, 0.0, dt],
        [0.0, 0.0, alpha, 0.0],
        [0.0, 0.0, 0.0, alpha],
    ])
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_transition_matrix", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(transition_matrix)
# Visible checks. One minute with alpha = 0.9, from x = 0, y = 0, w = (1, 2) m/s: Bob moves 60 m and
# 120 m, and his own velocity decays to (0.9, 1.8) m/s.
A = check_array(transition_matrix(60.0, 0.9), "A", (4, 4), "A maps the state [x, y, wx, wy] to the next one.")
check_close(A @ np.array([0.0, 0.0, 1.0, 2.0]), [60.0, 120.0, 0.9, 1.8], "A @ [0, 0, 1, 2] with dt = 60, alpha = 0.9",
            "Position gains dt times velocity (top-right block); velocity is multiplied by alpha (bottom-right).")
check_close(A @ np.array([5.0, -3.0, 0.0, 0.0]), [5.0, -3.0, 0.0, 0.0], "A @ [5, -3, 0, 0]",
            "With w = 0 Bob stays put: the position block is the identity, not damped.")
passed("transition_matrix")

# %% nbgrader={"grade": true, "grade_id": "test_transition_matrix", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of transition_matrix (1 point): random dt and alpha.
# Validate (and this cell) first checks that transition_matrix passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(transition_matrix)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_transition_matrix
check_transition_matrix(transition_matrix)
### END HIDDEN TESTS

# %% nbgrader={"grade": false, "grade_id": "observation_matrix", "locked": false, "schema_version": 3, "solution": true, "task": false}
def observation_matrix():
    """H (2 x 4) of (6): the GPS sees the position [x, y] of the state [x, y, wx, wy]."""
    ### BEGIN SOLUTION
    return np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_observation_matrix", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(observation_matrix)
# Visible checks: H picks the position out of the state.
H = check_array(observation_matrix(), "H", (2, 4), "H maps a state (4,) to a GPS fix (2,), so it is 2 x 4.")
check_close(H @ np.array([100.0, 200.0, 0.3, 0.4]), [100.0, 200.0], "H @ [100, 200, 0.3, 0.4]",
            "The GPS reports x and y, the first two entries of the state.")
passed("observation_matrix")

# %% nbgrader={"grade": true, "grade_id": "test_observation_matrix", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of observation_matrix (1 point): H against the reference.
# Validate (and this cell) first checks that observation_matrix passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(observation_matrix)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_observation_matrix
check_observation_matrix(observation_matrix)
### END HIDDEN TESTS

# %% [markdown]
# Here is one of Bob's drifts: two hours after he falls in behind the island, with a fix every minute.
# `ocean.simulate_drift` integrates the real current with Runge-Kutta substeps. That is the *truth*. None of
# our estimators will use it, apart from scoring them.

# %% nbgrader={"grade": false, "grade_id": "one_drift", "locked": true, "schema_version": 3, "solution": false, "task": false}
drift = ocean.simulate_drift(flow, np.random.default_rng(9))
print(f"{len(drift.t)} fixes, from t = {drift.t[0] / 60:.0f} min; Bob starts at {drift.position[0].round()} m "
      f"and travels {np.linalg.norm(np.diff(drift.position, axis=0), axis=1).sum() / 1e3:.1f} km")
print("the first three fixes are off by", np.linalg.norm(drift.fixes[:3] - drift.position[:3], axis=1).round(), "m")


# %% [markdown]
# ## 3. The simplest estimator: a trailing moving average
#
# The handout's Figure 1 estimates Bob's position as the mean of the last three fixes. Averaging three
# independent errors divides their variance by 3. But in the current Bob moves a median of about 25 m a minute, <!-- claim: castaway-bob/bob-speed-current -->
# so the mean of the fixes from the last two minutes sits about one minute's travel behind him. <!-- claim: castaway-bob/moving-average-lags -->
#
# > **Handout correction.** The handout calls this estimator a "fixed-lag mean". In estimation, *fixed-lag* names
# > something else: a **fixed-lag smoother** estimates the state at fix $n - L$ from the fixes up to $n$, so it uses
# > $L$ fixes from *after* the time it estimates, and answers $L$ minutes late. The handout's estimator uses no later
# > fix. It is a *trailing* (causal) moving average, and we call the blank `trailing_mean`.
#
# Write `trailing_mean(y, order=3)`. The estimate at fix $n$ is the mean of fixes $n - \text{order} + 1$ to
# $n$. Those are the current fix and the ones before it, never a later one: the rescuers can't wait for the
# future. The first fixes have fewer than `order` fixes before them, so average the ones there are. A graded
# function must run without warnings: one that warns fails its test.

# %% nbgrader={"grade": false, "grade_id": "trailing_mean", "locked": false, "schema_version": 3, "solution": true, "task": false}
def trailing_mean(y, order=3):
    """Mean of the last `order` fixes (the current one included): y (n, 2) [m] -> (n, 2) [m]."""
    ### BEGIN SOLUTION
    y = np.asarray(y, dtype=float)
    estimates = np.empty_like(y)
    for n in range(len(y)):
        # x^[n] = (y[n-order+1] + ... + y[n]) / order, and no fix from after n
        window = y[max(0, n - order + 1): n + 1]
        estimates[n] = window.mean(axis=0)
    return estimates
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_trailing_mean", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(trailing_mean)
# Visible checks on five fixes you can average by hand.
y_hand = np.array([[0.0, 0.0], [3.0, 0.0], [6.0, 3.0], [9.0, 6.0], [0.0, 0.0]])
est = check_array(trailing_mean(y_hand), "trailing_mean(y)", (5, 2), "There is one estimate per fix.")
# First, the rule of a trailing mean (a student review: a centred window was told to fix its start).
changed = y_hand.copy()
changed[4] = [900.0, 900.0]
# (a fairness review: the message showed the student's own first estimates as "expected", as if they were the answer)
moved = check_array(trailing_mean(changed), "trailing_mean(y) with the last fix moved", (5, 2))
check_true(np.allclose(moved[:4], est[:4], rtol=1e-7, atol=1e-9),
           "moving the last fix to (900, 900) changed your first four estimates",
           "An estimate must not use fixes that come after it: the estimate at fix k averages fix k and the ones before.")
check_close(est[0], [0.0, 0.0], "the first estimate", "At the first fix there is only that fix to average.")
check_close(est[1], [1.5, 0.0], "the second estimate", "At the second fix, average the two fixes there are so far.")
check_close(est[2:], [[3.0, 1.0], [6.0, 3.0], [5.0, 3.0]], "estimates 3 to 5",
            "From the third fix on, average exactly the last three fixes, the current one included.")
check_close(trailing_mean(y_hand, order=1), y_hand, "trailing_mean(y, order=1)", "Order 1 is the fixes themselves.")
passed("trailing_mean")

# %% nbgrader={"grade": true, "grade_id": "test_trailing_mean", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of trailing_mean (2 points): random fixes of several lengths and orders.
# Validate (and this cell) first checks that trailing_mean passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(trailing_mean)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_trailing_mean
check_trailing_mean(trailing_mean)
### END HIDDEN TESTS

# %% [markdown]
# ## 4. The Kalman gain
#
# A Kalman filter corrects a prediction $\vec x^-$ (covariance $P$) with a fix $\vec y$:
# $\hat{\vec x} = \vec x^- + K(\vec y - H\vec x^-)$ (12). For *any* gain $K$, the error of $\hat{\vec x}$ has the
# covariance (13), the **Joseph form**:
#
# $$\hat P = (I - KH)\,P\,(I - KH)^T + K K_v K^T, \tag{13}$$
#
# where $K_v = R$ is the GPS covariance. The handout minimises its trace, (14)-(17), and finds the gain
#
# $$K = P H^T (H P H^T + K_v)^{-1}. \tag{18}$$
#
# At that gain (13) simplifies to $\hat P = (I - KH)P$. For a general gain it does not: expanding (13) shows the
# two differ by $(KS - PH^T)K^T$, with $S = HPH^T + K_v$, which vanishes at (18). The Joseph form costs a few more
# products, but it is right for any gain, and as a sum of two positive semi-definite terms, no error in the gain can
# make it indefinite. The short form has no such guard: Section 8 shows what rounding does to it.
#
# Write both. Use `np.linalg.solve` rather than `np.linalg.inv`: solving $S K^T = H P$ with
# $S = HPH^T + K_v$ (both symmetric) is cheaper and more accurate than forming $S^{-1}$.

# %% nbgrader={"grade": false, "grade_id": "kalman_gain", "locked": false, "schema_version": 3, "solution": true, "task": false}
def kalman_gain(P, H, R):
    """K (n x m) of (18) from P (n x n), H (m x n) and R = K_v (m x m)."""
    ### BEGIN SOLUTION
    S = H @ P @ H.T + R
    # K = P H^T S^-1   (18), so K^T = S^-1 H P (P and S are symmetric)
    return np.linalg.solve(S, H @ P).T
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_kalman_gain", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(kalman_gain)
# Visible checks. One state seen directly: P = 4, R = 4 gives K = 4 / (4 + 4) = 1/2.
K = check_array(kalman_gain(np.array([[4.0]]), np.array([[1.0]]), np.array([[4.0]])), "K", (1, 1))
check_close(K, [[0.5]], "K for P = 4, H = 1, R = 4", "K = P H^T (H P H^T + R)^-1 = 4 / 8 here.")
# Bob's 4-state case with P = I and R = I: the GPS halves the position error, and w is uncorrelated.
H_gps = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])  # H of (6), written out: this check tests kalman_gain alone
K = check_array(kalman_gain(np.eye(4), H_gps, np.eye(2)), "K", (4, 2),
                "K maps an innovation (m = 2) to a state correction (n = 4), so it is n x m = 4 x 2.")
check_close(K, [[0.5, 0.0], [0.0, 0.5], [0.0, 0.0], [0.0, 0.0]], "K for P = I4, H = [I2 0], R = I2")
passed("kalman_gain")

# %% nbgrader={"grade": true, "grade_id": "test_kalman_gain", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of kalman_gain (2 points): random P, H, R of several sizes.
# Validate (and this cell) first checks that kalman_gain passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(kalman_gain)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_kalman_gain
check_kalman_gain(kalman_gain)
### END HIDDEN TESTS

# %% nbgrader={"grade": false, "grade_id": "joseph_covariance", "locked": false, "schema_version": 3, "solution": true, "task": false}
def joseph_covariance(P, K, H, R):
    """P^ (n x n) of (13) for any gain K (n x m), from P (n x n), H (m x n), R (m x m)."""
    ### BEGIN SOLUTION
    I_KH = np.eye(P.shape[0]) - K @ H
    # P^ = (I - K H) P (I - K H)^T + K K_v K^T   (13)
    return I_KH @ P @ I_KH.T + K @ R @ K.T
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_joseph_covariance", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(joseph_covariance)
# Visible checks with one state, P = 4, H = 1, R = 4: for a gain k, (13) is (1 - k)^2 4 + k^2 4.
P1, H1, R1 = np.array([[4.0]]), np.array([[1.0]]), np.array([[4.0]])
for k, want in ((0.0, 4.0), (1.0, 4.0), (0.5, 2.0), (0.25, 2.5)):
    got = check_array(joseph_covariance(P1, np.array([[k]]), H1, R1), f"joseph_covariance with k = {k}", (1, 1))
    check_close(got, [[want]], f"P^ for P = 4, R = 4 and gain k = {k}",
                "(13) is (1 - k)^2 P + k^2 R here: with k = 0 you keep P, with k = 1 you take the GPS error R.")
rng = np.random.default_rng(0)
P4 = random_spd(rng, 4)
H_gps = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])  # H of (6), written out: this check tests joseph_covariance alone
check_symmetric(joseph_covariance(P4, rng.standard_normal((4, 2)), H_gps, np.eye(2)), "P^",
                "(13) is symmetric by construction, for any gain: (I - K H) P (I - K H)^T + K R K^T. Check the "
                "transposes: each product ends with the transpose of the factor it starts with.")
# Two states, P = I, H = [[1, 0]], R = [[1]] and the gain K = [[1], [1]]: I - K H = [[0, 0], [-1, 1]], so (13) is
# [[0, 0], [0, 2]] + K R K^T = [[0, 0], [0, 2]] + [[1, 1], [1, 1]].
check_close(joseph_covariance(np.eye(2), np.array([[1.0], [1.0]]), np.array([[1.0, 0.0]]), np.eye(1)),
            [[1.0, 1.0], [1.0, 3.0]], "P^ for P = I, H = [[1, 0]], R = [[1]] and K = [[1], [1]]",
            "(13) is (I - K H) P (I - K H)^T + K R K^T: the transpose goes on the right-hand factor.")
passed("joseph_covariance")

# %% nbgrader={"grade": true, "grade_id": "test_joseph_covariance", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of joseph_covariance (2 points): random P, H, R and arbitrary (not optimal) gains.
# Validate (and this cell) first checks that joseph_covariance passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(joseph_covariance)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_joseph_covariance
check_joseph_covariance(joseph_covariance)
### END HIDDEN TESTS

# %% [markdown]
# Is (18) really the minimum of (14)? Below, on random problems, we perturb your gain in random directions
# and compare the trace of your Joseph covariance. If your two functions are right, no perturbed gain does
# better, <!-- claim: castaway-bob/no-perturbed-gain-does-better --> and each curve is a parabola with its minimum at the optimal gain. (The exact gap is
# $\operatorname{tr}(E S E^T) > 0$ for a perturbation $E$. Expand (13) with $K + E$ to see why.)

# %% nbgrader={"grade": false, "grade_id": "gain_is_optimal", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(kalman_gain, joseph_covariance)
gaps = ocean.gain_trace_experiment(kalman_gain, joseph_covariance, np.random.default_rng(1))
print(f"{gaps.size} perturbed gains on {gaps.shape[0]} random problems: "
      f"{np.sum(gaps < 0)} did better than (18); the smallest increase of the trace is {gaps.min():.1e}")
ax = ocean.plot_gain_trace(kalman_gain, joseph_covariance, np.random.default_rng(2))

# %% [markdown]
# **Written answer 1 (3 points).** Derive the gain (18) the handout's way. Expand the trace of (13) in $K$, set its
# derivative with respect to $K$ to zero, and solve. Then explain why this critical point is a minimum. The handout (after its
# equation (16)) settles that in one line: every matrix in the problem is positive semi-definite, hence so is the
# solution, hence the critical point is a minimum. Say what is wrong with that reasoning. You may use $\partial\,\mathrm{tr}(KA)/\partial K = A^T$ and
# $\partial\,\mathrm{tr}(KBK^T)/\partial K = 2KB$ for a symmetric $B$.

# %% [markdown] nbgrader={"grade": true, "grade_id": "optimal_gain", "locked": false, "points": 3, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** Write $S = HPH^T + K_v$, the covariance of the innovation. Expanding (13), and using
# $\mathrm{tr}\,X = \mathrm{tr}\,X^T$ and the symmetry of $P$,
# $$\mathrm{tr}\,\hat P = \mathrm{tr}\,P - 2\,\mathrm{tr}(KHP) + \mathrm{tr}(K S K^T),$$
# which is the handout's (15)-(16) with $HPH^T$ and $K_v$ collected into $S$. Its derivative is
# $\partial\,\mathrm{tr}\,\hat P/\partial K = -2PH^T + 2KS$, since $(HP)^T = PH^T$ for a symmetric $P$. Setting it to zero
# gives $KS = PH^T$, so $K = PH^TS^{-1}$, which is (18). $S$ is invertible because $K_v$ is positive definite.
#
# It is a minimum because $\mathrm{tr}\,\hat P$ is a quadratic function of $K$ whose quadratic part,
# $\mathrm{tr}(KSK^T) = \sum_i k_i^T S k_i$ over the rows $k_i$ of $K$, is positive for every $K \ne 0$, since $S$ is
# positive definite. The function is therefore strictly convex, and its one critical point is the global minimum.
# Equivalently, at the optimal $K$ the cross terms cancel and $\hat P(K + E) = \hat P(K) + ESE^T$ for any $E$, so the
# trace grows by $\mathrm{tr}(ESE^T) > 0$: the gap the experiment above measures.
#
# Where the handout is loose. (a) It argues that "all matrices involved are positive semi-definite", so the solution is
# too, "implying the critical point is a minimum". $K$ is $n \times m$, not square, so it is neither definite nor
# semi-definite, and the definiteness of a solution says nothing about the curvature at it. What makes the point a
# minimum is that the Hessian ($2S$, acting on each row of $K$) is positive definite. (b) Its motivation is to make the
# singular values of $\hat P$ small, but the trace is only their sum; that the minimiser of the sum shrinks every
# direction needs the stronger fact $\hat P(K+E) - \hat P(K) = ESE^T \succeq 0$, so (18) minimises $\hat P$ in the
# matrix order, not only its trace. (c) The middle term of (17), $-2P^TH^T$, needs $P$ symmetric to become $-2PH^T$.
#
# **Rubric (3 points).** 1 point: the expansion and the derivative, arriving at (18) with $S = HPH^T + K_v$ and no
# sign or transpose error. 1 point: a correct reason for a minimum (a convex quadratic whose curvature is the positive
# definite $S$, or the completed square $\hat P(K+E) = \hat P(K) + ESE^T$). 1 point: names a loose step with the right
# reason: (a) $K$ is not square and a solution's definiteness does not decide the Hessian, or (b) the trace is the sum
# of the eigenvalues, so minimising it does not by itself shrink each one. Either (a) or (b) earns the point.
# ### END SOLUTION

# %% [markdown]
# ## 5. One filter step
#
# A step of the filter takes the estimate $(\hat{\vec x}, \hat P)$ at the last fix and the new fix $\vec y$.
# It returns the estimate at the new fix:
#
# - predict: $\vec x^- = A\hat{\vec x} + \vec u$ (10) and $P^- = A \hat P A^T + Q$ (11), where $\vec u$ is a *known
#   input*: something that moves the state and that we know, such as the current in Section 6;
# - update: the gain (18) from $P^-$, then $\hat{\vec x}_{new} = \vec x^- + K(\vec y - H\vec x^-)$ (12), and the Joseph form (13).
#
# Write `kalman_step`. With `u=None` there is no input. Call your `kalman_gain` and `joseph_covariance`.

# %% nbgrader={"grade": false, "grade_id": "kalman_step", "locked": false, "schema_version": 3, "solution": true, "task": false}
def kalman_step(x, P, y, A, H, Q, R, u=None):
    """One predict (with optional known input u (n,)) and update: returns x (n,), P (n x n)."""
    ### BEGIN SOLUTION
    x_pred = A @ x if u is None else A @ x + u
    # P^-[n+1] = A P A^T + Q   (11)
    P_pred = A @ P @ A.T + Q
    # K = P^- H^T (H P^- H^T + K_v)^-1   (18)
    K = kalman_gain(P_pred, H, R)
    # x^ = x^- + K (y - H x^-)   (12)
    x_new = x_pred + K @ (y - H @ x_pred)
    # P^ = (I - K H) P^- (I - K H)^T + K K_v K^T   (13)
    P_new = joseph_covariance(P_pred, K, H, R)
    return x_new, P_new
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_kalman_step", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(kalman_step)
# Visible checks with one state: x = 0, P = 1, A = 1, Q = 1, H = 1, R = 2 and a fix y = 4.
# Predict: x- = 0, P- = 2. Update: K = 2 / 4 = 1/2, x = 0 + (4 - 0) / 2 = 2, P = (1/2)^2 2 + (1/2)^2 2 = 1.
one = np.array([[1.0]])
x_new, P_new = check_pair(kalman_step(np.array([0.0]), one, np.array([4.0]), one, one, one, 2 * one),
                          "kalman_step(...)", "x", "P")
check_close(check_array(x_new, "x", (1,)), [2.0], "x after one step",
            "x = x- + K (y - H x-) = 0 + (4 - 0) / 2: the innovation is y - H x-, and the gain K = P- H^T (H P- H^T + R)^-1 "
            "= 2 / 4 = 1/2 comes from the predicted P- = A P A^T + Q = 2, not from the P you were given.")
check_close(check_array(P_new, "P", (1, 1)), [[1.0]], "P after one step",
            "Predict P- = A P A^T + Q = 2, then update it with the Joseph form (13): (1 - K)^2 P- + K^2 R = 1.")
# The same with a known input u = 1: x- = 1, so x = 1 + (4 - 1) / 2 = 2.5, and P does not change.
x_u, P_u = check_pair(kalman_step(np.array([0.0]), one, np.array([4.0]), one, one, one, 2 * one, u=np.array([1.0])),
                      "kalman_step(..., u=...)", "x", "P")
# P first: an input added to the covariance too also moves x, and its hint is the covariance's.
check_close(P_u, [[1.0]], "P with a known input", "A known input moves the mean, not the covariance.")
check_close(x_u, [2.5], "x with a known input u = 1",
            "The prediction is x- = A x + u = 1, and the update starts from it: x = x- + K (y - H x-).")
# A known input where A is not 1: x = 1, P = 1, A = 2, Q = 1, R = 5, u = 1 and a fix y = 5. Predict: x- = A x + u = 3,
# P- = 4 + 1 = 5. Update: K = 5 / 10 = 1/2, so x = 3 + (5 - 3) / 2 = 4 and P = (1/2)^2 5 + (1/2)^2 5 = 2.5.
x_u, P_u = check_pair(kalman_step(np.array([1.0]), one, np.array([5.0]), 2 * one, one, one, 5 * one, u=np.array([1.0])),
                      "kalman_step(..., u=...)", "x", "P")
# P first: a P- without A (P + Q) also makes x wrong, through K
check_close(P_u, [[2.5]], "P with A = 2 and a known input", "Predict P- = A P A^T + Q = 5, then update with K = 1/2.")
check_close(x_u, [4.0], "x with A = 2 and a known input u = 1",
            "The input is added after A moves the estimate, x- = A x + u = 2 * 1 + 1, not A (x + u).")
# A known input of two entries: two states, x = 0, P = I, A = I, Q = I, H = I, R = I, u = [1, 2] and a fix y = [4, 5].
# Predict: x- = u = [1, 2], P- = 2 I. Update: K = 2/3 I, x = [1, 2] + (2/3) [3, 3] = [3, 4], P = (1/3)^2 2 I + (2/3)^2 I = 2/3 I.
two = np.eye(2)
returned = kalman_step(np.zeros(2), two, np.array([4.0, 5.0]), two, two, two, two, u=np.array([1.0, 2.0]))
x_u, P_u = check_pair(returned, "kalman_step(..., u=...)", "x", "P")
check_close(x_u, [3.0, 4.0], "x with a known input u = [1, 2]", "The prediction is x- = A x + u, for a u of any size.")
check_close(P_u, 2.0 / 3.0 * two, "P with a known input u = [1, 2]", "A known input moves the mean, not the covariance.")
# Bob's shapes: a 4-state step, with A of (4) for dt = 60 s and alpha = 0.9, and H of (6), written out: this
# check tests kalman_step alone.
A_60 = np.array([[1.0, 0.0, 60.0, 0.0], [0.0, 1.0, 0.0, 60.0], [0.0, 0.0, 0.9, 0.0], [0.0, 0.0, 0.0, 0.9]])
H_gps = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])
x4, P4 = check_pair(kalman_step(np.zeros(4), np.eye(4), np.zeros(2), A_60, H_gps, np.eye(4), np.eye(2)),
                    "kalman_step(...)", "x", "P")
check_array(x4, "x for Bob's 4-state model", (4,))
check_symmetric(check_array(P4, "P for Bob's 4-state model", (4, 4)), "P",
                "Predict P- = A P A^T + Q: A on the left and its transpose on the right keep P symmetric.")
passed("kalman_step")

# %% nbgrader={"grade": true, "grade_id": "test_kalman_step", "locked": true, "points": 3, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of kalman_step (3 points): random models of several sizes, with and without a known input.
# Validate (and this cell) first checks that kalman_step passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(kalman_step)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_kalman_step
check_kalman_step(kalman_step)
### END HIDDEN TESTS

# %% [markdown]
# ## 6. Two Kalman filters
#
# **Rank 2: position only** (the handout's Figure 2). The filter knows nothing about the sea. Its state is
# Bob's position, and its model is a random walk: each minute Bob moves by an unknown step,
# $\vec x[k+1] = \vec x[k] + \vec e[k]$ with $\vec e \sim \mathcal N(0, \sigma_{walk}^2 I_2)$. We take
# $\sigma_{walk} = 30$ m, the distance a 0.5 m/s current carries Bob in a minute. So $A = H = I_2$,
# $Q = \sigma_{walk}^2 I_2$ and $R = \sigma_{GPS}^2 I_2$.
#
# Write `run_rank2(y, sigma_walk, sigma_gps)`. Start from the first fix with covariance $R$ (the first
# estimate *is* the first fix), then call your `kalman_step` for each later fix. Return all $n$ estimates
# (shape $(n, 2)$) and covariances ($(n, 2, 2)$).

# %% nbgrader={"grade": false, "grade_id": "run_rank2", "locked": false, "schema_version": 3, "solution": true, "task": false}
def run_rank2(y, sigma_walk=30.0, sigma_gps=50.0):
    """Rank-2 random-walk filter: y (n, 2) [m] -> estimates (n, 2) [m], covariances (n, 2, 2) [m^2]."""
    ### BEGIN SOLUTION
    n = len(y)
    # x[k+1] = x[k] + e[k], e ~ N(0, sigma_walk^2 I_2);  y[k] = x[k] + n_y, n_y ~ N(0, sigma_gps^2 I_2)
    A, H = np.eye(2), np.eye(2)
    Q, R = sigma_walk**2 * np.eye(2), sigma_gps**2 * np.eye(2)
    xs, Ps = np.empty((n, 2)), np.empty((n, 2, 2))
    # the first estimate is the first fix, as uncertain as the GPS
    xs[0], Ps[0] = y[0], R
    for k in range(1, n):
        xs[k], Ps[k] = kalman_step(xs[k - 1], Ps[k - 1], y[k], A, H, Q, R)
    return xs, Ps
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_run_rank2", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(run_rank2)
# Visible checks. Five identical fixes: every estimate is that point, and the covariance shrinks from R.
y_same = np.tile([100.0, -200.0], (5, 1))
xs, Ps = check_pair(run_rank2(y_same), "run_rank2(y)", "estimates", "covariances")
check_array(xs, "the estimates", (5, 2), "One estimate (x, y) per fix.")
check_array(Ps, "the covariances", (5, 2, 2), "One 2 x 2 covariance per fix.")
check_close(xs, y_same, "the estimates from five identical fixes", "If every fix says the same, so does the filter.")
check_close(Ps[0], SIGMA_GPS**2 * np.eye(2), "the first covariance", "Start from the first fix, with covariance R.")
# Another GPS, sigma_gps = 10 m: the first covariance is R = 10^2 I.
_, Ps_10 = check_pair(run_rank2(y_same, sigma_gps=10.0), "run_rank2(y, sigma_gps=10.0)", "estimates", "covariances")
check_close(Ps_10[0], 100.0 * np.eye(2), "the first covariance with sigma_gps = 10 m",
            "Start from R = sigma_gps^2 I, built from the argument sigma_gps, not from the notebook's SIGMA_GPS.")
# Second fix by hand: P- = 2500 + 900 = 3400, K = 3400 / 5900, P = K R = 3400 * 2500 / 5900.
check_close(Ps[1], 3400 * 2500 / 5900 * np.eye(2), "the second covariance",
            "Predict with Q = sigma_walk^2 I, then update with R = sigma_gps^2 I: variances, not standard deviations.")
# Third fix by hand, from the second covariance P1 = 3400 * 2500 / 5900 (about 1441): P- = P1 + 900, and
# P = P- * 2500 / (P- + 2500) = (P1 + 900) * 2500 / (P1 + 3400), about 1209.
P1 = 3400 * 2500 / 5900
check_close(Ps[2], (P1 + 900) * 2500 / (P1 + 3400) * np.eye(2), "the third covariance",
            "Start each step from the previous estimate and covariance, not from the first.")
# With sigma_gps = 10 m, once Q is checked, the second covariance: P- = 100 + 900 = 1000, updated with R = 100 to
# 1000 * 100 / 1100 (a fairness review: an R from SIGMA_GPS with a first covariance from the argument passed every check).
check_close(Ps_10[1], 1000.0 * 100.0 / 1100.0 * np.eye(2), "the second covariance with sigma_gps = 10 m",
            "Update with R = sigma_gps^2 I from the argument sigma_gps too, not from the notebook's SIGMA_GPS.")
# Two different fixes, once the covariances (and so Q and K) are right (a student review: a filter that paired
# estimate k with another fix passed every check): the second estimate moves from the first fix, (0, 0), towards the
# second by K = 3400 / 5900.
xs_two, _ = check_pair(run_rank2(np.array([[0.0, 0.0], [100.0, 0.0]])), "run_rank2(y)", "estimates", "covariances")
check_close(xs_two[1], [100.0 * 3400 / 5900, 0.0], "the second estimate from the fixes (0, 0) and (100, 0)",
            "Update estimate k with fix k: x_k = x_k- + K (y[k] - x_k-), with K = 3400 / 5900 here.")
passed("run_rank2")

# %% nbgrader={"grade": true, "grade_id": "test_run_rank2", "locked": true, "points": 3, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of run_rank2 (3 points): random fixes and noise levels.
# Validate (and this cell) first checks that run_rank2 passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(run_rank2)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_run_rank2
check_run_rank2(run_rank2)
### END HIDDEN TESTS

# %% [markdown]
# **Rank 4: the state of (1), and the known current** (the handout's Figure 3). The GPS fixes and the
# model both say where Bob is. But the model above ignores the current, the largest thing that moves
# him. The rescuers have the current, as a forecast or a map. Here they have our flow, exactly.
#
# The rank-4 filter uses $A$ and $H$ from Section 2, and it adds the current as a **known input** of its
# position prediction, evaluated where the filter believes Bob is:
#
# $$\vec x[n+1] = A\vec x[n] + \begin{bmatrix} dt\,\vec u(\hat{\vec p}[n], t_n) \\ 0 \\ 0 \end{bmatrix}
#   + \begin{bmatrix} 0 \\ 0 \\ \vec F[n] \end{bmatrix},
#   \qquad Q = \mathrm{diag}(0, 0, \sigma_F^2, \sigma_F^2),$$
#
# where $\hat{\vec p}[n]$ is the position part of the estimate $\hat{\vec x}[n]$.

# %% [markdown]
# **Written answer 2 (3 points).** Derive this model from Bob's motion,
# $d\vec p/dt = \vec u(\vec p, t) + \vec w[n]$ over $[t_n, t_n + dt]$, and $\vec w[n+1] = \alpha\vec w[n] + \vec F[n]$.
# Name the two approximations it makes, and say why each one is small here. Explain why the position rows of
# $Q$ are zero.

# %% [markdown] nbgrader={"grade": true, "grade_id": "rank4_model", "locked": false, "points": 3, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** Integrating over the minute,
# $\vec p(t_n + dt) = \vec p(t_n) + \int_{t_n}^{t_n+dt} \vec u(\vec p(s), s)\,ds + dt\,\vec w[n]$, because $\vec w$ is
# constant during the step. The $dt\,\vec w[n]$ term and $\vec w[n+1] = \alpha\vec w[n] + \vec F[n]$ are exactly
# $A\vec x[n] + [0, 0, \vec F]^T$ with $A$ of (4). The integral is approximated in two ways:
# (1) a one-point (Euler) rule, $\int \approx dt\,\vec u(\vec p[n], t_n)$. Its error is at most about
# $\tfrac12 dt^2\,|D\vec u/Dt| \sim \tfrac12 (60\ \mathrm s)^2 \cdot U^2/D \approx 0.5$ m; measured against Bob's
# Runge-Kutta drift it is about 0.1 m RMS and never above 0.5 m, <!-- claim: castaway-bob/euler-error-small --> far below the 50 m GPS error;
# (2) $\vec u$ is evaluated at the estimate $\hat{\vec p}[n]$ instead of the unknown true $\vec p[n]$. This makes the
# input known and the model linear. The error is $dt\,\nabla\vec u\,(\vec p - \hat{\vec p})$. Along Bob's drifts $|\nabla\vec u|$ is a few
# $10^{-4}\ \mathrm{s^{-1}}$, <!-- claim: castaway-bob/velocity-gradient-size --> so the error is about
# $60\ \mathrm s \cdot 3\times 10^{-4}\ \mathrm{s^{-1}} \cdot 30\ \mathrm m \approx 0.5$ m; measured over the drifts it is
# about 0.5 m RMS, <!-- claim: castaway-bob/current-at-estimate-error --> also small. (An extended
# Kalman filter would keep it, through the Jacobian $\nabla\vec u$.)
# The random force acts only on Bob's own velocity. The position changes only through $\vec w$ and the known current,
# so no noise enters the position rows: $Q = \mathrm{diag}(0, 0, \sigma_F^2, \sigma_F^2)$. The handout's
# $\sigma_F\mathbb I_4$ would also add noise to the positions, which the model does not have.
#
# **Rubric (3 points).** 1 point: the integral of $d\vec p/dt$ over the step, giving $A\vec x[n]$ plus a
# current term. 1 point: both approximations named (Euler in time; the current at the estimate), with a size
# or an argument why each is small. 1 point: $Q$'s zero position rows explained (the force drives $\vec w$
# only; the handout's $\sigma_F \mathbb I_4$ is a slip).
# ### END SOLUTION

# %% [markdown]
# Write `run_rank4(y, flow, t, ...)`. `flow(p, t)` returns the current (m/s) at a position `p` (shape (2,))
# and a time `t` (s); `t` holds the times of the fixes. Start from the first fix with $\vec w = 0$ and
# covariance $\mathrm{diag}(\sigma_{GPS}^2, \sigma_{GPS}^2, \sigma_w^2, \sigma_w^2)$. Here
# $\sigma_w^2 = \sigma_F^2/(1-\alpha^2)$ is the steady spread of Bob's own velocity. Then step with your
# `kalman_step` and the input $\vec u = [dt\,\vec u(\hat{\vec p}, t_{k-1}), 0, 0]$. Use your
# `transition_matrix` and `observation_matrix`.

# %% nbgrader={"grade": false, "grade_id": "run_rank4", "locked": false, "schema_version": 3, "solution": true, "task": false}
def run_rank4(y, flow, t, alpha=0.95, sigma_F=0.02, sigma_gps=50.0, dt=60.0):
    """Rank-4 filter with the current as known input: estimates (n, 4), covariances (n, 4, 4)."""
    ### BEGIN SOLUTION
    n = len(y)
    A, H = transition_matrix(dt, alpha), observation_matrix()
    # Q = diag(0, 0, sigma_F^2, sigma_F^2): F drives w only (the handout's sigma_F I_4 in (11) is a slip)
    Q = np.diag([0.0, 0.0, sigma_F**2, sigma_F**2])
    R = sigma_gps**2 * np.eye(2)
    xs, Ps = np.empty((n, 4)), np.empty((n, 4, 4))
    # first estimate: the first fix, and w = 0 with its stationary variance sigma_F^2 / (1 - alpha^2)
    var_w = sigma_F**2 / (1.0 - alpha**2)
    xs[0] = [y[0][0], y[0][1], 0.0, 0.0]
    Ps[0] = np.diag([sigma_gps**2, sigma_gps**2, var_w, var_w])
    for k in range(1, n):
        # x[k] = A x[k-1] + [dt u(x^[k-1], t[k-1]); 0, 0] + [0; 0; F]: the current, at the estimate
        u = np.concatenate((dt * flow(xs[k - 1, :2], t[k - 1]), [0.0, 0.0]))
        xs[k], Ps[k] = kalman_step(xs[k - 1], Ps[k - 1], y[k], A, H, Q, R, u=u)
    return xs, Ps
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_run_rank4", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(run_rank4)
# Visible checks. (a) Still water and Bob not moving: the fixes sit on one point, and so do the estimates.
t_hand = 60.0 * np.arange(6)
still = lambda p, t: np.zeros(2)
y_same = np.tile([100.0, -200.0], (6, 1))
xs, Ps = check_pair(run_rank4(y_same, still, t_hand), "run_rank4(y, flow, t)", "estimates", "covariances")
check_array(xs, "the estimates", (6, 4), "The state is [x, y, wx, wy]: one row per fix.")
check_array(Ps, "the covariances", (6, 4, 4), "One 4 x 4 covariance per fix.")
check_close(xs, np.tile([100.0, -200.0, 0.0, 0.0], (6, 1)), "the estimates in still water",
            "Start from the first fix with w = 0; with no current and identical fixes nothing moves.", atol=1e-9)
check_close(Ps[0], np.diag([SIGMA_GPS**2, SIGMA_GPS**2, SIGMA_F**2 / (1 - ALPHA**2), SIGMA_F**2 / (1 - ALPHA**2)]),
            "the first covariance", "diag(sigma_gps^2, sigma_gps^2, sigma_w^2, sigma_w^2), sigma_w^2 = sigma_F^2 / (1 - alpha^2).")
# Another damping, alpha = 0.5 (a student review: the notebook's ALPHA in place of the argument passed every check).
_, Ps_half = check_pair(run_rank4(y_same, still, t_hand, alpha=0.5), "run_rank4(y, flow, t, alpha=0.5)", "estimates",
                        "covariances")
check_close(Ps_half[0], np.diag([SIGMA_GPS**2, SIGMA_GPS**2, SIGMA_F**2 / 0.75, SIGMA_F**2 / 0.75]),
            "the first covariance with alpha = 0.5",
            "Use the argument alpha, not the notebook's ALPHA: sigma_w^2 = sigma_F^2 / (1 - alpha^2) = sigma_F^2 / 0.75.")
# (b) A uniform 0.5 m/s current and perfect fixes that drift with it: the filter predicts each fix exactly.
drifting = lambda p, t: np.array([0.5, 0.0])
y_drift = np.column_stack((30.0 * np.arange(6), np.zeros(6)))
xs, _ = check_pair(run_rank4(y_drift, drifting, t_hand), "run_rank4(y, flow, t)", "estimates", "covariances")
check_close(xs, np.column_stack((y_drift, np.zeros((6, 2)))), "the estimates in a uniform 0.5 m/s current",
            "Add dt * flow(position estimate, t[k-1]) to the predicted position: 30 m per minute here.", atol=1e-9)
# (c) A current that speeds up, u = (t / 600, 0) m/s, the same everywhere, and perfect fixes that drift with it. Over the
# minute from t[k-1] it carries Bob dt * t[k-1] / 600 = 0, 6, 12, 18, 24 m, so he is at x = 0, 0, 6, 18, 36, 60 m.
speeding = lambda p, t: np.array([t / 600.0, 0.0])
y_speeding = np.column_stack(([0.0, 0.0, 6.0, 18.0, 36.0, 60.0], np.zeros(6)))
xs, _ = check_pair(run_rank4(y_speeding, speeding, t_hand), "run_rank4(y, flow, t)", "estimates", "covariances")
check_close(xs, np.column_stack((y_speeding, np.zeros((6, 2)))), "the estimates in a current that speeds up",
            "The current that carries Bob from fix k - 1 to fix k is the one at the start of the step: "
            "flow(position estimate, t[k-1]), not t[k].", atol=1e-9)
# (e) Noisy fixes in still water, with a current that records where it is asked for: the filter should take the
# current at its last estimate, where it thinks Bob is (xs[k-1, :2]), at the start of each of the 5 steps, not at the
# last fix (the estimates are not the fixes here).
asked = []
# (a lambda: the draft's def of it counted as a hidden body in the release's leak check)
recording = lambda p, t: (asked.append(np.array(p, dtype=float)[..., :2]), np.zeros(2))[1]
y_noisy = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 100.0], [0.0, 100.0], [0.0, 0.0], [50.0, 50.0]])
xs_noisy, _ = check_pair(run_rank4(y_noisy, recording, t_hand), "run_rank4(y, flow, t)", "estimates", "covariances")
check_close(check_array(np.array(asked[:5]), "the positions where the current was taken", (5, 2),
                        "Take the current once per step, flow(position, t[k-1]), for the 5 steps after the first fix."),
            xs_noisy[:5, :2], "the positions where the current was taken",
            "Take the current at the last estimate, xs[k-1, :2], where the filter thinks Bob is: not at the last fix "
            "y[k-1], nor at the position predicted ahead.")
# (d) Back in still water (a): the second position variance by hand. The forecast's is the first one plus the drift of
# the unknown w over a minute, p = sigma_gps^2 + dt^2 sigma_w^2 (Q adds nothing to the position), and the fix makes it
# p sigma_gps^2 / (p + sigma_gps^2). Process noise on the position too, sigma_F^2 = 4e-4 m^2 more in p, changes it by
# only 1e-4 m^2 (8e-8 of it): hence the tight tolerance, which every correct form of the update meets.
p_pred = SIGMA_GPS**2 + 60.0**2 * SIGMA_F**2 / (1 - ALPHA**2)
check_close(Ps[1, 0, 0], p_pred * SIGMA_GPS**2 / (p_pred + SIGMA_GPS**2),
            "the position variance after the second fix in still water",
            "If your transition_matrix, kalman_gain, joseph_covariance and kalman_step are right, look at Q and R: "
            "Q = diag(0, 0, sigma_F^2, sigma_F^2), as the process noise drives Bob's own velocity w, not his position, "
            "and R = sigma_gps^2 I, a variance.",
            rtol=1e-10, show_expected=False)
# (f) Back to alpha = 0.5, now that (d) has checked Q: the second covariance, from a forecast with A of (4) for
# alpha = 0.5 and dt = 60 s, then the update of (18) and (13).
A_half = np.array([[1.0, 0.0, 60.0, 0.0], [0.0, 1.0, 0.0, 60.0], [0.0, 0.0, 0.5, 0.0], [0.0, 0.0, 0.0, 0.5]])
P_pred = A_half @ Ps_half[0] @ A_half.T + np.diag([0.0, 0.0, SIGMA_F**2, SIGMA_F**2])
P_half = P_pred - P_pred[:, :2] @ np.linalg.solve(P_pred[:2, :2] + SIGMA_GPS**2 * np.eye(2), P_pred[:2, :])
check_close(Ps_half[1], P_half, "the second covariance with alpha = 0.5",
            "Build A from the argument alpha too, transition_matrix(dt, alpha), not from the notebook's ALPHA.")
# (g) Another GPS, sigma_gps = 10 m, in still water (a fairness review: P0 and R built from the notebook's SIGMA_GPS
# passed every check): P0 starts from 10^2 on the position, and the second position variance is p 10^2 / (p + 10^2),
# with p = 10^2 + dt^2 sigma_w^2 as in (d).
_, Ps_10 = check_pair(run_rank4(y_same, still, t_hand, sigma_gps=10.0), "run_rank4(y, flow, t, sigma_gps=10.0)",
                      "estimates", "covariances")
var_w = SIGMA_F**2 / (1 - ALPHA**2)
check_close(Ps_10[0], np.diag([100.0, 100.0, var_w, var_w]), "the first covariance with sigma_gps = 10 m",
            "Build P0 from the argument sigma_gps, not from the notebook's SIGMA_GPS: diag(sigma_gps^2, sigma_gps^2, ...).")
p_10 = 10.0**2 + 60.0**2 * var_w
check_close(Ps_10[1, 0, 0], p_10 * 10.0**2 / (p_10 + 10.0**2), "the position variance after the second fix with sigma_gps = 10 m",
            "Build R = sigma_gps^2 I from the argument sigma_gps, not from the notebook's SIGMA_GPS.", rtol=1e-10,
            show_expected=False)
# (h) Another random force, sigma_F = 0.05 m/s, in still water (a fairness review: Q, or the first velocity variance,
# from the notebook's SIGMA_F passed every check): sigma_w^2 = sigma_F^2 / (1 - alpha^2) in P0, and the second
# covariance, from the forecast A P0 A^T + Q with Q = diag(0, 0, sigma_F^2, sigma_F^2), then the update, as in (f).
_, Ps_F = check_pair(run_rank4(y_same, still, t_hand, sigma_F=0.05), "run_rank4(y, flow, t, sigma_F=0.05)",
                     "estimates", "covariances")
var_w_F = 0.05**2 / (1 - ALPHA**2)
check_close(Ps_F[0], np.diag([SIGMA_GPS**2, SIGMA_GPS**2, var_w_F, var_w_F]), "the first covariance with sigma_F = 0.05 m/s",
            "Build sigma_w^2 = sigma_F^2 / (1 - alpha^2) from the argument sigma_F, not from the notebook's SIGMA_F.")
A_95 = np.array([[1.0, 0.0, 60.0, 0.0], [0.0, 1.0, 0.0, 60.0], [0.0, 0.0, ALPHA, 0.0], [0.0, 0.0, 0.0, ALPHA]])
P_pred_F = A_95 @ Ps_F[0] @ A_95.T + np.diag([0.0, 0.0, 0.05**2, 0.05**2])
P_F = P_pred_F - P_pred_F[:, :2] @ np.linalg.solve(P_pred_F[:2, :2] + SIGMA_GPS**2 * np.eye(2), P_pred_F[:2, :])
check_close(Ps_F[1], P_F, "the second covariance with sigma_F = 0.05 m/s",
            "Build Q = diag(0, 0, sigma_F^2, sigma_F^2) from the argument sigma_F, not from the notebook's SIGMA_F.")
passed("run_rank4")

# %% nbgrader={"grade": true, "grade_id": "test_run_rank4", "locked": true, "points": 4, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of run_rank4 (4 points): random fixes in random currents and parameters, and a drift in Bob's ocean.
# Validate (and this cell) first checks that run_rank4 passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(run_rank4)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_run_rank4
check_run_rank4(run_rank4)
### END HIDDEN TESTS

# %% [markdown]
# **A control.** Compared with the rank-2 filter, the rank-4 filter changes two things at once: it has a
# velocity in its state, and it knows the current. To tell the two apart we add a filter with the same four states
# and *no* current map, a **constant-velocity (CV) filter**. Its velocity is Bob's velocity over the ground, which it
# must learn from the fixes. Its model is (4) with $\alpha = 1$: $\vec x[k+1] = A\vec x[k] + [0, 0, \vec e[k]]^T$ with
# $\vec e \sim \mathcal N(0, \sigma_v^2 I_2)$, a random walk of the velocity, and $\sigma_v = \sigma_F = 0.02$ m/s. It starts
# from the first fix with velocity $0 \pm$ the current's speed, the size of the velocity it has to learn, just as the
# rank-4 filter starts from the spread of Bob's own velocity. `ocean.constant_velocity_filter` builds it from your
# `kalman_step`, `transition_matrix` and `observation_matrix`. (Section 8 says how it bears on the handout's rank-2
# filter, and checks that its step does not flatter the rank-4 filter.)

# %% [markdown]
# Now all four estimators follow Bob's drift. On the left is the whole drift over the vortex street. On
# the right is a zoom on 16 minutes, with the filters' 2-sigma ellipses drawn to scale. An ellipse
# shows where the filter believes Bob is, with 86 % probability.

# %% nbgrader={"grade": false, "grade_id": "tracks_figure", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(trailing_mean, kalman_step, transition_matrix, observation_matrix, run_rank2, run_rank4)
run_cv = ocean.constant_velocity_filter(kalman_step, transition_matrix, observation_matrix, sigma_v0=flow.current)
tracks = ocean.run_estimators(drift, flow, trailing_mean, run_rank2, run_cv, run_rank4)
fig = ocean.plot_tracks(flow, drift, tracks)
ax = ocean.plot_errors(drift, tracks)


# %% [markdown]
# ## 7. Which estimator is best?
#
# One drift is an anecdote. To compare the estimators, score each one on many drifts: different start
# points, start times and forces.
#
# Write the two scores:
# - `track_rmse(estimates, truth)`: the root mean square *distance* between estimate and truth over a drift,
#   $\sqrt{\frac1n\sum_k \lVert\hat{\vec p}[k] - \vec p[k]\rVert^2}$, in metres. Both inputs have shape $(n, 2)$.
# - `ellipse_area(P, n_sigma=2.0)`: the area of the ellipse $\{\vec d : \vec d^T P^{-1}\vec d \le n_\sigma^2\}$ for each
#   2 x 2 covariance in `P` (shape $(\dots, 2, 2)$). Its semi-axes are $n_\sigma\sqrt{\lambda_i}$, where
#   $\lambda_i$ are the eigenvalues of $P$. The area is therefore $\pi n_\sigma^2 \sqrt{\det P}$.

# %% nbgrader={"grade": false, "grade_id": "track_rmse", "locked": false, "schema_version": 3, "solution": true, "task": false}
def track_rmse(estimates, truth):
    """RMSE [m] of estimates (n, 2) [m] against the truth (n, 2) [m], by 2-D distance."""
    ### BEGIN SOLUTION
    error = np.asarray(estimates, dtype=float) - np.asarray(truth, dtype=float)
    # RMSE = sqrt( (1/n) sum_k |x^[k] - x[k]|^2 ), |.| the 2-D distance
    return float(np.sqrt(np.mean(np.sum(error**2, axis=-1))))
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_track_rmse", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(track_rmse)
# Visible checks: errors of 5 m (a 3-4-5 triangle) and 0 m give sqrt((25 + 0) / 2) = 3.536 m.
value = track_rmse(np.array([[3.0, 4.0], [7.0, 7.0]]), np.array([[0.0, 0.0], [7.0, 7.0]]))
check_array(value, "track_rmse(...)", (), "Return one number: the RMSE over the whole track.")
check_close(value, np.sqrt(12.5), "track_rmse for errors of 5 m and 0 m",
            "Square the 2-D distance of each fix, average over the fixes, then take the square root.")
passed("track_rmse")

# %% nbgrader={"grade": true, "grade_id": "test_track_rmse", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of track_rmse (1 point): random tracks of several lengths.
# Validate (and this cell) first checks that track_rmse passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(track_rmse)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_track_rmse
check_track_rmse(track_rmse)
### END HIDDEN TESTS

# %% nbgrader={"grade": false, "grade_id": "ellipse_area", "locked": false, "schema_version": 3, "solution": true, "task": false}
def ellipse_area(P, n_sigma=2.0):
    """Area [m^2] of the n_sigma ellipse of each covariance in P (..., 2, 2): shape (...)."""
    ### BEGIN SOLUTION
    return np.pi * n_sigma**2 * np.sqrt(np.linalg.det(P))
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_ellipse_area", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(ellipse_area)
# Visible checks: P = diag(3^2, 2^2) m^2 has 2-sigma semi-axes 6 m and 4 m, so an area of 24 pi m^2.
area = check_array(ellipse_area(np.diag([9.0, 4.0])), "ellipse_area(diag(9, 4))", (), "One area per 2 x 2 covariance.")
check_close(area, 24 * np.pi, "the 2-sigma area of diag(9, 4)", "The area is pi n_sigma^2 sqrt(det P).")
check_close(ellipse_area(np.diag([9.0, 4.0]), n_sigma=1.0), 6 * np.pi, "the 1-sigma area of diag(9, 4)",
            "Use the argument n_sigma, not the number 2: the area grows as n_sigma^2.")
areas = check_array(ellipse_area(np.stack([np.eye(2), 4 * np.eye(2), np.diag([9.0, 4.0])])), "ellipse_area of 3 covariances",
                    (3,), "Work on a stack of covariances: np.linalg.det works on the last two axes.")
check_close(areas, [4 * np.pi, 16 * np.pi, 24 * np.pi], "the areas of a stack of covariances")
passed("ellipse_area")

# %% nbgrader={"grade": true, "grade_id": "test_ellipse_area", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of ellipse_area (1 point): random stacks of covariances and several n_sigma.
# Validate (and this cell) first checks that ellipse_area passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(ellipse_area)
### BEGIN HIDDEN TESTS
from solutions.castaway_bob.hidden_tests import check_ellipse_area
check_ellipse_area(ellipse_area)
### END HIDDEN TESTS

# %% [markdown]
# Now the comparison of the four estimators: 50 seeded drifts in Bob's current. The table gives each estimator's RMSE (mean,
# spread and median over the drifts) and the number of drifts on which it was best. For the filters it
# also gives the mean 2-sigma area (1 ha = $10^4\ \mathrm{m^2}$) and how often Bob was inside that ellipse.
# For honest ellipses that is $1 - e^{-2} = 86.5\,\%$. The last row is an ablation, not a fifth estimator: the
# rank-4 filter told that the sea is still (`run_rank4` with a current of zero), which keeps its model of Bob's damped
# velocity and loses only the map.

# %% nbgrader={"grade": false, "grade_id": "compare_current", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
require(trailing_mean, kalman_step, transition_matrix, observation_matrix, run_rank2, run_rank4, track_rmse, ellipse_area)
drifts = ocean.simulate_drifts(flow, np.random.default_rng(2024), 50)
raw = np.array([track_rmse(d.fixes, d.position) for d in drifts])
current_result = ocean.compare(drifts, flow, trailing_mean, run_rank2, run_cv, run_rank4, track_rmse, ellipse_area)
print("Bob's current, 0.5 m/s; rank-2 random-walk step sigma_walk = 30 m")
print(ocean.format_comparison(current_result, raw))

# %% [markdown]
# The handout claims that the rank-4 filter beats the rank-2 filter, and that the rank-2 filter beats the
# moving average. Now try the same drifts (the same seed: the same starts, start times, forces and GPS errors) in
# **slack water**: the same eddies at a tenth of the speed (0.05 m/s), as at the turn of the tide. There Bob moves
# only about 5 m a minute, <!-- claim: castaway-bob/bob-speed-slack -->
# so the rank-2 filter's random walk needs a smaller step.
#
# A step chosen on the very drifts it is scored on would flatter the rank-2 filter. So we chose it on a separate
# **tuning set**: 50 other slack-water drifts from the same simulator (seed 7; the comparison uses seed 2024). Of the
# steps 5, 10, 15, 20, 25 and 30 m, $\sigma_{walk} = 15$ m scored best on the tuning set, and the comparison below
# uses it. <!-- claim: castaway-bob/slack-walk-step-tuned -->
# The CV control starts from the slack water's speed, 0.05 m/s.

# %% nbgrader={"grade": false, "grade_id": "compare_slack", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
require(trailing_mean, kalman_step, transition_matrix, observation_matrix, run_rank2, run_rank4, track_rmse, ellipse_area)
slack = flow.scaled(0.1)
slack_drifts = ocean.simulate_drifts(slack, np.random.default_rng(2024), 50)
raw = np.array([track_rmse(d.fixes, d.position) for d in slack_drifts])
slack_cv = ocean.constant_velocity_filter(kalman_step, transition_matrix, observation_matrix, sigma_v0=slack.current)
slack_result = ocean.compare(slack_drifts, slack, trailing_mean, run_rank2, slack_cv, run_rank4, track_rmse,
                              ellipse_area, sigma_walk=15.0)  # 15 m: chosen on the tuning set, not on these drifts
print("Slack water, 0.05 m/s; rank-2 random-walk step sigma_walk = 15 m (chosen on the tuning set, seed 7)")
print(ocean.format_comparison(slack_result, raw))

# %% nbgrader={"grade": false, "grade_id": "comparison_figure", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(trailing_mean, kalman_step, transition_matrix, observation_matrix, run_rank2, run_rank4, track_rmse, ellipse_area)
fig = ocean.plot_comparison({"current, 0.5 m/s": current_result, "slack water, 0.05 m/s": slack_result})

# %% [markdown]
# **Written answer 3 (2 points).** Does the handout's ranking hold? Use the two tables and the figure (its right-hand panels pair each drift's scores). Compared with the rank-2
# filter, the rank-4 filter adds two ingredients: a velocity in the state, and the map of the current. What does each
# contribute, in the current and in slack water? (The CV control has the first and not the second.) When does the
# rank-2 filter beat the moving average, and why not always? (Not scored, but worth a look: are the filters' 2-sigma
# ellipses honest?)

# %% [markdown] nbgrader={"grade": true, "grade_id": "discussion", "locked": false, "points": 2, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** The rank-4 filter is best in both currents, at about 30 m RMSE in each, best of the four on most
# drifts (42 of 50 here in the current, 32 of 50 in slack water; over many drifts about 9 in 10 in the current and 2
# in 3 or more in slack water: which drifts, and how many, depends on the draw), <!-- claim: castaway-bob/rank4-best-in-both -->
# and with the smallest ellipses. <!-- claim: castaway-bob/rank4-smallest-ellipses -->
# That its two scores agree so closely is no coincidence: both tables use the same seed, so the drifts share their starts,
# forces and GPS errors, and with an exact map the filter's error obeys the same equations whatever the current is,
# apart from the small error of evaluating the current at the estimate instead of at Bob. On matched drifts its RMSE in
# the two currents differs by less than 1 m on nearly every drift. <!-- claim: castaway-bob/rank4-same-in-both --> The CV
# control and the no-map ablation separate its ingredients.
#
# *In the 0.5 m/s current* the rank-2 filter is no better than the moving average: both are near 48-50 m. <!-- claim: castaway-bob/rank2-ties-moving-average-in-current -->
# Its random walk assumes that Bob's next step averages to zero, but the
# current moves him about 25 m every minute in a steady direction, so the filter lags behind him, by about
# $v\,dt\,(1-K)/K$ for a steady-state gain $K$: $K \approx 0.45$ at $\sigma_{walk} = 30$ m, a lag of about 31 m, and
# what we measure along his track is within a few per cent of that. <!-- claim: castaway-bob/rank2-lag-formula --> A small $\sigma_{walk}$ averages more
# fixes but lags more; a large one lags less but averages fewer. No $\sigma_{walk}$ from 5 to 60 m brings it more than
# 2 m below the moving average. <!-- claim: castaway-bob/rank2-best-step-only-ties --> A velocity in the state removes most of
# that lag: the CV control is about 16 m better than the rank-2 filter, at about 33 m, on nearly every drift. <!-- claim: castaway-bob/velocity-state-gain-in-current -->
# The current map gains a further 3 to 4 m on average, to about
# 30 m, on most drifts: <!-- claim: castaway-bob/current-map-gain-in-current --> the CV filter must learn each change of the
# current from noisy fixes, while the rank-4 filter is told. Without the map the rank-4 model is useless here: its damped
# velocity, a few cm/s, cannot follow a 0.5 m/s current, and told that the sea is still it scores about 60 m, worse than
# the moving average. <!-- claim: castaway-bob/no-map-fails-in-current -->
#
# *In slack water* Bob barely moves, so the random walk is a good model. With a small step (15 m, chosen on the tuning
# set, not on the drifts scored) the rank-2 filter averages many fixes and beats the moving average clearly (about 33 m against 42 m) on nearly every drift. <!-- claim: castaway-bob/rank2-beats-moving-average-in-slack -->
# A velocity in the state then adds little: the CV control is
# about 1-2 m better than the rank-2 filter, on more drifts than not. <!-- claim: castaway-bob/velocity-state-small-gain-in-slack -->
# The rank-4 filter is about 1-2 m better than the CV control, on most drifts. <!-- claim: castaway-bob/rank4-gain-in-slack -->
# The ablation splits that edge: the map is worth only about half a metre (the rank-4 filter beats its no-map ablation
# on about 2 drifts in 3), <!-- claim: castaway-bob/map-gain-in-slack --> and the rest, about 1 m, comes from the model of
# Bob's damped velocity ($\alpha = 0.95$, which keeps the velocity estimate small, where the CV control lets it wander). <!-- claim: castaway-bob/damping-gain-in-slack -->
#
# So the velocity state is what matters in a strong current, where the map adds a further 3-4 m; in slack water every
# ingredient adds a metre or two at most, and the map only about half a metre. The handout's ranking of rank 4 over
# rank 2 holds everywhere, but its ranking of rank 2 over the moving average holds only in slack water. The ellipses of
# the CV control and the rank-4 filter are honest: they hold Bob 85-90 % of the time, against 86.5 % for honest
# ellipses. The rank-2 filter's hold him about 83 % of the time in the current (slightly overconfident) and about 92 %
# in slack water (too wide). <!-- claim: castaway-bob/coverage -->
#
# **Rubric (2 points).** 1 point: reads the tables correctly: rank 4 best in both currents; rank 2 about equal to or
# worse than the moving average in the current, better in slack water; the CV control far better than rank 2 in the
# current and only a little better in slack water. 1 point: attributes the gains: the velocity state removes the random
# walk's lag behind a steadily drifting Bob (most of the gain in the current); the current map is worth 3-4 m in the
# current (the CV control's gap) but little in slack water, where the no-map row shows that most of the rank-4 filter's
# small edge comes from its damped-velocity model. Give full marks to a student who reads the rank-4 filter's edge in
# slack water as small, or who says the tables cannot credit it to the map. The ellipses' honesty is not scored: the
# coverage numbers are not required, and a student who leaves that part out loses nothing.
# ### END SOLUTION

# %% [markdown]
# ## 8. Going further
#
# Nothing in this section is graded. It holds the details behind the main text: how the flow was made, an
# experiment on rounding, and checks that the comparison's settings are fair. Its claims are checked like all the
# others.

# %% [markdown]
# ### The flow, and an honest caveat
#
# A real island wake has a Reynolds number $Re = UD/\nu$ of about $5 \times 10^8$ (water's $\nu$ is
# $10^{-6}\ \mathrm{m^2/s}$). No 2-D grid can resolve that. We simulated the wake at $Re = 150$, where a clean vortex street forms and a grid of
# 240 x 100 cells resolves it. Then we rescaled it to the ocean: diameter $D = 1$ km, current
# $U = 0.5$ m/s, and one time unit $D/U = 2000$ s. At $Re = 150$ the viscosity is $UD/Re = 3.3\ \mathrm{m^2/s}$.
# Read that as an *eddy* viscosity, the mixing of all the motion smaller than the grid. That value is
# plausible for the upper ocean. PhiFlow solves the 2-D incompressible equations (7)-(8) on cells of 100 m, with a
# pressure-projection step like the one the handout describes; we ship means over blocks of 2 x 2 cells.
#
# > **Handout correction.** Taking the divergence of the momentum equation (8) with $\nabla\cdot\vec u = 0$
# > removes both $\partial_t \vec u$ and the viscous term, since $\nabla\cdot\nabla^2\vec u = \nabla^2(\nabla\cdot\vec u) = 0$.
# > The pressure equation is therefore $\nabla^2 p = -\rho\,\nabla\cdot(\vec u\cdot\nabla\vec u)$, not (9) as printed.
# > The $\eta$ in (8) is the kinematic viscosity $\nu$.

# %% [markdown]
# ### The Joseph form under rounding
#
# At the optimal gain the Joseph form (13) equals the short form $(I - KH)P$. But a
# computed gain is never exactly optimal: it carries rounding errors. For a gain $K + E$ with an error $E$, the
# Joseph form gives exactly $\hat P(K + E) = \hat P(K) + ESE^T$, for the whole matrix: the error is of second order
# in $E$, symmetric, and positive semi-definite, so it can only widen the covariance. The short form gives
# $(I - KH)P - EHP$: its error is of first order, and nothing keeps it symmetric or positive. The cell below rounds your gain
# to single precision (a relative error of about $6\times10^{-8}$, as if the filter ran in `float32`) on 300 random
# 4-state problems, and updates with both forms in double precision from that same gain. Each row makes the fixes more
# precise relative to the prior: $R$ is the given fraction of the prior's mean variance.

# %% nbgrader={"grade": false, "grade_id": "joseph_rounding", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(kalman_gain, joseph_covariance)
rounding = ocean.rounding_experiment(kalman_gain, joseph_covariance, np.random.default_rng(3),
                                     ratios=(1e-2, 1e-4, 1e-6, 1e-8, 1e-10))
print("Share of 300 problems whose updated covariance has a negative eigenvalue, and the median of")
print("max|P - P^T| / max|P|, with the gain rounded to single precision:")
print(ocean.format_rounding(rounding))


# %% [markdown]
# The short form's covariance is no longer symmetric: its relative asymmetry is about $3\times10^{-8}$, the
# rounding of the gain, against less than $10^{-14}$ for the Joseph form, at every ratio. <!-- claim: castaway-bob/short-form-loses-symmetry -->
#
# When the fixes are $10^8$ times more precise than the prediction (in variance), the short form has a negative
# eigenvalue, a negative variance, in most problems, and the Joseph form in none; at ratios of $10^{-6}$ and above
# neither does. The threshold sits where $R/P^-$ is about the gain's relative error, $6\times10^{-8}$: the updated
# position variance is then about $R$, and the short form's error $-EHP$ is about $6\times10^{-8}P$, as large as it. <!-- claim: castaway-bob/short-form-loses-definiteness -->
# (Rounding inside the Joseph form's own products can still make it indefinite, but only when an eigenvalue is as
# small as the machine precision times the largest.)
#
# Bob's filter is far from that regime: after the first minutes its
# GPS variance is larger than its predicted position variance at every fix, <!-- claim: castaway-bob/bob-far-from-rounding-trouble --> and
# in double precision the two forms give him the same covariances to better than $10^{-9}$ (relative). <!-- claim: castaway-bob/forms-agree-for-bob --> For
# Bob the Joseph form is insurance; for precise sensors or low-precision arithmetic it is a necessity.

# %% [markdown]
# ### Why a control, and its step
#
# The handout gives no model for its rank-2 filter, and it says that the filter estimates velocity as well as
# position covariances. So its rank-2 filter may carry a velocity too. A filter that does is our CV control, and the
# comparison covers that reading of the handout as well.
#
# We did not tune the control against the rank-4 filter: its step is $\sigma_F$. Of the steps
# $\sigma_v$ = 0.01, 0.015, 0.02 and 0.03 m/s, 0.02 m/s gives a mean RMSE within 0.5 m of the best in both
# currents (in slack water 0.015 m/s is a few tenths of a metre better). <!-- claim: castaway-bob/cv-step-near-best -->

# %% [markdown]
# ### The slack-water step, chosen on other drifts
#
# In the current we gave the random walk a step of one minute's travel. In slack water that rule gives 5 m, and on
# the tuning set it does worse than the moving average. <!-- claim: castaway-bob/slack-walk-minute-step-too-small -->
# The random walk must also absorb Bob's slow but steady drift over the many minutes the filter remembers, and a
# step that small cannot.
#
# The choice of 15 m does not hang on which drifts we tune on. It also scores best of the six steps on three other
# sets of 50 slack-water drifts, and on the 50 drifts of the comparison itself, so tuning on those would have picked
# the same step. <!-- claim: castaway-bob/slack-walk-step-robust -->
# The optimum is flat, though. A step of 12.5 m, between two steps of the grid, scores within 0.3 m of 15 m on each of
# these sets (better on some, worse on others), while 10 m costs about 0.5 to 2 m and 20 m about 1.5 to 2 m. <!-- claim: castaway-bob/slack-walk-optimum-flat -->
# To see it yourself, draw the tuning set with `ocean.simulate_drifts(flow.scaled(0.1), np.random.default_rng(7), 50)`
# and average `track_rmse(run_rank2(d.fixes, sigma_walk=s)[0], d.position)` over its drifts `d` for each step `s`.

# %% [markdown]
# ### To explore
#
# The rank-4 filter was given the *exact* current. A real forecast is wrong by 10-30 %. Try
# `run_rank4(drift.fixes, flow.scaled(0.8), drift.t)` on drifts in the true `flow`, and see how much of its advantage
# survives. Is its 2-sigma ellipse still honest? Try a larger `sigma_F` in the filter too.
