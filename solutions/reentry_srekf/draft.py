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
# # Lab reentry-srekf: a square-root extended Kalman filter for a falling Starship
#
# A SpaceY Starship is falling back through the atmosphere in an orientation nobody planned for, so
# its drag is unknown. A range-only radar on a hill watches it fall. In this lab you estimate the
# vehicle's altitude, its velocity **and** its ballistic drag coefficient from those ranges alone,
# with an extended Kalman filter that carries each covariance as an upper-triangular square root.
#
# **What you will do**
# 1. Write the ballistic process model $\mathbf{f}(\mathbf{x})$ and its Jacobian.
# 2. Write the radar's range model and its Jacobian.
# 3. Write the marginal of a Gaussian in square-root form, for any set of indices.
# 4. Write the conditional of a Gaussian in square-root form, for any two sets of indices.
# 5. Write the square-root time update.
# 6. Write the square-root measurement update, built on your conditional.
# 7. Run the filter your functions make up, and draw the missing panel of its figure.
# 8. to 11. See what the square roots protect against, read the filter's errors and its NEES, find
#    where the radar loses sight of the altitude, and meet an impossible estimate.
#
# **What is graded, and about how long each part takes**
#
# | part | what you write | points | about |
# |---|---|---|---|
# | 1. The ballistic process model | `ballistic_dynamics`, `ballistic_jacobian` | 1 | 30 min |
# | 2. The range measurement model | `radar_predict`, `radar_jacobian` | 1 | 10 min |
# | 3. Marginal distributions | `marginal` | 1 | 20 min |
# | 4. Conditional distributions | `conditional` | 1 | 25 min |
# | 5. The square-root time update | `sqrt_time_update` | 1.5 | 20 min |
# | 6. The square-root measurement update | `sqrt_measurement_update` | 1.5 | 25 min |
# | 7. State estimation and visualisation | `plot_ballistic_coefficient` | 0.5 | 15 min |
# | 8–11. Reading the filter | four written answers (questions 8 to 11) | 2.5 | 55 min |
# | **all** | 9 functions, 4 written answers | **10** | **about 3 h 20 min** |
#
# Hidden tests grade the code blanks; the written answers are marked by hand. Section 12, *Going further*,
# holds notes and experiments behind the main text: read it if you like, nothing there is graded.
#
# Every covariance $\mathbf{P}$ in this lab is carried as an upper-triangular $\mathbf{S}$ with
# $\mathbf{S}^\mathsf{T}\mathbf{S} = \mathbf{P}$. A row of $\mathbf{S}$ times $-1$ gives the same $\mathbf{P}$, so
# either sign is right: every check compares $\mathbf{S}^\mathsf{T}\mathbf{S}$, never $\mathbf{S}$ itself.
#
# **How this notebook works.** Each blank is one function in a cell marked `YOUR CODE HERE`. The read-only cell
# below it runs *visible checks* on cases you can work out by hand, and their messages say what to fix. When your
# work is graded, *hidden tests* compare your function with a reference on random inputs (random states, Gaussians
# of 2 to 7 dimensions, random index sets), so write general code. Each function is graded on its own: a mistake in
# one blank costs only that blank's points. Return new arrays, and never write into the ones you are given.
#
# **Locked cells.** The grey cells are read-only: grading puts back the original of each. Write only in the cells
# marked `YOUR CODE HERE` and `YOUR ANSWER HERE`. Before you submit, press **Validate** in the toolbar: it lists each
# blank that is not written yet or does not pass its visible checks.
#
# *Credit.* This lab follows Lab 5, "Square-root extended Kalman filter", of the course MCHA4400 at the
# University of Newcastle, Australia (Semester 2, 2023), written for C++ with Eigen and VTK; the handout names
# no author. We add two blanks (the square-root updates, which the handout gives ready-made) and the questions
# of parts 8 to 11, so our marks differ from its five. The Python text, code and simulated data are our own,
# and so are any errors.

# %% nbgrader={"grade": false, "grade_id": "setup", "locked": true, "schema_version": 3, "solution": false, "task": false}
# Set-up: run this cell first.
# %xmode Minimal
# %matplotlib inline
import numpy as np
import matplotlib.pyplot as plt
from matplotlib.figure import Figure
from scipy.linalg import block_diag, solve_triangular
from scipy.stats import norm

from course import starship
from course.starship import G, L, M, P0, R, T0, RADAR_R1, RADAR_R2
from course.starship import check_band_plot, check_jacobian, check_square_root
from course.checks import check_array, check_close, check_pair, passed, require, validate

# %% [markdown]
# ## The data
#
# The radar reports the range to the vehicle every 0.1 s for 50 s. Our data file has the handout's
# format: a header line, then one line per measurement with the time, the true altitude, velocity and
# ballistic coefficient (we simulated the fall, so we know them), the true range and the measured range.
# The measured range has Gaussian noise of standard deviation $\sigma_\text{rng} = 50$ m.

# %% nbgrader={"grade": false, "grade_id": "load_data", "locked": true, "schema_version": 3, "solution": false, "task": false}
data = starship.load()
print(f"{len(data)} measurements from t = {data.t[0]:g} s to t = {data.t[-1]:g} s")
print(f"true state at t = 0: h = {data.h[0]:g} m, v = {data.v[0]:g} m/s, c = {data.c[0]:g} m^2/kg")
print(f"range noise: sample standard deviation {np.std(data.range_meas - data.range_true):.1f} m")


# %% [markdown]
# ## 1. The ballistic process model (1 point)
#
# The state is
#
# $$\mathbf{x} = \begin{bmatrix} h \\ v \\ c \end{bmatrix}, \tag{1}$$
#
# where $h$ [m] is the altitude, $v$ [m/s] the vertical velocity (up is positive, so the falling
# vehicle has $v < 0$) and $c$ [m²/kg] the ballistic drag coefficient. The mean dynamics are
# $\dot{\mathbf{x}} = \mathbf{f}(\mathbf{x})$ with
#
# $$\mathbf{f}(\mathbf{x}) = \begin{bmatrix} v \\ d - g \\ 0 \end{bmatrix}, \tag{3}$$
#
# where the drag acceleration $d = \tfrac{1}{2}\rho v^2 c$ (4) is positive: it pushes up against the fall.
# With $v^2$ in it, equations (4) and (10) assume a falling vehicle, $v < 0$ (for a climbing one the drag
# would have to point down, $-\tfrac{1}{2}\rho v|v|c$). Our vehicle only falls: use (10) as written.
# The air density follows from the ideal gas law $\rho = pM/(RT)$ (5), a temperature that falls linearly
# with altitude, $T = T_0 - Lh$ (8), and hydrostatic equilibrium, which gives the barometric formula
#
# $$p = p_0 \left(1 - \frac{Lh}{T_0}\right)^{\frac{gM}{RL}}. \tag{9}$$
#
# Together,
#
# $$d = \frac{1}{2}\frac{M p_0}{R}\left(\frac{1}{T_0 - Lh}\right)\left(1 - \frac{Lh}{T_0}\right)^{\frac{gM}{RL}} v^2 c. \tag{10}$$
#
# The constants are in the set-up cell: `P0` $= 101\,325$ Pa, `T0` $= 288.15$ K, `G` $= 9.81$ m/s², `M`
# $= 0.028\,964\,4$ kg/mol, `R` $= 8.314\,47$ J/(mol K) and `L` $= 0.0065$ K/m. The process model adds white
# noise, $\dot{\mathbf{x}} = \mathbf{f}(\mathbf{x}) + \dot{\mathbf{w}}$, with power spectral density
# $\mathbf{Q} = \mathrm{diag}(0,\ 10^{-20},\ 25\times 10^{-12})$ (12): the ballistic coefficient is allowed to
# drift slowly.
#
# Write `ballistic_dynamics(x)`, which returns $\mathbf{f}(\mathbf{x})$ as an array of shape `(3,)`
# (0.5 points), and `ballistic_jacobian(x)`, which returns $\partial\mathbf{f}/\partial\mathbf{x}$ as a
# $3 \times 3$ array whose row $i$ holds the derivatives of $f_i$ with respect to $h$, $v$ and $c$ (0.5
# points). *Hint for the Jacobian:* by (8) and (10), $d$ is proportional to $T^{gM/(RL) - 1}$, and
# $\mathrm{d}T/\mathrm{d}h = -L$.

# %% nbgrader={"grade": false, "grade_id": "ballistic_dynamics", "locked": false, "schema_version": 3, "solution": true, "task": false}
def ballistic_dynamics(x):
    """Mean dynamics f(x), shape (3,), of x = [h (m), v (m/s), c (m^2/kg)]."""
    ### BEGIN SOLUTION
    h, v, c = np.asarray(x, dtype=float)
    # (8) T = T0 - L h
    T = T0 - L * h
    # (9) p = p0 (1 - L h / T0)^(g M / (R L))
    p = P0 * (1 - L * h / T0) ** (G * M / (R * L))
    # (5) rho = p M / (R T)
    rho = p * M / (R * T)
    # (4) d = rho v^2 c / 2
    d = 0.5 * rho * v**2 * c
    # (3) f = [v, d - g, 0]
    return np.array([v, d - G, 0.0])
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_ballistic_dynamics", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(ballistic_dynamics)
# Visible checks. At sea level T = T0 and p = p0, so the density is p0 M / (R T0) = 1.225 kg/m^3.
f = check_array(ballistic_dynamics(np.array([0.0, -100.0, 1e-3])), "ballistic_dynamics(x)", (3,),
                "Return one array, np.array([f1, f2, f3]).")
rho_sea_level = P0 * M / (R * T0)
check_close(f, [-100.0, 0.5 * rho_sea_level * 100.0**2 * 1e-3 - G, 0.0],
            "f at h = 0 m, v = -100 m/s, c = 0.001 m^2/kg",
            "Here the drag is d = 1.225 * 100^2 * 0.001 / 2 = 6.125 m/s^2, upwards, so f2 = d - g.")
check_close(ballistic_dynamics(np.array([8000.0, -300.0, 0.0])), [-300.0, -G, 0.0],
            "f with c = 0 (no drag, so free fall)", "f = [v, -g, 0] when there is no drag.")
# The standard atmosphere has a density of 0.3639 kg/m^3 at 11 km; your drag implies rho = (f2 + g) / (v^2 c / 2).
f = ballistic_dynamics(np.array([11000.0, -200.0, 1e-3]))
check_close((f[1] + G) / (0.5 * 200.0**2 * 1e-3), 0.3639, "the air density at h = 11 km implied by your f2",
            "Check the exponent gM/(RL), about 5.26, and that T = T0 - L h is used in rho = p M / (R T).", rtol=2e-3)
