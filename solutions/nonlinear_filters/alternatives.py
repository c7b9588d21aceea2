"""Correct answers to the nonlinear-filters blanks that differ from the model answers the way students' answers
do, written from the release notebook's text: each must keep full marks (tests/test_alternatives.py)."""

from autograder.catalogues.alternatives import Alternative

ALTERNATIVES = (
    Alternative("cubature_points", "interleaved", "a loop that puts +sqrt(n) e_i and -sqrt(n) e_i next to each other",
                '''def cubature_points(n):
    points = []
    for i in range(n):
        e = np.zeros(n)
        e[i] = np.sqrt(n)
        points.append(e)
        points.append(-e)
    return np.array(points), np.ones(2 * n) / (2 * n)
'''),
    Alternative("cubature_points", "negative-first", "the points on the negative axes first",
                '''def cubature_points(n):
    Z = np.concatenate((-np.sqrt(n) * np.eye(n), np.sqrt(n) * np.eye(n)))
    w = np.full(2 * n, 0.5 / n)
    return Z, w
'''),
    Alternative("cubature_points", "list", "returns a list [Z, w]",
                '''def cubature_points(n):
    r = n**0.5
    return [np.vstack([r * np.identity(n), -r * np.identity(n)]), np.repeat(1 / (2 * n), 2 * n)]
'''),
    Alternative("unscented_points", "interleaved", "a loop over the axes, the centre first",
                '''def unscented_points(n, kappa=1.0):
    points, weights = [np.zeros(n)], [kappa / (n + kappa)]
    for i in range(n):
        for sign in (1.0, -1.0):
            z = np.zeros(n)
            z[i] = sign * np.sqrt(n + kappa)
            points.append(z)
            weights.append(1 / (2 * (n + kappa)))
    return np.array(points), np.array(weights)
'''),
    Alternative("unscented_points", "centre-last", "the centre point last, the weights filled then set",
                '''def unscented_points(n, kappa=1.0):
    scale = np.sqrt(n + kappa)
    Z = np.vstack((scale * np.eye(n), -scale * np.eye(n), np.zeros(n)))
    w = np.ones(2 * n + 1) / (2 * (n + kappa))
    w[-1] = kappa / (n + kappa)
    return Z, w
'''),
    Alternative("unscented_points", "one-minus", "the centre weight as 1 minus the side weights",
                '''def unscented_points(n, kappa=1.0):
    side = 1.0 / (2.0 * (n + kappa))
    Z = np.zeros((2 * n + 1, n))
    Z[1:n + 1] = np.sqrt(n + kappa) * np.eye(n)
    Z[n + 1:] = -np.sqrt(n + kappa) * np.eye(n)
    w = np.concatenate(([1.0 - 2 * n * side], side * np.ones(2 * n)))
    return Z, w
'''),
    Alternative("cut4_points", "binary-signs", "the sign patterns from the bits of 0 ... 2^n - 1, conjugate points first",
                '''def cut4_points(n):
    bits = (np.arange(2**n)[:, None] >> np.arange(n)[None, :]) & 1
    signs = 1.0 - 2.0 * bits
    r1, r2 = np.sqrt((n + 2) / 2), np.sqrt((n + 2) / (n - 2))
    w1, w2 = 4 / (n + 2) ** 2, (n - 2) ** 2 / (2**n * (n + 2) ** 2)
    Z = np.vstack((r2 * signs, r1 * np.eye(n), -r1 * np.eye(n)))
    w = np.concatenate((np.full(2**n, w2), np.full(2 * n, w1)))
    return Z, w
'''),
    Alternative("cut4_points", "loops", "loops over the axes and over itertools.product's sign patterns",
                '''def cut4_points(n):
    points, weights = [], []
    for i in range(n):
        for sign in (-1, 1):
            z = np.zeros(n)
            z[i] = sign * np.sqrt((n + 2) / 2)
            points.append(z)
            weights.append(4 / (n + 2) ** 2)
    for pattern in itertools.product((-1, 1), repeat=n):
        points.append(np.sqrt((n + 2) / (n - 2)) * np.array(pattern, dtype=float))
        weights.append((n - 2) ** 2 / (n + 2) ** 2 / 2**n)
    return np.array(points), np.array(weights)
'''),
    Alternative("cut4_points", "weights-sum-to-one", "the conjugate weight from 2n w1 + 2^n w2 = 1",
                '''def cut4_points(n):
    w1 = 4.0 / (n + 2) ** 2
    w2 = (1.0 - 2 * n * w1) / 2**n
    signs = np.array(list(itertools.product((1.0, -1.0), repeat=n)))
    Z = np.concatenate((np.sqrt((n + 2) / 2) * np.eye(n), -np.sqrt((n + 2) / 2) * np.eye(n),
                        np.sqrt((n + 2) / (n - 2)) * signs))
    return Z, np.concatenate((w1 * np.ones(2 * n), w2 * np.ones(2**n)))
'''),
    Alternative("moment_error", "loop-factorial2", "a loop over the monomials, the Gaussian moments from scipy.special.factorial2",
                '''def moment_error(Z, w, degree):
    n = Z.shape[1]
    largest = 0.0
    for combo in itertools.combinations_with_replacement(range(n), degree):
        powers = np.bincount(combo, minlength=n)
        rule = np.sum(w * np.prod(Z**powers, axis=1))
        exact = 1.0
        for a in powers:
            if a % 2 == 1:
                exact = 0.0
            elif a > 0:
                exact *= scipy.special.factorial2(a - 1, exact=True)
        largest = max(largest, abs(rule - exact))
    return largest
'''),
    Alternative("moment_error", "exponent-table", "an exponent table from itertools.product, powers broadcast over the points",
                '''def moment_error(Z, w, degree):
    n = Z.shape[1]
    powers = np.array([a for a in itertools.product(range(degree + 1), repeat=n) if sum(a) == degree])

    def gaussian_moment(a):
        return 0.0 if a % 2 else float(np.prod(np.arange(a - 1, 0, -2)))

    exact = np.array([np.prod([gaussian_moment(a) for a in row]) for row in powers])
    rule = w @ np.prod(Z[:, None, :] ** powers[None, :, :], axis=2)
    return float(np.abs(rule - exact).max())
'''),
    Alternative("moment_error", "dict-of-monomials", "counts each monomial's exponents in a dict and tracks the largest error",
                '''def moment_error(Z, w, degree):
    errors = []
    for index in itertools.combinations_with_replacement(range(Z.shape[1]), degree):
        counts = {}
        for i in index:
            counts[i] = counts.get(i, 0) + 1
        rule = w @ np.prod(Z[:, list(index)], axis=1)
        exact = 1.0
        for a in counts.values():
            exact *= 0.0 if a % 2 else scipy.special.factorial(a) / (2 ** (a // 2) * scipy.special.factorial(a // 2))
        errors.append(abs(rule - exact))
    return max(errors)
'''),
    Alternative("sigma_point_predict", "loops", "loops over the points with np.outer",
                '''def sigma_point_predict(m, P, f, Z, w, Q):
    S = symmetric_sqrt(P)
    Y = f(np.array([m + S @ z for z in Z]))
    m_new = np.zeros_like(Y[0])
    for w_i, y_i in zip(w, Y):
        m_new = m_new + w_i * y_i
    P_new = Q.copy()
    for w_i, y_i in zip(w, Y):
        P_new = P_new + w_i * np.outer(y_i - m_new, y_i - m_new)
    return m_new, P_new
'''),
    Alternative("sigma_point_predict", "own-root", "its own symmetric root from np.linalg.eigh, and np.einsum",
                '''def sigma_point_predict(m, P, f, Z, w, Q):
    values, vectors = np.linalg.eigh(P)
    S = vectors @ np.diag(np.sqrt(values)) @ vectors.T
    Y = f(m + Z @ S.T)
    m_new = np.einsum("i,ij->j", w, Y)
    D = Y - m_new
    P_new = np.einsum("i,ij,ik->jk", w, D, D) + Q
    return m_new, (P_new + P_new.T) / 2
'''),
    Alternative("sigma_point_predict", "raw-moment", "the covariance as the raw second moment minus m m^T",
                '''def sigma_point_predict(m, P, f, Z, w, Q):
    X = m + Z @ symmetric_sqrt(P)
    Y = f(X)
    m_new = w @ Y
    P_new = (Y.T * w) @ Y - np.outer(m_new, m_new) + Q
    return m_new, 0.5 * (P_new + P_new.T)
'''),
    Alternative("sigma_point_update", "loops", "loops over the points with np.outer, the innovation -sum_i w_i E_i",
                '''def sigma_point_update(m, P, y, h, R, Z, w, angles=()):
    S = symmetric_sqrt(P)
    X = np.array([m + S @ z for z in Z])
    E = h(X) - y
    for a in angles:
        E[:, a] = wrap_angle(E[:, a])
    e_bar = w @ E
    P_yy, P_xy = R.copy(), np.zeros((len(m), len(y)))
    for w_i, x_i, e_i in zip(w, X, E):
        P_yy = P_yy + w_i * np.outer(e_i - e_bar, e_i - e_bar)
        P_xy = P_xy + w_i * np.outer(x_i - m, e_i - e_bar)
    K = np.linalg.solve(P_yy, P_xy.T).T
    m_new = m + K @ (-e_bar)
    P_new = P - K @ P_yy @ K.T
    return m_new, (P_new + P_new.T) / 2
'''),
    Alternative("sigma_point_update", "y-hat", "forms y_hat = y + sum_i w_i E_i and the covariance P - P_xy P_yy^-1 P_xy^T by a Cholesky solve",
                '''import scipy.linalg

def sigma_point_update(m, P, y, h, R, Z, w, angles=()):
    X = m + Z @ symmetric_sqrt(P)
    E = h(X) - y
    E[:, list(angles)] = wrap_angle(E[:, list(angles)])
    y_hat = y + w @ E
    D = E - (y_hat - y)
    P_yy = D.T @ (w[:, None] * D) + R
    P_xy = (X - m).T @ (w[:, None] * D)
    factor = scipy.linalg.cho_factor(P_yy)
    m_new = m + P_xy @ scipy.linalg.cho_solve(factor, y - y_hat)
    P_new = P - P_xy @ scipy.linalg.cho_solve(factor, P_xy.T)
    return m_new, (P_new + P_new.T) / 2
'''),
    Alternative("sigma_point_update", "einsum", "np.einsum for the weighted sums, the gain by solving with P_yy^T",
                '''def sigma_point_update(m, P, y, h, R, Z, w, angles=()):
    DX = Z @ symmetric_sqrt(P)
    E = h(m + DX) - y
    if len(angles) > 0:
        E[:, angles] = wrap_angle(E[:, angles])
    DY = E - np.einsum("i,ij->j", w, E)
    P_yy = np.einsum("i,ij,ik->jk", w, DY, DY) + R
    P_xy = np.einsum("i,ij,ik->jk", w, DX, DY)
    K = np.linalg.solve(P_yy.T, P_xy.T).T
    m_new = m - K @ np.einsum("i,ij->j", w, E)
    P_new = P - K @ P_yy @ K.T
    return m_new, 0.5 * (P_new + P_new.T)
'''),
    Alternative("ekf_update", "inverse", "the gain with np.linalg.inv, the Joseph form with np.eye(len(m))",
                '''def ekf_update(m, P, y, h, H_jacobian, R, angles=()):
    e = y - h(m)
    for a in angles:
        e[a] = wrap_angle(e[a])
    H = H_jacobian(m)
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    I_KH = np.eye(len(m)) - K @ H
    P_new = I_KH @ P @ I_KH.T + K @ R @ K.T
    return m + K @ e, (P_new + P_new.T) / 2
'''),
    Alternative("ekf_update", "short-form", "the short covariance form (I - K H) P, right at the optimal gain",
                '''def ekf_update(m, P, y, h, H_jacobian, R, angles=()):
    e = y - h(m)
    e[list(angles)] = wrap_angle(e[list(angles)])
    H = H_jacobian(m)
    S = H @ P @ H.T + R
    K = np.linalg.solve(S, H @ P).T
    P_new = (np.eye(m.size) - K @ H) @ P
    return m + K @ e, 0.5 * (P_new + P_new.T)
'''),
    Alternative("ekf_update", "angle-of-exp", "wraps the bearing innovation with np.angle(np.exp(1j e))",
                '''def ekf_update(m, P, y, h, H_jacobian, R, angles=()):
    innovation = y - h(m)
    for a in angles:
        innovation[a] = np.angle(np.exp(1j * innovation[a]))
    H = H_jacobian(m)
    S = H @ P @ H.T + R
    K = np.linalg.solve(S.T, (P @ H.T).T).T
    A = np.eye(len(m)) - K @ H
    P_new = A @ P @ A.T + K @ R @ K.T
    return m + K @ innovation, (P_new + P_new.T) / 2
'''),
    Alternative("bootstrap_pf_step", "multivariate-normal", "noise from rng.multivariate_normal, R^-1 by a solve, normalised by hand",
                '''def bootstrap_pf_step(X, logw, y, rng, f, h, Q, R, angles=(), ess_fraction=0.7):
    N, n = X.shape
    X = f(X) + rng.multivariate_normal(np.zeros(n), Q, size=N)
    E = y - h(X)
    for a in angles:
        E[:, a] = wrap_angle(E[:, a])
    logw = logw - 0.5 * np.sum(E * np.linalg.solve(R, E.T).T, axis=1)
    top = logw.max()
    logw = logw - (top + np.log(np.sum(np.exp(logw - top))))
    weights = np.exp(logw)
    if 1.0 / np.sum(weights**2) < ess_fraction * N:
        X = X[systematic_resample(weights, rng)]
        logw = np.full(N, -np.log(N))
    return X, logw
'''),
    Alternative("bootstrap_pf_step", "own-systematic", "its own systematic resampling with np.searchsorted, and R^-1 by an inverse",
                '''def bootstrap_pf_step(X, logw, y, rng, f, h, Q, R, angles=(), ess_fraction=0.7):
    N = len(X)
    L = np.linalg.cholesky(Q)
    X = f(X) + rng.standard_normal(X.shape) @ L.T
    E = y - h(X)
    E[:, list(angles)] = wrap_angle(E[:, list(angles)])
    logw = logw - 0.5 * np.einsum("ij,jk,ik->i", E, np.linalg.inv(R), E)
    logw = logw - scipy.special.logsumexp(logw)
    w = np.exp(logw)
    ess = 1 / np.sum(w * w)
    if ess < ess_fraction * N:
        positions = (rng.random() + np.arange(N)) / N
        parents = np.minimum(np.searchsorted(np.cumsum(w), positions), N - 1)
        X = X[parents]
        logw = -np.log(N) * np.ones(N)
    return X, logw
'''),
    Alternative("bootstrap_pf_step", "noise-by-columns", "draws the noise as an (n, N) array and multiplies by L from the left",
                '''def bootstrap_pf_step(X, logw, y, rng, f, h, Q, R, angles=(), ess_fraction=0.7):
    N, n = X.shape
    X_new = f(X) + (np.linalg.cholesky(Q) @ rng.standard_normal((n, N))).T
    residual = y[None, :] - h(X_new)
    if angles:
        residual[:, angles] = wrap_angle(residual[:, angles])
    L_R = np.linalg.cholesky(R)
    z = np.linalg.solve(L_R, residual.T)
    logw_new = logw - 0.5 * np.sum(z**2, axis=0)
    logw_new -= scipy.special.logsumexp(logw_new)
    if 1.0 / np.exp(scipy.special.logsumexp(2 * logw_new)) < ess_fraction * N:
        X_new = X_new[systematic_resample(np.exp(logw_new), rng)]
        logw_new = np.full(N, -np.log(N))
    return X_new, logw_new
'''),
    Alternative("bootstrap_pf_step", "spawned-streams", "one child generator of rng for the noise and another for the resampling (rng.spawn)",
                '''def bootstrap_pf_step(X, logw, y, rng, f, h, Q, R, angles=(), ess_fraction=0.7):
    noise_rng, resample_rng = rng.spawn(2)
    N = X.shape[0]
    X = f(X) + noise_rng.standard_normal(X.shape) @ np.linalg.cholesky(Q).T
    E = y - h(X)
    E[:, list(angles)] = wrap_angle(E[:, list(angles)])
    logw = logw - 0.5 * np.sum(E * np.linalg.solve(R, E.T).T, axis=1)
    logw = logw - scipy.special.logsumexp(logw)
    if 1.0 / np.sum(np.exp(2 * logw)) < ess_fraction * N:
        X = X[systematic_resample(np.exp(logw), resample_rng)]
        logw = np.full(N, -np.log(N))
    return X, logw
'''),
)
