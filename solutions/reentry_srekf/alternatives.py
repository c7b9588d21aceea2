"""Correct answers to the reentry-srekf blanks that differ from the model answer, written from the release
notebook's text the way students write them: each must keep full marks on every submission seed."""

from autograder.catalogues.alternatives import Alternative

ALTERNATIVES = (
    # ballistic_dynamics
    Alternative("ballistic_dynamics", "equation-10", "the drag written out as equation (10) in one expression",
                '''def ballistic_dynamics(x):
    """Mean dynamics f(x), shape (3,), of x = [h (m), v (m/s), c (m^2/kg)]."""
    h, v, c = x
    d = 0.5 * (M * P0 / R) * (1 / (T0 - L * h)) * (1 - L * h / T0) ** (G * M / (R * L)) * v**2 * c
    return np.array([v, d - G, 0.0])
'''),
    Alternative("ballistic_dynamics", "exp-log", "the pressure as exp((gM/(RL)) log1p(-Lh/T0)), the state read with float()",
                '''def ballistic_dynamics(x):
    """Mean dynamics f(x), shape (3,), of x = [h (m), v (m/s), c (m^2/kg)]."""
    h, v, c = float(x[0]), float(x[1]), float(x[2])
    T = T0 - L * h
    p = P0 * np.exp(G * M / (R * L) * np.log1p(-L * h / T0))
    rho = p * M / (R * T)
    return np.array([v, rho * v * v * c / 2 - G, 0])
'''),
    Alternative("ballistic_dynamics", "math-module", "scalar arithmetic with the math module, the result filled into np.zeros(3)",
                '''def ballistic_dynamics(x):
    """Mean dynamics f(x), shape (3,), of x = [h (m), v (m/s), c (m^2/kg)]."""
    import math

    h, v, c = (float(value) for value in x)
    exponent = G * M / (R * L)
    rho = P0 * math.pow(1 - L * h / T0, exponent) * M / (R * (T0 - L * h))
    f = np.zeros(3)
    f[0] = v
    f[1] = 0.5 * rho * v**2 * c - G
    return f
'''),
    # ballistic_jacobian
    Alternative("ballistic_jacobian", "via-density", "dd/dh through d rho/dh = rho (L - gM/R) / T, the hydrostatic form of (9)",
                '''def ballistic_jacobian(x):
    """Jacobian df/dx of the ballistic dynamics, shape (3, 3)."""
    h, v, c = x
    T = T0 - L * h
    rho = P0 * (1 - L * h / T0) ** (G * M / (R * L)) * M / (R * T)
    drho_dh = rho * (L - G * M / R) / T
    J = np.zeros((3, 3))
    J[0, 1] = 1.0
    J[1, 0] = 0.5 * v**2 * c * drho_dh
    J[1, 1] = rho * v * c
    J[1, 2] = 0.5 * rho * v**2
    return J
'''),
    Alternative("ballistic_jacobian", "calls-dynamics", "the drag taken from the student's own ballistic_dynamics, d = f2 + g, so dd/dv = 2 d / v",
                '''def ballistic_jacobian(x):
    """Jacobian df/dx of the ballistic dynamics, shape (3, 3)."""
    h, v, c = x
    d = ballistic_dynamics(x)[1] + G
    T = T0 - L * h
    k = G * M / (R * L)
    rho = P0 * (1 - L * h / T0) ** k * M / (R * T)
    return np.array([[0.0, 1.0, 0.0],
                     [-L * (k - 1) * d / T, 2 * d / v, rho * v**2 / 2],
                     [0.0, 0.0, 0.0]])
'''),
    Alternative("ballistic_jacobian", "rows-stacked", "the Jacobian stacked from three row vectors with np.vstack",
                '''def ballistic_jacobian(x):
    """Jacobian df/dx of the ballistic dynamics, shape (3, 3)."""
    h, v, c = np.asarray(x, dtype=float)
    n = G * M / (R * L)
    T = T0 - L * h
    rho = (M * P0 / R) / T * (1 - L * h / T0) ** n
    d = rho * v**2 * c / 2
    row_h = np.array([0.0, 1.0, 0.0])
    row_v = np.array([d * L * (1 - n) / T, rho * v * c, rho * v**2 / 2])
    return np.vstack([row_h, row_v, np.zeros(3)])
'''),
    # radar_predict
    Alternative("radar_predict", "sqrt", "np.sqrt of the sum of squares, with np.atleast_1d",
                '''def radar_predict(x):
    """Predicted range (m) from the radar to the vehicle, shape (1,)."""
    h = x[0]
    return np.atleast_1d(np.sqrt(RADAR_R1**2 + (h - RADAR_R2) ** 2))
'''),
    Alternative("radar_predict", "norm", "np.linalg.norm of the offset vector",
                '''def radar_predict(x):
    """Predicted range (m) from the radar to the vehicle, shape (1,)."""
    offset = np.array([RADAR_R1, x[0] - RADAR_R2])
    return np.array([np.linalg.norm(offset)])
'''),
    Alternative("radar_predict", "math-hypot", "math.hypot on floats, reshaped to (1,)",
                '''def radar_predict(x):
    """Predicted range (m) from the radar to the vehicle, shape (1,)."""
    import math

    return np.reshape(math.hypot(float(x[0]) - RADAR_R2, RADAR_R1), (1,))
'''),
    # radar_jacobian
    Alternative("radar_jacobian", "calls-predict", "the range from the student's radar_predict, the row filled into np.zeros((1, 3))",
                '''def radar_jacobian(x):
    """Jacobian of the range with respect to x = [h, v, c], shape (1, 3)."""
    H = np.zeros((1, 3))
    H[0, 0] = (x[0] - RADAR_R2) / radar_predict(x)[0]
    return H
'''),
    Alternative("radar_jacobian", "sqrt-reshape", "np.sqrt for the range, a flat row reshaped to (1, 3)",
                '''def radar_jacobian(x):
    """Jacobian of the range with respect to x = [h, v, c], shape (1, 3)."""
    dh = x[0] - RADAR_R2
    rng_ = np.sqrt(RADAR_R1**2 + dh**2)
    return np.array([dh / rng_, 0, 0]).reshape(1, 3)
'''),
    Alternative("radar_jacobian", "chain-rule", "the derivative of sqrt(u) by the chain rule, 0.5 u^-1/2 du/dh",
                '''def radar_jacobian(x):
    """Jacobian of the range with respect to x = [h, v, c], shape (1, 3)."""
    h = float(x[0])
    u = RADAR_R1**2 + (h - RADAR_R2) ** 2
    return np.array([[0.5 * u**-0.5 * 2 * (h - RADAR_R2), 0.0, 0.0]])
'''),
    # marginal
    Alternative("marginal", "reduced-qr", "Q and R from np.linalg.qr's reduced mode, Q unused",
                '''def marginal(mu, S, idx):
    """Marginal of the entries idx: mu (n,), S (n, n) -> mu_I (n_I,), upper-triangular S_I (n_I, n_I)."""
    mu, S, idx = np.asarray(mu), np.asarray(S), np.asarray(idx)
    Q, R_ = np.linalg.qr(S[:, idx])
    return mu[idx], R_
'''),
    Alternative("marginal", "positive-diagonal", "scipy's economic QR, its rows signed so that the diagonal is positive",
                '''def marginal(mu, S, idx):
    """Marginal of the entries idx: mu (n,), S (n, n) -> mu_I (n_I,), upper-triangular S_I (n_I, n_I)."""
    import scipy.linalg

    idx = list(idx)
    _, S_I = scipy.linalg.qr(np.asarray(S)[:, idx], mode="economic")
    signs = np.where(np.diag(S_I) < 0, -1.0, 1.0)
    return np.asarray(mu)[idx], signs[:, None] * S_I
'''),
    Alternative("marginal", "cholesky", "the marginal covariance S_I^T S_I formed and factorised by Cholesky",
                '''def marginal(mu, S, idx):
    """Marginal of the entries idx: mu (n,), S (n, n) -> mu_I (n_I,), upper-triangular S_I (n_I, n_I)."""
    S_cols = np.asarray(S)[:, idx]
    P_I = S_cols.T @ S_cols
    return np.asarray(mu)[idx], np.linalg.cholesky(P_I).T
'''),
    # conditional
    Alternative("conditional", "lower-solve", "R1^-T applied as a lower-triangular solve with R1.T",
                '''def conditional(mu, S, idx_a, idx_b, x_b):
    """p(x[idx_a] | x[idx_b] = x_b): mu (n,), S (n, n) -> mu_c (n_A,), upper-triangular S_c (n_A, n_A)."""
    mu, S = np.asarray(mu, dtype=float), np.asarray(S, dtype=float)
    idx_a, idx_b = np.asarray(idx_a), np.asarray(idx_b)
    nb = len(idx_b)
    R_ = np.linalg.qr(np.hstack([S[:, idx_b], S[:, idx_a]]), mode="r")
    R1, R2, R3 = R_[:nb, :nb], R_[:nb, nb:], R_[nb:, nb:]
    z = solve_triangular(R1.T, np.asarray(x_b) - mu[idx_b], lower=True)
    return mu[idx_a] + R2.T @ z, R3
'''),
    Alternative("conditional", "inverse", "R1^-T as np.linalg.inv(R1).T (an inverse the text advises against, but correct)",
                '''def conditional(mu, S, idx_a, idx_b, x_b):
    """p(x[idx_a] | x[idx_b] = x_b): mu (n,), S (n, n) -> mu_c (n_A,), upper-triangular S_c (n_A, n_A)."""
    mu, S = np.asarray(mu, dtype=float), np.asarray(S, dtype=float)
    k = len(idx_b)
    _, Rfull = np.linalg.qr(np.concatenate([S[:, idx_b], S[:, idx_a]], axis=1))
    R1, R2, R3 = Rfull[:k, :k], Rfull[:k, k:], Rfull[k:, k:]
    mu_c = mu[idx_a] + R2.T @ np.linalg.inv(R1).T @ (np.asarray(x_b) - mu[idx_b])
    return mu_c, R3
'''),
    Alternative("conditional", "positive-diagonal-solve", "the QR's rows signed to a positive diagonal, and a general np.linalg.solve with R1.T",
                '''def conditional(mu, S, idx_a, idx_b, x_b):
    """p(x[idx_a] | x[idx_b] = x_b): mu (n,), S (n, n) -> mu_c (n_A,), upper-triangular S_c (n_A, n_A)."""
    mu, S = np.asarray(mu, dtype=float), np.asarray(S, dtype=float)
    idx_a, idx_b = list(idx_a), list(idx_b)
    R_ = np.linalg.qr(S[:, idx_b + idx_a], mode="r")
    R_ = np.sign(np.diag(R_))[:, None] * R_
    nb = len(idx_b)
    R1, R2, R3 = R_[:nb, :nb], R_[:nb, nb:], R_[nb:, nb:]
    mu_c = mu[idx_a] + R2.T @ np.linalg.solve(R1.T, np.asarray(x_b, dtype=float) - mu[idx_b])
    return mu_c, R3
'''),
    # sqrt_time_update
    Alternative("sqrt_time_update", "stacked-blocks", "[S J_x^T; S_Q J_w^T] stacked from J's two blocks instead of blkdiag(S, S_Q) J^T",
                '''def sqrt_time_update(mu, S, f_and_jacobian, S_Q):
    """Predict through a linearised step: mu (n,), S (n, n), S_Q (q, q) -> mu_next (n,), upper-triangular S_next (n, n)."""
    mu_next, J = f_and_jacobian(mu)
    n = len(mu)
    A = np.vstack([S @ J[:, :n].T, S_Q @ J[:, n:].T])
    return mu_next, np.linalg.qr(A, mode="r")
'''),
    Alternative("sqrt_time_update", "positive-diagonal", "scipy's economic QR with its rows signed to a positive diagonal",
                '''def sqrt_time_update(mu, S, f_and_jacobian, S_Q):
    """Predict through a linearised step: mu (n,), S (n, n), S_Q (q, q) -> mu_next (n,), upper-triangular S_next (n, n)."""
    import scipy.linalg

    mu_next, J = f_and_jacobian(np.asarray(mu, dtype=float))
    S_z = block_diag(S, S_Q)
    _, R_ = scipy.linalg.qr(S_z @ J.T, mode="economic")
    d = np.sign(np.diag(R_))
    d[d == 0] = 1.0
    return np.asarray(mu_next), d[:, None] * R_
'''),
    Alternative("sqrt_time_update", "transposed-product", "(J S_z^T)^T for the pre-array, Q and R from the reduced QR",
                '''def sqrt_time_update(mu, S, f_and_jacobian, S_Q):
    """Predict through a linearised step: mu (n,), S (n, n), S_Q (q, q) -> mu_next (n,), upper-triangular S_next (n, n)."""
    mu_next, J = f_and_jacobian(mu)
    pre = (J @ block_diag(S, S_Q).T).T
    Q, S_next = np.linalg.qr(pre)
    return mu_next, S_next
'''),
    # sqrt_measurement_update
    Alternative("sqrt_measurement_update", "inline-conditional", "the conditional of the tail on the head written out from the joint R factor, without calling conditional",
                '''def sqrt_measurement_update(mu, S, y, h_and_jacobian, S_R):
    """Condition on y: mu (n,), S (n, n), y (m,), S_R (m, m) -> mu_next (n,), upper-triangular S_next (n, n)."""
    y = np.atleast_1d(np.asarray(y, dtype=float))
    m, n = y.size, len(mu)
    y_hat, H = h_and_jacobian(mu)
    A = np.block([[S @ H.T, S], [S_R, np.zeros((m, n))]])
    R_ = np.linalg.qr(A, mode="r")
    R1, R2, R3 = R_[:m, :m], R_[:m, m:], R_[m:, m:]
    mu_next = mu + R2.T @ solve_triangular(R1, y - y_hat, trans="T")
    return mu_next, R3
'''),
    Alternative("sqrt_measurement_update", "stacked-arrays", "the pre-array built with vstack and hstack, conditional called with lists of indices",
                '''def sqrt_measurement_update(mu, S, y, h_and_jacobian, S_R):
    """Condition on y: mu (n,), S (n, n), y (m,), S_R (m, m) -> mu_next (n,), upper-triangular S_next (n, n)."""
    mu = np.asarray(mu, dtype=float)
    y = np.reshape(y, -1)
    m, n = len(y), len(mu)
    h_mu, H = h_and_jacobian(mu)
    top = np.hstack([S @ H.T, S])
    bottom = np.hstack([S_R, np.zeros((m, n))])
    _, R_joint = np.linalg.qr(np.vstack([top, bottom]))
    mean_joint = np.concatenate([np.reshape(h_mu, -1), mu])
    return conditional(mean_joint, R_joint, list(range(m, m + n)), list(range(m)), y)
'''),
    Alternative("sqrt_measurement_update", "positive-diagonal", "the joint R factor's rows signed to a positive diagonal (scipy's QR) before conditioning",
                '''def sqrt_measurement_update(mu, S, y, h_and_jacobian, S_R):
    """Condition on y: mu (n,), S (n, n), y (m,), S_R (m, m) -> mu_next (n,), upper-triangular S_next (n, n)."""
    import scipy.linalg

    mu, S, S_R = np.asarray(mu, float), np.asarray(S, float), np.atleast_2d(S_R)
    y = np.atleast_1d(y).astype(float)
    m, n = len(y), len(mu)
    h_mu, H = h_and_jacobian(mu)
    R_ = scipy.linalg.qr(np.block([[S @ H.T, S], [S_R, np.zeros((m, n))]]), mode="r")[0]
    R_ = R_[: m + n]
    R_ = np.where(np.diag(R_)[:, None] < 0, -R_, R_)
    return conditional(np.r_[h_mu, mu], R_, np.arange(m, m + n), np.arange(m), y)
'''),
    # plot_ballistic_coefficient
    Alternative("plot_ballistic_coefficient", "words", "'Time (seconds)' and 'c (m²/kg)', the band drawn last, the legend placed by matplotlib",
                '''def plot_ballistic_coefficient(ax, t, c_true, c_mean, c_std):
    """Draw truth, estimate and 99.7% region of c (m^2/kg) against t (s) on ax; return ax."""
    ax.plot(t, c_true, "k-", label="true c")
    ax.plot(t, c_mean, "b--", label="estimated c")
    ax.fill_between(t, c_mean - 3 * c_std, c_mean + 3 * c_std, alpha=0.3, label="mean ± 3 std")
    ax.set_xlabel("Time (seconds)")
    ax.set_ylabel("c (m²/kg)")
    ax.set_title("Ballistic drag coefficient")
    ax.legend()
    return ax
'''),
    Alternative("plot_ballistic_coefficient", "iso", "ISO labels, 'time $t$ / s' and '$c$ / m$^2$ kg$^{-1}$', with LaTeX in the legend",
                '''def plot_ballistic_coefficient(ax, t, c_true, c_mean, c_std):
    """Draw truth, estimate and 99.7% region of c (m^2/kg) against t (s) on ax; return ax."""
    lower = c_mean - 3 * c_std
    upper = c_mean + 3 * c_std
    ax.fill_between(t, lower, upper, color="tab:orange", alpha=0.2, label=r"$\\mu_c \\pm 3\\sigma_c$")
    ax.plot(t, c_true, label="$c$ (truth)")
    ax.plot(t, c_mean, label=r"$\\mu_c$ (estimate)")
    ax.set(xlabel="time $t$ / s", ylabel="$c$ / m$^2$ kg$^{-1}$", title="$c$ against time")
    ax.legend(loc="best")
    return ax
'''),
    Alternative("plot_ballistic_coefficient", "legend-handles", "unlabelled artists named by ax.legend(handles, labels), "
                "'t, sec' and 'c in m$^2$/kg' (fairness review: lost its points through grade)",
                '''def plot_ballistic_coefficient(ax, t, c_true, c_mean, c_std):
    """Draw truth, estimate and 99.7% region of c (m^2/kg) against t (s) on ax; return ax."""
    truth, = ax.plot(t, c_true, "k")
    estimate, = ax.plot(t, c_mean, "C0--")
    band = ax.fill_between(t, c_mean + 3 * c_std, c_mean - 3 * c_std, color="C0", alpha=0.2)
    ax.set_xlabel("t, sec")
    ax.set_ylabel("c in m$^2$/kg")
    ax.set_title("Ballistic coefficient")
    ax.legend([truth, estimate, band], ["truth", "estimate", "99.7% region"])
    return ax
'''),
    Alternative("plot_ballistic_coefficient", "brackets-in", "'t in s' and 'ballistic coefficient [m^2/kg]', arrays converted first, a grid",
                '''def plot_ballistic_coefficient(ax, t, c_true, c_mean, c_std):
    """Draw truth, estimate and 99.7% region of c (m^2/kg) against t (s) on ax; return ax."""
    t, c_true, c_mean, c_std = map(np.asarray, (t, c_true, c_mean, c_std))
    ax.plot(t, c_mean, color="red", label="EKF estimate")
    ax.plot(t, c_true, color="black", linestyle=":", label="Truth")
    ax.fill_between(t, c_mean + 3 * c_std, c_mean - 3 * c_std, color="red", alpha=0.15, label="99.7% confidence region")
    ax.set_xlabel("t in s")
    ax.set_ylabel("ballistic coefficient [m^2/kg]")
    ax.set_title("Ballistic coefficient estimate")
    ax.grid()
    ax.legend(loc="lower right")
    return ax
'''),
)