passed("ballistic_dynamics")

# %% nbgrader={"grade": true, "grade_id": "test_ballistic_dynamics", "locked": true, "points": 0.5, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of ballistic_dynamics (0.5 points): random states across the lower atmosphere.
# Validate (and this cell) first checks that ballistic_dynamics passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(ballistic_dynamics)
### BEGIN HIDDEN TESTS
from solutions.reentry_srekf.hidden_tests import check_ballistic_dynamics
check_ballistic_dynamics(ballistic_dynamics)
### END HIDDEN TESTS

# %% nbgrader={"grade": false, "grade_id": "ballistic_jacobian", "locked": false, "schema_version": 3, "solution": true, "task": false}
def ballistic_jacobian(x):
    """Jacobian df/dx of the ballistic dynamics, shape (3, 3)."""
    ### BEGIN SOLUTION
    h, v, c = np.asarray(x, dtype=float)
    T = T0 - L * h
    exponent = G * M / (R * L)
    # (10) d = (M p0 / (2 R)) (T0 - L h)^-1 (1 - L h / T0)^(g M / (R L)) v^2 c
    rho = P0 * (1 - L * h / T0) ** exponent * M / (R * T)
    d = 0.5 * rho * v**2 * c
    # d is proportional to T^(gM/(RL) - 1) with dT/dh = -L, so dd/dh = d L (1 - gM/(RL)) / T
    dd_dh = d * L * (1 - exponent) / T
    # dd/dv = rho v c, dd/dc = rho v^2 / 2
    dd_dv = rho * v * c
    dd_dc = 0.5 * rho * v**2
    return np.array(
        [
            [0.0, 1.0, 0.0],
            [dd_dh, dd_dv, dd_dc],
            [0.0, 0.0, 0.0],
        ]
    )
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_ballistic_jacobian", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(ballistic_dynamics, ballistic_jacobian)
# Visible checks: the rows you can write down at once, then central finite differences of your
# ballistic_dynamics (so make sure it passed its own checks first).
x = np.array([9000.0, -300.0, 1e-3])
J = check_array(ballistic_jacobian(x), "ballistic_jacobian(x)", (3, 3), "One row per f_i, one column per state.")
check_close(J[0], [0.0, 1.0, 0.0], "row 0 of the Jacobian (the derivatives of f1 = v)")
check_close(J[2], [0.0, 0.0, 0.0], "row 2 of the Jacobian (the derivatives of f3 = 0)")
for x in (np.array([9000.0, -300.0, 1e-3]), np.array([2000.0, -150.0, 2e-3]), np.array([14000.0, -450.0, 5e-4])):
    check_jacobian(ballistic_jacobian(x), ballistic_dynamics, x, "ballistic_jacobian(x)",
                   "Column 0 is d/dh: the density changes with altitude. Column 1 is d/dv, column 2 is d/dc.")
passed("ballistic_jacobian")

# %% nbgrader={"grade": true, "grade_id": "test_ballistic_jacobian", "locked": true, "points": 0.5, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of ballistic_jacobian (0.5 points): random states across the lower atmosphere.
# Validate (and this cell) first checks that ballistic_jacobian passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(ballistic_jacobian)
### BEGIN HIDDEN TESTS
from solutions.reentry_srekf.hidden_tests import check_ballistic_jacobian
check_ballistic_jacobian(ballistic_jacobian)
### END HIDDEN TESTS

# %% [markdown]
# ## 2. The range measurement model (1 point)
#
# The radar's antenna is at $(r_1, r_2) = (5000\ \text{m}, 5000\ \text{m})$: 5 km to the side of the
# vehicle's line of fall, at an altitude of 5 km (`RADAR_R1`, `RADAR_R2`). It measures the range
#
# $$h_\text{rng}(\mathbf{x}) = \sqrt{r_1^2 + (h - r_2)^2}, \tag{13}$$
#
# with Gaussian noise of standard deviation $\sigma_\text{rng} = 50$ m. Write `radar_predict(x)`, which
# returns the range as an array of shape `(1,)` (0.5 points), and `radar_jacobian(x)`, which returns its
# Jacobian with respect to $\mathbf{x}$, shape `(1, 3)` (0.5 points).
#
# Notice that the range is stationary where the vehicle passes the radar's altitude, $h = r_2$: there
# $\partial h_\text{rng}/\partial h = 0$. Part 10 shows what that costs the filter.

# %% nbgrader={"grade": false, "grade_id": "radar_predict", "locked": false, "schema_version": 3, "solution": true, "task": false}
def radar_predict(x):
    """Predicted range (m) from the radar to the vehicle, shape (1,)."""
    ### BEGIN SOLUTION
    h = float(np.asarray(x, dtype=float)[0])
    # (13) h_rng = sqrt(r1^2 + (h - r2)^2)
    return np.array([np.hypot(RADAR_R1, h - RADAR_R2)])
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_radar_predict", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(radar_predict)
# Visible checks on 3-4-5 triangles: 3750 m above or below the radar, the range is 6250 m.
y = check_array(radar_predict(np.array([8750.0, -300.0, 1e-3])), "radar_predict(x)", (1,),
                "Return an array with one entry, np.array([range]).")
check_close(y, [6250.0], "the range at h = 8750 m", "The sides are r1 = 5000 m and h - r2 = 3750 m.")
check_close(radar_predict(np.array([1250.0, -100.0, 5e-4])), [6250.0], "the range at h = 1250 m, below the radar")
check_close(radar_predict(np.array([5000.0, -300.0, 1e-3])), [5000.0],
            "the range when the vehicle is level with the radar (h = r2)", "Then the range is r1.")
passed("radar_predict")

# %% nbgrader={"grade": true, "grade_id": "test_radar_predict", "locked": true, "points": 0.5, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of radar_predict (0.5 points): random states.
# Validate (and this cell) first checks that radar_predict passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(radar_predict)
### BEGIN HIDDEN TESTS
from solutions.reentry_srekf.hidden_tests import check_radar_predict
check_radar_predict(radar_predict)
### END HIDDEN TESTS

# %% nbgrader={"grade": false, "grade_id": "radar_jacobian", "locked": false, "schema_version": 3, "solution": true, "task": false}
def radar_jacobian(x):
    """Jacobian of the range with respect to x = [h, v, c], shape (1, 3)."""
    ### BEGIN SOLUTION
    h = float(np.asarray(x, dtype=float)[0])
    h_rng = np.hypot(RADAR_R1, h - RADAR_R2)
    # d h_rng / dh = (h - r2) / h_rng; the range does not depend on v or c
    return np.array([[(h - RADAR_R2) / h_rng, 0.0, 0.0]])
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_radar_jacobian", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(radar_predict, radar_jacobian)
# Visible checks on the same 3-4-5 triangles, then finite differences of your radar_predict.
H = check_array(radar_jacobian(np.array([8750.0, -300.0, 1e-3])), "radar_jacobian(x)", (1, 3),
                "One row (one measurement), one column per state.")
check_close(H, [[0.6, 0.0, 0.0]], "the Jacobian at h = 8750 m",
            "d/dh sqrt(r1^2 + (h - r2)^2) = (h - r2) / range = 3750 / 6250; the range does not depend on v or c.")
check_close(radar_jacobian(np.array([1250.0, -100.0, 5e-4])), [[-0.6, 0.0, 0.0]],
            "the Jacobian at h = 1250 m, below the radar", "Below the radar, climbing brings the vehicle closer.")
x = np.array([12000.0, -400.0, 1e-3])
check_jacobian(radar_jacobian(x), radar_predict, x, "radar_jacobian(x)")
passed("radar_jacobian")

# %% nbgrader={"grade": true, "grade_id": "test_radar_jacobian", "locked": true, "points": 0.5, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of radar_jacobian (0.5 points): random states.
# Validate (and this cell) first checks that radar_jacobian passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(radar_jacobian)
### BEGIN HIDDEN TESTS
from solutions.reentry_srekf.hidden_tests import check_radar_jacobian
check_radar_jacobian(radar_jacobian)
### END HIDDEN TESTS

# %% [markdown]
# ## 3. Marginal distributions of a Gaussian (1 point)
#
# A square-root filter never forms the covariance $\mathbf{P}$. It keeps an upper-triangular
# $\mathbf{S}$ with $\mathbf{S}^\mathsf{T}\mathbf{S} = \mathbf{P}$, and writes
# $p(\mathbf{x}) = \mathcal{N}^{\frac{1}{2}}(\mathbf{x}; \boldsymbol{\mu}, \mathbf{S})$ (17). Partition
# $\mathbf{x} = [\mathbf{x}_a;\ \mathbf{x}_b]$ and $\mathbf{S}$ into blocks to match:
#
# $$\begin{bmatrix} \mathbf{P}_{aa} & \mathbf{P}_{ab} \\ \mathbf{P}_{ba} & \mathbf{P}_{bb} \end{bmatrix}
# = \begin{bmatrix} \mathbf{S}_1 & \mathbf{S}_2 \\ \mathbf{0} & \mathbf{S}_3 \end{bmatrix}^\mathsf{T}
#   \begin{bmatrix} \mathbf{S}_1 & \mathbf{S}_2 \\ \mathbf{0} & \mathbf{S}_3 \end{bmatrix}
# = \begin{bmatrix} \mathbf{S}_1^\mathsf{T}\mathbf{S}_1 & \mathbf{S}_1^\mathsf{T}\mathbf{S}_2 \\
#   \mathbf{S}_2^\mathsf{T}\mathbf{S}_1 & \mathbf{S}_2^\mathsf{T}\mathbf{S}_2 + \mathbf{S}_3^\mathsf{T}\mathbf{S}_3 \end{bmatrix}. \tag{18}$$
#
# > **Handout correction.** The handout gives $\mathbf{P}_{ab}$ the size $n_b \times n_a$. It is
# > $n_a \times n_b$: its rows belong to $\mathbf{x}_a$ and its columns to $\mathbf{x}_b$.
#
# The marginal of the head is easy: $\mathbf{S}_a = \mathbf{S}_1$ (19). The tail needs an upper-triangular
# $\mathbf{S}_b$ with $\mathbf{S}_b^\mathsf{T}\mathbf{S}_b = \mathbf{S}_2^\mathsf{T}\mathbf{S}_2 + \mathbf{S}_3^\mathsf{T}\mathbf{S}_3$
# (20), and a QR decomposition gives one: if $[\mathbf{S}_2;\ \mathbf{S}_3] = \mathbf{Q}[\mathbf{R}_1;\ \mathbf{0}]$,
# then $\mathbf{S}_b = \mathbf{R}_1$, because $\mathbf{Q}$ is orthogonal.
#
# The same idea works for any index vector $\mathcal{I}$, contiguous or not, in any order (indices start at 0
# in Python: the handout's $\mathcal{I} = [3\ 5\ 1]$ is `[2, 4, 0]` here). Picking rows
# *and* columns $\mathcal{I}$ of $\mathbf{P}$ is the same as picking the columns $\mathcal{I}$ of $\mathbf{S}$:
# $\mathbf{P}_{\mathcal{I}\mathcal{I}} = \mathbf{S}_{:,\mathcal{I}}^\mathsf{T}\mathbf{S}_{:,\mathcal{I}}$. The tall matrix
# $\mathbf{S}_{:,\mathcal{I}}$ is not triangular, so take its QR decomposition,
# $\mathbf{S}_{:,\mathcal{I}} = \mathbf{Q}[\mathbf{R}_1;\ \mathbf{0}]$, and
#
# $$p(\mathbf{x}_\mathcal{I}) = \mathcal{N}^{\frac{1}{2}}(\mathbf{x}_\mathcal{I};\ \boldsymbol{\mu}_\mathcal{I},\ \mathbf{S}_\mathcal{I}), \qquad \mathbf{S}_\mathcal{I} = \mathbf{R}_1. \tag{22}$$
#
# You never need $\mathbf{Q}$: `np.linalg.qr(A, mode="r")` returns just the triangle (a *Q-less* QR).
# Write `marginal(mu, S, idx)`, returning the pair `(mu_I, S_I)` with `S_I` upper triangular. The sign of
# each row of `S_I` is yours to choose; the checks compare $\mathbf{S}_\mathcal{I}^\mathsf{T}\mathbf{S}_\mathcal{I}$.

