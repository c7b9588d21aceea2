"""Correct answers to the castaway-bob blanks that differ from the model answers the way students' answers do,
written from the release notebook's text: each must keep full marks (tests/test_alternatives.py)."""

from autograder.catalogues.alternatives import Alternative

ALTERNATIVES = (
    Alternative("transition_matrix", "eye-entries", "starts from the identity and sets the dt and alpha entries",
                '''def transition_matrix(dt, alpha):
    A = np.eye(4)
    A[0, 2] = A[1, 3] = dt
    A[2, 2] = A[3, 3] = alpha
    return A
'''),
    Alternative("transition_matrix", "blocks", "assembles A from 2 x 2 blocks with np.block",
                '''def transition_matrix(dt, alpha):
    I2, O2 = np.eye(2), np.zeros((2, 2))
    return np.block([[I2, dt * I2], [O2, alpha * I2]])
'''),
    Alternative("transition_matrix", "kron", "the one-axis matrix [[1, dt], [0, alpha]] for both axes, by np.kron",
                '''def transition_matrix(dt, alpha):
    return np.kron(np.array([[1.0, dt], [0.0, alpha]]), np.eye(2))
'''),
    Alternative("observation_matrix", "eye-2-4", "np.eye(2, 4), the identity's first two rows",
                '''def observation_matrix():
    return np.eye(2, 4)
'''),
    Alternative("observation_matrix", "hstack", "the identity beside a block of zeros",
                '''def observation_matrix():
    return np.hstack((np.eye(2), np.zeros((2, 2))))
'''),
    Alternative("observation_matrix", "eye-rows", "the first two rows of the 4 x 4 identity",
                '''def observation_matrix():
    return np.eye(4)[:2]
'''),
    Alternative("trailing_mean", "cumsum", "vectorised with cumulative sums",
                '''def trailing_mean(y, order=3):
    y = np.asarray(y, dtype=float)
    totals = np.vstack((np.zeros((1, y.shape[1])), np.cumsum(y, axis=0)))
    end = np.arange(1, len(y) + 1)
    start = np.maximum(end - order, 0)
    return (totals[end] - totals[start]) / (end - start)[:, None]
'''),
    Alternative("trailing_mean", "sum-over-count", "a loop that sums the window and divides by how many fixes it holds",
                '''def trailing_mean(y, order=3):
    estimates = np.zeros((len(y), 2))
    for n in range(len(y)):
        first = n - order + 1
        if first < 0:
            first = 0
        total = np.zeros(2)
        for k in range(first, n + 1):
            total += y[k]
        estimates[n] = total / (n - first + 1)
    return estimates
'''),
    Alternative("trailing_mean", "comprehension", "a list comprehension of window means",
                '''def trailing_mean(y, order=3):
    return np.array([np.mean(y[max(0, n + 1 - order):n + 1], axis=0) for n in range(len(y))])
'''),
    Alternative("trailing_mean", "backwards", "a loop back from each fix that stops at the first fix, counting what it adds",
                '''def trailing_mean(y, order=3):
    n = len(y)
    out = np.zeros((n, 2))
    for k in range(n):
        total = np.zeros(2)
        count = 0
        for j in range(k, k - order, -1):
            if j < 0:
                break
            total += y[j]
            count += 1
        out[k] = total / count
    return out
'''),
    Alternative("kalman_gain", "inverse", "K = P H^T (H P H^T + R)^-1 with np.linalg.inv",
                '''def kalman_gain(P, H, R):
    return P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
'''),
    Alternative("kalman_gain", "cho-solve", "a Cholesky solve with the innovation covariance",
                '''import scipy.linalg

def kalman_gain(P, H, R):
    S = H @ P @ H.T + R
    return scipy.linalg.cho_solve(scipy.linalg.cho_factor(S), H @ P.T).T
'''),
    Alternative("kalman_gain", "solve-right", "solves K S = P H^T from the right, through the transposes",
                '''def kalman_gain(P, H, R):
    S = H @ P @ H.T + R
    return np.linalg.solve(S.T, (P @ H.T).T).T
'''),
    Alternative("joseph_covariance", "expanded", "(13) multiplied out: P - K H P - P H^T K^T + K (H P H^T + R) K^T",
                '''def joseph_covariance(P, K, H, R):
    KH = K @ H
    return P - KH @ P - P @ KH.T + K @ (H @ P @ H.T + R) @ K.T
'''),
    Alternative("joseph_covariance", "symmetrised", "the Joseph form with np.dot, then symmetrised",
                '''def joseph_covariance(P, K, H, R):
    M = np.identity(len(P)) - np.dot(K, H)
    P_new = np.dot(np.dot(M, P), M.T) + np.dot(np.dot(K, R), K.T)
    return 0.5 * (P_new + P_new.T)
'''),
    Alternative("joseph_covariance", "einsum", "writes the two products with np.einsum",
                '''def joseph_covariance(P, K, H, R):
    M = np.eye(P.shape[0]) - K @ H
    return np.einsum("ij,jk,lk->il", M, P, M) + np.einsum("ij,jk,lk->il", K, R, K)
'''),
    Alternative("kalman_step", "short-form", "updates the covariance in the short form (I - K H) P^-, right at the optimal gain",
                '''def kalman_step(x, P, y, A, H, Q, R, u=None):
    x_pred = A @ x
    if u is not None:
        x_pred = x_pred + u
    P_pred = A @ P @ A.T + Q
    K = kalman_gain(P_pred, H, R)
    x_new = x_pred + K @ (y - H @ x_pred)
    P_new = (np.eye(len(x)) - K @ H) @ P_pred
    return x_new, P_new
'''),
    Alternative("kalman_step", "inline", "writes the gain and the Joseph form inline, with an inverse",
                '''def kalman_step(x, P, y, A, H, Q, R, u=None):
    x_pred = A @ x + (0 if u is None else u)
    P_pred = A @ P @ A.T + Q
    K = P_pred @ H.T @ np.linalg.inv(H @ P_pred @ H.T + R)
    I_KH = np.eye(len(x)) - K @ H
    return x_pred + K @ (y - H @ x_pred), I_KH @ P_pred @ I_KH.T + K @ R @ K.T
'''),
    Alternative("kalman_step", "list", "returns a list [x, P], the input added as np.zeros when there is none",
                '''def kalman_step(x, P, y, A, H, Q, R, u=None):
    if u is None:
        u = np.zeros_like(x)
    x_minus = np.dot(A, x) + u
    P_minus = np.dot(A, np.dot(P, A.T)) + Q
    K = kalman_gain(P_minus, H, R)
    return [x_minus + np.dot(K, y - np.dot(H, x_minus)), joseph_covariance(P_minus, K, H, R)]
'''),
    Alternative("kalman_step", "in-place-input", "adds the known input in place to the predicted mean",
                '''def kalman_step(x, P, y, A, H, Q, R, u=None):
    x_pred = A @ x
    if u is not None:
        x_pred += u
    P_pred = A @ P @ A.T + Q
    K = kalman_gain(P_pred, H, R)
    return x_pred + K @ (y - H @ x_pred), joseph_covariance(P_pred, K, H, R)
'''),
    Alternative("run_rank2", "lists", "keeps the running estimate and appends to lists",
                '''def run_rank2(y, sigma_walk=30.0, sigma_gps=50.0):
    I = np.eye(2)
    Q, R = np.diag([sigma_walk**2, sigma_walk**2]), np.diag([sigma_gps**2, sigma_gps**2])
    x, P = np.array(y[0], dtype=float), R.copy()
    estimates, covariances = [x], [P]
    for fix in y[1:]:
        x, P = kalman_step(x, P, fix, I, I, Q, R)
        estimates.append(x)
        covariances.append(P)
    return np.array(estimates), np.array(covariances)
'''),
    Alternative("run_rank2", "inline", "writes the random-walk filter's equations inline (A = H = I)",
                '''def run_rank2(y, sigma_walk=30.0, sigma_gps=50.0):
    n = len(y)
    Q, R = sigma_walk**2 * np.eye(2), sigma_gps**2 * np.eye(2)
    xs, Ps = np.zeros((n, 2)), np.zeros((n, 2, 2))
    xs[0], Ps[0] = y[0], R
    for k in range(1, n):
        P_pred = Ps[k - 1] + Q
        K = P_pred @ np.linalg.inv(P_pred + R)
        xs[k] = xs[k - 1] + K @ (y[k] - xs[k - 1])
        I_K = np.eye(2) - K
        Ps[k] = I_K @ P_pred @ I_K.T + K @ R @ K.T
    return xs, Ps
'''),
    Alternative("run_rank2", "tuple-of-arrays", "builds A, H with np.identity and returns a tuple of stacked arrays",
                '''def run_rank2(y, sigma_walk=30.0, sigma_gps=50.0):
    A = H = np.identity(2)
    Q = np.identity(2) * sigma_walk**2
    R = np.identity(2) * sigma_gps**2
    xs, Ps = [np.asarray(y[0], dtype=float)], [R]
    for k in range(1, len(y)):
        x_k, P_k = kalman_step(xs[-1], Ps[-1], y[k], A, H, Q, R, u=None)
        xs.append(x_k)
        Ps.append(P_k)
    return (np.stack(xs), np.stack(Ps))
'''),
    Alternative("run_rank4", "zeros-input", "fills the input vector's first two entries, and keeps the running state",
                '''def run_rank4(y, flow, t, alpha=0.95, sigma_F=0.02, sigma_gps=50.0, dt=60.0):
    A, H = transition_matrix(dt, alpha), observation_matrix()
    Q = np.zeros((4, 4))
    Q[2, 2] = Q[3, 3] = sigma_F**2
    R = np.eye(2) * sigma_gps**2
    sigma_w2 = sigma_F**2 / (1 - alpha**2)
    x = np.array([y[0][0], y[0][1], 0.0, 0.0])
    P = np.diag([sigma_gps**2, sigma_gps**2, sigma_w2, sigma_w2])
    xs, Ps = [x], [P]
    for k in range(1, len(y)):
        u = np.zeros(4)
        u[:2] = dt * flow(x[:2], t[k - 1])
        x, P = kalman_step(x, P, y[k], A, H, Q, R, u)
        xs.append(x)
        Ps.append(P)
    return np.array(xs), np.array(Ps)
'''),
    Alternative("run_rank4", "inline", "writes the prediction with the current and the update inline, with the gain and Joseph blanks",
                '''def run_rank4(y, flow, t, alpha=0.95, sigma_F=0.02, sigma_gps=50.0, dt=60.0):
    n = len(y)
    A, H = transition_matrix(dt, alpha), observation_matrix()
    Q = np.diag([0.0, 0.0, sigma_F**2, sigma_F**2])
    R = sigma_gps**2 * np.eye(2)
    xs, Ps = np.zeros((n, 4)), np.zeros((n, 4, 4))
    xs[0, :2] = y[0]
    Ps[0] = np.diag([sigma_gps**2] * 2 + [sigma_F**2 / (1.0 - alpha**2)] * 2)
    for k in range(1, n):
        x_pred = A @ xs[k - 1]
        x_pred[:2] += dt * flow(xs[k - 1, :2], t[k - 1])
        P_pred = A @ Ps[k - 1] @ A.T + Q
        K = kalman_gain(P_pred, H, R)
        xs[k] = x_pred + K @ (y[k] - H @ x_pred)
        Ps[k] = joseph_covariance(P_pred, K, H, R)
    return xs, Ps
'''),
    Alternative("run_rank4", "concatenate", "the input as np.r_[dt * current, 0, 0], the first state by np.append",
                '''def run_rank4(y, flow, t, alpha=0.95, sigma_F=0.02, sigma_gps=50.0, dt=60.0):
    A = transition_matrix(dt, alpha)
    H = observation_matrix()
    Q = sigma_F**2 * np.diag([0.0, 0.0, 1.0, 1.0])
    R = sigma_gps**2 * np.identity(2)
    xs = np.empty((len(y), 4))
    Ps = np.empty((len(y), 4, 4))
    xs[0] = np.append(y[0], [0.0, 0.0])
    Ps[0] = np.diag([sigma_gps**2, sigma_gps**2, sigma_F**2 / (1 - alpha * alpha), sigma_F**2 / (1 - alpha * alpha)])
    for k in range(1, len(y)):
        current = flow(xs[k - 1][0:2], t[k - 1])
        xs[k], Ps[k] = kalman_step(xs[k - 1], Ps[k - 1], y[k], A, H, Q, R, u=np.r_[dt * current, 0.0, 0.0])
    return xs, Ps
'''),
    Alternative("track_rmse", "norm", "the distances by np.linalg.norm",
                '''def track_rmse(estimates, truth):
    distances = np.linalg.norm(np.asarray(estimates) - np.asarray(truth), axis=1)
    return np.sqrt(np.mean(distances**2))
'''),
    Alternative("track_rmse", "loop", "a loop over the fixes, returning a Python float",
                '''def track_rmse(estimates, truth):
    total = 0.0
    for e, x in zip(estimates, truth):
        total += (e[0] - x[0]) ** 2 + (e[1] - x[1]) ** 2
    return float((total / len(truth)) ** 0.5)
'''),
    Alternative("track_rmse", "sum-over-n", "the sum of every squared coordinate error over the number of fixes",
                '''def track_rmse(estimates, truth):
    error = estimates - truth
    return np.sqrt(np.sum(error**2) / error.shape[0])
'''),
    Alternative("track_rmse", "frobenius", "the Frobenius norm of the errors over the square root of the number of fixes",
                '''def track_rmse(estimates, truth):
    d = np.asarray(estimates, dtype=float) - np.asarray(truth, dtype=float)
    return np.linalg.norm(d) / np.sqrt(len(d))
'''),
    Alternative("ellipse_area", "eigenvalues", "pi times the two semi-axes n_sigma sqrt(lambda_i), from np.linalg.eigvalsh",
                '''def ellipse_area(P, n_sigma=2.0):
    lam = np.linalg.eigvalsh(P)
    return np.pi * (n_sigma * np.sqrt(lam[..., 0])) * (n_sigma * np.sqrt(lam[..., 1]))
'''),
    Alternative("ellipse_area", "explicit-det", "the 2 x 2 determinant written out",
                '''def ellipse_area(P, n_sigma=2.0):
    P = np.asarray(P)
    det = P[..., 0, 0] * P[..., 1, 1] - P[..., 0, 1] * P[..., 1, 0]
    return np.pi * n_sigma**2 * np.sqrt(det)
'''),
    Alternative("ellipse_area", "product-of-eigenvalues", "sqrt of the product of the eigenvalues",
                '''def ellipse_area(P, n_sigma=2.0):
    return n_sigma**2 * np.pi * np.sqrt(np.prod(np.linalg.eigvalsh(P), axis=-1))
'''),
    Alternative("ellipse_area", "semi-axes-product", "pi times the product of the semi-axes n_sigma sqrt(lambda), by np.prod",
                '''def ellipse_area(P, n_sigma=2.0):
    lam = np.linalg.eigvalsh(P)
    return np.pi * np.prod(n_sigma * np.sqrt(lam), axis=-1)
'''),
)
