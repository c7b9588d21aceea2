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
# # Lab reentry-pf: tracking a falling object, and its ballistic coefficient, with a particle filter
#
# An object (a meteorite, or a space module) falls through the atmosphere. A radar on the ground measures its
# altitude ten times a second, with errors of about 500 m. From those readings we want its altitude, its speed and
# its **ballistic coefficient** $\beta$, which sums up how its mass, shape and size let the air slow it down. The
# model is nonlinear, so you will write a **particle filter**: a cloud of thousands of guesses, moved by the model,
# weighed against each reading, and resampled.
#
# **What you will do**
# 1. Write the model, and simulate the truth and the radar readings.
# 2. Write the handout's particle filter (an *auxiliary particle filter*) one piece at a time.
# 3. Measure it against a yardstick of how well $\beta$ can be known, and check the health of its resampling.
# 4. If you want more: read a study of many settings, and judge which of its differences are real (not graded).
#
# **What is graded, and about how long each part takes**
#
# | part | what you write | points | about |
# |---|---|---|---|
# | 1. The model | `tracking_dynamics` | 1 | 15 min |
# | 2. The truth and the radar | `simulate_radar` | 2 | 20 min |
# | 3. The prior cloud | `initial_cloud` | 1 | 10 min |
# | 4. One step of the particle filter | `pf_step` | 3 | 70 min |
# | 6. The filter over half a minute | `run_particle_filter` | 2 | 30 min |
# | 7. Show and tell, and a yardstick | the question on $\beta$ | 2 | 45 min |
# | **all** | 5 functions, 1 written answer | **11** | **about 3 h 10 min** |
#
# Add about 15 minutes to read this introduction, and 5 for section 5, which has no blank.
#
# Section 8, "Going further", is optional reading: nothing there is graded.
#
# **How this notebook works.** Each blank is one function in a cell that says `YOUR CODE HERE`. Below it, a
# read-only cell runs *visible checks* on cases you can work out by hand; their messages say what to fix. When you
# are graded, *hidden tests* compare your function with a reference on random inputs, and each function is graded
# on its own. The test of `pf_step` is statistical: a correct step fails it with probability below one in a million.
# A graded function must leave the arrays it is given unchanged, and draw every random number from the `rng` it is
# given, never from `np.random`. You may add cells of your own to try things out: they are not graded. The
# written answer is marked by hand. The grey cells are locked: grading puts back their originals. Before you submit, press **Validate**: it lists each blank that is not written yet or
# fails its visible checks.
#
# *Credit.* This lab follows the Day 5 exercise of the course "Bayesian Scientific Computing" by Daniela
# Calvetti and Erkki Somersalo (Case Western Reserve University), given in Lyngby in December 2019. Its
# model, numbers and algorithm are theirs. The auxiliary particle filter is due to Pitt and Shephard (1999),
# the bootstrap filter to Gordon, Salmond and Smith (1993). The text, code and data here are our own, and so
# are any errors. Where the handout is ambiguous, we say so and say which reading we use.

# %% nbgrader={"grade": false, "grade_id": "setup", "locked": true, "schema_version": 3, "solution": false, "task": false}
# Set-up: run this cell first.
# %xmode Minimal
# %matplotlib inline
from functools import partial

import numpy as np
import matplotlib.pyplot as plt
from scipy.integrate import solve_ivp

from course import falling_object
from course.falling_object import (BETA_INIT, CHOSEN_STD, DT, ETA, GAMMA, INNOVATION_STD, PRIOR_STD, SIGMA, V_INIT,
                                   X0_TRUE, FilterHistory, G, ResamplingHealth, check_history,
                                   credibility_interval)
from course.checks import check_array, check_close, check_pair, check_true, passed, require, validate

# %% [markdown]
# ## 1. The model
#
# The state is $x = [h, v, \beta]$: the altitude $h$ in **m**, the **downward** speed $v$ in **m/s** ($v > 0$
# while the object falls) and the ballistic coefficient $\beta$ in kg/(m s$^2$). The object falls,
# gravity pulls it down, and the air drags it back in proportion to the air density $\rho(h)$ and $v^2$:
#
# $$\frac{dh}{dt} = -v \quad (1), \qquad \frac{dv}{dt} = g - g\,\frac{\rho(h)\, v^2}{2\beta} \quad (2), \qquad
#   \frac{d\beta}{dt} = 0 \quad (3), \qquad \rho(h) = \gamma\, e^{-\eta h} \quad (4),$$
#
# with $g$ = `G` = 9.81 m/s$^2$, $\gamma$ = `GAMMA` = 1.754 kg/m$^3$ and $\eta$ = `ETA` = 1.39e-4 1/m. Together,
# $\dot x = f(x)$ with $f(x) = [-v,\ g - g\rho(h)v^2/(2\beta),\ 0]$ (5). Equation (3) says that $\beta$ is a
# constant of the object; we just do not know it.
#
# A cloud of $N$ particles is an array of shape `(3, N)`: rows $h$, $v$, $\beta$, and column $\ell$ is particle
# $x^{(\ell)}$. Write `tracking_dynamics(t, x)`, the handout's `TrackingDynamics`, so that it takes one state,
# shape `(3,)`, or a cloud, shape `(3, N)`, and returns $f$ with the same shape. The ODE solver passes the time `t`;
# the model does not use it. No loop: `h, v, beta = x` unpacks the rows, and NumPy works on all of them at once.
# For $d\beta/dt$ write `np.zeros_like(beta)`, not `0`: a bare 0 has the shape of one state, not of a cloud.

# %% nbgrader={"grade": false, "grade_id": "load_data", "locked": true, "schema_version": 3, "solution": false, "task": false}
data = falling_object.load()
print(f"{data.t.size} radar readings, t = {data.t[0]:.1f} s to {data.t[-1]:.1f} s, every {DT} s")
print(f"truth at t = 0: h = {data.x_true[0, 0]:.0f} m, v = {data.x_true[1, 0]:.0f} m/s, beta = {data.x_true[2, 0]:.0f}")
print(f"first readings b_0, b_1, b_2 = {np.round(data.b[:3])} m (radar noise sigma = {SIGMA:.0f} m)")

# %% nbgrader={"grade": false, "grade_id": "tracking_dynamics", "locked": false, "schema_version": 3, "solution": true, "task": false}
def tracking_dynamics(t, x):
    """f(x) of equation (5) for x of shape (3,) or (3, N); returns the same shape."""
    ### BEGIN SOLUTION
    h, v, beta = np.asarray(x, dtype=float)
    # rho(h) = gamma exp(-eta h)   (4)
    rho = GAMMA * np.exp(-ETA * h)
    # dh/dt = -v   (1);   dv/dt = g - g rho(h) v^2 / (2 beta)   (2);   dbeta/dt = 0   (3)
    return np.stack([-v, G - G * rho * v**2 / (2 * beta), np.zeros_like(beta)])
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_tracking_dynamics", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(tracking_dynamics)
# Visible checks. At the ground (h = 0) the density is gamma = 1.754 kg/m^3. For v = 200 m/s and beta = 1754 the
# drag is g rho v^2 / (2 beta) = 9.81 * 1.754 * 200^2 / 3508 = 9.81 * 20 = 196.2 m/s^2, so f = [-200, 9.81 - 196.2, 0].
f = check_array(tracking_dynamics(0.0, np.array([0.0, 200.0, 1754.0])), "tracking_dynamics(0, [0, 200, 1754])", (3,),
                "One state in, one derivative [dh/dt, dv/dt, dbeta/dt] out.")
check_close(f, [-200.0, 9.81 - 196.2, 0.0], "f at h = 0 m, v = 200 m/s, beta = 1754",
            "dh/dt = -v (v > 0 is downward), dv/dt = g - g rho v^2 / (2 beta), dbeta/dt = 0.")
# Far above the atmosphere (h = 1000 km) there is no air: free fall, dv/dt = g.
check_close(tracking_dynamics(0.0, np.array([1e6, 3000.0, 2e4])), [-3000.0, 9.81, 0.0], "f at h = 1000 km",
            "Is rho(h) = GAMMA * exp(-ETA * h), with the minus sign?")
# A cloud of three particles, shape (3, 3): column l is the derivative of particle l alone.
cloud = np.array([[0.0, 1e6, 30_000.0], [200.0, 3000.0, 2500.0], [1754.0, 2e4, 19_161.0]])
F = check_array(tracking_dynamics(0.0, cloud), "tracking_dynamics(0, cloud) for 3 particles", (3, 3),
                "Unpack the rows with h, v, beta = x and build the result with np.stack; np.zeros_like(beta) "
                "gives dbeta/dt = 0 of the right shape.")
check_close(F[:, 0], f, "the derivative of particle 0 of the cloud", "Each column should depend on its own particle only.")
passed("tracking_dynamics")

# %% nbgrader={"grade": true, "grade_id": "test_tracking_dynamics", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of tracking_dynamics (1 point): random single states and clouds of 1, 7 and 1000 particles.
# Validate (and this cell) first checks that tracking_dynamics passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(tracking_dynamics)
### BEGIN HIDDEN TESTS
from solutions.reentry_pf.hidden_tests import check_tracking_dynamics
check_tracking_dynamics(tracking_dynamics)
### END HIDDEN TESTS

