"""The messages of the visible checks read as sentences, for the solved notebook and for every
catalogued mistake; and an exception raised inside a student's function is explained."""

from __future__ import annotations

import re

import numpy as np
import pytest

from autograder import cells
from autograder.authoring.visible_checks import visible_verdicts
from autograder.labs import Lab
from autograder.catalogues.mistakes import catalogue
from course.checks import check_array, count, explain, is_plural
from course.starship import check_square_root
from over_labs import over_labs

# "1 fixes", "1 random estimates": a count of one with a plural noun.
ONE_WITH_PLURAL = re.compile(r"(?<![\d.,\-])\b1 (?:random )?([a-z]+s)\b")
NOT_PLURAL = {"is", "was", "has", "does", "minus", "plus", "less", "class", "mass"}
# "2 fix", "60 time": a count above one with a singular noun the labs count.
MANY_WITH_SINGULAR = re.compile(
    r"(?<![\d.,\-])\b(?:[02-9]|\d{2,}) (?:random )?(fix|estimate|time|point|particle|step|reading|hour|run|drift|sample)\b(?!\w)"
)
# "the estimates ... is not right", "x_a ... are not right"
VERDICT = re.compile(r"^(?:\w+: )?(.*?) (is|are) not right", re.MULTILINE)
# "the estimates contains NaN", "x_a contain NaN"
NAN_VERDICT = re.compile(r"^(?:\w+: )?(.*?) (contains|contain) NaN", re.MULTILINE)


def grammar_problems(message: str) -> list[str]:
    """What this test can check of a message's grammar: counts and the agreement of its verdict."""
    problems = [f"'1 {m.group(1)}'" for m in ONE_WITH_PLURAL.finditer(message) if m.group(1) not in NOT_PLURAL]
    problems += [f"'{m.group(0)}'" for m in MANY_WITH_SINGULAR.finditer(message)]
    for subject, verb in VERDICT.findall(message):
        if (verb == "are") != is_plural(subject):
            problems.append(f"'{subject} {verb} not right'")
    for subject, verb in NAN_VERDICT.findall(message):
        if (verb == "contain") != is_plural(subject):
            problems.append(f"'{subject} {verb} NaN'")
    return problems


def test_the_grammar_checks_catch_what_they_claim_to():
    assert grammar_problems("trailing_mean(y, order=3) on 1 random fixes is not right") == ["'1 fixes'"]
    assert grammar_problems("the estimates of a constant from fixes [2, 2] is not right: expected")
    assert grammar_problems("x_a on 2 time is not right")
    assert grammar_problems("x_a for the fix y = [12 mi, 70 mph] is not right: expected [11. 69.]") == []
    assert grammar_problems("the variances after one and two fixes are not right") == []
    assert grammar_problems("the estimates contains NaN or infinite entries: [nan]") == ["'the estimates contains NaN'"]
    assert grammar_problems("x_a contains NaN or infinite entries: [nan]") == []
    assert is_plural("the first four estimates after changing the last fix"), "a student review: '... fix is not right'"
    assert not is_plural("the first estimate") and is_plural("the last two covariances")
    assert count(1, "random fix") == "1 random fix" and count(3, "random fix") == "3 random fixes"
    assert count(2, "estimate") == "2 estimates" and is_plural("the estimates") and not is_plural("NEES of e")


def _message(error: BaseException, blank: str) -> str:
    return explain(error, error.__traceback__, [blank]) or f"{type(error).__name__}: {error}"


@over_labs
def test_visible_check_messages_of_every_mistake_read_as_sentences(lab: Lab):
    """Each catalogued mistake in place of the model answer, with its blank's visible checks, in the
    solved notebook run in this process (autograder/authoring/visible_checks.py)."""
    mistakes = catalogue(lab)
    model = cells.model_answers(cells.read(lab.source_notebook))
    verdicts = visible_verdicts(lab, [(f"{m.blank}/{m.slug}", m.blank, m.apply(model[m.blank])) for m in mistakes])
    rendered = {key: _message(error, key.split("/")[0]) for key, error in verdicts.items() if error is not None}
    # most mistakes fail their visible checks; those that do must say so in sentences
    assert len(rendered) >= len(mistakes) // 2, sorted(rendered)
    problems = {key: grammar_problems(message) for key, message in rendered.items()}
    assert not {k: p for k, p in problems.items() if p}, {k: (p, rendered[k]) for k, p in problems.items() if p}