# %% nbgrader={"grade": false, "grade_id": "marginal", "locked": false, "schema_version": 3, "solution": true, "task": false}
def marginal(mu, S, idx):
    """Marginal of the entries idx: mu (n,), S (n, n) -> mu_I (n_I,), upper-triangular S_I (n_I, n_I)."""
    ### BEGIN SOLUTION
    mu, S = np.asarray(mu, dtype=float), np.asarray(S, dtype=float)
    idx = np.asarray(idx, dtype=int).reshape(-1)
    # (22) S_{:,I} = Q [R1; 0]  =>  S_I = R1 (Q-less QR)
    S_I = np.linalg.qr(S[:, idx], mode="r")
    return mu[idx], S_I
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_marginal", "locked": true, "schema_version": 3, "solution": false, "task": false}
# Visible checks on a 5-dimensional Gaussian with a random upper-triangular square root S.
rng = np.random.default_rng(5)
S = np.linalg.qr(rng.standard_normal((5, 5)) + 5 * np.eye(5), mode="r")
mu = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
P = S.T @ S
require(marginal)
# The head [0, 1]: equation (19) says S_I is the top-left block of S.
mu_I, S_I = check_pair(marginal(mu, S, [0, 1]), "marginal(mu, S, idx)", "mu_I", "S_I")
check_close(check_array(mu_I, "mu_I for idx = [0, 1]", (2,)), [1.0, 2.0], "mu_I for the head idx = [0, 1]")
check_square_root(check_array(S_I, "S_I for idx = [0, 1]", (2, 2)), S[:2, :2].T @ S[:2, :2],
                  "S_I for the head idx = [0, 1]", "For a head, S_I is the top-left block of S (equation 19).")
# The handout's example I = [3 5 1], which is [2, 4, 0] with Python's indices from 0.
mu_I, S_I = marginal(mu, S, [2, 4, 0])
check_close(mu_I, [3.0, 5.0, 1.0], "mu_I for idx = [2, 4, 0]", "Keep the entries in the order of idx.")
check_square_root(S_I, P[np.ix_([2, 4, 0], [2, 4, 0])], "S_I",
                  "With idx = [2, 4, 0], S_I.T @ S_I must be P[idx][:, idx]: take a Q-less QR of the columns S[:, idx] "
                  "(equation 22).")
mu_I, S_I = marginal(mu, S, np.array([4]))
check_square_root(S_I, P[np.ix_([4], [4])], "S_I for the last entry alone, idx = np.array([4])",
                  "S_I.T @ S_I is the variance P[4, 4], the squared length of the column S[:, 4].")
passed("marginal")

# %% nbgrader={"grade": true, "grade_id": "test_marginal", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of marginal (1 point): random Gaussians of 2 to 7 dimensions; heads, tails, segments,
# non-contiguous and non-ascending index sets.
# Validate (and this cell) first checks that marginal passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(marginal)
### BEGIN HIDDEN TESTS
from solutions.reentry_srekf.hidden_tests import check_marginal
check_marginal(marginal)
### END HIDDEN TESTS

# %% [markdown]
# ## 4. Conditional distributions of a Gaussian (1 point)
#
# In covariance form, conditioning $\mathbf{x}_a$ on $\mathbf{x}_b$ gives
#
# $$p(\mathbf{x}_a | \mathbf{x}_b) = \mathcal{N}\left(\mathbf{x}_a;\ \boldsymbol{\mu}_a + \mathbf{P}_{ab}\mathbf{P}_{bb}^{-1}(\mathbf{x}_b - \boldsymbol{\mu}_b),\ \mathbf{P}_{aa} - \mathbf{P}_{ab}\mathbf{P}_{bb}^{-1}\mathbf{P}_{ba}\right). \tag{23a}$$
#
# In square-root form the tail given the head is cheap: with the blocks of (18),
# $p(\mathbf{x}_b | \mathbf{x}_a) = \mathcal{N}^{\frac{1}{2}}(\mathbf{x}_b;\ \boldsymbol{\mu}_b + \mathbf{S}_2^\mathsf{T}\mathbf{S}_1^{-\mathsf{T}}(\mathbf{x}_a - \boldsymbol{\mu}_a),\ \mathbf{S}_3)$ (25):
# one triangular solve, and the lower-right block of $\mathbf{S}$.
#
# For any sets $\mathcal{A}$ (the entries we want) and $\mathcal{B}$ (the entries we know), put the known
# ones first. The columns $[\mathbf{S}_{:,\mathcal{B}}\ \ \mathbf{S}_{:,\mathcal{A}}]$ are a square root of the
# covariance of $[\mathbf{x}_\mathcal{B};\ \mathbf{x}_\mathcal{A}]$ (29), but not a triangular one, so take a QR
# decomposition (30):
#
# $$\begin{bmatrix} \mathbf{S}_{:,\mathcal{B}} & \mathbf{S}_{:,\mathcal{A}} \end{bmatrix} = \mathbf{Q}\begin{bmatrix} \mathbf{R}_1 & \mathbf{R}_2 \\ \mathbf{0} & \mathbf{R}_3 \end{bmatrix}.$$
#
# Now $\mathcal{B}$ is the head, and (25) applies:
#
# $$p(\mathbf{x}_\mathcal{A} | \mathbf{x}_\mathcal{B}) = \mathcal{N}^{\frac{1}{2}}\left(\mathbf{x}_\mathcal{A};\ \boldsymbol{\mu}_\mathcal{A} + \mathbf{R}_2^\mathsf{T}\mathbf{R}_1^{-\mathsf{T}}(\mathbf{x}_\mathcal{B} - \boldsymbol{\mu}_\mathcal{B}),\ \mathbf{R}_3\right). \tag{31}$$
#
# Apply $\mathbf{R}_1^{-\mathsf{T}}$ with a triangular solve, `solve_triangular(R1, z, trans="T")`, not with an
# inverse. Write `conditional(mu, S, idx_a, idx_b, x_b)`, returning the pair `(mu_c, S_c)` with `S_c` upper
# triangular.

# %% nbgrader={"grade": false, "grade_id": "conditional", "locked": false, "schema_version": 3, "solution": true, "task": false}
def conditional(mu, S, idx_a, idx_b, x_b):
    """p(x[idx_a] | x[idx_b] = x_b): mu (n,), S (n, n) -> mu_c (n_A,), upper-triangular S_c (n_A, n_A)."""
    ### BEGIN SOLUTION
    mu, S = np.asarray(mu, dtype=float), np.asarray(S, dtype=float)
    idx_a = np.asarray(idx_a, dtype=int).reshape(-1)
    idx_b = np.asarray(idx_b, dtype=int).reshape(-1)
    x_b = np.asarray(x_b, dtype=float).reshape(-1)
    n_b = idx_b.size
    # (29)-(30) [S_{:,B}  S_{:,A}] = Q [R1 R2; 0 R3], a Q-less QR of the permuted columns
    R_ba = np.linalg.qr(S[:, np.concatenate([idx_b, idx_a])], mode="r")
    R1, R2, R3 = R_ba[:n_b, :n_b], R_ba[:n_b, n_b:], R_ba[n_b:, n_b:]
    # (31) mu_{A|B} = mu_A + R2^T R1^-T (x_B - mu_B), with R1^-T applied by a triangular solve
    mu_c = mu[idx_a] + R2.T @ solve_triangular(R1, x_b - mu[idx_b], trans="T")
    # (31) S_{A|B} = R3
    return mu_c, R3
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_conditional", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(conditional)
# Visible checks. By hand: P = [[4, 2], [2, 3]] and mu = [1, 2]. Given x_1 = 5, equation (23a) gives
# the mean 1 + (2/3)(5 - 2) = 3 and the variance 4 - 2 * 2 / 3 = 8/3.
S_small = np.array([[2.0, 1.0], [0.0, np.sqrt(2.0)]])  # S_small.T @ S_small = [[4, 2], [2, 3]]
mu_c, S_c = check_pair(conditional(np.array([1.0, 2.0]), S_small, [0], [1], np.array([5.0])),
                       "conditional(mu, S, idx_a, idx_b, x_b)", "mu_c", "S_c")
check_close(check_array(mu_c, "mu_c", (1,)), [3.0], "mu_c for x_0 given x_1 = 5",
            "mu_a + P_ab / P_bb (x_b - mu_b) = 1 + (2/3)(5 - 2). Are the columns in the order [S[:, idx_b], S[:, idx_a]]?")
check_square_root(check_array(S_c, "S_c", (1, 1)), [[8.0 / 3.0]], "S_c for x_0 given x_1 = 5",
                  "S_c is the block R3 of the QR, and S_c.T @ S_c should be 4 - 4/3.")
