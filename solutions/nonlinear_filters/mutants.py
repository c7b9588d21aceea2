"""Mutants of nonlinear-filters' reference that compute the same answer (autograder/authoring/mutants.py):
each id with the reason a reviewer can check. Every other mutant must fail its blank's hidden test.

The reference is written for stacks of problems (m (..., n), P (..., n, n)); the blanks take one
problem (m (n,), P (n, n), X (N, n), logw (N,)), as their docstrings in the notebook say. On those
arrays an axis counted from the end is the same as one counted from the start: for a matrix,
swapaxes(-1, -2), swapaxes(1, -2), swapaxes(-1, 0) are all its transpose; swapaxes(-2, -2) and
swapaxes(0, -2) leave it as it is, which changes nothing where the matrix is symmetric already.
"""

_TRANSPOSE = "on a matrix (the blank takes one problem, not a stack) this swapaxes is the transpose all the same"
_SYMMETRIC = ("P_new is symmetric to rounding: averaging it with itself instead of its transpose changes it by "
              "rounding only")
_ONE_D = "on a 1-D array (one problem, not a stack) axis 0 is axis -1"

EQUIVALENT: dict[tuple[str, str], str] = {
    ("cut4_points", "operator@7:52"): "signs are +-1: dividing by them is multiplying by them",
    ("moment_error", "constant@4:106/plus-one"): "reshape infers the one negative size, whatever its value: -2 as -1",
    ("moment_error", "operator@9:11"): "half is used only where the power is even (np.where), and there powers / 2 "
                                       "is powers // 2",
    **{("sigma_point_predict", mutant): _TRANSPOSE for mutant in ("sign@10:38/drop", "constant@10:43/zero",
                                                                 "constant@11:53/zero")},
    **{("sigma_point_predict", mutant): _SYMMETRIC for mutant in ("sign@11:48/drop", "constant@11:49/plus-one",
                                                                 "constant@11:49/zero")},
    **{("sigma_point_update", mutant): _TRANSPOSE for mutant in (
        "sign@14:38/drop", "constant@14:43/zero", "sign@15:38/drop", "constant@15:43/zero", "sign@17:44/drop",
        "constant@17:49/zero", "sign@17:62/drop", "constant@17:67/zero", "sign@20:38/drop", "constant@20:43/zero",
        "constant@21:53/zero")},
    **{("sigma_point_update", mutant): _SYMMETRIC for mutant in ("sign@21:48/drop", "constant@21:49/plus-one",
                                                                "constant@21:49/zero")},
    **{("ekf_update", mutant): _TRANSPOSE for mutant in (
        "sign@8:27/drop", "constant@8:32/zero", "sign@9:43/drop", "constant@9:48/zero", "sign@13:31/drop",
        "constant@13:36/zero", "sign@13:60/drop", "constant@13:65/zero", "constant@14:53/zero")},
    **{("ekf_update", mutant): _SYMMETRIC for mutant in ("sign@14:48/drop", "constant@14:49/plus-one",
                                                        "constant@14:49/zero")},
    ("ekf_update", "constant@12:24/zero"): "m is 1-D: m.shape[0] is m.shape[-1]",
    ("bootstrap_pf_step", "constant@8:17/zero"): "X is (N, n): X.shape[0] is X.shape[-2]",
    ("bootstrap_pf_step", "operator@10:8"): "the noise is N(0, Q), and so is its negative: the text asks for a draw "
                                            "from N(0, Q), and the draws of -v have that law",
    ("bootstrap_pf_step", "index@15:59/plus-one"): "R is square: R.shape[1] is R.shape[0]",
    ("bootstrap_pf_step", "index@15:59/minus-one"): "R is square: R.shape[-1] is R.shape[0]",
    ("bootstrap_pf_step", "constant@15:67/plus-one"): "R is square: R.shape[1] is R.shape[0]",
    ("bootstrap_pf_step", "sign@16:57/drop"): "the innovations are (N, p): axis 1 is axis -1",
    ("bootstrap_pf_step", "constant@18:54/zero"): _ONE_D,
    ("bootstrap_pf_step", "constant@18:66"): "logw is 1-D: logsumexp without keepdims is a scalar, which "
                                             "broadcasts as the kept (1,) does",
    ("bootstrap_pf_step", "constant@20:49/zero"): _ONE_D,
    ("bootstrap_pf_step", "comparison@21:15"): "the effective sample size equals ess_fraction N exactly with "
                                               "probability zero",
    ("bootstrap_pf_step", "constant@23:92/zero"): "X is (N, n): axis 0 is axis -2",
}