def test_an_exception_inside_a_blank_names_the_call_its_inputs_and_a_likely_cause():
    namespace = {"__name__": "__main__", "np": np}
    exec(compile(
        "def gain_information_form(B, H, R):\n"
        "    RinvH = np.linalg.solve(R, H)\n"
        "    return np.linalg.solve(np.linalg.inv(B) - H.T @ RinvH, RinvH.T)\n", "<cell-1>", "exec"), namespace)
    with pytest.raises(np.linalg.LinAlgError) as raised:
        exec(compile("K = gain_information_form(np.diag([4.0, 9.0]), np.eye(2), np.diag([4.0, 1.0]))",
                     "<cell-2>", "exec"), namespace)
    message = explain(raised.value, raised.value.__traceback__, ["gain_information_form"])
    assert message is not None
    assert message.startswith("LinAlgError in your gain_information_form: Singular matrix")
    assert "B = array of shape (2, 2), [[4., 0.], [0., 9.]]" in message
    assert "R = array of shape (2, 2), [[4., 0.], [0., 1.]]" in message
    assert "sign error or a missing term" in message
    # an error outside the student's functions is left alone
    try:
        np.linalg.solve(np.zeros((2, 2)), np.ones(2))
    except np.linalg.LinAlgError as error:
        assert explain(error, error.__traceback__, ["gain_information_form"]) is None


def test_the_shapes_a_check_wants_are_said_for_an_error_about_shapes_only():
    """A student review: an error about NaN probabilities was followed by the check's hint on the result's shape.
    The later shape checks of a call's result speak to a crash about shapes, not to another one."""
    import linecache

    namespace = {"__name__": "__main__", "np": np, "check_array": check_array}
    exec(compile("def draw(w, rng):\n    return rng.choice(len(w), size=len(w), p=w / w.sum())\n", "<cell-3>", "exec"),
         namespace)
    cell = ('k = draw(W, np.random.default_rng(0))\n'
            'check_array(k, "the parents", (3,), "One parent index per particle.")\n')
    linecache.cache["<cell-4>"] = (len(cell), None, cell.splitlines(True), "<cell-4>")

    def message(weights) -> str:
        namespace["W"] = weights
        with pytest.raises(ValueError) as raised:
            exec(compile(cell, "<cell-4>", "exec"), namespace)
        return " ".join(explain(raised.value, raised.value.__traceback__, ["draw"]).split())

    assert "One parent index per particle" not in message(np.array([np.nan, 1.0, 1.0])), "NaN probabilities: not shapes"
    assert "What the check says for this case: One parent index per particle." in message(np.ones((3, 2)))


def test_a_nan_check_agrees_with_its_name_and_a_crash_is_explained_without_the_labs_names():
    """A fairness review of the messages: "the estimates contains NaN"; the explanation of a solve whose shapes do not
    fit spoke of solve(A, b), where A is train-kf's model matrix; `if u:` on an input of two entries was explained as
    a value that the function cannot work with."""
    for name, verb in (("the estimates", "contain"), ("x_a", "contains")):
        for check in (lambda: check_array(np.array([[1.0, np.nan]]), name, (1, 2)),
                      lambda: check_square_root(np.array([[1.0, np.nan], [0.0, 1.0]]), np.eye(2), name)):
            with pytest.raises(AssertionError) as caught:
                check()
            assert str(caught.value).startswith(f"{name} {verb} NaN or infinite entries"), caught.value
    namespace = {"__name__": "__main__", "np": np}
    exec(compile(
        "def gain(B, H, R):\n"
        "    return np.linalg.solve(H @ B @ H.T + R, B @ H.T).T\n"
        "def step(x, u=None):\n"
        "    if u:\n"
        "        x = x + u\n"
        "    return x\n", "<cell-1>", "exec"), namespace)
    for call, blank, said in (("gain(np.eye(2), np.eye(1, 2), np.eye(1))", "gain", "np.linalg.solve(M, b) got shapes"),
                              ("step(np.zeros(2), np.ones(2))", "step", "write `if u is not None:`")):
        with pytest.raises(ValueError) as raised:
            exec(compile(call, "<cell-2>", "exec"), namespace)
        message = " ".join(explain(raised.value, raised.value.__traceback__, [blank]).split())
        assert said in message and "solve(A" not in message, message


