"""Mutants of train-kf's reference that compute the same answer (autograder/authoring/mutants.py):
each id with the reason a reviewer can check. Every other mutant must fail its blank's hidden test."""

EQUIVALENT: dict[tuple[str, str], str] = {
    ("gain_information_form", "index@2:8/plus-one"): "B is square: B.shape[1] is B.shape[0]",
    ("gain_information_form", "index@2:8/minus-one"): "B is square: B.shape[-1] is B.shape[0]",
    ("gain_information_form", "constant@2:16/plus-one"): "B is square: B.shape[1] is B.shape[0]",
    ("run_filter", "index@14:23/minus-one"): "x0 is 1-D: x0.shape[-1] is x0.shape[0]",
}
