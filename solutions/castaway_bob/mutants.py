"""Mutants of castaway-bob's reference that compute the same answer (autograder/authoring/mutants.py):
each id with the reason a reviewer can check. Every other mutant must fail its blank's hidden test."""

EQUIVALENT: dict[tuple[str, str], str] = {
    ("trailing_mean", "drop-statement@7:4"): "y is already a float array (n, 2): np.asarray(y, dtype=float) is y",
    ("joseph_covariance", "index@3:18/plus-one"): "P is square: P.shape[1] is P.shape[0]",
    ("joseph_covariance", "index@3:18/minus-one"): "P is square: P.shape[-1] is P.shape[0]",
    ("joseph_covariance", "constant@3:26/plus-one"): "P is square: P.shape[1] is P.shape[0]",
    ("run_rank4", "constant@26:49/plus-one"): "flow(p, t) reads the position's two coordinates only: xs[k - 1, :3] "
                                              "adds the drift velocity's first entry, which no current reads",
    ("track_rmse", "sign@4:55/drop"): "the errors are (n, 2): axis 1 is axis -1",
}