def _run_in_kernel(cells_source: list[str], folder) -> tuple:
    """The cells run in a fresh kernel, as a student runs them: the notebook, each cell's error output (or None),
    and each error's text on one line, without colours."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(s) for s in cells_source])
    NotebookClient(nb, timeout=120, allow_errors=True, kernel_name="python3",
                   resources={"metadata": {"path": str(folder)}}).execute()
    errors = [next((o for o in c.outputs if o.output_type == "error"), None) for c in nb.cells]
    text = [" ".join(re.sub(r"\x1b\[[0-9;]*m", "", "\n".join(e.traceback)).split()) if e else "" for e in errors]
    return nb, errors, text


def test_a_check_after_a_blank_that_a_syntax_error_stopped_says_so(tmp_path):
    """A blank whose cell has a SyntaxError defines nothing; its check cell's NameError points at that cell (a
    student trial of reentry-pf found a bare "NameError: name 'pf_step' is not defined"). A name that no cell
    run defines keeps Python's own message."""
    cells_source = [
        "%xmode Minimal\nimport numpy as np\nfrom course.checks import check_close, passed, require",
        "def step(x):\n    return np.array([x, 0.0]",
        'require(step)\ncheck_close(step(1.0), [1.0, 0.0], "step(1)")\npassed("step")',
        'require(later)',
    ]
    _, errors, text = _run_in_kernel(cells_source, tmp_path)
    assert errors[1].ename == "SyntaxError"
    assert text[2] == ("NameError: name 'step' is not defined. The cell with `def step(...)` was run, but it stopped "
                       "with an error before step was defined: most often a SyntaxError (a missing bracket, colon or "
                       "comma, or a wrong indent), which stops the whole cell. Fix the error that cell shows, run it "
                       "again, then this one."), text[2]
    assert errors[3].ename == "NameError" and "was run, but it stopped" not in text[3], text[3]