# %% [markdown]
# ## 2. The truth and the radar
#
# The radar reads the altitude at $t_j = j\,\Delta t$, $\Delta t$ = 0.1 s, $j = 0, 1, \dots, 300$: half a minute.
# Each reading is the true altitude plus Gaussian noise,
#
# $$b_j = q^T x(t_j) + \varepsilon_j = h(t_j) + \sigma e_j, \qquad q = [1, 0, 0]^T, \qquad e_j \sim N(0, 1),$$
#
# with $\sigma$ = `SIGMA` = 500 m. Write `simulate_radar(x0, t, sigma, rng)`. It computes the noiseless truth
# `x_true`, shape `(3, len(t))`, with `scipy.integrate.solve_ivp(..., method="RK45", t_eval=t)` (MATLAB's `ode45`)
# from `x0` at `t[0]` to `t[-1]`, then draws `e = rng.standard_normal(len(t))` **in one call** from the `rng` you
# are given, and returns `(x_true, b)`.
#
# Every result is measured against the truth, so it must be far more accurate than the radar. Pass
# `rtol=1e-10, atol=1e-8` to `solve_ivp`: from the lab's start the altitude is then right to under 0.01 mm, where
# the default `rtol=1e-3` is about 20 m off. That is far below the radar's 500 m, but the visible checks compare your
# truth with the shipped one to 1 m. The price is about 650 evaluations of $f$ instead of 75. <!-- claim: reentry-pf/solver-tolerances -->
# (To see it yourself, in a cell of your own: solve with the defaults and with much tighter tolerances, then compare
# the altitudes `.y[0]` and the numbers of evaluations `.nfev`.) The shipped `data` came from this computation,
# from $x_0 = [61000\ \mathrm{m}, 3048\ \mathrm{m/s}, 19161]$; the visible checks compare your truth with it.

# %% nbgrader={"grade": false, "grade_id": "simulate_radar", "locked": false, "schema_version": 3, "solution": true, "task": false}
def simulate_radar(x0, t, sigma, rng):
    """Truth x_true (3, len(t)) from x0 at the times t [s], and readings b (len(t),) [m]."""
    ### BEGIN SOLUTION
    t = np.asarray(t, dtype=float)
    # x' = f(x), x(t_0) = x0, solved with RK45 (ode45) and reported at every t_j
    solution = solve_ivp(
        tracking_dynamics, (t[0], t[-1]), np.asarray(x0, dtype=float), method="RK45", t_eval=t, rtol=1e-10, atol=1e-8
    )
    if not solution.success:
        raise RuntimeError(f"solve_ivp failed: {solution.message}")
    x_true = solution.y
    # b_j = q^T x(t_j) + sigma e_j,  q = [1, 0, 0],  e ~ N(0, I) drawn in one call
    b = x_true[0] + sigma * rng.standard_normal(t.shape[0])
    return x_true, b
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_simulate_radar", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(simulate_radar)
# Visible checks on the lab's case: x0 = [61000 m, 3048 m/s, 19161], t_j = 0.1 j s for j = 0..300.
x_sim, b_sim = check_pair(simulate_radar(falling_object.X0_TRUE, data.t, SIGMA, np.random.default_rng(1)),
                          "simulate_radar", "x_true", "b")
x_sim = check_array(x_sim, "x_true", (3, 301), "One column per time t_j: rows h, v, beta (solve_ivp's .y).")
b_sim = check_array(b_sim, "b", (301,), "One reading per time t_j.")
check_close(x_sim[:, 0], falling_object.X0_TRUE, "the truth at t_0", "The solution starts at x0.")
# A grid that starts at t_0 = 5 s: the object is at x0 at t_0, not at t = 0.
x_late, _ = check_pair(simulate_radar(falling_object.X0_TRUE, np.array([5.0, 5.1]), SIGMA, np.random.default_rng(1)),
                       "simulate_radar", "x_true", "b")
check_close(check_array(x_late, "x_true on t = [5.0, 5.1] s", (3, 2))[:, 0], falling_object.X0_TRUE,
            "the truth at t_0 = 5 s", "Start the integration at t[0], where the object is at x0, not at t = 0.")
check_close(x_sim[2], np.full(301, 19_161.0), "the true beta", "dbeta/dt = 0: beta never changes.")
# The shipped truth came from the same equations with tight tolerances: yours should agree to 1 m and 0.25 m/s.
# Loose tolerances are off by tens of metres; hundreds or more point at the model or the start instead.
check_close(x_sim[0], data.x_true[0], "your true altitude against the shipped truth, to 200 m",
            "This is far more than loose tolerances explain: make tracking_dynamics pass its checks, and integrate "
            "from x0 at t[0].", rtol=0.0, atol=200.0, show_expected=False)
check_close(x_sim[0], data.x_true[0], "your true altitude against the shipped truth",
            "Pass tighter rtol and atol to solve_ivp: the default rtol = 1e-3 is about 20 m off here.",
            rtol=0.0, atol=1.0, show_expected=False)
check_close(x_sim[1], data.x_true[1], "your true speed against the shipped truth",
            "Pass tighter rtol and atol to solve_ivp.", rtol=0.0, atol=0.25, show_expected=False)
# The noise: b - h should be sigma times one call of rng.standard_normal(len(t)) on the generator you were given.
e = np.random.default_rng(1).standard_normal(301)
check_close(b_sim - x_sim[0], SIGMA * e, "the radar noise b - h",
            "Draw e = rng.standard_normal(len(t)) in one call, from the rng argument, and add sigma * e to h.",
            rtol=1e-9, atol=1e-6, show_expected=False)
passed("simulate_radar")

# %% nbgrader={"grade": true, "grade_id": "test_simulate_radar", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of simulate_radar (2 points): random starts, time grids and noise levels; the truth to 1 m
# and 0.25 m/s, and the noise draw by draw.
# Validate (and this cell) first checks that simulate_radar passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(simulate_radar)
### BEGIN HIDDEN TESTS
from solutions.reentry_pf.hidden_tests import check_simulate_radar
check_simulate_radar(simulate_radar)
### END HIDDEN TESTS

# %% [markdown]
# ## 3. The prior cloud
#
# The filter starts from a cloud of $N$ particles drawn around a first guess: the first reading for the
# altitude, and $v_\text{init}$ = `V_INIT` = 3000 m/s and $\beta_\text{init}$ = `BETA_INIT` = 20000 for the rest,
#
# $$x^{(\ell)} = \begin{bmatrix} b_0 \\ v_\text{init} \\ \beta_\text{init} \end{bmatrix} + C^{1/2} z^{(\ell)},
#   \qquad z^{(\ell)} \sim N(0, I_3), \qquad \ell = 1, \dots, N,$$
#
# where $C^{1/2}$ is diagonal with the prior standard deviations `PRIOR_STD` = (500 m, 200 m/s, 1500). Every
# particle gets the weight $1/N$. (The handout writes $w$ for both the random draws and the weights; we write
# $z$ for the draws, and keep $w$ for the weights.)
#
# Write `initial_cloud(b0, N, rng)`: draw all the $z^{(\ell)}$ as `rng.standard_normal((3, N))` **in one call**
# (column $\ell$ is $z^{(\ell)}$) and return the cloud, shape `(3, N)`, and the weights, shape `(N,)`.

# %% nbgrader={"grade": false, "grade_id": "initial_cloud", "locked": false, "schema_version": 3, "solution": true, "task": false}
def initial_cloud(b0, N, rng):
    """Prior cloud x (3, N) around [b0, V_INIT, BETA_INIT] and equal weights w (N,)."""
    ### BEGIN SOLUTION
    mean = np.array([b0, V_INIT, BETA_INIT])
    # x^(l) = [h_init, v_init, beta_init] + C^(1/2) z^(l),  z^(l) ~ N(0, I_3),  C^(1/2) = diag(PRIOR_STD)
    x = mean[:, None] + PRIOR_STD[:, None] * rng.standard_normal((3, N))
    # w^(l) = 1 / N
    w = np.full(N, 1.0 / N)
    return x, w
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_initial_cloud", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(initial_cloud)
# Visible checks. Four particles around b0 = 60000 m; the same seed gives the same standard normal draws z.
x_prior, w_prior = check_pair(initial_cloud(60_000.0, 4, np.random.default_rng(7)), "initial_cloud", "x", "w")
x_prior = check_array(x_prior, "the prior cloud", (3, 4), "One column per particle: rows h, v, beta.")
w_prior = check_array(w_prior, "the prior weights", (4,))
check_close(w_prior, np.full(4, 0.25), "the prior weights for N = 4", "Every particle starts with weight 1/N.")
z = np.random.default_rng(7).standard_normal((3, 4))
check_close(x_prior, np.array([[60_000.0], [3000.0], [20_000.0]]) + np.array([[500.0], [200.0], [1500.0]]) * z,
            "the prior cloud for b0 = 60000 and N = 4",
            "Draw z = rng.standard_normal((3, N)) from the rng argument (not np.random: the same seed must give "
            "the same cloud), in one call, multiply row i by the prior standard deviation of "
            "variable i (PRIOR_STD[:, None] * z), and add the mean [b0, V_INIT, BETA_INIT] as a column.")
