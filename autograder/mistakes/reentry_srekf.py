"""Plausible mistakes in the reentry-srekf blanks. Each one edits the model answer of one blank."""

from autograder.mistakes import Mistake

MISTAKES = (
    # ballistic_dynamics
    Mistake("ballistic_dynamics", "drag-sign", "f2 = -d - g: drag taken as pushing down, with the fall",
            "return np.array([v, d - G, 0.0])", "return np.array([v, -d - G, 0.0])"),
    Mistake("ballistic_dynamics", "inverse-exponent", "barometric exponent taken as R L / (g M), its inverse",
            "** (G * M / (R * L))", "** (R * L / (G * M))"),
    Mistake("ballistic_dynamics", "no-half", "d = rho v^2 c: forgets the 1/2 of equation (4)",
            "d = 0.5 * rho * v**2 * c", "d = rho * v**2 * c"),
    Mistake("ballistic_dynamics", "sea-level-temperature", "rho = p M / (R T0): the temperature of (8) left out",
            "rho = p * M / (R * T)", "rho = p * M / (R * T0)"),
    # ballistic_jacobian
    Mistake("ballistic_jacobian", "wrong-variable", "the drag derivatives with respect to h and v swapped",
            "[dd_dh, dd_dv, dd_dc]", "[dd_dv, dd_dh, dd_dc]"),
    Mistake("ballistic_jacobian", "density-constant", "dd/dh = 0: the density treated as constant in h",
            "dd_dh = d * L * (1 - exponent) / T", "dd_dh = 0.0"),
    Mistake("ballistic_jacobian", "dv-no-factor-2", "dd/dv = rho v c / 2: the 2 from v^2 dropped",
            "dd_dv = rho * v * c", "dd_dv = 0.5 * rho * v * c"),
    Mistake("ballistic_jacobian", "dh-sign", "dd/dh with the sign of dT/dh = -L lost",
            "dd_dh = d * L * (1 - exponent) / T", "dd_dh = d * L * (exponent - 1) / T"),
    # radar_predict
    Mistake("radar_predict", "no-r1", "range = |h - r2|: forgets the radar's horizontal offset",
            "np.hypot(RADAR_R1, h - RADAR_R2)", "np.abs(h - RADAR_R2)"),
    Mistake("radar_predict", "r2-sign", "range with (h + r2)^2",
            "np.hypot(RADAR_R1, h - RADAR_R2)", "np.hypot(RADAR_R1, h + RADAR_R2)"),
    Mistake("radar_predict", "no-sqrt", "returns the squared range",
            "np.array([np.hypot(RADAR_R1, h - RADAR_R2)])", "np.array([RADAR_R1**2 + (h - RADAR_R2) ** 2])"),
    # radar_jacobian
    Mistake("radar_jacobian", "inverted", "dr/dh = r / (h - r2), upside down",
            "(h - RADAR_R2) / h_rng", "h_rng / (h - RADAR_R2)"),
    Mistake("radar_jacobian", "wrong-column", "the derivative put in the velocity column",
            "[[(h - RADAR_R2) / h_rng, 0.0, 0.0]]", "[[0.0, (h - RADAR_R2) / h_rng, 0.0]]"),
    Mistake("radar_jacobian", "not-normalised", "dr/dh = h - r2: the derivative of r^2 / 2, not of r",
            "(h - RADAR_R2) / h_rng", "(h - RADAR_R2)"),
    # marginal
    Mistake("marginal", "no-qr", "S_I = S[idx][:, idx]: the block of S, without the QR of (22)",
            'S_I = np.linalg.qr(S[:, idx], mode="r")', "S_I = S[np.ix_(idx, idx)]"),
    Mistake("marginal", "sorted-index", "sorts the index vector, losing the order the caller asked for",
            "idx = np.asarray(idx, dtype=int).reshape(-1)", "idx = np.sort(np.asarray(idx, dtype=int).reshape(-1))"),
    Mistake("marginal", "rows-not-columns", "QR of the rows S[idx, :] transposed, not of the columns",
            'np.linalg.qr(S[:, idx], mode="r")', 'np.linalg.qr(S[idx, :].T, mode="r")'),
    # conditional
    Mistake("conditional", "no-permutation", "QR of S itself, without selecting and permuting the columns",
            'np.linalg.qr(S[:, np.concatenate([idx_b, idx_a])], mode="r")', 'np.linalg.qr(S, mode="r")'),
    Mistake("conditional", "a-before-b", "columns ordered [S_A, S_B]: conditions the wrong way round",
            "np.concatenate([idx_b, idx_a])", "np.concatenate([idx_a, idx_b])"),
    Mistake("conditional", "no-transpose", "R1^-1 where (31) has R1^-T",
            'trans="T"', 'trans="N"'),
    Mistake("conditional", "innovation-sign", "mu_B - x_B where (31) has x_B - mu_B",
            "x_b - mu[idx_b]", "mu[idx_b] - x_b"),
    # plot_ballistic_coefficient
    Mistake("plot_ballistic_coefficient", "2-sigma", "draws the 95% band, mean +/- 2 std, as the 99.7% one",
            "c_mean - 3 * c_std, c_mean + 3 * c_std", "c_mean - 2 * c_std, c_mean + 2 * c_std"),
    Mistake("plot_ballistic_coefficient", "variance-band", "mean +/- 3 c_std**2: the variance used as a spread",
            "c_mean - 3 * c_std, c_mean + 3 * c_std", "c_mean - 3 * c_std**2, c_mean + 3 * c_std**2"),
    Mistake("plot_ballistic_coefficient", "no-legend", "no legend: truth, estimate and band cannot be told apart",
            '    ax.legend(loc="upper right")\n', ""),
    Mistake("plot_ballistic_coefficient", "truth-missing", "plots the estimate twice, never the truth",
            "ax.plot(t, c_true,", "ax.plot(t, c_mean,"),
)