def test_in_a_kernel_a_check_blames_another_blank_only_when_it_may_be_the_cause_and_says_each_thing_once(tmp_path):
    """A student's kernel. A sign error in gain raises LinAlgError inside it; its check says which call raised it,
    with the inputs and the likely cause. The check of update, which calls gain, blames gain first, as the error
    was raised inside it; Validate's validate() says that once. twice fails for its own reason (a shape error in
    its own line) while scale, which it uses, fails its check with a wrong result: both are said, twice's own error
    first; a blank that failed its check by crashing, and did not crash here, is not blamed. An error
    inside a blank that passes its checks blames nobody else, and a cell that is not a check says what raised,
    then once that a blank it uses fails its checks. An error outside any blank keeps IPython's own traceback."""
    cells_source = [
        "%xmode Minimal\nimport numpy as np\nfrom course.checks import check_close, passed, require, validate",
        "def gain(B, H, R):\n    RinvH = np.linalg.solve(R, H)\n    return np.linalg.solve(np.linalg.inv(B) - H.T @ RinvH, RinvH.T)",
        'require(gain)\nK = gain(np.diag([4.0, 9.0]), np.eye(2), np.diag([4.0, 1.0]))\npassed("gain")',
        "def update(B, H, R):\n    return gain(B, H, R) @ H",
        'require(update)\ncheck_close(update(np.eye(2), np.eye(2), np.eye(2)), 0.5 * np.eye(2), "U")\npassed("update")',
        "validate(update)",
        "validate(gain)",
        "1 / 0",
        'def scale(x):\n    return 3 * x',
        'require(scale)\ncheck_close(scale(1.0), 2.0, "scale(1)", "Multiply by 2.")\npassed("scale")',
        "def twice(x):\n    return np.eye(2) @ scale(x)",
        'require(twice)\ncheck_close(twice(np.ones(3)), [2.0, 2.0, 2.0], "twice(ones(3))")\npassed("twice")',
        'def half(x):\n    return np.eye(2) @ x / 2',
        'require(half)\ncheck_close(half(np.ones(2)), [0.5, 0.5], "half(ones(2))")\npassed("half")',
        "def halves(x):\n    return half(x)",
        'require(halves)\ncheck_close(halves(np.ones(3)), [0.5, 0.5, 0.5], "halves(ones(3))")\npassed("halves")',
        "require(scale)\nscale(np.ones(2)) @ np.ones(3)",
        "def speeds(x):\n    return np.array([x[0], 0.0])",
        'require(speeds)\ncheck_close(speeds(np.ones((2, 3))), np.zeros((2, 3)), "speeds of 3")\npassed("speeds")',
        "def start(x0):\n    return speeds(x0) + 1.0",
        'require(start)\ncheck_close(start(np.zeros(2)), [0.0, 0.0], "start(0)", "Start at x0.")\npassed("start")',
        'def needed(x):\n    raise NotImplementedError("Not written yet: replace this line with your code.")',
        "def user(x):\n    return needed(x)",
        'require(user, needed)\ncheck_close(user(1.0), 1.0, "user(1)")\npassed("user")',
        "validate(user)",
        "outcome = np.linalg.solve(np.zeros((2, 2)), np.ones(2))",
        "print(outcome)",
        "def dyn(x):\n    return (x, x)",
        'require(dyn)\ncheck_array(dyn(np.ones(2)), "dyn(x)", (2,))\npassed("dyn")',
        "def step(x):\n    return dyn(x) * 2.5",
        'require(step)\ncheck_close(step(np.ones(2)), 2.5 * np.ones(2), "step(x)")\npassed("step")',
        "def loop(x):\n    return step(x)",
        'require(loop)\ncheck_close(loop(np.ones(2)), 2.5 * np.ones(2), "loop(x)")\npassed("loop")',
        "def outer(x):\n    return scale(x)",
        'require(outer)\ncheck_close(outer(1.0), 3.0, "outer(1)")\npassed("outer")',
        'require(outer)\nprint("a figure")',
        "def outer2(x):\n    return scale(x) + 1.0",
        'require(outer2)\ncheck_close(outer2(1.0), 3.0, "outer2(1)", "Add 1.")\npassed("outer2")',
        "validate(outer2)",
    ]
    nb, errors, text = _run_in_kernel(cells_source, tmp_path)
    assert [i for i, e in enumerate(errors) if e is None] == [0, 1, 3, 8, 10, 12, 13, 14, 17, 19, 21, 22, 27, 29, 31, 33, 34, 35, 36], text
    # a crash inside step, whose own check failed because of dyn: both are named, dyn as where to start (the student
    # review of issue 34: pf_step was blamed, tracking_dynamics, whose tuple pf_step multiplied, was not named)
    assert text[32].startswith("The error was raised inside your step, which does not pass its own visible checks yet."), text[32]
    assert "Its check in turn points at your dyn: start there." in text[32], text[32]
    # a name that an earlier cell sets, after the line where it stopped (the student review of issue 34: a bare
    # "NameError: name 'history' is not defined" under a figure, when the cell that runs the filter had failed)
    assert text[26] == ("NameError: name 'outcome' is not defined. A cell above sets it, at the line `outcome = "
                        "np.linalg.solve(np.zeros((2, 2)), np.ones(2))`, but that cell stopped with an error before "
                        "outcome got its value. Run it again and fix its error first: this cell needs what it makes."), text[26]
    # a check that stopped because another blank is not written: Validate says that, not "run the check cell"
    # (the student review of issue 34: it said "has not passed its visible checks since you last defined it")
    # once, and shortly (a student review: Validate quoted the check cell's whole message, nested)
    assert text[24] == ("NotPassingYet: user does not pass its visible checks yet: the check cell needs needed(), which "
                        "you have not written yet."), text[24]
    assert text[2].startswith("LinAlgError in your gain: Singular matrix"), text[2]
    assert "`K = gain(np.diag([4.0, 9.0]), np.eye(2), np.diag([4.0, 1.0]))` of this cell" in text[2]
    assert "B = array of shape (2, 2), [[4., 0.], [0., 9.]]" in text[2]
    assert "sign error or a missing term" in text[2]
    assert text[4].startswith("The error was raised inside your gain, which does not pass its own visible checks "
                              "yet. Make it pass its checks first"), text[4]
    assert "LinAlgError in your update (raised inside your gain): Singular matrix It was raised at the line" in text[4], text[4]
    # the certain cause first, then the first line of the check's error, once (not its whole message again)
    assert errors[5].ename == "NotPassingYet" and text[5] == (
        "NotPassingYet: update does not pass its visible checks yet: its check stopped with an error raised inside "
        "your gain, which does not pass its own visible checks yet. Fix it first. The error: LinAlgError in your "
        "update (raised inside your gain): Singular matrix."), text[5]
    assert text[6] == ("NotPassingYet: gain does not pass its visible checks yet. Its check cell above says: LinAlgError "
                       "in your gain: Singular matrix."), text[6]
    assert errors[7].ename == "ZeroDivisionError" and "in your" not in text[7]
    # twice's own error first, then scale, once
    assert text[11].startswith("ValueError in your twice: matmul"), text[11]
    assert text[11].endswith("This may come from your scale, which twice uses: it does not pass its own visible "
                             "checks yet. Make it pass its checks first (its check cell says what is wrong), then run "
                             "this cell again."), text[11]
    # raised inside half, which passes its checks: halves alone is named
    assert text[15].startswith("ValueError in your halves (raised inside your half): matmul") and "does not pass" not in text[15], text[15]
    assert "at the line `return np.eye(2) @ x / 2` of half" in text[15], text[15]
    assert text[16].startswith("ValueError: matmul") and text[16].endswith(
        "This may come from your scale, which this cell uses: it does not pass its own visible checks yet. Make "
        "it pass its checks first (its check cell says what is wrong), then run this cell again."), text[16]
    # a cell that shows results says first that a blank it needs fails its checks (the student review of issue 34:
    # wrong numbers printed with nothing to tell); a check cell does not (its own message says it)
    printed = ["".join(o.get("text", "") for o in c.outputs if o.output_type == "stream") for c in nb.cells]
    assert " ".join(printed[16].split()) == ("Note: your scale does not pass its visible checks yet, so what this cell "
                                             "shows may be wrong."), printed[16]
    assert "Note:" not in printed[11]
    # and of a blank that the blanks it needs call (the fairness review of castaway-bob: a figure's note named
    # kalman_step, run_rank2 and run_rank4, not the joseph_covariance they call, which was at fault)
    assert " ".join(printed[35].split()).startswith("Note: your scale does not pass its visible checks yet"), printed[35]
    # a wrong value from a blank whose callee fails its checks: the callee first, then the check's own finding, in the
    # check cell and in Validate (the fairness review of castaway-bob: a correct run_rank4 was told first to build A
    # from alpha, and only then that transition_matrix, which it calls, failed its checks)
    assert text[37] == ("This may come from your scale, which outer2 uses: it does not pass its own visible checks yet. "
                        "Make it pass its checks first (its check cell says what is wrong), then run this cell again. "
                        "AssertionError: outer2(1) is not right: expected 3 but got 4. Add 1."), text[37]
    assert text[38] == ("NotPassingYet: outer2 does not pass its visible checks yet. This may come from your scale, which "
                        "outer2 uses: it does not pass its own visible checks yet. Its check cell above says: outer2(1) is "
                        "not right. Add 1."), text[38]
    # speeds crashed in its own check (a ragged array for a matrix input) and did not raise here: start fails for its
    # own reason, and speeds is not blamed
    assert text[18].startswith("ValueError in your speeds:"), text[18]
    assert text[20] == "AssertionError: start(0) is not right: expected [0. 0.] but got [1. 1.]. Start at x0.", text[20]
    # said once: no message holds another's, and no sentence is said twice
    for said in text:
        sentences = re.split(r"(?<=\.) ", said)
        assert "said:" not in said and "(The" not in said and len(sentences) == len(set(sentences)), said