# Equation (23a) on the 5-dimensional Gaussian of the marginal checks: x[[4, 0, 2]] given x[[3, 1]].
idx_a, idx_b, x_b = [4, 0, 2], [3, 1], np.array([0.5, -1.0])
P_ab, P_bb = P[np.ix_(idx_a, idx_b)], P[np.ix_(idx_b, idx_b)]
mu_c, S_c = conditional(mu, S, idx_a, idx_b, x_b)  # R2 is n_B x n_A here, so (31) takes R2^T
check_close(mu_c, mu[idx_a] + P_ab @ np.linalg.solve(P_bb, x_b - mu[idx_b]), "mu_c for x[[4, 0, 2]] given x[[3, 1]]",
            "Equation (31): mu_A + R2^T R1^-T (x_B - mu_B). R1^-T needs trans='T' in solve_triangular.")
check_square_root(S_c, P[np.ix_(idx_a, idx_a)] - P_ab @ np.linalg.solve(P_bb, P_ab.T), "S_c for x[[4, 0, 2]] given x[[3, 1]]",
                  "S_c is R3, the lower-right block of the QR of the permuted columns.")
passed("conditional")

# %% nbgrader={"grade": true, "grade_id": "test_conditional", "locked": true, "points": 1, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of conditional (1 point): random Gaussians of 2 to 7 dimensions, conditioned on heads,
# tails, segments, non-contiguous and non-ascending index sets.
# Validate (and this cell) first checks that conditional passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(conditional)
### BEGIN HIDDEN TESTS
from solutions.reentry_srekf.hidden_tests import check_conditional
check_conditional(conditional)
### END HIDDEN TESTS

# %% [markdown]
# ## 5. The square-root time update (1.5 points)
#
# Between two radar pulses the belief moves with the model. Over a step, the process noise adds an
# increment $\mathbf{w}$ with covariance $\mathbf{Q}_w$. Write the step as a function of the state and the
# increment, $\mathbf{x}^+ = \mathbf{F}(\mathbf{x}, \mathbf{w})$, and linearise it at $(\boldsymbol{\mu}, \mathbf{0})$:
#
# $$\mathbf{x}^+ \approx \mathbf{F}(\boldsymbol{\mu}, \mathbf{0}) + \mathbf{J}\begin{bmatrix} \mathbf{x} - \boldsymbol{\mu} \\ \mathbf{w} \end{bmatrix},
# \qquad \mathbf{J} = \frac{\partial \mathbf{F}}{\partial [\mathbf{x};\ \mathbf{w}]} \in \mathbb{R}^{n \times (n + q)}.$$
#
# The pair $[\mathbf{x};\ \mathbf{w}]$ has mean $[\boldsymbol{\mu};\ \mathbf{0}]$ and the block-diagonal square root
# $\mathbf{S}_z = \mathrm{blkdiag}(\mathbf{S},\ \mathbf{S}_Q)$, with $\mathbf{S}_Q^\mathsf{T}\mathbf{S}_Q = \mathbf{Q}_w$. So
#
# $$\mathbf{P}^+ = \mathbf{J}\,\mathrm{blkdiag}(\mathbf{P}, \mathbf{Q}_w)\,\mathbf{J}^\mathsf{T}
# = (\mathbf{S}_z\mathbf{J}^\mathsf{T})^\mathsf{T}(\mathbf{S}_z\mathbf{J}^\mathsf{T}).$$
#
# $\mathbf{S}_z\mathbf{J}^\mathsf{T}$ is a square root of $\mathbf{P}^+$, but a tall, full one, $(n + q) \times n$. Its
# Q-less QR, $\mathbf{S}_z\mathbf{J}^\mathsf{T} = \mathbf{Q}[\mathbf{R};\ \mathbf{0}]$, gives the upper-triangular
# $\mathbf{S}^+ = \mathbf{R}$, exactly as in (22). $\mathbf{P}^+$ is never formed.
#
# Write `sqrt_time_update(mu, S, f_and_jacobian, S_Q)`. The argument `f_and_jacobian(mu)` returns the pair
# $(\mathbf{F}(\boldsymbol{\mu}, \mathbf{0}),\ \mathbf{J})$, and `S_Q` is the $q \times q$ upper-triangular square root of
# the increment's covariance ($q$ need not equal $n$). `block_diag` from SciPy is imported in the set-up
# cell. Return `(mu_next, S_next)`.
#
# For the Starship the filter passes one RK4 step of $\mathrm{d}\mathbf{x} = \mathbf{f}(\mathbf{x})\,\mathrm{d}t + \mathrm{d}\mathbf{w}$
# over $\Delta t$, with your `ballistic_dynamics`, differentiated stage by stage with your
# `ballistic_jacobian` (`starship.rk4_step_with_jacobian`), and $\mathbf{S}_Q = \mathrm{diag}(0,\ 10^{-10},\ 5\times 10^{-6})\sqrt{\Delta t}$,
# so that $\mathbf{Q}_w = \mathbf{Q}\Delta t$. The RK4 step stays given (Section 12 says why). Your blank is the part
# that makes the filter a square-root filter: the augmentation and the QR.

# %% nbgrader={"grade": false, "grade_id": "sqrt_time_update", "locked": false, "schema_version": 3, "solution": true, "task": false}
def sqrt_time_update(mu, S, f_and_jacobian, S_Q):
    """Predict through a linearised step: mu (n,), S (n, n), S_Q (q, q) -> mu_next (n,), upper-triangular S_next (n, n)."""
    ### BEGIN SOLUTION
    mu, S, S_Q = (np.asarray(a, dtype=float) for a in (mu, S, S_Q))
    mu_next, J = f_and_jacobian(mu)
    # square root of cov([x; w]) = blkdiag(P, Q): S_z = blkdiag(S, S_Q)
    S_z = block_diag(S, S_Q)
    # P+ = J blkdiag(P, Q) J^T = (S_z J^T)^T (S_z J^T), so S+ is the R of a Q-less QR of S_z J^T
    S_next = np.linalg.qr(S_z @ J.T, mode="r")
    return mu_next, S_next
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_sqrt_time_update", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(sqrt_time_update)
# Visible checks on a step you can do by hand: constant velocity over 2 s, x = [position (m), velocity (m/s)],
# x+ = A x + w, so J = [A, I] and F(mu, 0) = A mu = [10 - 2, -1].
A_cv = np.array([[1.0, 2.0], [0.0, 1.0]])
mu_cv = np.array([10.0, -1.0])
S_cv = np.array([[3.0, 1.0], [0.0, 2.0]])  # P = S^T S = [[9, 3], [3, 5]]
P_cv = S_cv.T @ S_cv
S_Q_cv = np.diag([0.0, 0.5])  # noise on the velocity only: Q_w = diag(0, 0.25)
step_cv = lambda m: (A_cv @ m, np.hstack([A_cv, np.eye(2)]))
returned = sqrt_time_update(mu_cv, S_cv, step_cv, S_Q_cv)  # J is n x (n + q): S_z = block_diag(S, S_Q), then S_z @ J.T
mu_next, S_next = check_pair(returned, "sqrt_time_update(mu, S, f_and_jacobian, S_Q)", "mu_next", "S_next")
check_close(check_array(mu_next, "mu_next", (2,)), [8.0, -1.0], "the predicted mean",
            "Return the mean that f_and_jacobian(mu) gives.")
check_square_root(check_array(S_next, "S_next", (2, 2)), A_cv @ P_cv @ A_cv.T + np.diag([0.0, 0.25]),
                  "S_next for the constant-velocity step",
                  "S_next is the R factor of the Q-less QR of block_diag(S, S_Q) @ J.T. The state's block comes first.")
# One noise input (q = 1) that pushes both states: J = [A, b] with b = [2, 2].
b_cv = np.array([[2.0], [2.0]])
mu_next, S_next = sqrt_time_update(mu_cv, S_cv, lambda m: (A_cv @ m, np.hstack([A_cv, b_cv])), np.array([[0.3]]))
check_square_root(S_next, A_cv @ P_cv @ A_cv.T + 0.09 * b_cv @ b_cv.T, "S_next with one noise input (q = 1)",
                  "S_Q's block has the size of S_Q (here 1 x 1), which need not be the size of S.")
# A noise whose two components are correlated: S_Q upper triangular but not diagonal, Q_w = S_Q.T @ S_Q.
S_Q_full = np.array([[0.4, 0.3], [0.0, 0.2]])  # Q_w = [[0.16, 0.12], [0.12, 0.13]]
mu_next, S_next = sqrt_time_update(mu_cv, S_cv, step_cv, S_Q_full)
check_square_root(S_next, A_cv @ P_cv @ A_cv.T + S_Q_full.T @ S_Q_full, "S_next with correlated noise, S_Q = [[0.4, 0.3], [0, 0.2]]",
                  "S_Q is the upper-triangular square root of Q_w (Q_w = S_Q.T @ S_Q): stack it as given, "
                  "block_diag(S, S_Q), not S_Q.T.")
passed("sqrt_time_update")

# %% nbgrader={"grade": true, "grade_id": "test_sqrt_time_update", "locked": true, "points": 1.5, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of sqrt_time_update (1.5 points): random steps of 2 to 7 states with 1 to n + 1 noise
# inputs, on well-conditioned and badly conditioned Gaussians.
# Validate (and this cell) first checks that sqrt_time_update passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(sqrt_time_update)
### BEGIN HIDDEN TESTS
from solutions.reentry_srekf.hidden_tests import check_sqrt_time_update
check_sqrt_time_update(sqrt_time_update)
### END HIDDEN TESTS

