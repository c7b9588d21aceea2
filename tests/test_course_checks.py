"""The check helpers that students see: they catch what they claim to, with useful messages."""

import numpy as np
import pytest

from autograder import cells
from course.checks import (NotWrittenYet, check_array, check_axis_label, check_close, check_pair, check_symmetric,
                           check_true, label_has_unit, parse_unit, random_spd, require)
from over_labs import over_labs
from random_draws import random_draws


@over_labs
def test_require_recognises_every_stub_that_nbgrader_generates(lab):
    for cell in cells.read(lab.release_notebook).cells:
        if cells.is_code_answer(cell):
            # the names the set-up cell gives the stubs (defaults such as INNOVATION_STD) are the reference module's too
            namespace = dict(vars(lab.reference()))
            exec(cell.source, namespace)
            [func] = [v for k, v in namespace.items() if callable(v) and k == cells.grade_id(cell)]
            with pytest.raises(NotWrittenYet, match=rf"needs {func.__name__}\(\), which you have not written yet"):
                require(func)


def test_require_lets_written_functions_through_and_lists_every_missing_one():
    def stub_a():
        raise NotImplementedError("Not written yet: replace this line with your code.")

    def stub_b():
        raise NotImplementedError("Not written yet: replace this line with your code.")

    def written():
        return 1

    require(written)
    with pytest.raises(NotWrittenYet, match=r"needs stub_a\(\) and stub_b\(\), .* Write them in their cells"):
        require(stub_a, written, stub_b)


def test_check_close_shows_expected_values_only_when_asked():
    with pytest.raises(AssertionError, match=r"expected\n\[1\. 2\.\]\nbut got\n\[1\. 3\.\]\. Hint"):
        check_close([1.0, 3.0], [1.0, 2.0], "x", "Hint")
    # a number on one line, as a sentence reads it (NumPy would print "1." and "16.", then ". Hint")
    with pytest.raises(AssertionError, match=r"^x is not right: expected 1 but got 16\. Hint$"):
        check_close(16.0, 1.0, "x", "Hint")
    with pytest.raises(AssertionError) as hidden:
        check_close([1.0, 3.0], [1.0, 2.0], "x", show_expected=False)
    assert "largest difference from the reference is 1" in str(hidden.value) and "2." not in str(hidden.value)
    check_close([1.0, 2.0 + 1e-12], [1.0, 2.0], "x")


def test_a_yes_no_check_says_in_words_what_is_wrong():
    check_true(True, "never said")
    check_true(np.array([True, True]), "never said")
    with pytest.raises(AssertionError) as raised:
        check_true(np.array([True, False]), "the correction is larger than 30 m", "Wrap the bearing.")
    assert str(raised.value) == "The correction is larger than 30 m. Wrap the bearing."
    assert "expected" not in str(raised.value)


def test_shape_and_pair_checks_say_what_was_wrong():
    with pytest.raises(AssertionError, match=r"should have shape \(2, 2\), but it has shape \(2,\)"):
        check_array(np.zeros(2), "B", (2, 2))
    with pytest.raises(AssertionError, match="is a tuple of 2 items"):
        check_array((np.zeros(2), np.eye(2)), "x", (2,))
    with pytest.raises(AssertionError, match="NaN or infinite"):
        check_array(np.array([np.nan, 1.0]), "x", (2,))
    with pytest.raises(AssertionError, match=r"should return two things, \(x_f, B_f\)"):
        check_pair(np.zeros(2), "predict", "x_f", "B_f")


@random_draws(false_fail=0.0, why="exact facts: F F^T + n I is symmetric with eigenvalues >= n; the draw picks F")
def test_symmetry_check_and_random_spd(seed):
    rng = np.random.default_rng([seed, 1])
    for n in range(1, 7):
        S = random_spd(rng, n)
        check_symmetric(S, "S")
        assert np.all(np.linalg.eigvalsh(S) > 0)
    with pytest.raises(AssertionError, match="should be symmetric"):
        check_symmetric(np.array([[1.0, 0.1], [0.0, 1.0]]), "B")