VISIBLY_FAILED = {
    "train-kf": ("gain_information_form/R-diagonal-reciprocal", "run_filter/update-before-predict", "nees/root",
                 "nees/divided-by-n", "kupdate/joseph-eye-2"),
    "castaway-bob": ("joseph_covariance/swapped-transposes", "run_rank2/restarts", "run_rank4/flow-at-new-time",
                     "run_rank4/handout-Q", "joseph_covariance/right-not-transposed", "kalman_step/input-inside-A",
                     "run_rank2/global-sigma-gps", "run_rank4/flow-at-fix", "run_rank4/flow-at-predicted-position",
                     "run_rank4/position-noise", "kalman_step/if-u", "run_rank4/global-sigma-gps",
                     "run_rank4/global-sigma-F", "run_rank4/global-sigma-F-spread"),
    "nonlinear-filters": ("moment_error/unweighted", "moment_error/degree-at-most", "bootstrap_pf_step/bearing-not-wrapped",
                          "bootstrap_pf_step/noise-before-f", "unscented_points/centre-weight-one-over-n-plus-kappa",
                          "ekf_update/angle-index-hard-coded", "ekf_update/wraps-every-component",
                          "bootstrap_pf_step/noise-L-untransposed"),
    "reentry-pf": ("run_particle_filter/health-made-every-step", "run_particle_filter/drops-innovation-std",
                   "run_particle_filter/ess-from-info"),
    "reentry-srekf": ("sqrt_time_update/noise-transposed", "sqrt_measurement_update/noise-transposed",
                      "sqrt_measurement_update/noise-variance"),
}
"""Mistakes that passed the visible checks until issue 30 added a hand-checkable case for each (a 2-state filter
that moves, a full R, a current that changes in time, ...), or a fairness review did (a NEES that is not 1, a scalar
state in kupdate, ...): the visible checks must keep failing them. The last four
of nonlinear-filters passed them until the fairness review of that lab added a case with kappa = 2, the angle at other
places of the measurement (p = 1, and the bearing first of p = 2), and a 2-D process noise with a non-diagonal Q.
The reentry ones passed them until the fairness review of those labs added a run with scripted parents (N = 3), a
non-diagonal S_Q and a non-diagonal S_R (reentry-pf's roots, counted by hand then, are now kept by the given
ResamplingHealth: made afresh at every step, it counts the latest parents, and the scripted run still sees it). castaway-bob's run_rank4/position-noise passed them until the science review
found case (d) too loose for it (8e-8 of the variance, under the default rtol of 1e-7). castaway-bob's kalman_step/if-u
passed them, as every u they gave had one entry, until the fairness review of the messages added a u of two.
castaway-bob's run_rank4/global-sigma-gps passed them until the fairness review of castaway-bob's checks (helper-42)
found that no case of run_rank4 gave another sigma_gps (case (g) now does); its sigma_F ones until the second round
of that review found the same of sigma_F (case (h)). reentry-pf's run_particle_filter/drops-innovation-std passed them
until a student trial's follow-up added a run with innovation_std = (1, 1, 1) and a look at the width of v's band;
its ess-from-info until the fairness review of issue 33's ResamplingHealth added the ESS at t_1."""