# A large cloud has the prior's mean and standard deviations.
x_big, _ = initial_cloud(60_000.0, 100_000, np.random.default_rng(8))
check_close(x_big.mean(axis=1), [60_000.0, 3000.0, 20_000.0], "the mean of 100000 prior particles", rtol=2e-3)
check_close(x_big.std(axis=1), PRIOR_STD, "the standard deviations of 100000 prior particles",
            "Scale by the standard deviations (500, 200, 1500), not by the variances.", rtol=0.02)
passed("initial_cloud")

# %% nbgrader={"grade": true, "grade_id": "test_initial_cloud", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of initial_cloud (1 point): random first readings, N = 1, 5 and 2000, seeded generators.
# Validate (and this cell) first checks that initial_cloud passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(initial_cloud)
### BEGIN HIDDEN TESTS
from solutions.reentry_pf.hidden_tests import check_initial_cloud
check_initial_cloud(initial_cloud)
### END HIDDEN TESTS

# %% [markdown]
# ## 4. One step of the particle filter (an auxiliary particle filter)
#
# Write `pf_step(x, w, b_next, rng, *, innovation_std=INNOVATION_STD, info=None)`. It takes the cloud `x`, shape
# `(3, N)`, at $t_j$, its normalised weights `w`, shape `(N,)`, and the next reading `b_next`, and returns the cloud
# at $t_{j+1}$ and its normalised weights. It takes four steps, the handout's (a) to (d); the next cells give them
# in the order you write them.
#
# **(a) Propagate** every particle with one Forward Euler step of the model:
# $\hat x^{(\ell)} = x^{(\ell)} + \Delta t\, f(x^{(\ell)})$, with $\Delta t$ = `DT` = 0.1 s. These are the
# *candidates*. One call of `tracking_dynamics` on the whole cloud does it: no loop over the particles.

# %% [markdown]
# **(b) Fitness.** Weigh each candidate by how well its altitude $\hat x^{(\ell)}_1$ explains the new reading,
# then normalise:
#
# $$\hat w^{(\ell)} = w^{(\ell)} \exp\Big(-\frac{1}{2\sigma^2}\big|\hat x^{(\ell)}_1 - b_{j+1}\big|^2\Big), \qquad
#   \hat w^{(\ell)} \leftarrow \hat w^{(\ell)} \Big/ \textstyle\sum_k \hat w^{(k)}.$$
#
# Compute it in logarithms. When a reading is tens of $\sigma$ from every particle, every exponential underflows
# to 0, and normalising gives 0/0. Instead, compute
# $\log \hat w^{(\ell)} = \log w^{(\ell)} - |\hat x^{(\ell)}_1 - b_{j+1}|^2 / 2\sigma^2$, subtract the largest, then
# exponentiate and normalise. The weights are the same, and nothing underflows. Here $\sigma$ is the global
# `SIGMA`. `np.log(w)` warns only if a weight is exactly 0: its `-inf` is then harmless, and no graded case has
# a weight of 0.

# %% [markdown]
# **(c) Resample and perturb.** Draw $N$ indices $k_1, \dots, k_N$ **with replacement**, with probabilities
# $\hat w$ (multinomial resampling: fit candidates are copied several times, unfit ones die out). Then give each
# copy its own random perturbation:
#
# $$x^{(\ell)}_\text{new} = \hat x^{(k_\ell)} + D^{1/2} z^{(\ell)}, \qquad z^{(\ell)} \sim N(0, I_3).$$
#
# $D^{1/2}$ is diagonal with the standard deviations `innovation_std`. Use the keyword argument, not the constant:
# its default is the handout's `INNOVATION_STD` = (100 m, 100 m/s, 5), and section 8 (Going further) tries others.
# `rng.choice(N, size=N, p=w_hat)` draws the indices, `x_hat[:, k]` copies the chosen columns, and
# `rng.standard_normal((3, N))` draws all the perturbations at once. Systematic resampling (one uniform, then
# $N$ evenly spaced points in the cumulative weights) also passes the visible checks and the hidden test; section 7
# says what it changes in the figures.
#
# Without the perturbation, the copies of a candidate would stay identical. The handout calls it the *innovation*;
# we call it the **artificial process noise**, since the model (5) has none: $D$ is a setting of the filter, not a
# property of the object.

# %% [markdown]
# **(d) Re-weigh.** The perturbation moved each particle away from the candidate it copies, so correct for it,
# again in logarithms, and normalise:
#
# $$w^{(\ell)} = \exp\Big(-\frac{1}{2\sigma^2}\Big(\big|(x^{(\ell)}_\text{new})_1 - b_{j+1}\big|^2
#   - \big|\hat x^{(k_\ell)}_1 - b_{j+1}\big|^2\Big)\Big).$$
#
# Unlike (b), (d) has no factor of the parent's old weight $w^{(k_\ell)}$: the resampling in (c) has already used the
# old weights, and every copy starts again with an equal share.
#
# > **Reading of the handout.** In (d) the handout writes $x_1^{(k_\ell)}$ for the second altitude. It means the
# > *propagated parent candidate* $\hat x^{(k_\ell)}_1$ from (a), before the perturbation. (In (c) its index range
# > $\{1, \dots, n\}$ means $\{1, \dots, N\}$.)

# %% [markdown]
# **Diagnostics.** If `info` is a dict (not `None`), store two things in it for section 6: `info["ess"]`, the
# effective sample size $1/\sum_\ell (\hat w^{(\ell)})^2$ of the fitness weights that (c) draws with, and
# `info["parents"]`, the indices $k_\ell$.

# %% [markdown]
# **What this algorithm is.** Steps (a) to (d) are an **auxiliary particle filter** (Pitt and Shephard, 1999): its
# resampling *looks ahead* at the next reading, and (d) corrects for that. The **bootstrap filter** (Gordon,
# Salmond and Smith, 1993) resamples with the current weights alone. It is given (`falling_object.bootstrap_step`),
# and section 7 runs both.

# %% nbgrader={"grade": false, "grade_id": "pf_step", "locked": false, "schema_version": 3, "solution": true, "task": false}
def pf_step(x, w, b_next, rng, *, innovation_std=INNOVATION_STD, info=None):
    """Steps (a)-(d): cloud x (3, N), weights w (N,), reading b_next [m] -> new (x, w)."""
    ### BEGIN SOLUTION
    N = x.shape[1]
    # (a) x^(l) = x^(l) + dt f(x^(l)): Forward Euler for every particle at once
    x_hat = x + DT * tracking_dynamics(0.0, x)
    # (b) log w^(l) = log w(l) - |x^_1(l) - b_{j+1}|^2 / (2 sigma^2)   (a zero weight gives -inf)
    with np.errstate(divide="ignore"):
        log_w_hat = np.log(w) - (x_hat[0] - b_next) ** 2 / (2 * SIGMA**2)
    # w^(l) = w^(l) / sum w^, computed as exp(log w^ - max log w^) / sum(...)
    w_hat = np.exp(log_w_hat - np.max(log_w_hat))
    w_hat /= np.sum(w_hat)
    # (c) k_l drawn with replacement with probabilities w^ (multinomial resampling): k_l is the
    #     first index whose cumulative weight exceeds u_l ~ U(0, 1). Sorting the u_l does not
    #     change the draw, and lets the search and the copy run through memory in order.
    cdf = np.cumsum(w_hat)
    cdf /= cdf[-1]
    k = np.searchsorted(cdf, np.sort(rng.random(N)), side="right")
    # x_new(l) = x^(k_l) + D^(1/2) z(l),  z(l) ~ N(0, I_3),  D^(1/2) = diag(innovation_std)
    x_new = x_hat[:, k] + np.asarray(innovation_std)[:, None] * rng.standard_normal((3, N))
    # (d) log w(l) = -(|x_new_1(l) - b_{j+1}|^2 - |x^_1(k_l) - b_{j+1}|^2) / (2 sigma^2),
    #     with x^_1(k_l) the propagated parent before the innovation
    log_w = -((x_new[0] - b_next) ** 2 - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2)
    # w(l) = w(l) / sum w
    w_new = np.exp(log_w - np.max(log_w))
    if info is not None:
        # diagnostics: ESS = 1 / sum w^2 of the resampling weights, and the parents k_l
        info["ess"] = 1.0 / np.sum(w_hat**2)
        info["parents"] = k
    return x_new, w_new / np.sum(w_new)
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_pf_step", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(pf_step)
rng = np.random.default_rng(5)
# Visible check 1: a cloud of 2000 particles around h = 60000 m and a reading 300 m below it. The step returns
# 2000 particles and 2000 normalised, non-negative weights.
x_c = np.array([[60_000.0], [3000.0], [20_000.0]]) + np.array([[500.0], [200.0], [1500.0]]) * rng.standard_normal((3, 2000))
w_c = np.full(2000, 1 / 2000)
x_new, w_new = check_pair(pf_step(x_c, w_c, 59_700.0, rng), "pf_step", "x", "w")
x_new = check_array(x_new, "the new particles", (3, 2000), "Return the new cloud, shape (3, N).")
w_new = check_array(w_new, "the new weights", (2000,), "Return one weight per particle.")
check_close(np.sum(w_new), 1.0, "the sum of the new weights", "Normalise the weights of step (d).")
check_close(np.minimum(w_new, 0.0), np.zeros(2000), "the negative part of the new weights", "Weights are never negative.")
# Here the reading says little about beta, so the new cloud keeps about the prior's spread of beta, 1500: resampling
# draws many different parents, not only the fittest.
check_close(np.std(x_new[2]), 1500.0, "the spread of beta in the new cloud",
            "Draw N indices at random with the probabilities w^ (for example rng.choice(N, size=N, p=w_hat)).", rtol=0.2)