# %% [markdown]
# ## 6. The square-root measurement update (1.5 points)
#
# A measurement $\mathbf{y} = \mathbf{h}(\mathbf{x}) + \mathbf{e}$, with noise $\mathbf{e} \sim \mathcal{N}^{\frac{1}{2}}(\mathbf{0}, \mathbf{S}_R)$,
# linearised at $\boldsymbol{\mu}$, is $\mathbf{y} \approx \mathbf{h}(\boldsymbol{\mu}) + \mathbf{H}(\mathbf{x} - \boldsymbol{\mu}) + \mathbf{e}$.
# Stack the measurement on top of the state. The pair $[\mathbf{y};\ \mathbf{x}]$ is then Gaussian with
# mean $[\mathbf{h}(\boldsymbol{\mu});\ \boldsymbol{\mu}]$ and covariance
#
# $$\begin{bmatrix} \mathbf{H}\mathbf{P}\mathbf{H}^\mathsf{T} + \mathbf{R} & \mathbf{H}\mathbf{P} \\ \mathbf{P}\mathbf{H}^\mathsf{T} & \mathbf{P} \end{bmatrix}
# = \mathbf{A}^\mathsf{T}\mathbf{A}, \qquad
# \mathbf{A} = \begin{bmatrix} \mathbf{S}\mathbf{H}^\mathsf{T} & \mathbf{S} \\ \mathbf{S}_R & \mathbf{0} \end{bmatrix},$$
#
# as multiplying out shows ($\mathbf{P} = \mathbf{S}^\mathsf{T}\mathbf{S}$, $\mathbf{R} = \mathbf{S}_R^\mathsf{T}\mathbf{S}_R$). $\mathbf{A}$ is
# square, $(n + m) \times (m + n)$, but not triangular: its Q-less QR gives an upper-triangular square root
# of the joint. The posterior $p(\mathbf{x} \mid \mathbf{y})$ is then the conditional of the tail $\mathbf{x}$ given
# the head $\mathbf{y}$, which is what your `conditional` computes (and cheaply, by (25), since $\mathbf{y}$
# is the head).
#
# Write `sqrt_measurement_update(mu, S, y, h_and_jacobian, S_R)`. The argument `h_and_jacobian(mu)`
# returns the pair $(\mathbf{h}(\boldsymbol{\mu}),\ \mathbf{H})$ of shapes `(m,)` and `(m, n)`; `y` has shape `(m,)` and `S_R`
# is $m \times m$. Use your `conditional` for the last step, and return `(mu_next, S_next)`. For the
# Starship, $m = 1$, $\mathbf{h}$ is your `radar_predict`, $\mathbf{H}$ your `radar_jacobian`, and $\mathbf{S}_R = [50\ \text{m}]$.

# %% nbgrader={"grade": false, "grade_id": "sqrt_measurement_update", "locked": false, "schema_version": 3, "solution": true, "task": false}
def sqrt_measurement_update(mu, S, y, h_and_jacobian, S_R):
    """Condition on y: mu (n,), S (n, n), y (m,), S_R (m, m) -> mu_next (n,), upper-triangular S_next (n, n)."""
    ### BEGIN SOLUTION
    mu, S, S_R = (np.asarray(a, dtype=float) for a in (mu, S, S_R))
    y = np.atleast_1d(np.asarray(y, dtype=float))
    m, n = y.size, mu.size
    y_pred, H = h_and_jacobian(mu)
    # joint of [y; x] = [H x + e; x] near mu: covariance [H P H^T + R, H P; P H^T, P], whose
    # square root is the R factor of the QR of [S H^T  S; S_R  0]
    S_joint = np.linalg.qr(np.block([[S @ H.T, S], [S_R, np.zeros((m, n))]]), mode="r")
    # p(x | y): the state (the tail) given the measurement (the head), with the joint mean [h(mu); mu]
    return conditional(np.concatenate([y_pred, mu]), S_joint, np.arange(m, m + n), np.arange(m), y)
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_sqrt_measurement_update", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(sqrt_measurement_update, conditional)
# Visible checks. First the noise's square root alone: a 3-state belief with a diagonal S (P = diag(9, 4, 1)), its
# first two entries measured with correlated noise, S_R = [[2, 1], [0, 1]] (R = S_R.T @ S_R = [[4, 2], [2, 2]]), and
# y = h(mu), so that the residual is zero and the mean does not move.
mu_d, S_d, H_d = np.array([10.0, -1.0, 0.5]), np.diag([3.0, 2.0, 1.0]), np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
S_R_d = np.array([[2.0, 1.0], [0.0, 1.0]])
returned = sqrt_measurement_update(mu_d, S_d, H_d @ mu_d, lambda m: (H_d @ m, H_d), S_R_d)  # [S H^T, S; S_R, 0]: 0 is m x n
mu_next, S_next = check_pair(returned, "sqrt_measurement_update(mu, S, y, h_and_jacobian, S_R)", "mu_next", "S_next")
check_array(mu_next, "mu_next", (3,))
P_d, R_d = S_d.T @ S_d, S_R_d.T @ S_R_d
K_d = np.linalg.solve(H_d @ P_d @ H_d.T + R_d, H_d @ P_d).T
check_square_root(check_array(S_next, "S_next", (3, 3)), P_d - K_d @ H_d @ P_d, "S_next with S_R = [[2, 1], [0, 1]]",
                  "S_R is the upper-triangular square root of R (R = S_R.T @ S_R): stack S_R itself, as given, under "
                  "the measurement's columns; not R, and not S_R.T.")
check_close(mu_next, mu_d, "the mean when y = h(mu)", "When y equals the predicted measurement h(mu), the residual is zero and the mean stays mu.")
# Then by hand: the constant-velocity belief of part 5 (mean [10, -1], P = [[9, 3], [3, 5]]), with
# its position measured, y = 13, noise standard deviation 2. The innovation variance is 9 + 4 = 13, the gain
# K = [9, 3] / 13, so the mean becomes [10 + 9 * 3 / 13, -1 + 3 * 3 / 13] and P becomes P - K [9, 3].
A_cv, mu_cv, S_cv = np.array([[1.0, 2.0], [0.0, 1.0]]), np.array([10.0, -1.0]), np.array([[3.0, 1.0], [0.0, 2.0]])
H_cv = np.array([[1.0, 0.0]])
mu_next, S_next = check_pair(sqrt_measurement_update(mu_cv, S_cv, np.array([13.0]), lambda m: (H_cv @ m, H_cv), np.array([[2.0]])),
                             "sqrt_measurement_update(mu, S, y, h_and_jacobian, S_R)", "mu_next", "S_next")
# The covariance first: a wrong block of the QR moves the mean too, while a residual of the wrong sign moves the mean alone.
K_cv = np.array([9.0, 3.0]) / 13.0
check_square_root(check_array(S_next, "S_next", (2, 2)), S_cv.T @ S_cv - np.outer(K_cv, [9.0, 3.0]), "the updated S",
                  "Take the Q-less QR of [[S @ H.T, S], [S_R, 0]] and condition the tail (the state) on the head (y). "
                  "With P = S.T @ S, the top blocks are S @ H.T and S itself, not (H @ S).T = S.T @ H.T, nor S.T: they "
                  "differ when S is not diagonal, as here.")
check_close(check_array(mu_next, "mu_next", (2,)), [10.0 + 27.0 / 13.0, -1.0 + 9.0 / 13.0], "the updated mean",
            "Condition on y with the joint mean [h(mu); mu]: the residual is y - h(mu), not h(mu) - y.")
# Two measurements with correlated noise on a 3-state Gaussian, against the covariance-form formulas.
rng = np.random.default_rng(6)
S3, mu3 = np.linalg.qr(rng.standard_normal((3, 3)) + 3 * np.eye(3), mode="r"), np.array([1.0, -2.0, 0.5])
H3, S_R3, y3 = rng.standard_normal((2, 3)), np.array([[0.5, 0.2], [0.0, 0.4]]), np.array([0.3, -0.7])
mu_next, S_next = sqrt_measurement_update(mu3, S3, y3, lambda m: (H3 @ m, H3), S_R3)
P3 = S3.T @ S3
K3 = np.linalg.solve(H3 @ P3 @ H3.T + S_R3.T @ S_R3, H3 @ P3).T
check_close(mu_next, mu3 + K3 @ (y3 - H3 @ mu3), "the mean after two measurements (m = 2)",
            "Build the blocks with the sizes of y and S_R (m = 2 here), not with 1.")
check_square_root(S_next, P3 - K3 @ H3 @ P3, "S_next after two measurements (m = 2)",
                  "S_R goes under the measurement's columns, zeros under the state's; S_R is a square root, not R.")
passed("sqrt_measurement_update")

# %% nbgrader={"grade": true, "grade_id": "test_sqrt_measurement_update", "locked": true, "points": 1.5, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of sqrt_measurement_update (1.5 points): 1 to n measurements of random linear models
# of 2 to 7 states, on well-conditioned and badly conditioned Gaussians (measurements up to 1e5 times
# more precise than the prior). Your conditional is replaced by the reference's here.
# Validate (and this cell) first checks that sqrt_measurement_update passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(sqrt_measurement_update)
### BEGIN HIDDEN TESTS
from solutions.reentry_srekf.hidden_tests import check_sqrt_measurement_update
check_sqrt_measurement_update(sqrt_measurement_update)
### END HIDDEN TESTS

# %% [markdown]
# ## 7. State estimation and visualisation (0.5 points)
#
# The filter itself is given: `starship.run_square_root_ekf` plays the part of the handout's `Event`, `State`
# and `Measurement` classes, and it calls the functions you wrote. Each measurement is an event at time
# $t_k$, processed in two steps: a time update from the previous event over $\Delta t = t_k - t_{k-1}$
# with your `sqrt_time_update` (skipped when $\Delta t = 0$, as for the first measurement at $t = 0$), and a
# measurement update with your `sqrt_measurement_update`, which calls your `conditional`.
#
# The initial belief is $\boldsymbol{\mu}_0 = [14\,000\ \text{m},\ -450\ \text{m/s},\ 0.0005\ \text{m}^2/\text{kg}]$
# with $\mathbf{S}_0 = \mathrm{diag}(2200,\ 100,\ 10^{-3})$. Run the filter; the report is laid out like the
# handout's terminal output ("Found 501 rows" counts the header line too). Ours is a different fall from
# the handout's, so expect different, but similar, numbers.

# %% nbgrader={"grade": false, "grade_id": "filter_run", "locked": true, "schema_version": 3, "solution": false, "task": false}
# NBVAL_CHECK_OUTPUT
require(ballistic_dynamics, ballistic_jacobian, radar_predict, radar_jacobian, conditional, sqrt_time_update,
        sqrt_measurement_update)
result = starship.run_square_root_ekf(data, ballistic_dynamics, ballistic_jacobian, radar_predict, radar_jacobian,
                                      sqrt_time_update, sqrt_measurement_update)
starship.print_report(data, result)


# %% [markdown]
# The figure of the handout shows each state against time: the truth, the estimate, and the 99.7%
# region, $\mu_i \pm 3\sigma_i$, where $\sigma_i$ is the standard deviation of the marginal of state $i$
# (from your `marginal`). Its ballistic-coefficient panel is missing. Write
# `plot_ballistic_coefficient(ax, t, c_true, c_mean, c_std)`, which draws on the matplotlib Axes `ax`:
#
# 1. the true ballistic coefficient `c_true` against time `t` [s],
# 2. the estimate `c_mean`,
# 3. the 99.7% region, filled (`ax.fill_between`) from `c_mean - 3 * c_std` to `c_mean + 3 * c_std`,
#
# with a label for each and a legend, axis labels with units, and a title. Return `ax`. The grader
# inspects the lines, the band, the axis labels, the legend and the title of your Axes; colours and styles are yours.