VISIBLE_MESSAGES = {
    "train-kf": {"nees/root": ("take no square root", None),
                 # n = 1: np.eye(2) in the Joseph form raises in a matrix product; the call's line says why
                 "kupdate/joseph-eye-2": ("np.eye(len(x_f))", None),
                 # the fairness review of the messages: an h in minutes was asked whether sigma was 15/60, and a predict that
                 # adds a Q of its own was sent to the order of A @ B @ A.T (a case with B = 0 now comes first)
                 "process_noise/hours-as-minutes": ("not the 1 minute of dt_min", "15/60 in place of 15"),
                 "predict/global-Q": ("add the Q that predict is given as its argument", "order of the product")},
    "castaway-bob": {"joseph_covariance/right-not-transposed": ("symmetric by construction", None),
                     "run_rank4/flow-at-fix": ("not at the last fix", None),
                     "run_rank4/position-noise": ("drives Bob's own velocity w, not his position", None),
                     "run_rank2/restarts": ("from the previous estimate and covariance", "expected 1 but got 0"),
                     # the fairness review of the messages: `if u:` passed every case (each u had one entry) and crashed
                     # in run_rank4's check; run_rank4's last check named Q as the cause, whatever blank was wrong
                     "kalman_step/if-u": ("write `if u is not None:`", None),
                     "run_rank4/handout-Q": ("If your transition_matrix, kalman_gain, joseph_covariance and kalman_step "
                                             "are right, look at Q", None),
                     # the fairness review of castaway-bob's checks (helper-42): a Q from the standard deviation was told to
                     # pair estimate k with fix k, an R from it to look at Q, a gain from P (or a P- without Q) to look at the
                     # state update, an input added to P too that the prediction is x- = A x + u, and a centred window
                     # was shown its own estimates as "expected"
                     "run_rank2/Q-std": ("Q = sigma_walk^2 I", "Update estimate k with fix k"),
                     "run_rank4/R-std": ("R = sigma_gps^2 I, a variance", None),
                     "kalman_step/gain-from-old-P": ("not from the P you were given", None),
                     "kalman_step/no-Q": ("P- = A P A^T + Q = 2", None),
                     "trailing_mean/includes-future": ("must not use fixes that come after it", "expected"),
                     "run_rank4/global-sigma-gps": ("not from the notebook's SIGMA_GPS", None)},
    "nonlinear-filters": {
        # the check of P_yy comes before the check of the mean, which a P_yy without R makes wrong as well
        "sigma_point_update/no-R": ("Did you add R to P_yy", None),
        # yes/no checks say in words what is wrong, not "expected 1 but got 0"
        "ekf_update/bearing-not-wrapped": ("moves the target by more than 30 m", "expected 1 but got 0"),
        "bootstrap_pf_step/noise-before-f": ("the variance of x_new - f(x)", "expected 1 but got 0"),
        # the angle's hint points at the cause without the line of code that fixes it
        "ekf_update/angle-index-hard-coded": ("whose indices are listed in angles", "wrap_angle(innovation["),
        "ekf_update/wraps-every-component": ("a range difference of 10 m is not an angle", "wrap_angle(innovation["),
    },
    "reentry-srekf": {
        # the check of S_R comes first, on a case whose residual is zero and whose S is diagonal
        "sqrt_measurement_update/noise-variance": ("S_R is the upper-triangular square root of R", "the residual is y - h(mu)"),
        "sqrt_measurement_update/noise-transposed": ("S_R is the upper-triangular square root of R", "not with 1"),
        # the name of the handout's S_I reads as a matrix, not as "S_I for idx = [2, 4, 0][2, 0]"
        "marginal/no-qr": ("but its entry [2, 0] (row 2, column 0", "[2, 4, 0]["),
        # the fairness review of the messages: (H @ S).T for S @ H.T was told of the residual's sign (S is checked first)
        "sqrt_measurement_update/H-S-transposed": ("not (H @ S).T = S.T @ H.T", "the residual is y - h(mu)"),
    },
    "reentry-pf": {
        # the fairness review of the messages: the means of the copies of particle 0 were checked before their spread,
        # which an innovation of the wrong size, or one draw for all, moves as well
        "pf_step/variance-innovation": ("standard deviations, not variances", "Propagate before you resample"),
        "pf_step/innovation-shared": ("its own draw of the innovation", "old weights w"),
        # a student trial: a loop that dropped innovation_std passed every visible check (a case with a small noise now
        # looks at the spread of v)
        "run_particle_filter/drops-innovation-std": ("innovation_std=innovation_std", None),
    },
}
"""Mistakes whose visible check must say a given phrase, the hint that points at the cause, and must not say
another (None: no such phrase). The fairness reviews found the square root's hint on a case whose NEES is 1, which
a square root leaves alone; a Joseph form without its right transpose told only the size of P^ - P^.T; a P_yy
without R told to check the innovation's sign; yes/no checks that said "expected 1 but got 0"; a stacked R or S_R.T
told of the residual's sign or of the blocks' sizes. The science review found a Joseph form with np.eye(2) whose hint
never showed (with n = 1 a matrix product raises first, and its explanation pointed at the transposes), and an
angle's hint that gave the line of code that wraps it. The fairness review of the messages found eight more that named
another cause than the one made (each entry of it says which)."""