# Visible check 2: particle 0 (h = 20000 m, v = 3000 m/s, beta = 20000) carries almost all the weight, and the
# others (beta = 30000) have weight 1e-12 each. Resampling then copies particle 0 every time, and the innovation
# spreads the copies around its candidate, whose altitude is 20000 - 0.1 * 3000 = 19700 m, with standard
# deviations (100, 100, 5).
x_d = np.tile([[20_000.0], [3000.0], [30_000.0]], 2000)
x_d[2, 0] = 20_000.0
w_d = np.full(2000, 1e-12)
w_d[0] = 1.0
x_new, w_new = pf_step(x_d, w_d / np.sum(w_d), 19_700.0, rng)
# Every particle has the altitude and speed of particle 0 here, so the spread of the new altitudes and speeds is the
# innovation's alone, whatever was resampled. It is checked first: an innovation of the wrong size moves the means too.
check_true(np.all(np.ptp(x_new[:2], axis=1) > 0), "the copies of particle 0 all have the same altitude and speed",
           "Give each new particle its own draw of the innovation, after resampling: x^[:, k] + "
           "innovation_std[:, None] * rng.standard_normal((3, N)), one column of draws per particle, not one for all.")
check_close(np.std(x_new[:2], axis=1), INNOVATION_STD[:2], "the spread of the altitudes and speeds of the copies of particle 0",
            "After resampling, add innovation_std[:, None] * rng.standard_normal((3, N)), with the argument innovation_std "
            "(INNOVATION_STD by default): it holds standard deviations, not variances, so do not square it.", rtol=0.1)
check_close(np.mean(x_new[2]), 20_000.0, "the mean beta of the new particles",
            "Resample with the probabilities of (b), which include the old weights w: almost every new particle should "
            "be a copy of particle 0.", rtol=0.0, atol=1.0)
check_close(np.mean(x_new[0]), 19_700.0, "the mean altitude of the new particles",
            "Propagate before you resample: Forward Euler moves h from 20000 m to 19700 m in 0.1 s.", rtol=0.0, atol=25.0)
check_close(np.std(x_new[2]), INNOVATION_STD[2], "the spread of beta of the copies of particle 0",
            "After resampling, add innovation_std[:, None] * rng.standard_normal((3, N)): standard deviations, not "
            "variances, and one fresh draw per new particle.", rtol=0.1)
# Visible check 3: a reading 70 sigma below the cloud. The weights must still be finite and normalised.
x_new, w_new = pf_step(x_c, w_c, 25_000.0, rng)  # A NaN error here means every exp() underflowed to 0: use log-weights.
w_new = check_array(w_new, "the weights after a reading 70 sigma from the cloud", (2000,),
                    "exp(-(h - b)^2 / (2 sigma^2)) is 0 for every particle here: work with log-weights and subtract "
                    "the largest before you exponentiate.")
check_close(np.sum(w_new), 1.0, "the sum of the weights after a distant reading")
# The fittest candidate is then the lowest one, at min(h - 0.1 v): resampling copies it and its nearest neighbours.
check_close(np.mean(x_new[0]), np.min(x_c[0] - 0.1 * x_c[1]), "the mean altitude after a reading far below the cloud",
            "The new particles should descend from the lowest candidates: if they come from the highest, check the sign of "
            "your log-weights, -(h - b)^2 / (2 sigma^2). If exp() of your fitness weights underflows to 0 for every "
            "particle, normalising gives NaN: work with log-weights.", rtol=0.0, atol=150.0)
# Visible check 4: the keyword innovation_std sets the artificial process noise D^(1/2), and a dict passed as info
# receives the ESS of the fitness weights (all the weight is on particle 0 here, so it is 1) and the parents k_l (all 0).
info = {}
x_new, w_new = pf_step(x_d, w_d / np.sum(w_d), 19_700.0, rng, innovation_std=np.array([50.0, 20.0, 1.0]), info=info)
check_close(np.std(x_new, axis=1), [50.0, 20.0, 1.0], "the spread of the copies of particle 0 with innovation_std=(50, 20, 1)",
            "Use the keyword argument innovation_std for D^(1/2), not the constant INNOVATION_STD.", rtol=0.1)
check_close(info.get("ess", np.nan), 1.0, "info['ess'] when one candidate has all the fitness weight",
            "Store info['ess'] = 1 / sum(w_hat**2), the ESS of the fitness weights (b), when info is a dict.", rtol=1e-6)
check_close(np.asarray(info.get("parents", [-1])), np.zeros(2000), "info['parents'] when every new particle copies particle 0",
            "Store the indices k you resampled with: info['parents'] = k.")
# Visible check 5: equal old weights, 20000 particles around h = 60000 m (so candidates around 59700 m), and a reading
# 500 m below the candidates. The candidates' altitudes (standard deviation 500 m) and the reading (sigma = 500 m) are two
# Gaussians: the new cloud's weighted mean altitude lies at about 59445 m (halfway; the 100 m process noise moves it
# 5 m), and the ESS of the fitness weights is about N sqrt(3)/2 exp(-1/6) = 0.733 N (the candidates' spread is
# sqrt(500^2 + 20^2) m, a little over 500 m).
rng_e = np.random.default_rng(6)
x_e = np.array([[60_000.0], [3000.0], [20_000.0]]) + np.array([[500.0], [200.0], [1500.0]]) * rng_e.standard_normal((3, 20_000))
info = {}
x_new, w_new = pf_step(x_e, np.full(20_000, 1 / 20_000), 59_200.0, rng_e, info=info)
check_close(info.get("ess", np.nan) / 20_000, np.sqrt(3) / 2 * np.exp(-1 / 6),
            "info['ess'] / N for equal old weights and a reading 500 m below the candidates",
            "It is the ESS 1 / sum(w_hat**2) of the fitness weights w^ of (b), made from the propagated candidates x^_1, "
            "not of the old weights (equal here, so their ESS is N).", rtol=0.02)
check_close(x_new[0] @ w_new, 59_450.0, "the weighted mean altitude of the new cloud",
            "(b) weighs the propagated candidates x^_1 = x_1 - dt v (not the old altitudes), and (d) divides out the "
            "parent's fitness: w = exp(-(|x_new_1 - b|^2 - |x^_1(k_l) - b|^2) / (2 sigma^2)).", rtol=0.0, atol=30.0)
# The weights of (d), exactly: from the new cloud, the parents k_l the step reported in info and the propagated
# candidates x^ = x + dt f(x), each new weight is exp(-(|x_new_1 - b|^2 - |x^_1(k_l) - b|^2) / (2 sigma^2)), normalised.
# (A student trial: no (d) moved the mean above by only about 5 m, and a (d) with the wrong sign by about 20 m, both
# inside its 30 m tolerance; hence this exact check.)
x_hat_e = x_e + DT * tracking_dynamics(0.0, x_e)
k_e = np.asarray(info.get("parents", np.zeros(20_000, dtype=int)))
log_d = -((x_new[0] - 59_200.0) ** 2 - (x_hat_e[0, k_e] - 59_200.0) ** 2) / (2 * SIGMA**2)
check_close(w_new, np.exp(log_d - log_d.max()) / np.sum(np.exp(log_d - log_d.max())), "the weights of step (d)",
            "(d) weighs each new particle by its own misfit minus its parent candidate's: w = exp(-(|x_new_1 - b|^2 - "
            "|x^_1(k_l) - b|^2) / (2 sigma^2)), normalised, with x^ the propagated candidates of (a) and k_l the parents "
            "you drew (info['parents']); a minus sign in front, and no old weight.", rtol=1e-6, atol=1e-15,
            show_expected=False)
# Visible check 6: unequal old weights. Every particle has the same state except beta: 10000 have beta = 20000 and an
# old weight 0.9/10000 each, 10000 have beta = 30000 and 0.1/10000. (b) makes the fitness weights proportional to the
# old weights here, so about 90% of the new particles copy a beta = 20000 particle. (d) then re-weighs each new
# particle by its own perturbation only: the new weighted mean of beta stays near 0.9 * 20000 + 0.1 * 30000 = 21000.
x_u = np.tile([[20_000.0], [3000.0], [20_000.0]], 20_000)
x_u[2, 10_000:] = 30_000.0
w_u = np.concatenate([np.full(10_000, 0.9 / 10_000), np.full(10_000, 0.1 / 10_000)])
x_new, w_new = pf_step(x_u, w_u, 19_700.0, np.random.default_rng(8))
check_close(x_new[2] @ w_new, 21_000.0, "the weighted mean beta after old weights of 0.9 and 0.1 for two groups",
            "(b) multiplies by the old weights w, and the resampling uses them: (d) must not multiply by them again. "
            "w = exp(-(|x_new_1 - b|^2 - |x^_1(k_l) - b|^2) / (2 sigma^2)), normalised, with no old weight in it.",
            rtol=0.0, atol=250.0)
