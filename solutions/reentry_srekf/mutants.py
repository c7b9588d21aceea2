"""Mutants of reentry-srekf's reference that compute the same answer (autograder/authoring/mutants.py):
each id with the reason a reviewer can check. Every other mutant must fail its blank's hidden test."""

_ARRAYS = "the blank is given float NumPy arrays (the notebook's calls and the hidden tests'): np.asarray returns them"
_RESHAPE = "reshape infers the one negative size, whatever its value: -2 as -1"
_STYLE = ("a style of the figure (transparency, line width, grid): the text asks for the truth, the estimate, the "
          "band, the axis labels with units and a legend, and leaves the styling to the student")

EQUIVALENT: dict[tuple[str, str], str] = {
    ("marginal", "drop-statement@6:4"): _ARRAYS,
    ("marginal", "drop-statement@7:4"): "idx is an integer array of indices already (1-D): the conversion changes nothing",
    ("marginal", "constant@7:46/plus-one"): _RESHAPE,
    ("conditional", "drop-statement@8:4"): _ARRAYS,
    ("conditional", "drop-statement@9:4"): "idx_a is an integer array of indices already (1-D)",
    ("conditional", "constant@9:50/plus-one"): _RESHAPE,
    ("conditional", "drop-statement@10:4"): "idx_b is an integer array of indices already (1-D)",
    ("conditional", "constant@10:50/plus-one"): _RESHAPE,
    ("conditional", "drop-statement@11:4"): "x_b is a 1-D float array already",
    ("conditional", "constant@11:48/plus-one"): _RESHAPE,
    ("sqrt_time_update", "drop-statement@9:4"): _ARRAYS,
    ("sqrt_measurement_update", "drop-statement@9:4"): _ARRAYS,
    ("sqrt_measurement_update", "drop-statement@10:4"): "y is given as a 1-D float array (m,), as the docstring says",
    ("plot_ballistic_coefficient", "drop-statement@4:4"): _ARRAYS,
    ("plot_ballistic_coefficient", "constant@6:69/scaled"): _STYLE,
    ("plot_ballistic_coefficient", "constant@6:85/plus-one"): _STYLE,
    ("plot_ballistic_coefficient", "constant@8:44/scaled"): _STYLE,
    ("plot_ballistic_coefficient", "constant@9:45/scaled"): _STYLE,
    ("plot_ballistic_coefficient", "drop-statement@11:4"): _STYLE,
    ("plot_ballistic_coefficient", "constant@11:24/scaled"): _STYLE,
}
