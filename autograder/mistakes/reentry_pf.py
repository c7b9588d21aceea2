"""Plausible mistakes in the reentry-pf blanks. Each one edits the model answer of one blank."""

from autograder.mistakes import Mistake

MISTAKES = (
    # tracking_dynamics
    Mistake("tracking_dynamics", "h-dot-plus-v", "h' = +v: the speed taken as upward, against the handout's v > 0 downward",
            "np.stack([-v, G", "np.stack([v, G"),
    Mistake("tracking_dynamics", "density-grows-with-height", "rho = gamma exp(+eta h): the atmosphere made denser upward",
            "np.exp(-ETA * h)", "np.exp(ETA * h)"),
    Mistake("tracking_dynamics", "no-two", "drag g rho v^2 / beta: the 2 of equation (2) left out",
            "/ (2 * beta)", "/ beta"),
    Mistake("tracking_dynamics", "scalar-zero", "beta' written as the scalar 0.0: right for one state, breaks a particle cloud",
            "np.zeros_like(beta)", "0.0"),
    # simulate_radar
    Mistake("simulate_radar", "default-tolerances", "solve_ivp's default rtol = 1e-3: the truth is off by about 20 m and 6 m/s",
            ", rtol=1e-10, atol=1e-8", ""),
    Mistake("simulate_radar", "variance-noise", "noise sigma^2 e instead of sigma e",
            "sigma * rng.standard_normal", "sigma**2 * rng.standard_normal"),
    Mistake("simulate_radar", "reads-speed", "the radar reading made from the speed x_2 instead of the altitude x_1",
            "b = x_true[0] + sigma", "b = x_true[1] + sigma"),
    # initial_cloud
    Mistake("initial_cloud", "variance-spread", "the prior spread C instead of C^(1/2): variances used as standard deviations",
            "PRIOR_STD[:, None] * rng", "PRIOR_STD[:, None] ** 2 * rng"),
    Mistake("initial_cloud", "draws-transposed", "draws of shape (N, 3), transposed: a different sample from the same generator",
            "rng.standard_normal((3, N))", "rng.standard_normal((N, 3)).T"),
    Mistake("initial_cloud", "unit-weights", "weights 1 instead of 1/N",
            "np.full(N, 1.0 / N)", "np.ones(N)"),
    # pf_step
    Mistake("pf_step", "unnormalised-weights", "the weights of (d) returned without dividing by their sum",
            "return x_new, w_new / np.sum(w_new)", "return x_new, w_new"),
    Mistake("pf_step", "argmax-resampling", "resampling by argmax: every new particle copies the fittest candidate",
            'k = np.searchsorted(cdf, np.sort(rng.random(N)), side="right")', "k = np.full(N, np.argmax(w_hat))"),
    Mistake("pf_step", "innovation-before-resampling", "the innovation added to the candidates before resampling, so copies stay identical",
            "x_new = x_hat[:, k] + INNOVATION_STD[:, None] * rng.standard_normal((3, N))",
            "x_new = (x_hat + INNOVATION_STD[:, None] * rng.standard_normal((3, N)))[:, k]"),
    Mistake("pf_step", "fitness-ignores-old-weights", "the fitness (b) made from the likelihood alone, dropping the old weights w",
            "log_w_hat = np.log(w) - (x_hat[0]", "log_w_hat = -(x_hat[0]"),
    Mistake("pf_step", "fitness-before-propagation", "the fitness (b) computed from the old altitudes x_1, not the candidates x^_1",
            "np.log(w) - (x_hat[0] - b_next)", "np.log(w) - (x[0] - b_next)"),
    Mistake("pf_step", "no-parent-term", "(d) without the parent's term |x^_1(k_l) - b|^2",
            " - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2)", ") / (2 * SIGMA**2)"),
    Mistake("pf_step", "no-log-weights", "exp(log w^) without subtracting the largest: underflows to 0/0 for a distant reading",
            "w_hat = np.exp(log_w_hat - np.max(log_w_hat))", "w_hat = np.exp(log_w_hat)"),
    Mistake("pf_step", "variance-innovation", "the innovation D w instead of D^(1/2) w",
            "INNOVATION_STD[:, None] * rng", "INNOVATION_STD[:, None] ** 2 * rng"),
    # credibility_interval
    Mistake("credibility_interval", "unsorted", "the interval read off the samples in their given order, not sorted",
            "s = np.sort(samples, axis=-1)", "s = np.asarray(samples)"),
    Mistake("credibility_interval", "one-based-in-python", "the handout's 1-based indices used as Python's 0-based ones: one place too high",
            "return s[..., i_min - 1], s[..., i_max - 1]", "return s[..., i_min], s[..., i_max]"),
    Mistake("credibility_interval", "bankers-rounding", "Python's round, which sends halves to even, instead of MATLAB's halves away from zero",
            "i_min = int(np.floor(a_min) + (a_min - np.floor(a_min) >= 0.5))\n"
            "    i_max = int(np.floor(a_max) + (a_max - np.floor(a_max) >= 0.5))",
            "i_min = round(a_min)\n    i_max = round(a_max)"),
    # run_particle_filter
    Mistake("run_particle_filter", "unweighted-mean", "the plain mean of the particles instead of the weighted mean",
            "history.mean[:, j] = x @ w", "history.mean[:, j] = np.mean(x, axis=1)"),
    Mistake("run_particle_filter", "stale-reading", "step j assimilates b_{j-1}: the readings one step late",
            "x, w = pf_step(x, w, b[j], rng)", "x, w = pf_step(x, w, b[j - 1], rng)"),
    Mistake("run_particle_filter", "ess-of-sum", "ESS as 1 / (sum w)^2, which is always 1",
            "1.0 / np.sum(w**2)", "1.0 / np.sum(w) ** 2"),
)