# Visible check 7: every draw comes from rng, so two generators of the same seed give the same step.
first = pf_step(x_c, w_c, 59_700.0, np.random.default_rng(7))
again = pf_step(x_c, w_c, 59_700.0, np.random.default_rng(7))
check_true(all(np.array_equal(a, b) for a, b in zip(first, again)),
           "two calls of pf_step with generators of the same seed gave different steps",
           "Draw every random number from the rng argument (rng.choice, rng.standard_normal), never from np.random: "
           "the grader and run_particle_filter give pf_step the generator to use.")
passed("pf_step")

# %% nbgrader={"grade": true, "grade_id": "test_pf_step", "locked": true, "points": 3, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of pf_step (3 points), statistical, with the reference tracking_dynamics: the weights follow (d)
# and sum to 1 (also for a distant reading); info['ess'] and info['parents']; the resampling follows the fitness weights (a chi-square test);
# the artificial process noise has the right spread and centre, also for another innovation_std; and the posterior of beta after a whole run agrees with
# reference runs. A correct step fails with probability below 1e-6.
# Validate (and this cell) first checks that pf_step passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(pf_step)
### BEGIN HIDDEN TESTS
from solutions.reentry_pf.hidden_tests import check_pf_step
check_pf_step(pf_step)
### END HIDDEN TESTS

# %% [markdown]
# ## 5. Weighted credibility intervals
#
# After step (d) the particles carry unequal weights, so every summary of the cloud must use them: the weighted
# mean, and weighted quantiles. Sort the samples $s_{(1)} \le \dots \le s_{(N)}$, carry each sample's weight
# $w_{(i)}$ along, and accumulate: $F_i = \sum_{k \le i} w_{(k)} / \sum_k w_k$. The **weighted quantile** of order
# $a \in [0, 1]$ is the first sorted sample whose cumulative weight reaches $a$,
#
# $$q(a) = s_{(i)}, \qquad i = \min\{i : F_i \ge a\}.$$
#
# The central $p\%$ credibility interval is $[\,q((1 - p/100)/2),\ q((1 + p/100)/2)\,]$, and $p = 0$ gives the
# weighted median twice.
#
# > **Handout correction.** The handout builds the interval by sorting the $N$ particle values and throwing away
# > the same *number* of them at each end, $i_\min = [(1 - p/100)N/2]$ and $i_\max = [(1 + p/100)N/2]$. That counts
# > every particle once, which is right only when the weights are equal: after resampling, but not after step (d),
# > which leaves unequal weights. With weights, throw away the same *weight* at each end.
#
# `falling_object.credibility_interval(samples, weights, p)` computes this for you (it is imported by the set-up
# cell as `credibility_interval`). It takes one variable's values `samples` (N,), their weights (N,), non-negative
# and not necessarily normalised, and $p$ in percent, a number or an array of numbers; it returns `(lo, hi)` with
# the shape of `p`. Its few lines, in `course/falling_object.py`, are worth reading: `np.argsort` sorts,
# `weights[order]` carries the weights along, and `np.searchsorted(F, a)` finds the first $i$ with $F_i \ge a$ for
# a whole array of orders $a$ at once. The cell below tries it on a case you can follow by hand.

# %% nbgrader={"grade": false, "grade_id": "credibility_example", "locked": true, "schema_version": 3, "solution": false, "task": false}
# The samples 4, 1, 3, 2 with the weights 0.1, 0.1, 0.7, 0.1: in sorted order 1, 2, 3, 4 the weights are 0.1, 0.1,
# 0.7, 0.1 and accumulate to 0.1, 0.2, 0.9, 1. The median (order 0.5) is 3, the 50% interval (orders 0.25 and 0.75)
# is [3, 3], and the 90% interval (orders 0.05 and 0.95) is [1, 4].
lo, hi = credibility_interval(np.array([4.0, 1.0, 3.0, 2.0]), np.array([0.1, 0.1, 0.7, 0.1]), np.array([0, 50, 90]))
print("p = 0, 50, 90:  lo =", lo, " hi =", hi)

# %% [markdown]
# ## 6. The filter over half a minute of readings
#
# `run_particle_filter(b, N, rng, *, step=None, innovation_std=INNOVATION_STD)` starts from
# `initial_cloud(b[0], N, rng)` at $t_0$, then for $j = 1, \dots, T$ takes one filter step with the reading `b[j]`.
# The step is `pf_step` unless another one is given (write `step = pf_step if step is None else step`); call it as
# `step(x, w, b[j], rng, innovation_std=innovation_std, info=info)` with one dict `info = {}`, made before the loop,
# so that it reports on its resampling. At every $t_j$, including $t_0$, record in a `FilterHistory` (from
# `course.falling_object`; `FilterHistory.empty(len(b), N)` makes one full of NaN for you to fill). Its fields
# `mean`, `median`, `lo50`, `hi50`, `lo90` and `hi90` have shape `(3, T + 1)`, rows $h$, $v$, $\beta$; `ess`,
# `ess_resample`, `parents` and `roots` have shape `(T + 1,)`. Fill, at each $j$:
#
# * `mean[:, j]`: the **weighted** mean $\sum_\ell w^{(\ell)} x^{(\ell)}$ of $h$, $v$ and $\beta$;
# * `median[:, j]`, `lo50[:, j]`, `hi50[:, j]`, `lo90[:, j]`, `hi90[:, j]`: the weighted median and the weighted
#   50% and 90% credibility intervals of each variable, from one call `lo, hi = credibility_interval(x[i], w,
#   np.array([0, 50, 90]))`: `lo` and `hi` have 3 entries, for the median (`lo[0]` = `hi[0]`), 50% and 90%;
# * `ess[j]`: the effective sample size $1 / \sum_\ell (w^{(\ell)})^2$ of the weights the step returned, which is
#   $N$ for equal weights and 1 when one particle has all the weight;
# * the health of the resampling, `ess_resample`, `parents` and `roots`: the given `ResamplingHealth` keeps the
#   books. Make one before the loop, `health = ResamplingHealth(N)`, and call `health.record(history, j, info)` once
#   at every $t_j$, after the step. It stores `info["ess"]`, the number of distinct indices in `info["parents"]`,
#   and the number of particles of $t_0$ that still have descendants (section 7 plots all three). At $t_0$ nothing
#   has been resampled, and it records $N$ for all three.
#
# Return the history. A loop over the readings is fine; there is still no loop over the particles.

# %% nbgrader={"grade": false, "grade_id": "run_particle_filter", "locked": false, "schema_version": 3, "solution": true, "task": false}
def run_particle_filter(b, N, rng, *, step=None, innovation_std=INNOVATION_STD):
    """A particle filter over the readings b (T + 1,) with N particles; returns a FilterHistory."""
    ### BEGIN SOLUTION
    step = pf_step if step is None else step
    history = FilterHistory.empty(len(b), N)
    health = ResamplingHealth(N)
    # the prior cloud at t_0 is centred on the first reading, h_init = b_0
    x, w = initial_cloud(b[0], N, rng)
    info: dict = {}
    for j in range(len(b)):
        if j > 0:
            # one step from t_{j-1} to t_j, with the reading b_j
            x, w = step(x, w, b[j], rng, innovation_std=innovation_std, info=info)
        # weighted mean sum_l w(l) x(l)
        history.mean[:, j] = x @ w
        for i in range(3):
            # weighted median (p = 0) and the weighted 50% and 90% credibility intervals
            lo, hi = credibility_interval(x[i], w, np.array([0.0, 50.0, 90.0]))
            history.median[i, j], history.lo50[i, j], history.hi50[i, j] = lo[0], lo[1], hi[1]
            history.lo90[i, j], history.hi90[i, j] = lo[2], hi[2]
        # ESS = 1 / sum_l w(l)^2
        history.ess[j] = 1.0 / np.sum(w**2)
        health.record(history, j, info)
    return history
    ### END SOLUTION

# %% nbgrader={"grade": false, "grade_id": "check_run_particle_filter", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(run_particle_filter, initial_cloud, pf_step)
# Visible checks on the first 21 readings (2 s) with N = 500.
short = run_particle_filter(data.b[:21], 500, np.random.default_rng(3))
check_history(short, n_times=21, n_particles=500)
# At t_0 every weight is 1/N: the ESS is N, nothing has been resampled, and the weighted mean is the plain mean of the
# prior cloud, drawn first from the generator you were given.
check_close(short.ess[0], 500.0, "the effective sample size at t_0", "ESS = 1 / sum w^2, which is N for equal weights.")
check_close([short.ess_resample[0], short.parents[0], short.roots[0]], [500.0, 500.0, 500.0],
            "ess_resample, parents and roots at t_0",
            "Before the first step nothing is resampled: call health.record(history, 0, info) at t_0, which records N.")
x_first, _ = initial_cloud(data.b[0], 500, np.random.default_rng(3))
check_close(short.mean[:, 0], x_first.mean(axis=1), "the mean at t_0",
            "At t_0 record the prior cloud from initial_cloud(b[0], N, rng), before any step.")
# With equal weights the weighted median of 500 values is the 250th or the 251st smallest (the cumulative weight of
# the 250th is 0.5 up to rounding): its distance to the nearer of the two is 0.
middle = np.sort(x_first, axis=1)[:, 249:251]
check_close(np.min(np.abs(short.median[:, :1] - middle), axis=1), np.zeros(3), "the weighted median at t_0",
            "Record the weighted median credibility_interval(x[i], w, 0), one of the samples (not np.median).")
