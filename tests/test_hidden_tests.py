"""The hidden tests fail every catalogued mistake the way its entry says, never show the reference's
values, and run on the reference, without nbgrader.

This is the fast twin of the grading round trip (tests/round_trip.py): it runs each blank's
``check_<blank>`` directly on the function each mistake defines, and on the reference.
"""

import ast
import inspect
import re
import traceback
from collections import Counter

import numpy as np
import pytest

from autograder import cells
from autograder.catalogues.mistakes import catalogue
from course.checks import check_close
from lab_code import answer_file, define, hidden_tests
from over_labs import LABS, over_labs


# -- smoke tests: they fail only if a check crashes or rejects the reference ----------------------------

@over_labs
def test_smoke_every_check_runs_and_accepts_the_reference(lab):
    """A smoke test (the reference cannot fail its own comparison unless a check is broken): every
    blank has a check, and it runs to the end on the reference function."""
    reference = lab.reference()
    for name in cells.blank_names(cells.read(lab.source_notebook)):
        getattr(hidden_tests(lab), f"check_{name}")(getattr(reference, name))


@over_labs
def test_smoke_every_check_accepts_the_model_answer_as_the_notebook_defines_it(lab):
    """A smoke test: the model answer, compiled from the notebook as a student's cell would be,
    passes (it differs from the reference module only by where it is defined)."""
    answers = cells.model_answers(cells.read(lab.source_notebook))
    for name in cells.blank_names(cells.read(lab.source_notebook)):
        getattr(hidden_tests(lab), f"check_{name}")(define(lab, answers[name], name))


# -- the mistakes -----------------------------------------------------------------------------------------

@over_labs
def test_each_blank_has_at_least_two_catalogued_mistakes(lab):
    counts = Counter(m.blank for m in catalogue(lab))
    blanks = cells.blank_names(cells.read(lab.source_notebook))
    assert set(counts) <= set(blanks), f"mistakes for unknown blanks: {set(counts) - set(blanks)}"
    assert all(counts[b] >= 2 for b in blanks), {b: counts[b] for b in blanks}
    ids = [m.student_id(lab) for m in catalogue(lab)]
    assert len(ids) == len(set(ids)), "mistake slugs are unique within a blank"


MISTAKES = [(lab, m) for lab in LABS for m in catalogue(lab)]


def _failure(lab, mistake, diagnosis: bool = True) -> BaseException | None:
    """What the blank's hidden test raises on the mistaken answer (None: it passes it), with the
    diagnosis's hint in its message, or without running the diagnosis (which re-raises the same
    exception: tests/test_diagnosis.py tests what it adds)."""
    answer = cells.model_answers(cells.read(lab.source_notebook))[mistake.blank]
    wrong = define(lab, mistake.apply(answer), mistake.blank)
    check = getattr(hidden_tests(lab), f"check_{mistake.blank}")
    try:
        (check if diagnosis else check.__wrapped__)(wrong)
    except Exception as error:  # noqa: BLE001 (which exception it is, is what the test checks)
        return error
    return None


@pytest.mark.parametrize("lab, mistake", MISTAKES, ids=[m.student_id(lab) for lab, m in MISTAKES])
def test_each_mistake_fails_its_blanks_hidden_tests_as_catalogued(lab, mistake):
    """A wrong answer fails with the hidden test's AssertionError, raised by the test, not by the
    student's code; a mistake catalogued with ``raises=`` another exception crashes the student's
    function with it. A check that crashes on its own (a TypeError in the test) fails this test."""
    error = _failure(lab, mistake, diagnosis=False)
    assert error is not None, f"{mistake.student_id(lab)} passes the hidden test of {mistake.blank}"
    where = [frame.filename for frame in traceback.extract_tb(error.__traceback__)]
    described = f"{type(error).__name__}: {error}"
    assert type(error) is mistake.raises, (
        f"{mistake.student_id(lab)} should fail with {mistake.raises.__name__} (its catalogue entry), "
        f"but the hidden test raised {described}")
    if issubclass(mistake.raises, AssertionError):  # the verdict, or a rule of the call (isolate.CallRuleBroken)
        assert where[-1] != answer_file(mistake.blank), f"the student's code raised it, not the hidden test: {described}"
        assert str(error).strip(), "the hidden test failed without a message for the student"
    else:
        assert answer_file(mistake.blank) in where, f"raised outside the student's function: {described}"


# -- the hidden tests hide the reference's values -----------------------------------------------------------

def _show_expected_parameter(function) -> bool:
    try:
        return "show_expected" in inspect.signature(function).parameters
    except (TypeError, ValueError):
        return False


