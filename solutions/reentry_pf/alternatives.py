"""Correct answers to the reentry-pf blanks that differ from the model answer, written from the release
notebook's text the way students write them: each must keep full marks on every submission seed."""

from autograder.catalogues.alternatives import Alternative

ALTERNATIVES = (
    # tracking_dynamics
    Alternative("tracking_dynamics", "np-array", "np.array of the three rows instead of np.stack, the drag factored out of g",
                '''def tracking_dynamics(t, x):
    """f(x) of equation (5) for x of shape (3,) or (3, N); returns the same shape."""
    h, v, beta = x
    rho = GAMMA * np.exp(-ETA * h)
    return np.array([-v, G * (1 - rho * v**2 / (2 * beta)), np.zeros_like(beta)])
'''),
    Alternative("tracking_dynamics", "preallocated", "an array like x filled row by row, indexing x[0], x[1], x[2]",
                '''def tracking_dynamics(t, x):
    """f(x) of equation (5) for x of shape (3,) or (3, N); returns the same shape."""
    x = np.asarray(x, dtype=float)
    f = np.zeros_like(x)
    rho = GAMMA * np.exp(-ETA * x[0])
    f[0] = -x[1]
    f[1] = G - G * rho * x[1] ** 2 / (2 * x[2])
    return f
'''),
    Alternative("tracking_dynamics", "vstack-divided", "np.vstack of the rows (then reshaped to x's shape), rho written as gamma / exp(eta h)",
                '''def tracking_dynamics(t, x):
    """f(x) of equation (5) for x of shape (3,) or (3, N); returns the same shape."""
    h, v, beta = x[0], x[1], x[2]
    rho = GAMMA / np.exp(ETA * h)
    drag = G * rho * v * v / (2.0 * beta)
    return np.vstack([-v, G - drag, 0.0 * beta]).reshape(np.shape(x))
'''),
    # simulate_radar
    Alternative("simulate_radar", "normal-and-lambda", "rng.normal(0, sigma, n) for the noise (the same draws), a lambda for the right-hand side, rtol 1e-9",
                '''def simulate_radar(x0, t, sigma, rng):
    """Truth x_true (3, len(t)) from x0 at the times t [s], and readings b (len(t),) [m]."""
    sol = solve_ivp(lambda time, state: tracking_dynamics(time, state), [t[0], t[-1]], x0, method="RK45",
                    t_eval=t, rtol=1e-9, atol=1e-6)
    x_true = sol.y
    b = x_true[0, :] + rng.normal(0.0, sigma, size=len(t))
    return x_true, b
'''),
    Alternative("simulate_radar", "dense-output", "the solver's dense output evaluated at t instead of t_eval, vectorized=True",
                '''def simulate_radar(x0, t, sigma, rng):
    """Truth x_true (3, len(t)) from x0 at the times t [s], and readings b (len(t),) [m]."""
    solution = solve_ivp(tracking_dynamics, (t[0], t[-1]), np.array(x0, dtype=float), method="RK45",
                         dense_output=True, vectorized=True, rtol=1e-11, atol=1e-9)
    x_true = solution.sol(t)
    e = rng.standard_normal(len(t))
    return x_true, x_true[0] + sigma * e
'''),
    Alternative("simulate_radar", "noise-first", "the noise drawn before the solve, into a list of arrays returned as a list",
                '''def simulate_radar(x0, t, sigma, rng):
    """Truth x_true (3, len(t)) from x0 at the times t [s], and readings b (len(t),) [m]."""
    e = rng.standard_normal(t.shape[0])
    out = solve_ivp(tracking_dynamics, t_span=(float(t[0]), float(t[-1])), y0=list(x0), t_eval=list(t),
                    rtol=1e-10, atol=1e-10)
    return [out.y, out.y[0] + e * sigma]
'''),
    # initial_cloud
    Alternative("initial_cloud", "diag-matrix", "C^(1/2) z as np.diag(PRIOR_STD) @ z, and weights np.ones(N) / N",
                '''def initial_cloud(b0, N, rng):
    """Prior cloud x (3, N) around [b0, V_INIT, BETA_INIT] and equal weights w (N,)."""
    w_draws = rng.standard_normal((3, N))
    mean = np.array([[b0], [V_INIT], [BETA_INIT]])
    x = mean + np.diag(PRIOR_STD) @ w_draws
    return x, np.ones(N) / N
'''),
    Alternative("initial_cloud", "row-loop", "a loop over the three rows of one draw",
                '''def initial_cloud(b0, N, rng):
    """Prior cloud x (3, N) around [b0, V_INIT, BETA_INIT] and equal weights w (N,)."""
    z = rng.standard_normal((3, N))
    mean = [b0, V_INIT, BETA_INIT]
    x = np.empty((3, N))
    for i in range(3):
        x[i, :] = mean[i] + PRIOR_STD[i] * z[i, :]
    w = np.full(N, 1 / N)
    return x, w
'''),
    Alternative("initial_cloud", "transposes", "the mean added to the transposed draws and transposed back, a tuple of float arrays",
                '''def initial_cloud(b0, N, rng):
    """Prior cloud x (3, N) around [b0, V_INIT, BETA_INIT] and equal weights w (N,)."""
    z = rng.standard_normal(size=(3, N))
    x = (np.array([b0, V_INIT, BETA_INIT]) + z.T * PRIOR_STD).T
    return (x, np.repeat(1.0 / N, N))
'''),
    # pf_step
    Alternative("pf_step", "choice-logsumexp", "rng.choice(N, size=N, p=w_hat) as the text suggests, normalised with scipy's logsumexp",
                '''def pf_step(x, w, b_next, rng, *, innovation_std=INNOVATION_STD, info=None):
    """Steps (a)-(d): cloud x (3, N), weights w (N,), reading b_next [m] -> new (x, w)."""
    from scipy.special import logsumexp

    N = x.shape[1]
    x_hat = x + DT * tracking_dynamics(0.0, x)
    with np.errstate(divide="ignore"):
        log_w_hat = np.log(w) - (x_hat[0] - b_next) ** 2 / (2 * SIGMA**2)
    w_hat = np.exp(log_w_hat - logsumexp(log_w_hat))
    k = rng.choice(N, size=N, p=w_hat / w_hat.sum())
    x_new = x_hat[:, k] + innovation_std[:, None] * rng.standard_normal((3, N))
    log_w = -((x_new[0] - b_next) ** 2 - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2)
    w_new = np.exp(log_w - logsumexp(log_w))
    if info is not None:
        info["ess"] = 1 / np.sum(w_hat**2)
        info["parents"] = k
    return x_new, w_new / w_new.sum()
'''),
    Alternative("pf_step", "multinomial-counts", "the counts drawn with rng.multinomial and repeated (parents in index order), (d) exponentiated without a shift",
                '''def pf_step(x, w, b_next, rng, *, innovation_std=INNOVATION_STD, info=None):
    """Steps (a)-(d): cloud x (3, N), weights w (N,), reading b_next [m] -> new (x, w)."""
    N = x.shape[1]
    # (a)
    x_hat = x + DT * tracking_dynamics(0, x)
    # (b) in logs, shifted by the largest
    log_fit = np.log(np.maximum(w, 1e-300)) - (x_hat[0] - b_next) ** 2 / (2 * SIGMA**2)
    fit = np.exp(log_fit - log_fit.max())
    fit = fit / fit.sum()
    # (c) how many copies of each candidate, then their indices
    counts = rng.multinomial(N, fit)
    k = np.repeat(np.arange(N), counts)
    noise = np.asarray(innovation_std).reshape(3, 1) * rng.standard_normal((3, N))
    x_new = x_hat[:, k] + noise
    # (d): only the innovation separates a particle from its parent, so the exponent stays small
    w_new = np.exp(-((x_new[0] - b_next) ** 2 - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2))
    if info is not None:
        info.update(ess=1.0 / (fit @ fit), parents=k)
    return x_new, w_new / np.sum(w_new)
'''),
    Alternative("pf_step", "unsorted-search", "uniforms searched unsorted in the unnormalised cumulative weights, the innovation as one rng.normal(x_hat[:, k], std) call",
                '''def pf_step(x, w, b_next, rng, *, innovation_std=INNOVATION_STD, info=None):
    """Steps (a)-(d): cloud x (3, N), weights w (N,), reading b_next [m] -> new (x, w)."""
    N = len(w)
    f = tracking_dynamics(0.0, x)
    x_hat = x + DT * f
    with np.errstate(divide="ignore"):
        logw = np.log(w) - 0.5 * ((x_hat[0] - b_next) / SIGMA) ** 2
    w_hat = np.exp(logw - np.max(logw))
    w_hat = w_hat / np.sum(w_hat)
    F = np.cumsum(w_hat)
    k = np.minimum(np.searchsorted(F, rng.uniform(0.0, F[-1], N), side="right"), N - 1)
    x_new = rng.normal(x_hat[:, k], np.asarray(innovation_std, dtype=float)[:, None])
    logw_new = -0.5 * ((x_new[0] - b_next) ** 2 - (x_hat[0][k] - b_next) ** 2) / SIGMA**2
    w_new = np.exp(logw_new - logw_new.max())
    w_new /= w_new.sum()
    if isinstance(info, dict):
        info["ess"] = 1.0 / np.sum(np.square(w_hat))
        info["parents"] = k
    return x_new, w_new
'''),
    Alternative("pf_step", "systematic", "systematic resampling: one uniform, N evenly spaced points searched in the cumulative weights (the text accepts it)",
                '''def pf_step(x, w, b_next, rng, *, innovation_std=INNOVATION_STD, info=None):
    """Steps (a)-(d): cloud x (3, N), weights w (N,), reading b_next [m] -> new (x, w)."""
    N = x.shape[1]
    x_hat = x + DT * tracking_dynamics(0.0, x)
    with np.errstate(divide="ignore"):
        log_w_hat = np.log(w) - (x_hat[0] - b_next) ** 2 / (2 * SIGMA**2)
    w_hat = np.exp(log_w_hat - log_w_hat.max())
    w_hat /= w_hat.sum()
    cdf = np.cumsum(w_hat)
    cdf /= cdf[-1]
    k = np.minimum(np.searchsorted(cdf, (rng.random() + np.arange(N)) / N, side="right"), N - 1)
    x_new = x_hat[:, k] + np.asarray(innovation_std)[:, None] * rng.standard_normal((3, N))
    log_w = -((x_new[0] - b_next) ** 2 - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2)
    w_new = np.exp(log_w - log_w.max())
    if info is not None:
        info["ess"] = 1.0 / np.sum(w_hat**2)
        info["parents"] = k
    return x_new, w_new / w_new.sum()
'''),
    Alternative("pf_step", "spawned-streams", "one child generator of rng for the resampling and another for the innovation (rng.spawn)",
                '''def pf_step(x, w, b_next, rng, *, innovation_std=INNOVATION_STD, info=None):
    """Steps (a)-(d): cloud x (3, N), weights w (N,), reading b_next [m] -> new (x, w)."""
    resample_rng, noise_rng = rng.spawn(2)
    N = x.shape[1]
    x_hat = x + DT * tracking_dynamics(0.0, x)
    with np.errstate(divide="ignore"):
        log_w_hat = np.log(w) - (x_hat[0] - b_next) ** 2 / (2 * SIGMA**2)
    w_hat = np.exp(log_w_hat - log_w_hat.max())
    w_hat = w_hat / w_hat.sum()
    k = resample_rng.choice(N, size=N, p=w_hat)
    x_new = x_hat[:, k] + np.asarray(innovation_std)[:, None] * noise_rng.standard_normal((3, N))
    log_w = -((x_new[0] - b_next) ** 2 - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2)
    w_new = np.exp(log_w - log_w.max())
    if info is not None:
        info["ess"] = 1.0 / np.sum(w_hat**2)
        info["parents"] = k
    return x_new, w_new / w_new.sum()
'''),
    # run_particle_filter
    Alternative("run_particle_filter", "separate-calls", "np.average for the mean, 1 / (w @ w) for the ESS, one credibility_interval call per p, step or pf_step",
                '''def run_particle_filter(b, N, rng, *, step=None, innovation_std=INNOVATION_STD):
    """A particle filter over the readings b (T + 1,) with N particles; returns a FilterHistory."""
    step = step or pf_step
    history = FilterHistory.empty(len(b), N)
    x, w = initial_cloud(b[0], N, rng)
    root = np.arange(N)
    info = {}
    for j in range(len(b)):
        if j == 0:
            history.ess_resample[0] = N
            history.parents[0] = N
        else:
            x, w = step(x, w, b[j], rng, innovation_std=innovation_std, info=info)
            root = root[info["parents"]]
            history.ess_resample[j] = info["ess"]
            history.parents[j] = np.unique(info["parents"]).size
        history.roots[j] = np.unique(root).size
        history.mean[:, j] = np.average(x, axis=1, weights=w)
        for i in range(3):
            history.median[i, j] = credibility_interval(x[i], w, 0)[0]
            history.lo50[i, j], history.hi50[i, j] = credibility_interval(x[i], w, 50)
            history.lo90[i, j], history.hi90[i, j] = credibility_interval(x[i], w, 90)
        history.ess[j] = 1 / (w @ w)
    return history
'''),
    Alternative("run_particle_filter", "fresh-info", "a fresh info dict for each step, the first time step recorded before the loop, the given ResamplingHealth",
                '''def run_particle_filter(b, N, rng, *, step=None, innovation_std=INNOVATION_STD):
    """A particle filter over the readings b (T + 1,) with N particles; returns a FilterHistory."""
    if step is None:
        step = pf_step
    h = FilterHistory.empty(len(b), N)
    x, w = initial_cloud(b[0], N, rng)
    health = ResamplingHealth(N)

    def record(j, info):
        h.mean[:, j] = np.sum(x * w, axis=1)
        for i in range(3):
            lo, hi = credibility_interval(x[i], w, [0, 50, 90])
            h.median[i, j] = lo[0]
            h.lo50[i, j], h.hi50[i, j] = lo[1], hi[1]
            h.lo90[i, j], h.hi90[i, j] = lo[2], hi[2]
        h.ess[j] = 1.0 / np.sum(w**2)
        health.record(h, j, info)

    record(0, None)
    for j in range(1, len(b)):
        info = {}
        x, w = step(x, w, b[j], rng, innovation_std=innovation_std, info=info)
        record(j, info)
    return h
'''),
    Alternative("run_particle_filter", "lists-then-arrays", "the summaries gathered in lists, one row per time, and copied into the history at the end",
                '''def run_particle_filter(b, N, rng, *, step=None, innovation_std=INNOVATION_STD):
    """A particle filter over the readings b (T + 1,) with N particles; returns a FilterHistory."""
    step = pf_step if step is None else step
    x, w = initial_cloud(b[0], N, rng)
    roots = np.arange(N)
    info = {"ess": N, "parents": np.arange(N)}
    rows = []
    for j in range(len(b)):
        if j > 0:
            x, w = step(x, w, b[j], rng, innovation_std=innovation_std, info=info)
            roots = roots[info["parents"]]
        intervals = [credibility_interval(x[i], w, np.array([0.0, 50.0, 90.0])) for i in range(3)]
        rows.append((x @ w, intervals, 1 / np.sum(w * w), info["ess"], len(np.unique(info["parents"])), len(np.unique(roots))))
    history = FilterHistory.empty(len(b), N)
    for j, (mean, intervals, ess, ess_resample, parents, n_roots) in enumerate(rows):
        history.mean[:, j] = mean
        history.median[:, j] = [lo[0] for lo, hi in intervals]
        history.lo50[:, j] = [lo[1] for lo, hi in intervals]
        history.hi50[:, j] = [hi[1] for lo, hi in intervals]
        history.lo90[:, j] = [lo[2] for lo, hi in intervals]
        history.hi90[:, j] = [hi[2] for lo, hi in intervals]
        history.ess[j], history.ess_resample[j], history.parents[j], history.roots[j] = ess, ess_resample, parents, n_roots
    return history
'''),
)