# the unit of each axis of the labs' plot blanks: labels that must pass, and labels that must fail
LABELS_WITH_UNIT = {
    "s": ["Time [s]", "Time (s)", "Time (seconds)", "time $t$ / s", "t [sec]", "time in s", "time in seconds",
          "Time, s", "$t$ [s]", r"$t\,/\,\mathrm{s}$", r"Time $[\mathrm{s}]$", "Time [Seconds]", "time t (s)",
          "Time (secs)", "t/s", "Time [s] since the first range"],
    "m^2/kg": ["c [m^2/kg]", "c (m²/kg)", "c [m$^2$/kg]", "$c$ / m$^2$ kg$^{-1}$", "ballistic coefficient c (m^2 kg^-1)",
               "c [m2/kg]", "c in m^2 per kg", "c [m**2/kg]", "ballistic coefficient [square metres per kilogram]",
               "c [m² kg⁻¹]", "c / (m^2/kg)", r"c [$\mathrm{m}^2/\mathrm{kg}$]", r"c [$\frac{m^2}{kg}$]",
               "c [m^2 / kg]", "Ballistic coefficient, m^2/kg", "c [m^2.kg^-1]", "c [m²kg⁻¹]", "c [m².kg⁻¹]",
               "c [m²·kg⁻¹]"],
    "kg/(m s^2)": ["beta [kg/(m s^2)]", r"$\beta$ [kg/(m s$^2$)]", "beta (kg m^-1 s^-2)", "beta / kg m⁻¹ s⁻²",
                   "beta [kg.m^-1.s^-2]", "beta [kg m⁻¹s⁻²]"],
    "kg/m^2": ["areal density [kg/m^2]", "areal density [kg m$^{-2}$]", "areal density (kg/m²)"],
}
LABELS_WITHOUT_UNIT = {
    "s": ["", "Time", "Time [m]", "Time (min)", "Time [ms]", "Time index", "Time [-]", "seconds", "[s]",
          "Time (samples)", "Times", "time step k"],
    "m^2/kg": ["", "c", "c [kg/m^2]", "c [kg m$^{-2}$]", "c [m/kg]", "Ballistic coefficient", "c [-]", "c [m^2]",
               "c [1/kg]", "c [s]", "c [m^2.kg]", "c [m²kg]", "c [m.kg^-1]", "c [2.5 m^2/kg]"],
    "kg/(m s^2)": ["beta", "beta [kg/(m s)]", "beta [kg m s^-2]"],
    "kg/m^2": ["areal density [m^2/kg]", "areal density [kg m$^{2}$]"],
}


@pytest.mark.parametrize("unit, label", [(u, label) for u, labels in LABELS_WITH_UNIT.items() for label in labels])
def test_an_axis_label_may_write_its_unit_any_common_way(unit, label):
    assert label_has_unit(label, unit)
    check_axis_label(label, unit, "plot", "time axis", "ax.set_xlabel('Time [s]')")


@pytest.mark.parametrize("unit, label", [(u, label) for u, labels in LABELS_WITHOUT_UNIT.items() for label in labels])
def test_an_axis_label_without_its_unit_fails_and_says_what_to_write(unit, label):
    assert not label_has_unit(label, unit)
    with pytest.raises(AssertionError, match=r"plot: label the time axis with the quantity and its unit \(.*\), "
                                             r"written any common way, for example ax.set_xlabel\('Time \[s\]'\); "):
        check_axis_label(label, unit, "plot", "time axis", "ax.set_xlabel('Time [s]')")


def test_units_parse_to_their_base_units():
    assert parse_unit("m^2/kg") == parse_unit("m^2 kg^-1") == parse_unit("(m^2)/(kg)") == {"m": 2, "kg": -1}
    assert parse_unit("kg/(m s^2)") == parse_unit("kg m^-1 s^-2") == {"kg": 1, "m": -1, "s": -2}
    assert parse_unit("m^2kg^-1") == parse_unit("kg^-1m^2") == {"m": 2, "kg": -1} and parse_unit("m2kg") is None
    assert parse_unit("seconds") == {"s": 1} and parse_unit("m/m") == {}
    assert parse_unit("min") is None and parse_unit("ms") is None and parse_unit("") is None


@random_draws(false_fail=0.0, why="whether a call wrote into an argument or drew from np.random does not depend on the draws")
def test_the_rule_watch_sees_writes_into_arguments_and_draws_from_numpys_global_generator(seed):
    """What a blank's check cell reports at passed() (course.checks._RuleWatch): each array argument a call wrote into,
    and a draw from np.random when the call was given a generator; an honest call, nothing."""
    import sys

    from course.checks import _RuleWatch

    def step(x, y, rng=None, *, scale=1.0):
        if rng is None:
            x += y  # writes into x
            return x
        if scale < 0:
            return x + np.random.standard_normal(x.shape)  # draws from the global generator
        return x + scale * rng.standard_normal(x.shape) + y

    def watched(*args, **kwargs):
        watch = _RuleWatch({step.__code__: "step"})
        sys.setprofile(watch)
        try:
            step(*args, **kwargs)
        finally:
            sys.setprofile(None)
        return watch.changed, watch.global_random

    assert watched(np.zeros(2), np.ones(2)) == ([("step", "x")], [])
    assert watched(np.zeros(2), np.ones(2), np.random.default_rng(seed), scale=-1.0) == ([], ["step"])
    assert watched(np.zeros(2), np.ones(2), np.random.default_rng(seed)) == ([], [])