# At t_1: the cloud after one pf_step with the reading b[1], from the same generator. Its weights are no longer equal.
rng = np.random.default_rng(3)
x_first, w_first = initial_cloud(data.b[0], 500, rng)
x_one, w_one = pf_step(x_first, w_first, data.b[1], rng)
check_close(short.mean[:, 1], x_one @ w_one, "the mean at t_1",
            "Step j uses the reading b[j]; record the weighted mean sum_l w_l x_l (x @ w), not the plain mean.")
check_close(short.ess[1], 1.0 / np.sum(w_one**2), "the ESS at t_1",
            "history.ess[j] is 1 / sum w^2 of the weights the step returned: not info['ess'] (the fitness weights that "
            "the step resampled with), and not the weights before the step.")
# The keyword innovation_std reaches the step. The prior's 90% band of v is 2 x 1.645 x 200 = 658 m/s wide. With the
# handout's noise, 100 m/s in every step, it is about 1200 m/s wide at t = 2 s; with a noise of 1 m/s per step it
# stays under 700 m/s.
small = run_particle_filter(data.b[:21], 500, np.random.default_rng(3), innovation_std=np.array([1.0, 1.0, 1.0]))
check_history(small, n_times=21, n_particles=500)
width_v = small.hi90[1, -1] - small.lo90[1, -1]
check_true(width_v < 800.0,
           f"with innovation_std = (1, 1, 1) the 90% band of v at t = 2 s is {width_v:.0f} m/s wide, about as wide as "
           "with the handout's noise (100 m/s per step), so the filter did not use the innovation_std it was given",
           "Pass it on to the step: step(x, w, b[j], rng, innovation_std=innovation_std, info=info). Without it, the "
           "step uses its default, the handout's INNOVATION_STD, in every run.")
# The bootstrap step resamples with the weights of the step before, so its ess_resample[j] is ess[j - 1].
boot = run_particle_filter(data.b[:6], 500, np.random.default_rng(4), step=partial(falling_object.bootstrap_step,
                           dynamics=tracking_dynamics), innovation_std=CHOSEN_STD)
check_close(boot.ess_resample[1:], boot.ess[:-1], "ess_resample of a bootstrap run against its ess one step earlier",
            "Call the step you are given (step = pf_step only when step is None) with innovation_std=innovation_std and "
            "info=info, then health.record(history, j, info).")
# A run you can follow by hand, N = 3, with a step that moves nothing and resamples with the parents [0, 0, 1], then
# [2, 2, 1]. Particle l's new parent is parents[l], whose root is root[parents[l]]: the roots become [0, 0, 1] (2 of
# them), then [1, 1, 0] (still 2). ResamplingHealth counts them if it sees each step's info once, after the step.
scripted_step = falling_object.scripted_step([np.array([0, 0, 1]), np.array([2, 2, 1])])
hand = run_particle_filter(data.b[:3], 3, np.random.default_rng(5), step=scripted_step)
check_close(hand.roots, [3.0, 2.0, 2.0], "history.roots of a run with the parents [0, 0, 1], then [2, 2, 1]",
            "Call health.record(history, j, info) once at every t_j, after the step to t_j, with the dict you passed to "
            "the step as info=info.")
passed("run_particle_filter")

# %% nbgrader={"grade": true, "grade_id": "test_run_particle_filter", "locked": true, "points": 2, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of run_particle_filter (2 points): random readings of 1 to 25 times, N = 50 to 1000, another
# innovation_std, and the bootstrap step, with the reference initial_cloud and pf_step, so
# that only your loop, summaries and diagnostics are graded.
# Validate (and this cell) first checks that run_particle_filter passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(run_particle_filter)
### BEGIN HIDDEN TESTS
from solutions.reentry_pf.hidden_tests import check_run_particle_filter
check_run_particle_filter(run_particle_filter)
### END HIDDEN TESTS

# %% [markdown]
# ## 7. Show and tell, and a yardstick
#
# Now the whole half minute with **the handout's setting**: the auxiliary filter of `pf_step`, $N$ = 5000
# particles, and artificial process noise (100 m, 100 m/s, 5): from here on, "the handout's setting". The report
# scores this one run over 0 to 30 s: the RMSE of the weighted mean, and how often the truth lay inside each band.

# %% nbgrader={"grade": false, "grade_id": "run_lab", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
# (the kit's tests check that this cell prints the same on every run)
require(run_particle_filter, initial_cloud, pf_step)
# the handout's setting: the auxiliary particle filter, N = 5000, artificial process noise (100 m, 100 m/s, 5)
history = run_particle_filter(data.b, falling_object.N_PARTICLES, np.random.default_rng(falling_object.RUN_SEED))
falling_object.print_report(data, history)

# %% [markdown]
# **The yardstick.** How well could $\beta$ be known from these readings? The noise-free model makes each altitude
# $h_j$ a function of the initial state $x_0 = (h_0, v_0, \beta)$. The sensitivities $s_j = \partial h_j / \partial
# x_0$ give the information that the readings $b_1, \dots, b_j$ hold; add the prior's, $C^{-1}$:
#
# $$J_j = C^{-1} + \sum_{i=1}^{j} \frac{s_i s_i^T}{\sigma^2}, \qquad \text{yardstick}_j = \sqrt{(J_j^{-1})_{33}}.$$
#
# We compute $J_j$ along the true trajectory; it uses the model and the noise level $\sigma$, not the values of the
# readings. The yardstick is then the **posterior standard deviation of $\beta$
# for the model linearised at the truth**: about the spread that an exact posterior would have here (not a floor
# that no filter can beat). `falling_object.beta_linearised_sd` computes it with your `tracking_dynamics`.

# %% nbgrader={"grade": false, "grade_id": "crb", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
# (the kit's tests check that this cell prints the same on every run)
require(tracking_dynamics)
yardstick = falling_object.beta_linearised_sd(tracking_dynamics, X0_TRUE, data.t)
for t_j in (0, 10, 15, 20, 25, 30):
    j = round(t_j / DT)
    print(f"t = {t_j:>2} s: yardstick (linearised posterior sd) of beta {yardstick[j]:6.0f}, "
          f"information / prior information {(PRIOR_STD[2] / yardstick[j]) ** 2:5.1f}")

# %% [markdown]
# By $t$ = 30 s the readings' information about $\beta$ is more than 50 times the prior's. <!-- claim: reentry-pf/yardstick-information -->
# It arrives late: at 10 s the yardstick is still the prior's 1500, at 15 s it is above 80% of it, and it falls
# fastest between 15 s and 25 s, when the object is low enough for the drag to matter. <!-- claim: reentry-pf/information-arrives-late -->

# %% [markdown]
# In the figure, the bottom row shows each curve minus the truth. In the $\beta$ panels, the dotted curves are the
# truth $\pm$ 1.645 times the yardstick: as wide as an exact posterior's 90% band. That band would be centred on its
# own estimate, so compare only the widths.

# %% nbgrader={"grade": false, "grade_id": "plot_tracking", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(run_particle_filter, tracking_dynamics)
axes = falling_object.plot_tracking(data, history, yardstick=yardstick,
                                    title="The handout's setting: auxiliary particle filter, N = 5000, noise (100, 100, 5)")
plt.show()

# %% [markdown]
# ### The health of the filter, and the bootstrap filter
#
# The weights that step (d) leaves are close to equal: their ESS stays above 0.6 $N$ at every step (10 fresh runs,
# handout's noise, $N$ = 2000). <!-- claim: reentry-pf/ess-after-d-high -->
# That says nothing about the resampling, which comes *before* (d). The next figure shows, for `pf_step` and the
# bootstrap filter: the ESS of the weights each step resampled with, the distinct parents each resampling drew, and
# the particles of $t_0$ that still have descendants (the roots).

# %% [markdown]
# The dashed lines are the baseline of a filter that learns nothing: *multinomial* resampling of equal weights.
# It keeps $1 - 1/e \approx$ 63% of the particles as distinct parents at each step, and after $n$ steps leaves
# about $2N/(n + 2)$ roots, by chance alone (genetic drift). <!-- claim: reentry-pf/equal-weights-drift -->
# Both baselines hold for multinomial resampling only. If your `pf_step` resamples systematically, its distinct
# parents and roots lie well above these lines: systematic resampling of equal weights keeps every particle.

# %% nbgrader={"grade": false, "grade_id": "plot_health", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(run_particle_filter, tracking_dynamics)
bootstrap = partial(falling_object.bootstrap_step, dynamics=tracking_dynamics)
boot = run_particle_filter(data.b, falling_object.N_PARTICLES, np.random.default_rng(falling_object.RUN_SEED), step=bootstrap)
axes = falling_object.plot_health(data, {"auxiliary (pf_step)": history, "bootstrap": boot})
plt.show()

# %% [markdown]
# One run is not enough to judge the width of $\beta$'s 90% band. The figure below takes the handout's noise from
# a study of 50 simulated half minutes (section 8, Going further), for $N$ = 500, 2000 and 5000.

# %% nbgrader={"grade": false, "grade_id": "band_widths", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(tracking_dynamics)
study = falling_object.load_tuning()
handout = [s for s in falling_object.TUNING_SETTINGS if s.filter == "auxiliary" and s.innovation_std == falling_object.HANDOUT_STD]
ax = falling_object.plot_band_widths(study, handout, data.t, yardstick)
plt.show()