@pytest.mark.parametrize("lab", [Lab(lab_id) for lab_id in sorted(VISIBLE_MESSAGES)], ids=sorted(VISIBLE_MESSAGES))
def test_the_visible_checks_name_the_cause(lab: Lab):
    """Each listed mistake in place of the model answer: the first visible check it fails names its cause."""
    mistakes = {f"{m.blank}/{m.slug}": m for m in catalogue(lab)}
    model = cells.model_answers(cells.read(lab.source_notebook))
    listed = [mistakes[key] for key in VISIBLE_MESSAGES[lab.id]]
    verdicts = visible_verdicts(lab, [(f"{m.blank}/{m.slug}", m.blank, m.apply(model[m.blank])) for m in listed])
    problems = []
    for key, (said, unsaid) in VISIBLE_MESSAGES[lab.id].items():
        message = "" if verdicts[key] is None else " ".join(_message(verdicts[key], key.split("/")[0]).split())
        if said not in message or (unsaid is not None and unsaid in message):
            problems.append(f"{key}: {message or 'passes the visible checks'}")
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("lab", [Lab(lab_id) for lab_id in sorted(VISIBLY_FAILED)], ids=sorted(VISIBLY_FAILED))
def test_the_visible_checks_fail_the_mistakes_they_were_given_a_case_for(lab: Lab):
    """Each listed mistake in place of the model answer, with its blank's visible checks, in the solved
    notebook run in this process (autograder/authoring/visible_checks.py)."""
    mistakes = {f"{m.blank}/{m.slug}": m for m in catalogue(lab)}
    model = cells.model_answers(cells.read(lab.source_notebook))
    listed = [mistakes[key] for key in VISIBLY_FAILED[lab.id]]
    verdicts = visible_verdicts(lab, [(f"{m.blank}/{m.slug}", m.blank, m.apply(model[m.blank])) for m in listed])
    passed_wrongly = [key for key, error in verdicts.items() if error is None]
    assert not passed_wrongly, f"these mistakes pass the visible checks of {lab.id}: {passed_wrongly}"