# %% nbgrader={"grade": false, "grade_id": "plot_ballistic_coefficient", "locked": false, "schema_version": 3, "solution": true, "task": false}
def plot_ballistic_coefficient(ax, t, c_true, c_mean, c_std):
    """Draw truth, estimate and 99.7% region of c (m^2/kg) against t (s) on ax; return ax."""
    ### BEGIN SOLUTION
    t, c_mean, c_std = (np.asarray(a, dtype=float) for a in (t, c_mean, c_std))
    ax.fill_between(
        t, c_mean - 3 * c_std, c_mean + 3 * c_std, color="C0", alpha=0.25, linewidth=0, label="99.7% region (±3σ)"
    )
    ax.plot(t, c_true, color="k", linewidth=1.5, label="truth")
    ax.plot(t, c_mean, color="C0", linewidth=1.5, linestyle="--", label="estimate")
    ax.set(title="Ballistic coefficient", xlabel="Time [s]", ylabel="c [m²/kg]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right")
    return ax
    ### END SOLUTION


# %% nbgrader={"grade": false, "grade_id": "check_plot_ballistic_coefficient", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(plot_ballistic_coefficient)
# Visible checks on four made-up points: we inspect the Axes your function draws on.
t_demo = np.array([0.0, 0.5, 1.0, 1.5])
c_true_demo = np.full(4, 1e-3)
c_mean_demo = np.array([5e-4, 8e-4, 9e-4, 1e-3])
c_std_demo = np.array([1e-3, 4e-4, 2e-4, 1e-4])
# An Axes of its own figure, not pyplot's current one: plt.plot would draw elsewhere, so draw on ax itself.
ax = Figure(figsize=(6, 3)).subplots()
returned = plot_ballistic_coefficient(ax, t_demo, c_true_demo, c_mean_demo, c_std_demo)
check_band_plot(ax, returned, t_demo, c_true_demo, c_mean_demo, c_std_demo, "plot_ballistic_coefficient")
passed("plot_ballistic_coefficient")

# %% nbgrader={"grade": true, "grade_id": "test_plot_ballistic_coefficient", "locked": true, "points": 0.5, "schema_version": 3, "solution": false, "task": false}
# Hidden tests of plot_ballistic_coefficient (0.5 points): random series; the lines, the band, the labels
# and the legend of the Axes are inspected.
# Validate (and this cell) first checks that plot_ballistic_coefficient passes its visible checks; the points come only
# from the hidden tests, which use the reference for every other blank.
validate(plot_ballistic_coefficient)
### BEGIN HIDDEN TESTS
from solutions.reentry_srekf.hidden_tests import check_plot_ballistic_coefficient
check_plot_ballistic_coefficient(plot_ballistic_coefficient)
### END HIDDEN TESTS

# %% [markdown]
# Here is the whole figure: altitude and velocity drawn by `starship.plot_results`, the ballistic
# coefficient by your function.

# %% nbgrader={"grade": false, "grade_id": "plot_results", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(ballistic_dynamics, ballistic_jacobian, radar_predict, radar_jacobian, conditional, sqrt_time_update,
        sqrt_measurement_update, marginal, plot_ballistic_coefficient)
fig, axes = starship.plot_results(data, result, marginal, plot_ballistic_coefficient)
plt.show()

# %% [markdown]
# **What the figure shows.** The first range leaves the altitude uncertain by about 57 m (one standard
# deviation), and on the way down its standard deviation stays between about 15 and 57 m, too thin to
# see at this scale. <!-- claim: reentry-srekf/sigma-h-range -->
# The velocity and the ballistic coefficient are not measured at all: the filter learns them from how the range
# *changes*, through the model. Section 12 follows how fast it learns each.

# %% [markdown]
# ## 8. Why square roots?
#
# Your filter never forms a covariance: it carries $\mathbf{S}$. The textbook EKF carries $\mathbf{P}$ and
# updates it as $\mathbf{P}^+ = \mathbf{P} - \mathbf{K}\mathbf{H}\mathbf{P}$, with the gain
# $\mathbf{K} = \mathbf{P}\mathbf{H}^\mathsf{T}(\mathbf{H}\mathbf{P}\mathbf{H}^\mathsf{T} + \mathbf{R})^{-1}$. In exact
# arithmetic the two are the same filter. In floating point they are not. When a measurement is much
# more precise than the prior, $\mathbf{P} - \mathbf{K}\mathbf{H}\mathbf{P}$ subtracts two nearly equal matrices to
# get a small one, and the rounding error of the big ones can exceed the small answer.
#
# The cell below conditions the initial belief ($\sigma_h = 2200$ m) on one range, for radars from
# 100 m down to $10^{-10}$ m precise, in five ways:
#
# - the short covariance form $\mathbf{P} - \mathbf{K}\mathbf{H}\mathbf{P}$, in single precision (`float32`, as a small
#   flight computer or a GPU may use) and in double precision (`float64`);
# - Joseph's covariance form $(\mathbf{I} - \mathbf{K}\mathbf{H})\mathbf{P}(\mathbf{I} - \mathbf{K}\mathbf{H})^\mathsf{T} + \mathbf{K}\mathbf{R}\mathbf{K}^\mathsf{T}$,
#   the same covariance as a sum of two positive semi-definite terms, in double precision;
# - the same QR as your update, in single precision (your update works in `float64`, so these values come
#   from the instructors' reference, shipped with the lab);
# - your `sqrt_measurement_update`, in double precision.
#
# Each altitude variance is compared with its exact
# value, $P_{hh}\sigma_\text{rng}^2 / (H_h^2 P_{hh} + \sigma_\text{rng}^2)$, a closed form that involves no
# cancellation because the prior is diagonal. A cross marks a covariance that is not positive definite (a
# zero or negative variance, or no Cholesky factor).
#

# %% nbgrader={"grade": false, "grade_id": "why_square_roots", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(radar_predict, radar_jacobian, conditional, sqrt_measurement_update)
comparison = starship.compare_first_update(sqrt_measurement_update, radar_predict, radar_jacobian, starship.FIRST_UPDATE_SIGMA)
fig, ax = starship.plot_first_update_comparison(comparison)
plt.show()
for name in ("covariance32", "covariance64", "joseph64", "square_root32", "square_root"):
    broken = comparison.sigma[~getattr(comparison, f"pd_{name}")]
    print(f"{name:>13}: " + (f"not positive definite from sigma_rng = {broken.max():.2g} m down" if broken.size
                             else "positive definite at every sigma_rng"))

# %% [markdown]
# **Question 8 (1 point).** Read the figure: from which radar precision on does each update return a
# covariance that is not positive definite? Explain why the short covariance form fails, why it fails at a
# much coarser radar in `float32` than in `float64`, and why the square-root form does not fail, in either
# precision. Does any of this matter for the lab's own radar, $\sigma_\text{rng} = 50$ m? (A hint: compare
# the sizes of the numbers that each form subtracts or factorises with the machine precision, about
# $10^{-7}$ in `float32` and $2 \times 10^{-16}$ in `float64`.)

# %% [markdown] nbgrader={"grade": true, "grade_id": "why_square_roots_answer", "locked": false, "points": 1, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** The short covariance form $\mathbf{P} - \mathbf{K}\mathbf{H}\mathbf{P}$ fails. In single precision it is
# wrong by 100%, the altitude variance coming out exactly zero, for every radar from about 0.3 m down; in
# double precision it is not positive definite from about $2 \times 10^{-5}$ m down, after its error has grown
# steadily as the radar got more precise. There the altitude variance comes out exactly zero, then
# $-9.3 \times 10^{-10}$ m² at every finer radar: one rounding unit of $P_{hh}$, the $\varepsilon P_{hh}$ error
# estimated below (code that orders the same operations differently may get exactly 0 instead). That is small in square metres, but negative; and since the exact variance falls as
# $\sigma_\text{rng}^2/H_h^2$, it is 7 times the exact variance at $10^{-5}$ m and $7 \times 10^{10}$ times at
# $10^{-10}$ m. <!-- claim: reentry-srekf/covariance-form-breaks -->
# The square-root form stays positive definite at every precision down to $10^{-10}$ m, within about
# $10^{-15}$ of the exact variance in double precision and within about $2 \times 10^{-7}$ in single
# precision, a few roundings of each: <!-- claim: reentry-srekf/square-root-form-holds --> what saves it is the form, not double
# precision. Joseph's form, also a covariance form, stays positive definite at every precision in double
# precision too, with an error that grows to about $2 \times 10^{-5}$ at $10^{-10}$ m (in this code's order of
# operations; another order can do better): <!-- claim: reentry-srekf/joseph-form-holds --> the
# failure belongs to the short form's subtraction. That form computes $P_{hh}^+ \approx \sigma_\text{rng}^2/H_h^2$ as
# the difference of two numbers of size $P_{hh} = 4.84 \times 10^6$ m². Their rounding error is about
# $\varepsilon P_{hh}$, so the relative error is about $\varepsilon (H_h \sigma_h / \sigma_\text{rng})^2$, which passes 1 near
# $\sigma_\text{rng} \approx H_h \sigma_h \sqrt{\varepsilon} \approx 1900\ \text{m} \times \sqrt{\varepsilon}$: about 0.7 m in `float32` and
# $3 \times 10^{-5}$ m in `float64`, an estimate within a factor of about two of the thresholds in the figure.
# The square-root form works with $\mathbf{S}$, whose entries are of the size of the standard deviations, not
# the variances, so it needs only half the digits, and an orthogonal QR does not amplify their rounding;
# and $\mathbf{S}^\mathsf{T}\mathbf{S}$ can never have a negative eigenvalue, whatever the rounding does to $\mathbf{S}$. For the
# lab's own radar none of this matters: at $\sigma_\text{rng} = 50$ m a single-precision covariance update is off by
# less than $10^{-4}$, and a single-precision covariance-form EKF follows the square-root filter over the whole
# shipped fall to within $10^{-4}$ in the variances and $10^{-3}\sigma$ in the means, positive definite throughout. <!-- claim: reentry-srekf/radar-50m-safe -->
# Square roots matter for ill-conditioned problems: measurements far more precise than
# the prior, states of very different scales, long runs in single precision.
#
# **Rubric (1 point).** 0.25 for thresholds read from the figure (short form in float32 near 0.1 to 1 m,
# in float64 near $10^{-5}$ to $10^{-4}$ m; Joseph's form and both square-root lines never); 0.25 for the
# cancellation in $\mathbf{P} - \mathbf{K}\mathbf{H}\mathbf{P}$ when the radar is much more precise than the prior (full
# credit also for saying that Joseph's form avoids this subtraction, so the failure is the short form's);
# 0.25 for the role of the machine precision (the error grows like $\varepsilon$ times the squared ratio of prior
# to measurement standard deviation, so the larger $\varepsilon$ of float32 fails first); 0.25 for why the square
# root is safe ($\mathbf{S}^\mathsf{T}\mathbf{S}$ is positive semi-definite by construction, the QR works on standard
# deviations, not their squares, so even float32 holds), or for noting that the 50 m radar is safe in
# either form and square roots pay off in ill-conditioned problems.
# ### END SOLUTION

