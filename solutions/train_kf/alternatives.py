"""Correct answers to the train-kf blanks that differ from the model answers the way students' answers do,
written from the release notebook's text: each must keep full marks (tests/test_alternatives.py)."""

from autograder.catalogues.alternatives import Alternative

ALTERNATIVES = (
    Alternative("gain_information_form", "inverses", "forms every inverse with np.linalg.inv, as the formula reads",
                '''def gain_information_form(B, H, R):
    R_inv = np.linalg.inv(R)
    return np.linalg.inv(np.linalg.inv(B) + H.T @ R_inv @ H) @ (R_inv @ H).T
'''),
    Alternative("gain_information_form", "solve-identity", "B^-1 and R^-1 by solving with the identity, then one solve",
                '''def gain_information_form(B, H, R):
    n, m = B.shape[0], R.shape[0]
    B_inv = np.linalg.solve(B, np.eye(n))
    R_inv = np.linalg.solve(R, np.eye(m))
    return np.linalg.solve(B_inv + H.T @ R_inv @ H, H.T @ R_inv)
'''),
    Alternative("gain_information_form", "cholesky", "Cholesky factors of B and R, and a Cholesky solve for the information matrix",
                '''import scipy.linalg

def gain_information_form(B, H, R):
    L = np.linalg.cholesky(B)
    L_inv = scipy.linalg.solve_triangular(L, np.eye(B.shape[0]), lower=True)
    B_inv = L_inv.T @ L_inv
    HtRinv = scipy.linalg.cho_solve(scipy.linalg.cho_factor(R, lower=True), H).T
    information = B_inv + HtRinv @ H
    return scipy.linalg.cho_solve(scipy.linalg.cho_factor(information), HtRinv)
'''),
    Alternative("gain_information_form", "cho-solve-all", "every solve a Cholesky solve: with B, with R, and with the information matrix",
                '''import scipy.linalg

def gain_information_form(B, H, R):
    n = B.shape[0]
    B_inv = scipy.linalg.cho_solve(scipy.linalg.cho_factor(B), np.eye(n))
    RiH = scipy.linalg.cho_solve(scipy.linalg.cho_factor(R), H)
    M = B_inv + H.T @ RiH
    return scipy.linalg.cho_solve(scipy.linalg.cho_factor(M), RiH.T)
'''),
    Alternative("gain_covariance_form", "inverse", "multiplies by the inverse of the innovation covariance",
                '''def gain_covariance_form(B, H, R):
    return B @ H.T @ np.linalg.inv(H @ B @ H.T + R)
'''),
    Alternative("gain_covariance_form", "cho-solve", "a Cholesky solve with the innovation covariance",
                '''import scipy.linalg

def gain_covariance_form(B, H, R):
    S = H @ B @ H.T + R
    return scipy.linalg.cho_solve(scipy.linalg.cho_factor(S), H @ B).T
'''),
    Alternative("gain_covariance_form", "solve-right", "solves K S = B H^T from the right, through the transposes",
                '''def gain_covariance_form(B, H, R):
    S = H @ B @ H.T + R
    PHt = B @ H.T
    return np.linalg.solve(S.T, PHt.T).T
'''),
    Alternative("process_noise", "outer", "Q = sigma^2 g g^T with g = (h, 1)",
                '''def process_noise(sigma, dt_min=1.0):
    g = np.array([dt_min / 60.0, 1.0])
    return sigma**2 * np.outer(g, g)
'''),
    Alternative("process_noise", "entries", "writes each entry out, with the position noise's sigma h",
                '''def process_noise(sigma, dt_min=1.0):
    h = dt_min / 60
    sigma_x = sigma * h
    return np.array([[sigma_x**2, sigma_x * sigma], [sigma * sigma_x, sigma**2]])
'''),
    Alternative("process_noise", "column", "Q = G sigma^2 G^T with the column G = [h; 1]",
                '''def process_noise(sigma, dt_min=1.0):
    G = np.array([[dt_min / 60.0], [1.0]])
    return G @ G.T * sigma**2
'''),
    Alternative("predict", "list", "returns a list [x_f, B_f], with np.dot",
                '''def predict(x, B, A, Q):
    x_f = np.dot(A, x)
    B_f = np.dot(np.dot(A, B), A.T) + Q
    return [x_f, B_f]
'''),
    Alternative("predict", "symmetrised", "symmetrises the forecast covariance",
                '''def predict(x, B, A, Q):
    B_f = A @ B @ A.T + Q
    return A @ x, (B_f + B_f.T) / 2
'''),
    Alternative("predict", "einsum", "writes the products with np.einsum",
                '''def predict(x, B, A, Q):
    x_f = np.einsum("ij,j->i", A, x)
    B_f = np.einsum("ij,jk,lk->il", A, B, A) + Q
    return x_f, B_f
'''),
    Alternative("kupdate", "joseph", "the Joseph form of the analysis covariance",
                '''def kupdate(x_f, B_f, y, H, R):
    K = gain_covariance_form(B_f, H, R)
    x_a = x_f + K @ (y - H @ x_f)
    I_KH = np.eye(len(x_f)) - K @ H
    B_a = I_KH @ B_f @ I_KH.T + K @ R @ K.T
    return x_a, B_a
'''),
    Alternative("kupdate", "information", "the information form of derivation 4, with gain_information_form",
                '''def kupdate(x_f, B_f, y, H, R):
    K = gain_information_form(B_f, H, R)
    x_a = x_f + K @ (y - H @ x_f)
    n = len(x_f)
    B_a = np.linalg.solve(np.linalg.solve(B_f, np.eye(n)) + H.T @ np.linalg.solve(R, H), np.eye(n))
    return x_a, B_a
'''),
    Alternative("kupdate", "inline-I-KH", "the gain written inline, and B_a = (I - K H) B",
                '''def kupdate(x_f, B_f, y, H, R):
    S = H @ B_f @ H.T + R
    K = B_f @ H.T @ np.linalg.inv(S)
    innovation = y - H @ x_f
    return x_f + K @ innovation, (np.eye(B_f.shape[0]) - K @ H) @ B_f
'''),
    Alternative("kupdate", "KSKt", "B_a = B_f - K S K^T with the innovation covariance S, symmetrised; the innovation as x_f - K (H x_f - y)",
                '''def kupdate(x_f, B_f, y, H, R):
    S = H @ B_f @ H.T + R
    K = gain_covariance_form(B_f, H, R)
    x_a = x_f - K @ (H @ x_f - y)
    B_a = B_f - K @ S @ K.T
    return x_a, 0.5 * (B_a + B_a.T)
'''),
    Alternative("kupdate", "information-gain-dot", "the information-form gain with .dot, and (I - K H) B symmetrised",
                '''def kupdate(x_f, B_f, y, H, R):
    K = gain_information_form(B_f, H, R)
    x_a = x_f + K.dot(y - H.dot(x_f))
    B_a = (np.eye(B_f.shape[0]) - K.dot(H)).dot(B_f)
    return x_a, (B_a + B_a.T) / 2
'''),
    Alternative("run_filter", "lists", "appends each analysis to lists and stacks them at the end",
                '''def run_filter(y, x0, B0, A, Q, H, R):
    estimates, covariances = [], []
    x, B = x0, B0
    for y_t in y:
        x_f, B_f = predict(x, B, A, Q)
        x, B = kupdate(x_f, B_f, y_t, H, R)
        estimates.append(x)
        covariances.append(B)
    return np.array(estimates), np.array(covariances)
'''),
    Alternative("run_filter", "inline", "writes the forecast and the analysis inline, without predict and kupdate",
                '''def run_filter(y, x0, B0, A, Q, H, R):
    T, n = len(y), len(x0)
    xs, Bs = np.zeros((T, n)), np.zeros((T, n, n))
    x, B = x0.copy(), B0.copy()
    for t in range(T):
        x = A @ x
        B = A @ B @ A.T + Q
        K = np.linalg.solve(H @ B @ H.T + R, H @ B).T
        x = x + K @ (y[t] - H @ x)
        B = B - K @ H @ B
        xs[t] = x
        Bs[t] = B
    return xs, Bs
'''),
    Alternative("run_filter", "chained", "chains kupdate(*predict(...)) and indexes the stored arrays from the previous row",
                '''def run_filter(y, x0, B0, A, Q, H, R):
    xs = np.empty((y.shape[0], x0.size))
    Bs = np.empty((y.shape[0], x0.size, x0.size))
    for t in range(y.shape[0]):
        previous = (x0, B0) if t == 0 else (xs[t - 1], Bs[t - 1])
        xs[t], Bs[t] = kupdate(*predict(*previous, A, Q), y[t], H, R)
    return xs, Bs
'''),
    Alternative("nees", "loop", "one solve per time in a loop",
                '''def nees(errors, covariances):
    return np.array([e @ np.linalg.solve(B, e) for e, B in zip(errors, covariances)])
'''),
    Alternative("nees", "einsum-inverse", "inverts the stack of covariances and contracts with np.einsum",
                '''def nees(errors, covariances):
    return np.einsum("ti,tij,tj->t", errors, np.linalg.inv(covariances), errors)
'''),
    Alternative("nees", "cholesky", "whitens each error with the Cholesky factor of its covariance",
                '''def nees(errors, covariances):
    L = np.linalg.cholesky(covariances)
    whitened = np.linalg.solve(L, errors[:, :, None])[:, :, 0]
    return np.sum(whitened**2, axis=1)
'''),
    Alternative("nees", "einsum-solve", "one stacked solve, then the dot products by np.einsum",
                '''def nees(errors, covariances):
    solved = np.linalg.solve(covariances, errors[..., None])[..., 0]
    return np.einsum("ti,ti->t", errors, solved)
'''),
    Alternative("nees", "triangular-loop", "a loop that whitens each error with a triangular solve against its Cholesky factor",
                '''import scipy.linalg

def nees(errors, covariances):
    out = np.empty(len(errors))
    for t in range(len(errors)):
        L = np.linalg.cholesky(covariances[t])
        z = scipy.linalg.solve_triangular(L, errors[t], lower=True)
        out[t] = z @ z
    return out
'''),
)