# %% [markdown]
# **The noise of the handout's setting.** The filter's only model error is the Forward Euler step, which misses the
# true trajectory by at most 2 m in $h$ and 1 m/s in $v$ per step. <!-- claim: reentry-pf/euler-error-small -->
# The noise in $v$, 100 m/s per step, is far larger. Its bands of $v$ are much too wide: in the study, the truth
# of $v$ lies inside the 50% band over 90% of the time, <!-- claim: reentry-pf/handout-v-too-wide -->
# and at 30 s the 90% interval reaches below zero (upward motion) in every one of the 50 runs. <!-- claim: reentry-pf/handout-v-upward -->

# %% [markdown]
# The numbers of your own run, for the question: the width of its 90% band of $\beta$ against an exact posterior's
# (2 $\times$ 1.645 $\times$ the yardstick) and the prior's, and its roots.

# %% nbgrader={"grade": false, "grade_id": "beta_numbers", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(run_particle_filter, tracking_dynamics)
falling_object.print_beta_band(data, history, yardstick)

# %% [markdown]
# **Question (2 points: 1 for (a), 1 for (b); a short paragraph each).** Read the $\beta$ panels and the figures
# after them, and the table above. (a) How does the 90% band of $\beta$ of your run compare with the yardstick's at
# 30 s? Does the gap say that the radar holds little information about $\beta$, or that the filter does not use it?
# How do you know? (The numbers are the evidence; a mechanism is welcome but not required.) (b) What happens to the
# ancestry of the cloud (the roots) over the half minute, and what does that do to the band of $\beta$? Explain with
# the resampling of step (c). (Each particle keeps about the $\beta$ of its root, as the noise in $\beta$ is small: a
# band that stays near the prior's width, one that ends wider than it, and one that narrows too early are all
# possible.) Quote the numbers you use, from the table,
# the figures or the text of this section (section 8 is not needed). Each part's point needs the comparison and a
# reason for it.

# %% [markdown] nbgrader={"grade": true, "grade_id": "beta_question", "locked": false, "points": 2, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** (a) The readings carry a lot of information about $\beta$: the yardstick falls from the prior's
# 1500 to about 200 by 30 s, <!-- claim: reentry-pf/yardstick-information --> most of it after 15 s, when the drag
# becomes strong. <!-- claim: reentry-pf/information-arrives-late --> The handout's setting does not use it.
# Its 90% band at 30 s is over 1.5 times the yardstick's width in every one of the 50 study runs, and in the median
# run with the handout's noise about 6 times with $N$ = 5000 and 5 times with $N$ = 2000. <!-- claim: reentry-pf/handout-band-far-from-yardstick -->
# With $N$ = 5000 the median band at 30 s is still about 85% of the prior's 90% band (4935; from 77% to 98% in the
# study's batches of 10 runs), <!-- claim: reentry-pf/handout-band-near-prior -->
# so the filter has learnt little about $\beta$. The gap means the filter throws information away, not that the
# radar says little about $\beta$. One cause is the noise in $v$: 100 m/s in every 0.1 s step lets the filter
# explain the drag's slowing as random kicks instead of as $\beta$.
# (b) The other cause is the resampling. Each step keeps about 60% of the particles as distinct parents, just under
# the 63% ($1 - 1/e$) that multinomial resampling keeps even when all weights are equal: <!-- claim: reentry-pf/parents-fraction -->
# most of the loss is the resampling's own randomness, not the weights.
# The losses compound. With equal weights, 300 resamplings leave about $2N/(n+2)$ = 33 of 5000 roots by chance alone, <!-- claim: reentry-pf/equal-weights-drift -->
# and the handout's setting keeps fewer than 30, below that baseline, in every study run,
# more than a third of that baseline in the median run. <!-- claim: reentry-pf/roots-collapse --> All the $\beta$
# values in the cloud then descend from those few, spread only by the artificial noise of 5 per step, so with
# $N$ = 500 and 2000 the band says more about the ancestry than about the readings. Even with $N$ = 5000 the band
# drifts by chance before the readings hold any information about $\beta$: from 1 s to 13 s the median run's band is
# 90% to 100% of the yardstick's, but in about a quarter of the study's runs it falls below 80% of it at some second. <!-- claim: reentry-pf/handout-band-narrow-early -->
# At 30 s, about 30% of the study's runs end with a band wider than the prior's, up to 1.6 times. <!-- claim: reentry-pf/handout-band-above-prior --> With $N$ = 5000 the noise in $v$
# matters more: a `pf_step` that resamples systematically keeps several times more roots, yet its band of $\beta$ at
# 30 s is still close to the prior's. <!-- claim: reentry-pf/systematic-still-wide --> With the handout's noise the median width at 30 s is much smaller
# with $N$ = 500 (about 1600) than with 2000 or 5000 (about 3550 and 4190), in every batch of 10 study runs too.
# With $N$ = 500 the median band is below 80% of the prior's already at 10 s, when the yardstick still equals the
# prior's sd, and at 30 s it is narrower than the yardstick in some runs. <!-- claim: reentry-pf/fewer-particles-narrower -->
# Such bands are over-confident: the yardstick barely depends on where it is evaluated. <!-- claim: reentry-pf/yardstick-insensitive -->
# The ESS after (d) hides all this: it stays high because (d) only
# corrects for the small perturbation. The fitness weights that drive the resampling drop below 0.35 $N$ at some
# reading in most runs with $N$ = 2000, <!-- claim: reentry-pf/fitness-ess --> but their median ESS over a run stays
# above 0.8 $N$, <!-- claim: reentry-pf/fitness-ess-typical --> so resampling only when the ESS falls below $N/2$
# would skip most steps. Systematic or residual resampling, which draw each parent close to $N w_l$ times, would also
# lose less diversity per step.
#
# **Rubric (2 points).** 1 point for (a): the band is several times wider than the yardstick's at 30 s (from the
# student's run or the study's), and the readings do hold the information (the yardstick falls to about 200, more
# than 50 times the prior's information), so it is the filter that does not use it. Naming a cause (the large noise
# in $v$, which lets the filter explain the drag's slowing as random kicks, or the resampling) is welcome but not
# required. 1 point for (b): the roots fall to a few tens of the 5000 (near or below the dashed baseline): every
# resampling copies some particles and drops others, so by 30 s all the $\beta$ values descend from a few particles
# of $t_0$, spread only by the small noise in $\beta$, and the band says more about that ancestry than about the
# readings. Whichever way the student's run falls earns the point, if it is read correctly: a band that stays near the
# prior's width, one that ends wider than it, or one that narrows early, before the readings say anything about
# $\beta$. The band is the spread of the $\beta$ of a few tens of roots drawn from the prior, so it lands above or
# below the prior's width by chance. Saying that smaller $N$ gives narrower,
# over-confident bands, or that the ESS after (d) does not show the collapse, is welcome but not required. A student whose `pf_step` resamples systematically sees more distinct
# parents and roots than the dashed lines: full marks for (b) if they say so, say that systematic resampling loses less
# diversity per step, and say what still limits the band (the noise in $v$, the small noise in $\beta$). A student who blames the weights instead of the resampling at every step,
# but reads the figures correctly otherwise, loses no points. Naming a remedy (systematic or residual resampling,
# resampling only when the ESS is low) is welcome but not required.
# ### END SOLUTION

# %% [markdown]
# ## 8. Going further
#
# Nothing in this section is graded. It holds the study of many settings behind section 7, how to judge which of
# its differences are real, and the checks and ablations behind the main text.

# %% [markdown]
# ### Tuning: a study of 14 settings
#
# **The study** ran each of 14 settings (the filter, $N$ and the artificial process noise) on the same 50 simulated
# half minutes: the lab's truth, fresh radar noise, fresh filter draws. The table gives, for each setting, the RMSE
# of the weighted mean of $h$, $v$ and $\beta$, and how often the truth lay inside the 50% and 90% bands (the
# *coverage*). Both are scored over the
# last 10 s, $t \ge$ 20 s, when the readings have said something about $\beta$. <!-- claim: reentry-pf/information-arrives-late -->

# %% [markdown]
# **How to read it.** The last row is what an exact posterior would score, in the same metric as the other rows:
# 50% to 53% for every 50% band and 90% to 92% for every 90% band. <!-- claim: reentry-pf/ideal-scored -->
# Coverage below that means over-confident bands (too narrow), above it under-confident ones (too wide).

# %% [markdown]
# Two rows are marked with the names the lab uses. **The handout's setting** is `auxiliary`, $N$ = 5000, noise
# (100, 100, 5): the filter of section 7. **The tuned setting** is `auxiliary`, $N$ = 2000, noise (10 m, 10 m/s,
# 50): less noise in $h$ and $v$, more in $\beta$, and fewer particles.

# %% [markdown]
# **Read the noise too.** Each number is a mean over 50 runs, and runs differ, $\beta$ most: with the handout's
# setting, one run's RMSE of $\beta$ lies between about 150 and 1200 in the study's runs (10th to 90th
# percentile). <!-- claim: reentry-pf/beta-rmse-spread -->
# So the table gives the mean RMSE of $\beta$ with two standard errors of that mean (`+-2se`): how precisely 50 runs
# pin the mean down, not the scatter between runs.
#
# To compare two settings, look at their difference, not at whether their ranges overlap (they can overlap while the
# difference is real). All settings ran on the same readings and filter seeds, so the column `diff` gives the mean,
# run by run, of the RMSE of $\beta$ minus the handout's setting's, with its own two standard errors. A range that
# excludes 0 shows a difference (at about the 95% level).
#
# The tuned setting was picked by looking at this table, so it is scored on the runs it was chosen on. A row picked
# from 14 by looking at the same runs looks better here than it will on new runs: a difference of about two standard
# errors is weak evidence.