def test_while_grading_only_a_check_cells_crash_is_explained_and_validate_does_nothing(tmp_path, monkeypatch):
    """nbgrader's autograder (NBGRADER_EXECUTION=autograde): the feedback page explains a crash in a visible check
    cell, whose inputs are the notebook's own, with the check's hint; a crash in any other cell, which could come
    from a hidden case, keeps IPython's own message; validate() lets every blank through."""
    from course.checks import GRADING

    monkeypatch.setenv("NBGRADER_EXECUTION", GRADING)
    cells_source = [
        "%xmode Minimal\nimport numpy as np\nfrom course.checks import check_array, passed, require, validate",
        "def grow(B):\n    return np.eye(2) @ B",
        'require(grow)\ncheck_array(grow(np.eye(3)), "grow(I3)", (3, 3), "Size the identity from B.")\npassed("grow")',
        "grow(np.eye(3))",
        "validate(grow)",
    ]
    nb, errors, text = _run_in_kernel(cells_source, tmp_path)
    assert [i for i, e in enumerate(errors) if e is None] == [0, 1, 4], text
    assert text[2].startswith("ValueError in your grow: matmul") and "Size the identity from B." in text[2], text[2]
    assert "B = array of shape (3, 3)" in text[2]
    assert "in your grow" not in text[3] and "B = array" not in text[3], text[3]


def test_in_a_kernel_a_write_into_an_argument_is_said_first_and_of_the_blank_that_made_it(tmp_path):
    """A student review: a kalman_step that wrote into P made its own check show a wrong "expected" value (the check
    had passed one array as P and Q), and the write was said only once every check had passed; a kalman_step that
    wrote into the y that run_rank2 gave it made run_rank2's check fail. The write is said first, and of the blank
    that made it. A blank that crashes inside one that passes its checks names the failing blank that fed it."""
    cells_source = [
        "%xmode Minimal\nimport numpy as np\nfrom course.checks import check_close, passed, require, validate",
        "def kstep(x, P, Q):\n    P += Q\n    return x, P",
        'require(kstep)\none, Q1 = np.eye(1), 2 * np.eye(1)\nx, P = kstep(np.zeros(1), one, Q1)\n'
        'check_close(P, one + Q1, "P", "Predict P- = P + Q.")\npassed("kstep")',
        "def inner(y):\n    y -= 1.0\n    return y",
        'require(inner)\ncheck_close(inner(np.ones(2)), [0.0, 0.0], "inner(1)")\npassed("inner")',
        "def outer(Y):\n    return inner(Y[0])",
        'require(outer)\ncheck_close(outer(np.ones((2, 2))), [0.0, 0.0], "outer(1)")\npassed("outer")',
        "validate(outer)",
        "def shape():\n    return np.eye(2, 3)",
        'require(shape)\ncheck_close(shape(), np.eye(3, 2), "shape()")\npassed("shape")',
        "def apply(H, x):\n    return H @ x",
        'require(apply)\ncheck_close(apply(np.eye(2), np.ones(2)), [1.0, 1.0], "apply")\npassed("apply")',
        "def run(x):\n    return apply(shape(), x)",
        'require(run)\ncheck_close(run(np.ones(2)), [1.0, 1.0], "run")\npassed("run")',
    ]
    nb, errors, text = _run_in_kernel(cells_source, tmp_path)
    assert text[2].startswith("AssertionError: kstep changed its argument P in place"), text[2]
    assert "That can also change what this check compares with. What the check said after that: AssertionError: P is " \
           "not right" in text[2], text[2]
    assert text[4].startswith("RuleBroken: inner changed its argument y in place"), text[4]
    assert text[6].startswith("RuleBroken: inner changed its argument y in place") and text[6].endswith(
        "(outer calls inner: fix inner first.)"), text[6]
    assert text[7].startswith("NotPassingYet: outer does not pass its visible checks yet. Its check cell above says: "
                              "RuleBroken: inner changed its argument y in place"), text[7]
    # raised inside apply, which passes its checks: shape, which fails its own and gave apply its H, is named
    assert text[13].startswith("ValueError in your run (raised inside your apply): matmul"), text[13]
    assert "This may come from your shape, which run uses: it does not pass its own visible checks yet" in text[13]