@over_labs
def test_every_comparison_in_the_hidden_tests_hides_the_expected_values(lab):
    """Every call of a helper that can print the expected values (it has ``show_expected``) passes
    ``show_expected=False`` literally: feedback shows the message to the student."""
    module = hidden_tests(lab)
    tree = ast.parse(inspect.getsource(module))
    calls = 0
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        name = node.func.id if isinstance(node.func, ast.Name) else getattr(node.func, "attr", None)
        target = getattr(module, name, None) if isinstance(node.func, ast.Name) else None
        if isinstance(node.func, ast.Attribute) and isinstance(node.func.value, ast.Name):
            target = getattr(getattr(module, node.func.value.id, None), name, None)
        if target is None or not _show_expected_parameter(target):
            continue
        calls += 1
        keywords = {k.arg: k.value for k in node.keywords}
        value = keywords.get("show_expected")
        assert isinstance(value, ast.Constant) and value.value is False, (
            f"{module.__name__} line {node.lineno}: {name}(...) without show_expected=False shows the reference's values")
    assert calls > 0, f"{module.__name__} compares nothing with a check helper"


NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def _matches(number: float, values: np.ndarray, half_unit: float) -> bool:
    k = np.searchsorted(values, number)
    near = values[max(k - 1, 0): k + 1]
    return bool(near.size) and float(np.min(np.abs(near - number))) <= half_unit


def leaked_numbers(message: str, values: np.ndarray, inputs: np.ndarray = np.array([]), digits: int = 4) -> list[str]:
    """The numbers in ``message`` written with at least ``digits`` significant digits that equal one
    of ``values`` to the precision they are written with, and none of the ``inputs`` (a case may
    name its inputs, and a reference output may repeat one). An error size printed with :.3g never
    qualifies; a matrix printed by np.array2string(precision=6) does."""
    values, inputs = np.sort(values[np.isfinite(values)]), np.sort(inputs[np.isfinite(inputs)])
    leaks = []
    for text in NUMBER.findall(message):
        mantissa, _, exponent = text.lower().lstrip("+-").partition("e")
        significant = mantissa.replace(".", "").lstrip("0")
        if len(significant) < digits:
            continue
        decimals = len(mantissa.partition(".")[2])
        half_unit = 0.5 * 10.0 ** (int(exponent or 0) - decimals) * (1 + 1e-9)
        if _matches(float(text), values, half_unit) and not _matches(float(text), inputs, half_unit):
            leaks.append(text)
    return leaks


def test_the_leak_detector_finds_expected_values_in_a_message():
    """The oracle below can fail: check_close's message with show_expected=True is caught, and the
    same comparison's message with show_expected=False is not."""
    expected = np.array([[1.234567, -0.0421337], [3.14159265, 2.0e-5]])
    for show, leaks in ((True, True), (False, False)):
        with pytest.raises(AssertionError) as caught:
            check_close(expected + 0.01, expected, "B_f", show_expected=show)
        assert bool(leaked_numbers(str(caught.value), expected.ravel())) is leaks, str(caught.value)


def _recording(function, inputs: list, outputs: list):
    def wrapper(*args, **kwargs):
        inputs.append((args, kwargs))
        result = function(*args, **kwargs)
        outputs.append(result)
        return result
    return wrapper


def _floats(value, out: list[float]) -> None:
    """Every float inside a returned value (arrays, tuples, lists, dicts, dataclass-like objects other
    than matplotlib's)."""
    if isinstance(value, (float, int, np.number, np.ndarray)) and not isinstance(value, bool):
        array = np.asarray(value)
        if array.dtype.kind in "fc":
            out.extend(np.abs(array.ravel()).astype(float).tolist() if array.dtype.kind == "c" else array.ravel().tolist())
    elif isinstance(value, (tuple, list)):
        for item in value:
            _floats(item, out)
    elif isinstance(value, dict):  # keyword arguments too
        for item in value.values():
            _floats(item, out)
    elif hasattr(value, "__dict__") and not callable(value) and not type(value).__module__.startswith("matplotlib"):
        for item in vars(value).values():  # not an Axes (the diagnosis hands one to the reference): it is cyclic
            _floats(item, out)


@pytest.mark.parametrize("lab, mistake", MISTAKES, ids=[m.student_id(lab) for lab, m in MISTAKES])
def test_a_failing_hidden_test_shows_no_reference_number(lab, mistake, monkeypatch):
    """The message a student reads when this mistake fails its hidden test holds no number that the
    reference computed while the test ran, other than the inputs it was given (every function of
    solutions.<module> is recorded). The check's own message is read: the diagnosis adds only a
    hint, which quotes no number (tests/test_diagnosis.py), and its own runs of the mistakes on a
    large case produce so many numbers that one of them matches a count the check states by chance."""
    reference = lab.reference()
    inputs: list = []
    outputs: list = []
    for name, function in vars(reference).items():
        if inspect.isfunction(function) and function.__module__ == reference.__name__:
            monkeypatch.setattr(reference, name, _recording(function, inputs, outputs))
    error = _failure(lab, mistake, diagnosis=False)
    assert error is not None
    given: list[float] = []
    computed: list[float] = []
    _floats(inputs, given)
    _floats(outputs, computed)
    assert leaked_numbers(str(error), np.array(computed, dtype=float), np.array(given, dtype=float)) == [], str(error)
