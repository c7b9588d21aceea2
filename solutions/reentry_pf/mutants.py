"""Mutants of reentry-pf's reference that compute the same answer (autograder/authoring/mutants.py):
each id with the reason a reviewer can check. Every other mutant must fail its blank's hidden test."""

_D_IN_RANGE = ("for readings up to tens of sigma from the cloud, the text's far case, the exponent of (d) stays far "
               "inside exp's range, so the shift by the largest log-weight cancels in the normalisation; the text "
               "asks for the shift in (b), and (d) exponentiated as written is a correct answer (the alternative "
               "multinomial-counts)")

EQUIVALENT: dict[tuple[str, str], str] = {
    ("simulate_radar", "drop-statement@11:4"): "t is a float array (the text's readings' times): np.asarray is t",
    ("simulate_radar", "constant@14:101/scaled"): "a relative tolerance of 1.5e-10 for RK45 gives the same trajectory "
                                                  "within the check's tolerance, which other correct solvers need",
    ("simulate_radar", "constant@14:113/scaled"): "an absolute tolerance of 1.5e-8 m for RK45 gives the same trajectory "
                                                  "within the check's tolerance, which other correct solvers need",
    ("simulate_radar", "index@20:48/minus-one"): "t is 1-D: t.shape[-1] is t.shape[0]",
    ("pf_step", "constant@22:39/scaled"): "the model is autonomous: tracking_dynamics ignores its time argument",
    ("pf_step", "drop-statement@33:4"): "the fitness weights are normalised already: their cumulative sum ends at 1 "
                                        "to rounding, and searchsorted of uniforms in [0, 1) picks the same parents",
    ("pf_step", "operator@36:12"): "the artificial process noise is N(0, D), and so is its negative: the draws of -w "
                                   "have the law the text asks for",
    ("pf_step", "operator@41:19"): _D_IN_RANGE,
    ("pf_step", "drop-term@41:19/right"): _D_IN_RANGE,
}