# %% [markdown]
# ## 9. Errors, bands and the NEES
#
# An error of 20 m is invisible against a fall of 12 km, so here are the errors themselves, truth minus estimate,
# each with its own $\pm 3\sigma$ band (sized to the bands after the first seconds, so the early, wide bands run off
# the axes). If the filter is consistent, each error stays inside its band about 99.7% of the time.
#
# One number checks all three states at once: the *normalised estimation error squared*,
# $\text{NEES}_k = \mathbf{e}_k^\mathsf{T}\mathbf{P}_k^{-1}\mathbf{e}_k = \lVert \mathbf{S}_k^{-\mathsf{T}}\mathbf{e}_k \rVert^2$ (a triangular
# solve, no inverse). For a consistent filter it is a $\chi^2$ variable with 3 degrees of freedom: mean 3,
# and inside $[0.22,\ 9.35]$ 95% of the time. The dotted line marks the moment the vehicle passes the
# radar's altitude (part 10).

# %% nbgrader={"grade": false, "grade_id": "errors_nees", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(ballistic_dynamics, ballistic_jacobian, radar_predict, radar_jacobian, conditional, sqrt_time_update,
        sqrt_measurement_update, marginal)
fig, axes = starship.plot_errors_and_nees(data, result, marginal)
plt.show()
nees = starship.normalised_estimation_error_squared(data.truth, result)
lower, upper = starship.nees_band()
std = starship.marginal_std(result, marginal)
inside = np.abs(data.truth - result.mu) <= 3 * std
print(f"NEES: mean {nees.mean():.2f}, inside [{lower:.2f}, {upper:.2f}] at {np.mean((nees >= lower) & (nees <= upper)):.1%} of the steps")
print("errors inside their 3-sigma bands: " + ", ".join(f"{name} {frac:.1%}" for name, frac in zip(starship.STATE_NAMES, inside.mean(axis=0))))

# %% [markdown]
# **Many falls.** One fall is one draw of the initial error and of the noise, and neighbouring steps of
# one fall are strongly correlated. The cell below filters 40 simulated falls, shipped with the lab
# (`course/data/starship_falls.npz`), each simulated like the fall of part 1 but from its own seed. Each starts
# from the same true state, $\mathbf{x}_0 = [15\,000\ \text{m},\ -500\ \text{m/s},\ 0.001\ \text{m}^2/\text{kg}]$, and its filter
# from its own initial mean, $\boldsymbol{\mu}_0 = \mathbf{x}_0 - \mathbf{S}_0^\mathsf{T}\mathbf{e}$ with $\mathbf{e} \sim \mathcal{N}(\mathbf{0}, \mathbf{I})$,
# so that the initial error is a draw from $\mathcal{N}(\mathbf{0}, \mathbf{P}_0)$, as the filter assumes. The NEES averaged
# over $F$ independent falls at one step is, for a consistent filter, $\chi^2(3F)/F$: for $F = 40$ it lies in
# $[2.29,\ 3.81]$ 95% of the time, a band much narrower than a single run's.
#
# Expect a spike at $t = 0$, about 10 in these 40 falls: the first range update is linearised across the prior's wide
# altitude (Section 12 shows how). <!-- claim: reentry-srekf/first-update-nees-spike -->
# The question below is about the rest of the fall. The cell takes a few seconds: it runs your filter 40 times,
# once per fall.

# %% nbgrader={"grade": false, "grade_id": "monte_carlo_nees", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(ballistic_dynamics, ballistic_jacobian, radar_predict, radar_jacobian, conditional, sqrt_time_update,
        sqrt_measurement_update)
falls = starship.filter_falls(starship.load_falls(), ballistic_dynamics, ballistic_jacobian, radar_predict,
                              radar_jacobian, sqrt_time_update, sqrt_measurement_update)
fig, ax = starship.plot_average_nees(falls)
plt.show()
average = falls.nees.mean(axis=0)
lower, upper = starship.average_nees_band(falls.nees.shape[0])
for start, stop in ((0, 5), (5, 10), (10, 20), (20, 30), (30, 40), (40, 50)):
    window = (falls.t >= start) & (falls.t < stop)
    inside = np.mean((average[window] >= lower) & (average[window] <= upper))
    print(f"t in [{start:2d}, {stop:2d}) s: average NEES {average[window].mean():.2f}, inside its band at {inside:.0%} of the steps")
single_lower, single_upper = starship.nees_band()
held = (falls.nees >= single_lower) & (falls.nees <= single_upper)
print(f"pooled over all falls and steps: {np.mean(held):.1%} of the NEES values inside the single-step band "
      f"[{single_lower:.2f}, {single_upper:.2f}] ({np.mean(held[:, falls.t < 20]):.1%} before 20 s, "
      f"{np.mean(held[:, falls.t >= 20]):.1%} from 20 s on)")

# %% [markdown]
# **Question 9 (0.5 points).** Are the errors of the shipped fall inside their bands, and is its NEES
# what a $\chi^2(3)$ variable would give? Is one fall enough to call the filter consistent? Then read the
# averaged NEES of the 40 falls: is the filter consistent, and if not, when, and is it over- or
# underconfident? Why does a score averaged over all steps hide this?

# %% [markdown] nbgrader={"grade": true, "grade_id": "errors_nees_answer", "locked": false, "points": 0.5, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** On the shipped fall every error stays inside its $\pm 3\sigma$ band at every step, <!-- claim: reentry-srekf/shipped-coverage -->
# and the NEES is inside its 95% band at about 96% of the steps, with a mean of
# about 3.3. <!-- claim: reentry-srekf/shipped-nees --> That looks consistent, but one fall is weak evidence: the error changes
# slowly, so neighbouring steps are strongly correlated, and the fall is a single draw of the initial error
# and the noise. The averaged NEES of the 40 falls is the proper test, and the filter fails it. In
# these 40 falls the average is above its band $[2.29,\ 3.81]$ at every step of the first 10 s; it is 7.3 on
# average from 5 to 10 s, and 4.4 from 10 to 20 s, where it is above the band at about two steps in three.
# Is that the filter, or only these 40 falls? Nine other sets of 40 falls, simulated in the same way from other
# seeds (500 to 539, and 1000 to 1039, 2000 to 2039, and so on up to 8000 to 8039), say it is the filter: in every
# set the average was above its band at every step from 5 to 10 s, and in eight sets of nine it was above the band
# on average from 10 to 20 s. How far above changes a lot from set to set, from 5.3 to 48 on average over 5 to 10 s
# and from 3.3 to 14 over 10 to 20 s, because a single fall with a large early error can lift an average of 40 a
# long way; and over the first 5 s the average was above its band at anything from a quarter to all of the steps,
# depending on the set. <!-- claim: reentry-srekf/average-nees-overconfident-early --> In these 40 falls the average then stays
# between 2.7 and 3.7 from 20 s on, inside its band at every step. Other sets of 40 differ here: over the nine
# other sets the average from 20 to 30 s ranged from 2.3 to 6.0. <!-- claim: reentry-srekf/average-nees-consistent-late -->
# Forty falls are too few to tell an average of 3.4 from 3, so the late part needs many more falls. Over 2000 fresh
# falls the averaged NEES, window by window, is well above 3 up to 20 s, about 3.7 from 20 to 30 s, 3.3 to 3.4 from
# 30 to 40 s and 3.1 from 40 to 50 s (a tenth or two from one batch of 2000 falls to another). <!-- claim: reentry-srekf/average-nees-many-falls -->
# (The spike at $t = 0$, about 10 in these falls, is the first range update, linearised across the prior's
# wide altitude, as the text says.) <!-- claim: reentry-srekf/first-update-nees-spike --> So the filter is inconsistent: overconfident
# (its covariance too small for its errors): strongly during its first 20 s or so, while it is learning $c$ and $v$,
# most likely because the EKF linearises the drag at a poorly known state; mildly up to 30 or 40 s; and it is close to
# consistent only from about 40 s on. <!-- claim: reentry-srekf/average-nees-many-falls --> A score that pools all steps of all falls hides
# this, because the long consistent part dilutes the early part: in these 40 falls 91% of the single NEES values
# lie inside the single-step band $[0.22,\ 9.35]$, not far from the 95% of a consistent filter, though the share is
# 85% before 20 s and 96% after. The other sets tell the same story: pooled, 86 to 94%, always short of 95% and
# always lower before 20 s than after. <!-- claim: reentry-srekf/pooled-nees-hides-it --> In about
# three falls in five, all three errors stay inside their $\pm 3\sigma$ bands throughout. <!-- claim: reentry-srekf/coverage-over-falls -->
#
# **Rubric (0.5 points).** 0.25 for reading the figures: the shipped fall's errors inside their bands and
# its NEES mostly inside its band with a mean near 3, and, in these 40 falls, the averaged NEES above its band
# through the first 10 s and at most steps of the next 10, and inside it from 20 s on (overconfident early,
# consistent later); 0.25 for the limits of
# one run (correlated steps, one draw) together with either of two arguments: why the average over falls at each
# step, against the narrow band $\chi^2(3F)/F$, is the right test where an average over time dilutes an
# inconsistency confined to part of the fall; or a sound reason for the early overconfidence, such as the
# linearisation while $c$ and $v$ are poorly known. Either argument with the limits of one run earns the full 0.25;
# neither the many-fall averages nor the split before and after 20 s is expected.
# ### END SOLUTION

# %% [markdown]
# ## 10. Where the radar loses sight of the altitude
#
# The range tells the filter about the altitude only through $H_h = \partial h_\text{rng}/\partial h = (h - r_2)/h_\text{rng}$.
# Look again at the altitude panel of the figure of part 9, and at its dotted line.

