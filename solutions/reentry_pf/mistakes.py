"""Plausible mistakes in the reentry-pf blanks. Each one edits the model answer of one blank."""

from autograder.catalogues.mistakes import Mistake
from autograder.hidden_tests.isolate import CallRuleBroken
from course.falling_object import InfoNotFilled, RecordedOutOfOrder

MISTAKES = (
    # tracking_dynamics
    Mistake("tracking_dynamics", "h-dot-plus-v", "h' = +v: the speed taken as upward, against the handout's v > 0 downward",
            "np.stack([-v, G", "np.stack([v, G",
            hint="Your tracking_dynamics behaves as if h' = +v: in this lab v > 0 is the speed downward, so the altitude falls."),
    Mistake("tracking_dynamics", "density-grows-with-height", "rho = gamma exp(+eta h): the atmosphere made denser upward",
            "np.exp(-ETA * h)", "np.exp(ETA * h)",
            hint="Your tracking_dynamics behaves as if the air grew denser upward: the exponent of rho(h) needs a minus sign."),
    Mistake("tracking_dynamics", "no-two", "drag g rho v^2 / beta: the 2 of equation (2) left out",
            "/ (2 * beta)", "/ beta",
            hint="Your tracking_dynamics behaves as if the 2 in the denominator of the drag, equation (2), were left out."),
    Mistake("tracking_dynamics", "drag-without-g", "drag rho v^2 / (2 beta): the factor g of equation (2) left out",
            "G - G * rho", "G - rho",
            hint="Your tracking_dynamics behaves as if the factor g were left out of the drag term: equation (2) has g rho(h) v^2 / (2 beta)."),
    Mistake("tracking_dynamics", "scalar-zero", "beta' written as the scalar 0.0: right for one state, breaks a particle cloud",
            "np.zeros_like(beta)", "0.0", raises=ValueError,
            hint="Your tracking_dynamics behaves as if beta' were the single number 0: that works for one state but not for a cloud of particles, so give it beta's shape."),
    # simulate_radar
    Mistake("simulate_radar", "default-tolerances", "solve_ivp's default rtol = 1e-3: the truth is off by about 20 m and 6 m/s",
            ", rtol=1e-10, atol=1e-8", "",
            hint="Your simulate_radar behaves as if solve_ivp ran with its default tolerances, which are far too loose here: set rtol and atol."),
    Mistake("simulate_radar", "starts-at-zero", "the truth integrated from t = 0 instead of the first time t[0]",
            "(t[0], t[-1])", "(0.0, t[-1])",
            hint="Your simulate_radar behaves as if the object were at x0 at t = 0 instead of at the first time t[0]: start solve_ivp's time span at t[0]."),
    Mistake("simulate_radar", "variance-noise", "noise sigma^2 e instead of sigma e",
            "sigma * rng.standard_normal", "sigma**2 * rng.standard_normal",
            hint="Your simulate_radar behaves as if the noise were sigma squared times a standard normal instead of sigma times it."),
    Mistake("simulate_radar", "reads-speed", "the radar reading made from the speed x_2 instead of the altitude x_1",
            "b = x_true[0] + sigma", "b = x_true[1] + sigma",
            hint="Your simulate_radar behaves as if the radar read the speed instead of the altitude."),
    # initial_cloud
    Mistake("initial_cloud", "variance-spread", "the prior spread C instead of C^(1/2): variances used as standard deviations",
            "PRIOR_STD[:, None] * rng", "PRIOR_STD[:, None] ** 2 * rng",
            hint="Your initial_cloud behaves as if the prior variances were used as standard deviations."),
    Mistake("initial_cloud", "draws-transposed", "draws of shape (N, 3), transposed: a different sample from the same generator",
            "rng.standard_normal((3, N))", "rng.standard_normal((N, 3)).T",
            hint="Your initial_cloud behaves as if it drew an (N, 3) array and transposed it: draw the (3, N) array in one call."),
    Mistake("initial_cloud", "unit-weights", "weights 1 instead of 1/N",
            "np.full(N, 1.0 / N)", "np.ones(N)",
            hint="Your initial_cloud behaves as if every weight were 1 instead of 1/N."),
    # pf_step
    Mistake("pf_step", "unnormalised-weights", "the weights of (d) returned without dividing by their sum",
            "return x_new, w_new / np.sum(w_new)", "return x_new, w_new",
            hint="Your pf_step behaves as if it returned the weights of (d) without dividing by their sum."),
    Mistake("pf_step", "argmax-resampling", "resampling by argmax: every new particle copies the fittest candidate",
            'k = np.searchsorted(cdf, np.sort(rng.random(N)), side="right")', "k = np.full(N, np.argmax(w_hat))",
            hint="Your pf_step behaves as if every new particle copied the fittest candidate: resampling draws parents at random with the fitness weights."),
    Mistake("pf_step", "innovation-before-resampling", "the innovation added to the candidates before resampling, so copies stay identical",
            "x_new = x_hat[:, k] + np.asarray(innovation_std)[:, None] * rng.standard_normal((3, N))",
            "x_new = (x_hat + np.asarray(innovation_std)[:, None] * rng.standard_normal((3, N)))[:, k]",
            hint="Your pf_step behaves as if the innovation were added to the candidates before resampling, so copies of a parent stay identical."),
    Mistake("pf_step", "fitness-ignores-old-weights", "the fitness (b) made from the likelihood alone, dropping the old weights w",
            "log_w_hat = np.log(w) - (x_hat[0]", "log_w_hat = -(x_hat[0]",
            hint="Your pf_step behaves as if the fitness (b) came from the likelihood alone, without the old weights w."),
    Mistake("pf_step", "fitness-before-propagation", "the fitness (b) computed from the old altitudes x_1, not the candidates x^_1",
            "np.log(w) - (x_hat[0] - b_next)", "np.log(w) - (x[0] - b_next)",
            hint="Your pf_step behaves as if the fitness (b) used the old altitudes instead of the propagated candidates x^_1."),
    Mistake("pf_step", "no-parent-term", "(d) without the parent's term |x^_1(k_l) - b|^2",
            " - (x_hat[0, k] - b_next) ** 2) / (2 * SIGMA**2)", ") / (2 * SIGMA**2)",
            hint="Your pf_step behaves as if the weights of (d) lacked the parent's term |x^_1(k_l) - b|^2."),
    Mistake("pf_step", "old-weights-twice", "(d) multiplied by the parents' old weights w[k]: the old weights counted twice",
            "w_new = np.exp(log_w - np.max(log_w))", "w_new = w[k] * np.exp(log_w - np.max(log_w))",
            hint="Your pf_step behaves as if (d) multiplied by the old weights again: (b) and the resampling used them already."),
    # A student trial (issue 33): a (d) with the wrong sign, or no (d) at all, passed every visible check (the
    # weighted mean of check 5 moves by about 5 m); an exact check of (d)'s weights now fails both.
    Mistake("pf_step", "d-sign-flipped", "(d) without its minus sign: particles that the perturbation moved away from the reading gain weight",
            "log_w = -((x_new[0] - b_next) ** 2", "log_w = ((x_new[0] - b_next) ** 2",
            hint="Your pf_step behaves as if the exponent of (d) had lost its minus sign: a particle that moved away "
                 "from the reading should lose weight."),
    Mistake("pf_step", "no-reweigh", "step (d) left out: equal weights after resampling",
            "w_new = np.exp(log_w - np.max(log_w))", "w_new = np.ones(N)",
            hint="Your pf_step behaves as if it left out step (d) and returned equal weights: the perturbation moved "
                 "each particle away from its candidate, and (d) corrects for it."),
    Mistake("pf_step", "no-log-weights", "exp(log w^) without subtracting the largest: underflows to 0/0 for a distant reading",
            "w_hat = np.exp(log_w_hat - np.max(log_w_hat))", "w_hat = np.exp(log_w_hat)",
            hint="Your pf_step behaves as if it exponentiated the log-weights without subtracting the largest first, which underflows for a distant reading."),
    Mistake("pf_step", "variance-innovation", "the innovation D z instead of D^(1/2) z",
            "np.asarray(innovation_std)[:, None] * rng", "np.asarray(innovation_std)[:, None] ** 2 * rng",
            hint="Your pf_step behaves as if the innovation were scaled by the variances instead of the standard deviations innovation_std."),
    Mistake("pf_step", "ignores-innovation-std", "the handout's INNOVATION_STD used whatever innovation_std the caller passes",
            "np.asarray(innovation_std)[:, None] * rng", "INNOVATION_STD[:, None] * rng",
            hint="Your pf_step behaves as if it always used INNOVATION_STD, whatever innovation_std the caller passes."),
    Mistake("pf_step", "ess-of-old-weights", "info['ess'] from the old weights w, not the fitness weights the resampling uses",
            'info["ess"] = 1.0 / np.sum(w_hat**2)', 'info["ess"] = 1.0 / np.sum(w**2)',
            hint="Your pf_step behaves as if info['ess'] came from the old weights w instead of the fitness weights that the resampling uses."),
    # run_particle_filter
    Mistake("run_particle_filter", "unweighted-mean", "the plain mean of the particles instead of the weighted mean",
            "history.mean[:, j] = x @ w", "history.mean[:, j] = np.mean(x, axis=1)",
            hint="Your run_particle_filter behaves as if the mean were the plain mean of the particles instead of the weighted mean."),
    Mistake("run_particle_filter", "stale-reading", "step j assimilates b_{j-1}: the readings one step late",
            "x, w = step(x, w, b[j], rng", "x, w = step(x, w, b[j - 1], rng",
            hint="Your run_particle_filter behaves as if step j assimilated the previous reading b_{j-1}: the readings arrive one step late."),
    # Issue 33: the resampling's books are kept by the given ResamplingHealth. Made afresh at every step it would count
    # the latest parents as the roots; it refuses, and it refuses a dict that no step filled. A fairness review: a call
    # before the step, a step called without info=info and a new dict given to the step all read an unfilled dict, so
    # the one catalogued entry for them names both fixes.
    Mistake("run_particle_filter", "health-made-every-step", "a new ResamplingHealth at every t_j: the roots counted as the latest parents",
            "        health.record(history, j, info)", "        ResamplingHealth(N).record(history, j, info)",
            raises=RecordedOutOfOrder,
            hint="Your run_particle_filter behaves as if it made a new ResamplingHealth at every step: make one before "
                 "the loop, so that it follows each particle's ancestry back to t_0."),
    Mistake("run_particle_filter", "health-reads-unfilled-dict", "the step called without info=info (or health.record called before the step): health.record reads a dict that no step filled",
            "x, w = step(x, w, b[j], rng, innovation_std=innovation_std, info=info)",
            "x, w = step(x, w, b[j], rng, innovation_std=innovation_std)", raises=InfoNotFilled,
            hint="Your run_particle_filter behaves as if health.record read a dict that no step had filled: pass the "
                 "same dict to the step as info=info, and call health.record(history, j, info) after the step to t_j."),
    Mistake("run_particle_filter", "ignores-step", "the step argument ignored: always the auxiliary pf_step",
            "step = pf_step if step is None else step", "step = pf_step",
            hint="Your run_particle_filter behaves as if it ignored the step argument and always used pf_step."),
    # A student trial: a loop that did not pass innovation_std to the step passed every visible check.
    Mistake("run_particle_filter", "drops-innovation-std", "the step called without innovation_std: every run uses the handout's noise",
            "x, w = step(x, w, b[j], rng, innovation_std=innovation_std, info=info)", "x, w = step(x, w, b[j], rng, info=info)",
            hint="Your run_particle_filter behaves as if it did not pass innovation_std on to the step, so every run used the "
                 "step's default, the handout's noise: call step(..., innovation_std=innovation_std, info=info)."),
    # A fairness review: history.ess taken from the step's info (the fitness weights) passed every visible check.
    Mistake("run_particle_filter", "ess-from-info", "history.ess from info['ess'], the ESS of the fitness weights, not of the weights the step returned",
            "history.ess[j] = 1.0 / np.sum(w**2)", 'history.ess[j] = info.get("ess", float(N))',
            hint="Your run_particle_filter behaves as if history.ess were info['ess'], the ESS of the weights the step "
                 "resampled with: record 1 / sum w^2 of the weights the step returned."),
    Mistake("run_particle_filter", "ess-of-sum", "ESS as 1 / (sum w)^2, which is always 1",
            "1.0 / np.sum(w**2)", "1.0 / np.sum(w) ** 2",
            hint="Your run_particle_filter behaves as if the ESS were 1 / (sum w)^2, which is always 1: square each weight before summing."),
    # A review of the fairness of grading: writing into an argument, or drawing from NumPy's global generator, kept the marks.
    Mistake("pf_step", "x-in-place", "moves the cloud it was given (x += dt f(x)) instead of a new one",
            "x_hat = x + DT * tracking_dynamics(0.0, x)", "x += DT * tracking_dynamics(0.0, x)\n    x_hat = x",
            raises=CallRuleBroken,
            hint="Leave the arrays you are given as they are and return new ones: write x = x + ..., or start from x.copy()."),
    Mistake("pf_step", "global-random", "draws the resampling's uniforms with np.random, not with rng",
            "np.sort(rng.random(N))", "np.sort(np.random.random(N))",
            raises=CallRuleBroken,
            hint="Draw every random number with rng: rng.standard_normal, rng.random, rng.choice."),
    # A review of the fairness of grading: a float32 answer was told to check the drag and the signs.
    Mistake("tracking_dynamics", "float32", "computes in single precision (float32)",
            "h, v, beta = np.asarray(x, dtype=float)", "h, v, beta = np.asarray(x, dtype=np.float32)",
            hint="It is in single precision (float32, about 7 significant digits): compute in float64, NumPy's default, and do not convert your arrays to float32."),
    # An adversarial review of issue 31: a step whose draws do not come from rng passed the statistical test.
    Mistake("pf_step", "own-generator", "draws once from rng, then from a generator of its own, np.random.default_rng()",
            "    N = x.shape[1]\n", "    N = x.shape[1]\n    rng.random()\n    rng = np.random.default_rng()\n",
            raises=CallRuleBroken,
            hint="Draw every random number with the rng it is given, so that the same seed gives the same result."),
    # A review of the fairness of the visible checks' messages: each was told of another cause.
    Mistake("pf_step", "innovation-shared", "one draw of the innovation, shape (3, 1), shared by every new particle",
            "rng.standard_normal((3, N))", "rng.standard_normal((3, 1))",
            hint="Your pf_step behaves as if every new particle shared one draw of the innovation: each particle needs a draw of its own, a column of rng.standard_normal((3, N))."),
    # A final review of issue 30: a step that drew from a copy of rng kept its marks; the caller's rng never moved.
    Mistake("pf_step", "rng-not-moved", "draws from a generator seeded with rng's state, so rng itself never moves",
            "    N = x.shape[1]\n", "    N = x.shape[1]\n    rng = np.random.default_rng(rng.bit_generator.state['state']['state'])\n",
            raises=CallRuleBroken, hint="Draw every random number with rng itself."),
)