# %% nbgrader={"grade": false, "grade_id": "tuning_table", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
# (the kit's tests check that this cell prints the same on every run)
require(tracking_dynamics)
study = falling_object.load_tuning()
# what an exact posterior would score over readings like the study's (linearised at the truth, expected values)
ideal = falling_object.ideal_scores(tracking_dynamics, X0_TRUE, data.t)
print(falling_object.format_tuning_table(study, ideal=ideal))

# %% nbgrader={"grade": false, "grade_id": "tuning_figure", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(tracking_dynamics)
axes = falling_object.plot_tuning(study, ideal=ideal)
plt.show()

# %% [markdown]
# The tuned setting on the shipped readings, scored over 0 to 30 s: compare settings with the table. This run is not
# typical: its 90% band of $\beta$ at 30 s is a little wider than the handout's setting's, <!-- claim: reentry-pf/shipped-tuned-band -->
# which happens in fewer than a quarter of the study's runs (in the median run it is about 0.6 of it). <!-- claim: reentry-pf/tuned-band-narrower -->
# To try your own setting, copy the two cells below and change `innovation_std` or $N$.

# %% nbgrader={"grade": false, "grade_id": "run_chosen", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
# (the kit's tests check that this cell prints the same on every run)
require(run_particle_filter, initial_cloud, pf_step, tracking_dynamics)
# the tuned setting on the shipped readings: N = 2000, noise (10, 10, 50) (copy this cell to try your own)
tuned = run_particle_filter(data.b, 2000, np.random.default_rng(falling_object.RUN_SEED), innovation_std=CHOSEN_STD)
falling_object.print_report(data, tuned)

# %% nbgrader={"grade": false, "grade_id": "plot_chosen", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(run_particle_filter, tracking_dynamics)
axes = falling_object.plot_tracking(data, tuned, yardstick=yardstick,
                                    title="The tuned setting: auxiliary particle filter, N = 2000, noise (10, 10, 50)")
plt.show()

# %% [markdown]
# **What the study shows.** Against the handout's setting, the tuned setting's RMSE of $h$ is 86 m against 188 m,
# less than half (0.46; from 0.43 to 0.50 in the study's five batches of 10 runs), and of $v$ 14 m/s against 92 m/s,
# less than a fifth (0.15; from 0.12 to 0.19). <!-- claim: reentry-pf/tuned-rmse-hv -->
# For $\beta$ it is 508 against 678, about a quarter lower. The paired difference is $-171 \pm 165$: just over two
# standard errors from 0, so the study shows it, but only weakly. (The two rows' own ranges, $\pm$ 94 and $\pm$ 109,
# overlap; that is not the test.) Both are above the exact posterior's 289. <!-- claim: reentry-pf/tuned-rmse-beta -->
# The evidence is weaker still because the tuned setting was chosen on these same runs. New runs are the fair test:
# on 50 fresh runs the tuned setting's RMSE of $\beta$ is about 0.7 of the handout's setting's, and the paired
# difference is more than two standard errors from 0, so the gain is real. By how much, 50 runs say only roughly: a 95%
# bootstrap interval of that ratio runs from about 0.55 to 0.8. <!-- claim: reentry-pf/tuned-beta-fresh -->
#
# None of the tuned setting's bands is over-confident: every band holds the truth at least as often as the exact
# posterior's. Its three 90% bands (96%, 100%, 97%, against the exact posterior's 90% to 91%) and the 50% bands of
# $v$ (93%) and $\beta$ (68%; from 55% to 76% in the study's batches of 10 runs) are under-confident. The 50% band of
# $h$ (55%, against 51%) is about right, or slightly wide. <!-- claim: reentry-pf/tuned-coverage -->
# Too little noise in $h$ makes it over-confident: with (3, 3, 5) and (3, 3, 50) the 90% band of $h$ holds the
# truth less than 80% of the time. <!-- claim: reentry-pf/small-noise-overconfident -->
# What to try next: less noise in $v$ than in $h$, or a noise in $\beta$ that shrinks as the readings become
# informative. Do not expect more particles to narrow the band of $\beta$: in section 7, fewer particles gave the
# narrower, over-confident bands. <!-- claim: reentry-pf/fewer-particles-narrower -->

# %% [markdown]
# ### The yardstick and other checks
#
# **The yardstick and the Van Trees bound.** The Van Trees bound averages the readings' information over truths
# drawn from the prior before it adds the prior's. It is a floor for the RMSE of any estimate of $\beta$, averaged
# over that prior, but not at one truth. At 20 s and at 30 s it is within 6% of the yardstick of section 7
# (about 210 against 200 at 30 s). <!-- claim: reentry-pf/yardstick-near-van-trees -->
# Like the yardstick, it is on the scale of the root of a mean squared error, which is larger than the table's mean
# of each run's RMSE (for the exact posterior, 323 against 289). <!-- claim: reentry-pf/ideal-metric -->
# From one prior draw to another, the linearised posterior sd at 30 s ranges from about 190 to 250 (10th to
# 90th percentile). <!-- claim: reentry-pf/yardstick-across-prior -->
# Near the lab's truth it barely moves: shifting the true $\beta$ by $\pm$400 or $v_0$ by $\pm$50 m/s changes it at
# 30 s by less than 3%. <!-- claim: reentry-pf/yardstick-insensitive -->
# So the lesson of section 7's question stands with either curve: in the median run, the band of the handout's setting is
# about 6 times as wide (and with the handout's noise and $N$ = 2000, about 5 times). <!-- claim: reentry-pf/handout-band-far-from-yardstick -->

# %% [markdown]
# **Why score only $t \ge$ 20 s?** Before about 15 s the readings say almost nothing about $\beta$, so even an exact
# posterior is close to the prior. The lab's truth, $\beta$ = 19161, happens to sit 0.56 prior standard deviations
# from the prior's mean. Over the whole run, an exact posterior's 50% band of $\beta$ would hold it about 72% of the
# time and its 90% band about 96%, which would look "too wide". <!-- claim: reentry-pf/ideal-whole-run -->

# %% [markdown]
# **Why 50 in $\beta$ and not 5?** With $N$ = 2000, noise (10, 10, 5) has about the same RMSE of $h$ and $v$ as the
# tuned setting (within 5%), but its 90% band of $\beta$ holds the truth 83% of the time (75% to 93% in the study's
# batches of 10 runs; the tuned setting: 97%, 93% to 100%). With $N$ = 500 that band holds the truth 17% of the time (10% to
# 32%; the tuned noise: 69%, 60% to 73%). <!-- claim: reentry-pf/beta-noise-robust -->
# The larger noise keeps the band from collapsing with the ancestry. The price is a band at 30 s 3 to 5 times the
# yardstick in the median run. <!-- claim: reentry-pf/tuned-band-width -->
# Even so, $N$ = 500 is too few for the tuned noise: its 90% band of $\beta$ then holds the truth less than 80% of the
# time. <!-- claim: reentry-pf/tuned-needs-particles -->
# Before the readings become informative, the tuned band of $\beta$ can grow wider than the prior's (in 30% to 70%
# of the study's runs it does at some second between 10 s and 18 s): <!-- claim: reentry-pf/tuned-band-widens-early -->
# the random walk of 50 per step adds about $50\sqrt{100}$ = 500 of spread every 10 s, faster than the early
# readings remove it.

# %% [markdown]
# **Bootstrap or auxiliary?** Here the look-ahead buys little: with the handout's noise and with the tuned noise
# ($N$ = 2000 both), the bootstrap filter's RMSE of $h$ and $v$ is within 10% of the auxiliary filter's, and the
# coverage of $h$ and $v$ within 7 percentage points. <!-- claim: reentry-pf/bootstrap-similar -->
# The numbers of $\beta$ differ too, but every paired difference (bootstrap minus auxiliary, run by run on the same
# readings) is within two standard errors of 0. <!-- claim: reentry-pf/bootstrap-similar -->
# The
# fitness weights of (b) are usually close to equal (with $N$ = 2000, the median of their ESS over a run is above
# 0.8 $N$ in each of 10 runs): <!-- claim: reentry-pf/fitness-ess-typical -->
# the radar's 500 m noise is broad next to the spread of the predicted altitudes, so looking ahead changes few
# draws.
#
# **Conventions.** As in the handout, $v$ is the *downward* speed and $\beta$ *divides* the drag: a dense, compact
# object has a large $\beta$ and is slowed little. Other texts may use an upward velocity, or a coefficient that
# multiplies the drag; check the signs before you compare their formulas with these.
#
# **Less random resampling.** Systematic or residual resampling draw each parent close to $N \hat w^{(\ell)}$ times,
# and resampling only when the ESS falls below about $N/2$ skips most steps. Both lose less diversity than
# multinomial resampling at every step. A resample-move step (an MCMC move after resampling) restores diversity
# without adding noise to the model.