# %% [markdown]
# **Question 10 (0.5 points).** From the figure, at what time is the altitude's band widest after the
# first seconds, and where is the vehicle then? Why does the band widen there, and why does it reach its
# widest a few seconds *after* the dotted line rather than at it?

# %% [markdown] nbgrader={"grade": true, "grade_id": "observability_answer", "locked": false, "points": 0.5, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** The vehicle passes the radar's altitude, $h = r_2 = 5000$ m, at $t \approx 33.9$ s (the
# dotted line). There $H_h = 0$: moving the vehicle a little up or down does not change the range, so a
# range carries no information about the altitude (and the same range fits $r_2 + \Delta$ and
# $r_2 - \Delta$). The filter can only carry $h$ forward with the model, and $\sigma_h$ grows, from about
# 20 m at $t = 30$ s to its largest, about 29 m, at $t \approx 38.4$ s, some 4.5 s after the crossing. The lag
# belongs to the filter, not to this fall: in the 40 falls of part 9 it is 4.1 to 4.9 s, and over nine other sets
# of 40 falls 3.6 to 5.0 s, and 4 to 5 s in nearly all falls. <!-- claim: reentry-srekf/sigma-h-peak-after-crossing --> The peak
# comes late because near the crossing $H_h$ is small, not only at it: the information each range adds
# grows like $H_h^2$, and only once the vehicle is some way below the radar does it again outweigh the
# uncertainty that the velocity keeps feeding into the altitude. Strictly, the range loses the altitude
# only to first order: near the crossing it is about $r_1 + \Delta^2/(2 r_1)$ with $\Delta = h - r_2$, so a
# range with 50 m noise resolves $|\Delta|$ only to about $\sqrt{2 r_1 \sigma_\text{rng}} \approx 700$ m, far coarser
# than the filter's $\sigma_h$ of 20 to 30 m there: in practice, no information. Over a window of ranges
# the system stays observable (the ranges before and after the crossing, tied together by the model, fix
# $h$ and $v$), which is why $\sigma_h$ stays bounded instead of growing without limit.
#
# **Rubric (0.5 points).** 0.25 for the time (about 38 s, within a second or two) and the place (just
# below the radar's altitude, after passing $h = r_2$ at about 34 s); 0.25 for the reason ($\partial h_\text{rng}/\partial h = 0$
# at $h = r_2$: no altitude information, so the prediction's growth wins until $|H_h|$ is large again;
# the second-order information and the observability over a window are not required).
# ### END SOLUTION

# %% [markdown]
# ## 11. A physically impossible estimate
#
# A ballistic coefficient cannot be negative: negative drag would pull the falling vehicle down faster.
# Yet the prior, $c \sim \mathcal{N}(0.0005,\ 0.001^2)$ m²/kg, puts about a third of its mass below zero,
# $\Phi(-0.5) \approx 0.31$. <!-- claim: reentry-srekf/prior-mass-below-zero --> On this fall the estimate itself goes there:
# around $t = 3$ s it is negative at six of the steps between $t = 2.6$ s and $3.4$ s, down to about
# $-2.2 \times 10^{-4}$ m²/kg. <!-- claim: reentry-srekf/c-estimate-negative --> The cell below prints where.

# %% nbgrader={"grade": false, "grade_id": "negative_c", "locked": true, "schema_version": 3, "solution": false, "task": false}
require(ballistic_dynamics, ballistic_jacobian, radar_predict, radar_jacobian, conditional, sqrt_time_update,
        sqrt_measurement_update)
negative = result.mu[:, 2] < 0
print(f"prior mass below zero: {norm.cdf(0.0, starship.MU0[2], starship.S0[2, 2]):.3f}")
if negative.any():
    print(f"c estimate negative at {negative.sum()} steps, from t = {result.t[negative][0]:.1f} s to "
          f"t = {result.t[negative][-1]:.1f} s; lowest {result.mu[:, 2].min():.3g} m^2/kg")
else:
    print("c estimate never negative")

# %% [markdown]
# **Question 11 (0.5 points).** Why can the EKF's estimate of $c$ become negative? Suppose the state held
# $\theta = \log c$ instead of $c$. What would change in $\mathbf{f}$, its Jacobian, the prior and the process
# noise, what would it gain, and what would it cost? (Answer in words: do not change the filter, whose
# numbers the handout prints.)

# %% [markdown] nbgrader={"grade": true, "grade_id": "negative_c_answer", "locked": false, "points": 0.5, "schema_version": 3, "solution": true, "task": false}
# ### BEGIN SOLUTION
# **Model answer.** The EKF's belief is Gaussian, and a Gaussian puts mass on the whole real line; the
# update moves the mean linearly with the residual, so a large early residual, acting through a broad
# prior, can carry the mean below zero, and nothing in the filter forbids it. Here the route is the
# correlation of $v$ and $c$: the first ranges fix how fast the vehicle falls, which a faster fall with
# less drag explains as well as a slower one with more, so the estimates of $v$ and $c$ become strongly
# correlated (about 0.78 at $t = 2$ s and 0.94 at $t = 3$ s on this fall), and correcting the velocity
# (the prior says $-450$ m/s, the truth is $-500$ m/s) pulls $c$ down with it. It is not only that initial
# error: started from the true $v_0$, or the true $h_0$ and $v_0$, the estimate still goes negative for a
# step or two. <!-- claim: reentry-srekf/c-negative-velocity-correlation --> Over the 40 simulated falls of part 9 it goes negative in
# about a quarter to a third of them. <!-- claim: reentry-srekf/c-negative-over-falls --> With $\theta = \log c$,
# $c = e^\theta > 0$ for every $\theta$. The drag becomes $d = \tfrac12 \rho v^2 e^\theta$, the Jacobian's entry
# $\partial f_2/\partial\theta = d$ replaces $\tfrac12\rho v^2$, and the other entries keep their form with
# $c = e^\theta$. The prior becomes a Gaussian in $\theta$, a log-normal in $c$ (for example with median
# 0.0005 and a spread of a factor of a few), and the process noise on $\theta$ becomes a *relative* drift of
# $c$. Gains: no impossible estimates, and a prior that can be broad without putting mass on $c < 0$.
# Costs: the model is more nonlinear in the new state, so the linearisation errors grow while
# $\theta$ is uncertain; the mean of $c$ is no longer $e^{\mu_\theta}$ but $e^{\mu_\theta + \sigma_\theta^2/2}$; and the
# prior and $\mathbf{Q}$ must be chosen anew, so the filter's numbers change.
#
# **Rubric (0.5 points).** 0.25 for the reason (a Gaussian belief and a linear update know nothing of
# the constraint, or the strong $v$–$c$ correlation through which the early velocity correction moves $c$); 0.25 for the log model with at least two of: $\partial f_2/\partial\theta = d$, a log-normal
# prior in $c$, relative process noise, and a cost (more nonlinearity, a biased $e^{\mu_\theta}$, re-chosen
# prior and noise).
# ### END SOLUTION

# %% [markdown]
# ## 12. Going further
#
# Nothing in this section is graded. It holds the notes behind the main text: where the model's atmosphere holds,
# why the RK4 step is given, how fast the filter learns $v$ and $c$, where the spike of the averaged NEES at $t = 0$
# comes from, why each simulated fall has its own initial mean, and a few experiments to try. Its claims are checked
# like all the others.

# %% [markdown]
# ### Where this atmosphere holds
#
# A temperature that falls linearly with altitude (8) describes the
# troposphere, up to about 11 km. Above that, in the lower stratosphere, the standard atmosphere's
# temperature stops falling and stays at 216.65 K up to 20 km, so the pressure falls faster than (9)
# says. Our vehicle starts at 15 km and spends the first 9.5 s of its fall above 11 km. <!-- claim: reentry-srekf/above-11-km-first-9-s -->
# There the model's air is too dense: by about 3% at 12 km and 9% at 15 km, compared with the standard
# atmosphere. <!-- claim: reentry-srekf/atmosphere-density-error --> Our simulated truth uses the same model, so the filter cannot
# notice. With real air it would: the ranges tell the filter the drag $d$, which is proportional to
# $\rho c$, so a density 9% too high would make the estimate of $c$ about 8% too low at the start of the
# fall, and the slow drift that $\mathbf{Q}$ allows $c$ would have to absorb the difference on the way down.

# %% [markdown]
# ### Why the RK4 step stays given
#
# The handout's lab code comes with the time step ready-made, and its text does not describe the discretisation.
# Ours puts the increment $\mathbf{w}$ into every RK4 stage and differentiates the whole step by the chain rule.
# With it the filter reproduces the numbers the handout prints, which another discretisation would change. Writing
# that Jacobian is an exercise in the chain rule, not in square roots, so `starship.rk4_step_with_jacobian` does it
# for you.

# %% [markdown]
# ### How fast the filter learns $v$ and $c$
#
# In the figure of part 7, the velocity comes first: its standard deviation falls from 100 m/s to about 20 m/s in
# the first 5 s. The drag coefficient takes longer, until the drag has bent the trajectory measurably: its standard
# deviation drops below 10% of $c$ at about $t = 8$ s and ends near 2% of $c$, and its band keeps the slowly drifting
# truth inside. <!-- claim: reentry-srekf/c-converges -->

# %% [markdown]
# ### The spike of the averaged NEES at $t = 0$
#
# The spike in the figure of part 9, about 10, rests on a few of the 40 falls. The first range update takes the
# range's slope at the prior mean, whose altitude is off the truth by about 2200 m in root-mean-square (the prior's
# standard deviation of $h$). The range is curved enough there to put the
# altitude too high by tens to hundreds of metres, against a posterior $\sigma_h$ of about 56 m. So about one first update in seven has a NEES above 9.35, where a consistent update has one in 40,
# while from $\sigma_h = 1000$ m down the rate is within about half a point of consistent. <!-- claim: reentry-srekf/first-update-nees-spike -->

# %% [markdown]
# ### Why each fall has its own initial mean
#
# In part 9 each fall's filter starts from its own initial mean, a draw around the true state. Starting every fall
# from the same $\boldsymbol{\mu}_0$ would give every fall the same initial error, and test the filter on that one
# error only.

# %% [markdown]
# ### To explore
#
# - Forty falls are still a sample: a feature of the averaged NEES may belong to these falls rather than to the
#   filter. To tell which, filter another set of 40, made by
#   `starship.simulate_falls(range(1000, 1040), ballistic_dynamics, radar_predict)`, and compare.
# - Try a worse initial guess, such as `mu0=np.array([14000.0, -450.0, 0.003])` in
#   `starship.run_square_root_ekf`, and watch how long the filter takes to recover.
