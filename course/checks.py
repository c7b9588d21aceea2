"""Check helpers for the visible tests in the lab notebooks.

Each helper raises ``AssertionError`` with a message that says what was expected, what your
function gave, and, where we can guess it, what to look at. They check properties; they never
compute a blank's answer.
"""

from __future__ import annotations

import ast
import inspect
import linecache
import os
import re
import sys
import textwrap
import tokenize
import traceback
from typing import Any, Callable

import numpy as np

NOT_WRITTEN = "Not written yet: replace this line with your code."
"""The message of the stub that stands in a blank until you write it."""


class NotWrittenYet(Exception):
    """A cell needs a blank that still holds its stub."""


class RuleBroken(AssertionError):
    """A check cell's call of a blank broke a rule every lab states (``_RuleWatch``); its message names the blank."""


class NotPassingYet(AssertionError):
    """``validate``: a blank does not pass its visible checks yet (its message already says why, once)."""


def require(*functions: Callable) -> None:
    """Stop a cell early, with a clear message, if a blank it needs is not written yet. In a cell that
    shows results (not a blank's check cell), say first which of the blanks it needs do not pass their
    visible checks: what the cell prints may then be wrong, with nothing else to tell."""
    _require_written(functions)
    if _hooks_installed() and _cell["checks"] is None:
        names = [getattr(f, "__name__", "") for f in functions]
        # and the blanks those call (a fairness review: a figure's note named kalman_step, run_rank2 and run_rank4,
        # but not the joseph_covariance they call, which was the one at fault)
        # the blanks they call first: a student starts with those (a fairness review: joseph_covariance came last)
        failing = _not_passing(list(dict.fromkeys([c for name in names for c in reversed(_calls(name))] + names)))
        if failing:
            w = _upstream(failing)
            print(wrap(f"Note: {w['your']} {w['does']} not pass {w['its']} visible checks yet, so what this cell "
                        "shows may be wrong."))


def _require_written(functions: tuple[Callable, ...]) -> None:
    """``require`` without the note: raise NotWrittenYet if one of ``functions`` still holds its stub."""
    if _hooks_installed():
        _cell["uses"].extend(getattr(f, "__name__", "") for f in functions)
    missing = [f.__name__ for f in functions if NOT_WRITTEN in getattr(getattr(f, "__code__", None), "co_consts", ())]
    if missing:
        w = _agreeing(len(missing))
        raise NotWrittenYet(
            f"This cell needs {listed([f'{name}()' for name in missing])}, which you have not written yet. Write "
            f"{w['it']} in {w['its']} {w['cell']} above (replace the line that raises NotImplementedError), run "
            f"{w['it']}, then run this cell again."
        )


def _not_written_message(caller: str | None, stub: str, here: str) -> str:
    """What a cell says when the stub of the blank ``stub`` raised inside it, called by the blank ``caller`` (None:
    by the cell itself): a student review found the whole crash report of a stub, blamed as a failing blank."""
    needs = f"{caller}() calls {stub}()" if caller and caller != stub else f"{here[0].upper()}{here[1:]} needs {stub}()"
    return wrap(f"NotWrittenYet: {needs}, which you have not written yet. Write it in its cell above (replace the line "
                f"that raises NotImplementedError), run it, then run {here} again.")


def check_array(value: Any, name: str, shape: tuple[int, ...], hint: str = "") -> np.ndarray:
    """Check that ``value`` is a finite NumPy array of the given shape, and return it as one."""
    if isinstance(value, tuple):
        raise AssertionError(
            f"{name} should be one array of shape {shape}, but it is a tuple of {len(value)} items. "
            f"{hint}".strip()
        )
    array = _as_array(value, name, f"one array of shape {shape}", hint)
    if array.shape != shape:
        # a student review: a column vector (n, 1) for a vector (n,) got no hint
        column = len(shape) == 1 and array.ndim == 2 and sorted(array.shape) == [1, shape[0]]
        vector = ("A column (n, 1) or a row (1, n) is not a vector (n,): keep vectors 1-D (x = A @ x, not "
                  "A @ x[:, None]), or flatten with .ravel(). " if column else "")
        raise AssertionError(
            f"{name} should have shape {shape}, but it has shape {array.shape}"
            f"{' (a single number)' if array.shape == () else ''}. {vector}{hint}".strip()
        )
    if not np.all(np.isfinite(array)):
        # a student review: an empty window's NaN got only the hint on the shape
        raise AssertionError(f"{name} {'contain' if is_plural(name) else 'contains'} NaN or infinite entries: {array}. "
                             "NaN comes from 0 / 0, the mean of an empty slice or the square root of a negative number; "
                             f"inf from a division by zero. {hint}".strip())
    return array


def _single_precision(value: Any) -> str:
    """The name of ``value``'s dtype if it is a floating-point type less precise than float64 (float32, float16)."""
    dtypes = [np.asarray(v).dtype for v in (value if isinstance(value, (tuple, list)) else [value])
              if isinstance(v, (np.ndarray, np.floating))]
    return next((str(d) for d in dtypes if d.kind in "fc" and d.itemsize < (8 if d.kind == "f" else 16)), "")


def _as_array(value: Any, name: str, wanted: str, hint: str) -> np.ndarray:
    """``value`` as an array of floats, or an AssertionError that says what it is instead (None, a dict, a
    list of arrays of different shapes...)."""
    if value is None:
        raise AssertionError(f"{name} should be {wanted}, but it is None: does the function end with a return? "
                             f"{hint}".strip())
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise AssertionError(f"{name} should be {wanted}, but it is a {type(value).__name__} that is not an array "
                             f"of numbers. {hint}".strip()) from None


def check_pair(value: Any, name: str, first: str, second: str) -> tuple[Any, Any]:
    """Check that a function returned a pair, such as ``(x_f, B_f)``, and unpack it."""
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        returned = _returned(value)  # a student review: "does it end with a return?."
        raise AssertionError(
            f"{name} should return two things, ({first}, {second}), for example "
            f"`return {first}, {second}`. It returned {returned}{'' if returned.endswith('?') else '.'}"
        )
    return value[0], value[1]


def _returned(value: Any) -> str:
    """What a function returned, said so that the difference from what was wanted shows."""
    if value is None:
        return "None: does it end with a return?"
    if isinstance(value, (tuple, list)):
        return f"a {type(value).__name__} of {count(len(value), 'item')}"
    if isinstance(value, np.ndarray):
        return f"one array of shape {value.shape}, not a tuple of two"
    return f"a {type(value).__name__}"


def check_close(
    actual: Any,
    expected: Any,
    name: str,
    hint: str = "",
    *,
    rtol: float = 1e-7,
    atol: float = 1e-9,
    show_expected: bool = True,
) -> None:
    """Check that ``actual`` equals ``expected`` to within ``rtol`` and ``atol``.

    With ``show_expected=False`` the message gives only the size of the error, not the
    expected numbers.
    """
    expected = np.asarray(expected, dtype=float)
    single = _single_precision(actual)
    actual = _as_array(actual, name, f"an array of shape {expected.shape}", hint)
    if actual.shape != expected.shape:
        raise AssertionError(
            f"{name} should have shape {expected.shape}, but it has shape {actual.shape}. {hint}".strip()
        )
    if np.allclose(actual, expected, rtol=rtol, atol=atol):
        return
    error = np.max(np.abs(actual - expected))
    if show_expected and expected.ndim == 0:
        # a number reads on one line ("expected 1 but got 16"), without NumPy's trailing point ("1.")
        detail = f"expected {float(expected):.6g} but got {float(actual):.6g}"
    elif show_expected:
        detail = f"expected\n{np.array2string(expected, precision=6)}\nbut got\n{np.array2string(actual, precision=6)}"
    else:
        detail = f"the largest difference from the reference is {error:.3g}"
    if single:
        # the check's own hint names a formula, which is not what is wrong (a review of issue 30: float32 answers)
        hint = (f"It is in single precision ({single}, about 7 significant digits): compute in float64, NumPy's "
                "default, and do not convert your arrays to float32.")
    raise AssertionError(f"{name} {'are' if is_plural(name) else 'is'} not right: {detail}. {hint}".strip())


_DETERMINERS = {"the", "your", "its", "their", "both", "all", "these", "those", "first", "last", "next", "two",
                "three", "four", "five", "six", "seven", "eight", "nine", "ten"}
"""Words before the head of a noun phrase: determiners, and the counts and orders that precede it ("the first four
estimates"): a student review found "the first four estimates ... is not right"."""
_SINGULAR_ENDINGS = ("ss", "us", "is", "ics")


def is_plural(name: str) -> bool:
    """Whether a check's name such as "the estimates of a constant" is a plural noun phrase.

    The head is the first word after determiners, counts and orders; it is plural if it is a lower-case English
    plural ("estimates", "variances"), and singular for symbols and acronyms ("x_a", "NEES").
    """
    words = name.replace(",", " ").split()
    while words and words[0].lower() in _DETERMINERS:
        words = words[1:]
    head = words[0] if words else ""
    return head.isalpha() and head.islower() and head.endswith("s") and not head.endswith(_SINGULAR_ENDINGS)


def count(n: int, noun: str) -> str:
    """"1 fix", "2 fixes": a number with its noun in agreement (the last word is made plural)."""
    if n == 1:
        return f"{n} {noun}"
    *first, last = noun.split(" ")
    return " ".join([f"{n}", *first, last + ("es" if last.endswith(("s", "x", "ch", "sh")) else "s")])


def check_symmetric(matrix: Any, name: str, hint: str = "") -> None:
    """Check that a covariance matrix is symmetric, to rounding error."""
    matrix = np.asarray(matrix, dtype=float)
    scale = max(1.0, float(np.max(np.abs(matrix))))
    asymmetry = float(np.max(np.abs(matrix - matrix.T)))
    if asymmetry > 1e-9 * scale:
        raise AssertionError(
            f"{name} should be symmetric, like every covariance matrix, but {name} - {name}.T "
            f"has an entry of size {asymmetry:.3g}. {hint}".strip()
        )


def check_true(condition: Any, what_is_wrong: str, hint: str = "") -> None:
    """Check a yes/no property of a result (``condition``, a bool or an array of them, all true).

    ``what_is_wrong`` says in words what it means when the property does not hold ("the correction for a
    bearing near +-pi is larger than 30 m"): the message says that, not "expected 1 but got 0".
    """
    if not bool(np.all(condition)):
        raise AssertionError(f"{what_is_wrong[:1].upper()}{what_is_wrong[1:]}. {hint}".strip())


def random_spd(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random symmetric positive definite n x n matrix with a modest condition number."""
    factor = rng.standard_normal((n, n))
    return factor @ factor.T + n * np.eye(n)


# ---------------------------------------------------------------------------------------------
# Axis labels: a quantity and its unit, written any common way
# ---------------------------------------------------------------------------------------------
_UNIT_SPELLINGS = {
    "s": ("s", "sec", "secs", "second", "seconds"),
    "m": ("m", "metre", "metres", "meter", "meters"),
    "kg": ("kg", "kilogram", "kilograms", "kilogramme", "kilogrammes"),
}
"""The base units the labs' axes use, each with the ways of writing it (words in any case)."""
_SPELLING_TO_UNIT = {spelling: unit for unit, spellings in _UNIT_SPELLINGS.items() for spelling in spellings}
_UNIT_TOKEN = re.compile(
    "(?P<unit>" + "|".join(sorted((f"(?i:{w})" if len(w) > 2 else w for w in _SPELLING_TO_UNIT), key=len, reverse=True))
    + r")(?:\s*\^\s*\(?(?P<power>[+-]?\d+)\)?(?![\d^])|(?P<digits>\d+)(?![\w^])|(?![\w^]))"
)
"""A unit and its power. After a power ("m^2", "m²") the next unit may follow at once ("m²kg⁻¹"), as it is plain
where one ends; a bare unit or digits ("m", "m2") must end the word ("ms" is not metres times seconds)."""
_SUPERSCRIPTS = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻⁺", "0123456789-+")


def _plain_label(text: str) -> str:
    """A label with LaTeX and Unicode notation spelled plainly: m$^{-2}$, m⁻², m**-2 all become m^-2."""
    text = text.replace("$", "").replace("−", "-").replace("**", "^")
    text = re.sub(r"\\(?:left|right|big|Big)\s*(?=[(\[\])])", "", text)
    text = re.sub(r"\\(?:mathrm|text|textrm|mathit|operatorname|rm)\s*", "", text)
    text = re.sub(r"\^\s*\{([^{}]*)\}", r"^\1", text)
    text = re.sub(r"\\[dt]?frac\s*\{([^{}]*)\}\s*\{([^{}]*)\}", r"(\1)/(\2)", text)
    text = re.sub(r"\\(?:cdot|times)|[·⋅×*]", " ", text)
    text = re.sub(r"\\[,;:! ]|~|\\quad", " ", text)
    text = text.replace("{", "").replace("}", "").replace("\\", "")
    text = re.sub(r"[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+", lambda m: "^" + m.group(0).translate(_SUPERSCRIPTS), text)
    text = re.sub(r"(?<=[A-Za-z0-9)])\.(?=\s*[A-Za-z(])", " ", text)  # a dot as the product, "m^2.kg^-1"; not 2.5
    text = re.sub(r"(?i)\bsquare\s+(\w+)", r"\1^2", text)
    text = re.sub(r"(?i)(\w+)\s+squared\b", r"\1^2", text)
    return re.sub(r"(?i)\s+per\s+", " / ", text)


def _depth_change(char: str) -> int:
    return 1 if char in "([" else -1 if char in ")]" else 0


def _balanced(text: str) -> bool:
    """Whether every bracket of ``text`` closes, and none closes before it opens."""
    depth = 0
    for char in text:
        depth += _depth_change(char)
        if depth < 0:
            return False
    return depth == 0


def _top_level(text: str, separator: str) -> list[int]:
    """Positions of ``separator`` in ``text`` outside every bracket."""
    depth, found = 0, []
    for i, char in enumerate(text):
        depth += _depth_change(char)
        if depth == 0 and char == separator:
            found.append(i)
    return found


def _unbracketed(text: str) -> str:
    """``text`` without the brackets around all of it: "(m^2/kg)" -> "m^2/kg", "(m) / (kg)" unchanged."""
    text = text.strip()
    while len(text) > 1 and text[0] + text[-1] in ("()", "[]") and _balanced(text[1:-1]):
        text = text[1:-1].strip()
    return text


def parse_unit(text: str) -> dict[str, int] | None:
    """The base units of a unit written plainly, as {unit: power} ("m^2/kg" -> {"m": 2, "kg": -1}), or
    None if ``text`` is not a product and quotient of the labs' units."""
    text = _unbracketed(text)
    if not text or not _balanced(text):
        return None
    cuts = [-1, *_top_level(text, "/"), len(text)]
    powers: dict[str, int] = {}
    for k, (start, stop) in enumerate(zip(cuts, cuts[1:])):
        part = _unbracketed(text[start + 1:stop])
        tokens = list(_UNIT_TOKEN.finditer(part))
        if not tokens or re.sub(r"\s+", "", _UNIT_TOKEN.sub("", part)):
            return None
        for token in tokens:
            power = int(token.group("power") or token.group("digits") or 1)
            unit = _SPELLING_TO_UNIT.get(token.group("unit")) or _SPELLING_TO_UNIT[token.group("unit").lower()]
            powers[unit] = powers.get(unit, 0) + (power if k == 0 else -power)
    return {unit: power for unit, power in powers.items() if power}


def label_has_unit(label: str, unit: str) -> bool:
    """Whether an axis label names a quantity and gives it the unit ``unit`` (written as "s" or "m^2/kg").

    The unit may be written in brackets ("Time [s]", "c (m²/kg)"), after "in" ("time in seconds"), after
    a comma ("time, s"), or ISO's way after a slash ("time $t$ / s", "c / (m^2/kg)"); in symbols or
    words (s, sec, seconds; m^2/kg, m$^2$ kg$^{-1}$, m^2.kg^-1, m²kg⁻¹, square metres per kilogram).
    Something other than the unit must name the quantity.
    """
    want = parse_unit(unit)
    text = _plain_label(label)
    candidates = []  # (unit text, the rest of the label)
    for match in re.finditer(r"[(\[]", text):
        depth, start = 0, match.start()
        for stop in range(start, len(text)):
            depth += _depth_change(text[stop])
            if depth == 0:
                candidates.append((text[start:stop + 1], text[:start] + text[stop + 1:]))
                break
    for found in re.finditer(r"(?i)\bin\b", text):
        candidates.append((text[found.end():], text[:found.start()]))
    for cut in _top_level(text, "/") + _top_level(text, ","):
        candidates.append((text[cut + 1:], text[:cut]))
    return any(re.search(r"[A-Za-z]", rest) and parse_unit(candidate) == want for candidate, rest in candidates)


def check_axis_label(label: str, unit: str, name: str, axis: str, example: str) -> None:
    """Check that the label of one axis of ``name``'s plot names its quantity with the unit ``unit``
    (see ``label_has_unit``); ``axis`` says which axis in words, ``example`` shows a label that passes."""
    if not label_has_unit(label, unit):
        given = f"its label is '{label}'" if label else "it has no label"
        raise AssertionError(
            f"{name}: label the {axis} with the quantity and its unit ({unit}), written any common way, for "
            f"example {example}; {given}."
        )


def passed(name: str) -> None:
    """Report that a blank passed its visible checks (``validate`` remembers it for this definition), or fail
    if a call of it in this check cell broke a rule that every lab states (see ``_RuleWatch``)."""
    watch = _watch["now"]
    broken = watch.broken(name) if watch is not None else None
    if broken is not None:
        _after_cell()
        raise RuleBroken(broken)
    function = sys._getframe(1).f_globals.get(name)
    if function is not None:
        _passed[name] = function
        _failed.pop(name, None)
    print(f"{name}: all visible checks passed. Hidden tests on random cases run when you are graded.")


# ---------------------------------------------------------------------------------------------
# What a student sees when a check fails, and what Validate checks.
#
# In a student's kernel (JupyterLab, or nbgrader's Validate) importing this module installs two
# IPython hooks: one notes which cell is running (a blank's visible checks end with
# passed("<name>")), and one rewrites an exception that escapes a cell, so that it says which
# call of your function raised it, with which inputs, what such an error usually means and what
# the check says for that call; and, when another blank that the cell uses may be the cause, it
# says so once. In nbgrader's autograder (NBGRADER_EXECUTION=autograde) ``validate`` does nothing
# (points come only from the grader), and only the visible check cells' errors are rewritten, for
# the feedback page: their inputs are the notebook's own, while another cell's error could come
# from a hidden case, whose inputs a message must not show.
# ---------------------------------------------------------------------------------------------

GRADING = "autograde"
"""The value of NBGRADER_EXECUTION while nbgrader autogrades (nbgrader sets it for the kernel)."""

_passed: dict[str, Callable] = {}
"""Blank name -> the function object that last passed its visible checks."""
_failed: dict[str, tuple[Callable, str, bool, tuple[str, ...], bool]] = {}
"""Blank name -> the function that last failed its visible checks, what they said (without blaming another
blank), whether it failed by raising an error of its own (a crash) rather than by a wrong result, the other
blanks its check blamed, and whether the error was raised inside one of those."""
_cell: dict[str, Any] = {"checks": None, "uses": []}
"""The running cell: the blank whose checks it runs (or None), and the blanks it requires."""

_CHECK_CELL = re.compile(r"""^\s*passed\(\s*["'](\w+)["']\s*\)""", re.MULTILINE)

LINE_WIDTH = 80
"""Messages are wrapped to this width: nbgrader's Validate cuts longer lines."""


def _grading() -> bool:
    return os.environ.get("NBGRADER_EXECUTION") == GRADING


def listed(names: list[str]) -> str:
    """'a', 'a and b', 'a, b and c'."""
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def wrap(text: str, first_line_taken: int = 0) -> str:
    """``text`` wrapped to LINE_WIDTH, paragraph by paragraph (the first line shares its width with a prefix)."""
    paragraphs = []
    for i, paragraph in enumerate(text.split("\n")):
        indent = " " * first_line_taken if i == 0 else ""
        paragraphs.append(textwrap.fill(paragraph, LINE_WIDTH, initial_indent=indent, break_long_words=False,
                                        break_on_hyphens=False)[len(indent):])
    return "\n".join(paragraphs)


HEADLINE_CHARS = 400
"""How much of a check's message ``headline`` keeps."""
_NUMBERS = re.compile(r": expected .*? but got .*?(?=\. (?!nan\b|inf\b)[A-Za-z(`]|\.?$)")
"""check_close's numbers ("...: expected [[0. 1.]] but got [[0. 2.]]"), which the notebook shows under the check."""
_SENTENCE_END = re.compile(r"(?<=[a-z0-9)\]'`])\. (?=[A-Z(`])")


def _cut(text: str) -> str:
    """``text`` cut between words to HEADLINE_CHARS, with "..." (not "...." after a full stop)."""
    return text[: HEADLINE_CHARS - 3].rsplit(" ", 1)[0].rstrip(".,;:") + "..."


def _ended(sentence: str) -> str:
    """``sentence`` with a full stop, unless it ends with its own ("Did you invert B and R?", not "R?.")."""
    return sentence if sentence.endswith((".", "?", "!")) else f"{sentence}."


def headline(message: str) -> str:
    """What a check's message says first, on one line: its verdict and the sentence after it (the check's hint),
    without the numbers, the inputs or the error's type when it is an AssertionError (the check's own words);
    at most HEADLINE_CHARS long, cut between words."""
    text = re.sub(r"^AssertionError: ", "", " ".join(message.split()))
    # a crash (explain): its first line, without where it was raised and the inputs
    text = _NUMBERS.sub("", text.split(" It was raised ")[0].split(" got these inputs:")[0])
    first, *rest = [sentence.rstrip(".") for sentence in _SENTENCE_END.split(text)]
    if len(first) > HEADLINE_CHARS:
        return _cut(first)
    for i, sentence in enumerate(rest):  # the hint: its first sentence always, the others as far as they fit whole
        if len(first) + 2 + len(sentence) > HEADLINE_CHARS:
            if i == 0:
                first = _cut(f"{first}. {sentence}")
            break
        first = f"{first}. {sentence}"
    return first


def _current(name: str) -> Callable | None:
    shell = _shell()
    namespace = shell.user_ns if shell is not None else {}
    return namespace.get(name)


def _passes(name: str) -> bool:
    """Whether the blank ``name``, as it is defined now, passed its visible checks."""
    function = _current(name)
    return function is not None and _passed.get(name) is function


def _crashed(name: str) -> bool:
    """Whether the blank ``name``, as it is defined now, failed its visible checks by raising an error itself."""
    failed = _failed.get(name)
    return failed is not None and failed[0] is _current(name) and failed[2]


def _not_passing(names: list[str]) -> list[str]:
    return [name for name in dict.fromkeys(names) if not _passes(name)]


def _agreeing(n: int) -> dict[str, str]:
    """The words that agree with ``n`` blanks: "it ... it ... its cell ... does ... that", or "them ... they ... their cells ...
    do ... those"."""
    one = n == 1
    return {"it": "it" if one else "them", "they": "it" if one else "they", "its": "its" if one else "their",
            "cell": "cell" if one else "cells",
            "does": "does" if one else "do", "that": "that" if one else "those"}


def _upstream(names: list[str]) -> dict[str, str]:
    """The words that agree with a list of blanks: "your kupdate, which does ... its", or "... do ... their"."""
    return {"your": "your " + listed(names), **_agreeing(len(names))}


def validate(function: Callable) -> None:
    """Stop unless ``function`` is written and passes its visible checks (what Validate checks).

    The graded cell below each blank runs this before its hidden tests. It fails while the blank
    still holds its stub, or while its visible checks (the cell above) fail or have not been run
    since it was last defined. When nbgrader autogrades, it does nothing: the hidden tests alone
    give the points, so a visible check that fails because of another blank costs nothing.
    """
    if _grading():
        return
    _require_written((function,))
    name = function.__name__
    if _passed.get(name) is function:
        return
    failed = _failed.get(name)
    if failed is not None and failed[0] is function:
        # the first sentence of what the check cell says, not all of it again (a student review: Validate
        # listed every message twice over, nested)
        said = headline(failed[1])
        message = f"{name} does not pass its visible checks yet. Its check cell above says: {_ended(said)}"
        if failed[1].startswith(f"{NotWrittenYet.__name__}: "):
            needs = _SENTENCE_END.split(" ".join(failed[1].split()))[0].split(": ", 1)[1]
            message = f"{name} does not pass its visible checks yet: {needs[0].lower()}{needs[1:]}."
        if failed[3]:
            w = _upstream(list(failed[3]))
            failing = f"{w['does']} not pass {w['its']} own visible checks yet"
            if failed[4]:  # the certain cause first
                message = (f"{name} does not pass its visible checks yet: its check stopped with an error raised "
                           f"inside {w['your']}, which {failing}. Fix {w['it']} first. The error: {_ended(said)}")
            else:
                user = name if set(failed[3]) <= set(_calls(name)) else "its check"
                blame = f"This may come from {w['your']}, which {user} uses: {w['they']} {failing}."
                # as the check cell says it: a wrong value after the blank that may have made it, a crash before
                message = (f"{name} does not pass its visible checks yet. {blame} Its check cell above says: {_ended(said)}"
                           if failed[1].startswith(f"{AssertionError.__name__}: ") else f"{message} {blame}")
    else:
        message = (f"{name} has not passed its visible checks since you last defined it: run the check "
                   f"cell below {name} and fix what its message says.")
    raise NotPassingYet(wrap(message, len("NotPassingYet: ")))


# What an exception raised inside a student's function usually means: its type, a pattern its message matches
# (lower case), and a sentence. The first entry that matches gives the sentence.
_MEANINGS: list[tuple[str, str, str]] = [
    ("LinAlgError", "singular", "A matrix that you solve with or invert is singular. In a filter that usually means "
     "a sign error or a missing term: a sum such as H B H^T + R or B^-1 + H^T R^-1 H that lost a term, "
     "or subtracts one instead of adding it."),
    ("LinAlgError", "positive definite", "A Cholesky factorisation got a matrix that is not symmetric positive "
     "definite. That usually means a sign error or a missing term in a covariance, or a covariance that is "
     "not symmetric (compute it as A @ B @ A.T, or symmetrise it)."),
    ("LinAlgError", "must be square", "A matrix that you solve with, invert or factorise is not square: check "
     "its shape and your transposes."),
    ("LinAlgError", "at least two-dimensional", "A linear-algebra routine got a 1-D array where it needs a "
     "matrix: give it shape (n, n), for example [[v]] for a single variance."),
    ("LinAlgError", "", "A linear-algebra routine failed on the matrix it was given: check that the matrix is the "
     "one the equation names, square and well conditioned (a sign error or a missing term can break it)."),
    # M, not A: in train-kf and castaway-bob, A is the name of the model's transition matrix
    ("ValueError", r"^solve\w*:.*core dimension", "np.linalg.solve(M, b) got shapes that do not fit: it needs a "
     "square M, (m, m), and a b with m rows, (m,) or (m, k). Check your transposes. (Only if b is a stack of "
     "vectors, shape (T, m): NumPy 2 reads it as one matrix, not as T vectors; solve with b[..., None] and take "
     "[..., 0] of the result.)"),
    ("ValueError", "matmul", "Two arrays in a matrix product (@) have shapes that do not fit. Check the "
     "transposes, the order of the factors, and whether a vector should have shape (n,) or (n, 1)."),
    ("ValueError", "broadcast", "Two arrays have shapes that cannot be combined element by element. Compare "
     "the shapes of the inputs above with the ones your code builds, and check whether you meant a matrix "
     "product (@) rather than *."),
    ("ValueError", "aligned", "Two arrays in a product have shapes that do not fit. Check the transposes and "
     "the order of the factors."),
    ("ValueError", "inhomogeneous|input arrays must have the same shape", "An array was built from pieces of "
     "different shapes, such as an array beside a plain number: give every piece the shape of the arrays "
     "beside it (np.zeros_like(a), np.full_like(a, value) for one of those arrays a) and join them with np.stack."),
    ("ValueError", "concatenation axis must match", "The blocks you join (np.block, np.concatenate, np.vstack) "
     "do not line up: the blocks side by side need the same number of rows, and the blocks one above the "
     "other the same number of columns. Compare the shape of each block."),
    ("ValueError", "probabilities contain nan", "The probabilities you drew with contain NaN. That usually means "
     "every weight underflowed to 0 and normalising divided 0 by 0: work with log-weights and subtract the "
     "largest before you exponentiate."),
    ("ValueError", "probabilities are not non-negative", "Some of the probabilities you drew with are negative: "
     "a weight is never negative. Check the signs in your weights, or your log-weights before np.exp."),
    ("ValueError", "probabilities do not sum to 1", "The probabilities you drew with do not sum to 1: normalise "
     "the weights (w / np.sum(w)) after their last change and before you draw with them."),
    # a student review: `if h > 0:` on an array of altitudes got only the advice on optional arguments
    ("ValueError", "truth value of an array", "An array of several entries was used where Python needs one True or "
     "False (an if, a while, and, or): such an array is neither. For a condition on each entry, as in `if h > 0:` "
     "with an array h, compute both branches with np.where(h > 0, a, b) or use a mask; to ask whether an optional "
     "argument such as u was given, write `if u is not None:`; np.any(...) and np.all(...) ask about all entries."),
    ("ValueError", "", "A function got a value it cannot work with: compare the shapes and values of the "
     "inputs above with what the function expects."),
    # a student review: a percentage p read as a fraction got only the advice on loops
    ("IndexError", "", "An index is out of range: it is too large for its axis. Check how each index is computed, "
     "and the units of what it comes from (a percentage from 0 to 100, a fraction from 0 to 1?), the range of your "
     "loop, and which axis holds time and which holds the state."),
    ("TypeError", "", "A function got arguments it does not accept, or a value of the wrong type. Check "
     "the arguments of each call, and that you call functions and index arrays, not the other way round."),
    ("NameError", "", "A name is not defined: a typo, or a variable that exists only in another cell. A "
     "blank should use only its arguments, the other blanks and what the set-up cell imports."),
    ("UnboundLocalError", "", "A variable is used before it gets a value, for example one set only inside "
     "an if or a loop that did not run."),
    ("ZeroDivisionError", "", "A division by zero: check the denominators, and whether a length or a "
     "count can be zero here."),
    ("AttributeError", "", "A value does not have the attribute or method that the code uses: check its "
     "type (an array, a tuple, a number?)."),
    ("RecursionError", "", "The function calls itself without end: did you call the blank itself where "
     "you meant another function?"),
    ("NotImplementedError", "", "A blank that this one calls is not written yet: write it first."),
]


_SHAPE_ERROR = re.compile(r"shape|matmul|broadcast|aligned|dimension|inhomogeneous|axis|size|index")
"""What the message of an error about the shapes of arrays says."""


def _meaning(error: BaseException) -> str:
    kind, text = type(error).__name__, str(error).lower()
    for name, pattern, meaning in _MEANINGS:
        if kind == name and re.search(pattern, text):
            return meaning
    return "Read the error above and look at the line of your function that raised it."


def _describe(value: Any, room: int = LINE_WIDTH) -> str:
    """A short description of an argument: shape and, when small and they fit in ``room`` columns, the values."""
    if isinstance(value, np.ndarray):
        shape = f"array of shape {value.shape}"
        if value.size <= 9 and value.dtype.kind in "biuf":
            values = np.array2string(value, precision=4, suppress_small=True, separator=", ").replace("\n", "")
            described = f"{shape}, {' '.join(values.split())}"
            return described if len(described) <= room else shape
        return shape
    if isinstance(value, (int, float, np.integer, np.floating, bool, str)) or value is None:
        text = repr(value)
        return text if len(text) <= 40 else text[:37] + "..."
    if isinstance(value, (tuple, list)):
        return f"{type(value).__name__} of {len(value)} items"
    if isinstance(value, np.random.Generator):
        return "a random generator"
    if callable(value):
        return f"the function {getattr(value, '__name__', type(value).__name__)}"
    return type(value).__name__


CHECK_HINT = "What the check says for this case:"
"""What introduces, in the message of a crash, the hint that the check cell gives for the call that crashed."""


def _in_cell(frame: Any) -> bool:
    """Whether ``frame`` runs a notebook cell's own code (not a function defined in it)."""
    return frame.f_code.co_name == "<module>" and frame.f_globals.get("__name__") == "__main__"


def _assigned(statement: ast.stmt) -> set[str]:
    """The names that an assignment statement binds (none for another statement)."""
    targets = statement.targets if isinstance(statement, ast.Assign) else [getattr(statement, "target", None)]
    return {node.id for target in targets if target is not None for node in ast.walk(target)
            if isinstance(node, ast.Name)}


def _hints_in(statement: ast.stmt, namespace: dict, about: set[str] | None = None) -> list[str]:
    """The hints (a ``hint`` argument written as text) of the check helpers that ``statement`` calls; with
    ``about``, only of the check_array calls on one of those names (what the results should look like)."""
    found = []
    for call in (node for node in ast.walk(statement) if isinstance(node, ast.Call)):
        helper = namespace.get(call.func.id) if isinstance(call.func, ast.Name) else None
        try:
            parameters = list(inspect.signature(helper).parameters) if callable(helper) else []
        except (TypeError, ValueError):
            parameters = []
        if "hint" not in parameters:
            continue
        if about is not None and (helper is not check_array or not about & {
                n.id for a in call.args for n in ast.walk(a) if isinstance(n, ast.Name)}):
            continue
        position = parameters.index("hint")
        given = call.args[position] if position < len(call.args) else next(
            (k.value for k in call.keywords if k.arg == "hint"), None)
        if isinstance(given, ast.Constant) and isinstance(given.value, str) and given.value:
            found.append(given.value)
    return found


def _tokens(lines: list[str]) -> list[tokenize.TokenInfo]:
    """The tokens of a cell's lines, or none if they do not tokenize."""
    try:
        return list(tokenize.generate_tokens(iter(lines).__next__))
    except (tokenize.TokenError, SyntaxError):
        return []


def _check_hints(cell: Any, line: int, about_shapes: bool = True) -> list[str]:
    """What a check cell says to do about the call of a blank at ``line`` of the cell that ``cell`` (a
    frame) runs: a comment on that line, else the hints of the checks in the statement that makes the
    call, else, for an error ``about_shapes``, those of the later shape checks (check_array) of what that
    statement assigned, until it is assigned again: a check of the values says what a wrong value means, not
    what a crash does.

    A check cell thus keeps its hints in one place, its checks, and a crash shows them too."""
    lines = linecache.getlines(cell.f_code.co_filename, cell.f_globals)
    try:
        statements = ast.parse("".join(lines)).body
    except SyntaxError:
        return []
    at = next((s for s in statements if s.lineno <= line <= (s.end_lineno or s.lineno)), None)
    if at is None:
        return []
    comment = next((token.string.lstrip("# ") for token in _tokens(lines)
                    if token.type == tokenize.COMMENT and token.start[0] == line), "")
    if comment:
        return [comment]
    hints = _hints_in(at, cell.f_globals)
    if hints:
        return list(dict.fromkeys(hints))
    # the shapes that the results should have speak to an error about shapes only (a student review: a shape hint
    # under an error about NaN probabilities)
    names = _assigned(at) if about_shapes else set()
    for later in statements[statements.index(at) + 1:]:
        if not names:
            break
        hints += _hints_in(later, cell.f_globals, names)
        # a name checked and assigned again from itself (m = check_array(m, ...)) is still the call's result
        read = {n.id for n in ast.walk(later) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
        names -= _assigned(later) - read
    return list(dict.fromkeys(hints))


def _calls_through(tb: Any, blanks: list[str]) -> tuple[list[tuple[Any, Any]], list[int]]:
    """The calls a traceback passed through (each frame with its entry), and the indices of those that run
    one of ``blanks`` (functions defined in the notebook)."""
    calls = list(zip((frame for frame, _ in traceback.walk_tb(tb)), traceback.extract_tb(tb)))
    return calls, [i for i, (frame, _) in enumerate(calls)
                   if frame.f_code.co_name in blanks and frame.f_globals.get("__name__") == "__main__"]


def explain(error: BaseException, tb: Any, blanks: list[str], here: str = "this cell") -> str | None:
    """A message for an exception raised inside one of ``blanks``; None if none of them raised it.

    It names the blank, the line of it that raised, the call (and its inputs) that led there, what such an
    error usually means and, in a check cell, the check's own hint for that call. ``here`` names the cell that
    made the call, as the reader of the message knows it."""
    if isinstance(error, (AssertionError, NotWrittenYet)):
        return None
    calls, inside = _calls_through(tb, blanks)
    if not inside:
        return None
    outer, inner = calls[inside[0]][0], calls[inside[-1]][0]
    caller = (calls[inside[0] - 1][1].line or "").strip() if inside[0] > 0 else ""
    raising = (calls[inside[-1]][1].line or "").strip()
    code = outer.f_code
    arguments = code.co_varnames[: code.co_argcount + code.co_kwonlyargcount]
    inputs = "\n".join(f"  {name} = {_describe(outer.f_locals.get(name), LINE_WIDTH - len(name) - 5)}"
                       for name in arguments)
    name = code.co_name
    at = f"at the line `{raising}` of {inner.f_code.co_name}" if raising else f"in {inner.f_code.co_name}"
    during = ""
    if caller:
        frame = calls[inside[0] - 1][0]
        place = here if _in_cell(frame) else f"{frame.f_code.co_name} ({frame.f_globals.get('__name__')})"
        during = f", during the line `{caller}` of {place}"
    cell = next(((frame, entry) for frame, entry in calls[:inside[0]] if _in_cell(frame)), None)
    hints = " ".join(_check_hints(cell[0], cell[1].lineno, _SHAPE_ERROR.search(str(error).lower()) is not None)
                     if cell is not None else [])
    # a sentence of the meaning that the check's hint says too is said once, in the hint
    meaning = " ".join(s for s in re.split(r"(?<=\.) ", _meaning(error)) if s not in hints)
    return "\n".join([
        # both blanks when one raised inside the other: the fault is in the callee, or in what the caller gave it
        wrap(f"{type(error).__name__} in your {name}"
             + (f" (raised inside your {inner.f_code.co_name})" if inner.f_code.co_name != name else "") + f": {error}"),
        wrap(f"It was raised {at}{during}. {name} got these inputs:"),
        inputs,
        wrap(meaning),
        *([wrap(f"{CHECK_HINT} {hints}")] if hints else []),
    ])


def _shell() -> Any:
    """The running IPython shell, or None. A shell exists only once IPython is imported, so a plain
    Python process (the grader, pytest) never imports IPython for this."""
    ipython = sys.modules.get("IPython")
    return ipython.get_ipython() if ipython is not None else None


def changed_arguments_failure(name: str, changed: list[str]) -> str:
    """Why a function that wrote into the arrays it was given fails (its check here, its hidden test when graded)."""
    first = changed[0]
    which = f"its argument {first}" if len(changed) == 1 else "its arguments " + ", ".join(changed)
    return (f"{name} changed {which} in place (with {first} += ..., {first}[...] = ... or an in-place function). "
            f"The code that calls {name} still needs what it passed in: a filter's loop that keeps it, or a check "
            f"that uses it again. Leave the arrays you are given as they are and return new ones: write "
            f"{first} = {first} + ..., or start from {first}.copy(). (np.asarray({first}) and "
            f"{first}.astype(float, copy=False) give back the very array you were given, not a copy.)")


def global_random_failure(name: str) -> str:
    """Why a function that drew from NumPy's global generator, when it was given one, fails."""
    return (f"{name} drew random numbers from NumPy's global generator (np.random.standard_normal, np.random.choice, "
            f"...), not from the rng it was given, so the same seed does not give the same result. Draw every random "
            f"number with rng: rng.standard_normal, rng.random, rng.choice.")


class _RuleWatch:
    """While a blank's check cell runs, what each call of that blank, or of a blank it calls, does that the rules
    every lab states forbid: writing into an array it was given, or drawing from NumPy's global generator when it
    was given a generator. A student review: a kalman_step that wrote into y passed its own checks, and the check
    of run_rank4, which calls it, then blamed run_rank4; one that wrote into P made its own check show a wrong
    "expected" value (the check had passed the same array as P and Q). ``passed`` reports what was found, and so
    does a check that fails, first."""

    def __init__(self, codes: dict[Any, str]) -> None:
        self.codes = codes
        self.calls: list[tuple[Any, list[tuple[str, np.ndarray, np.ndarray]], Any]] = []
        self.changed: list[tuple[str, str]] = []
        self.global_random: list[str] = []

    def __call__(self, frame: Any, event: str, arg: Any) -> None:
        code = frame.f_code
        if code not in self.codes:
            return
        if event == "call":
            names = code.co_varnames[: code.co_argcount + code.co_kwonlyargcount]
            given = [frame.f_locals.get(n) for n in names]
            arrays = [(n, v, v.copy()) for n, v in zip(names, given) if isinstance(v, np.ndarray)]
            generator = any(isinstance(v, np.random.Generator) for v in given)
            self.calls.append((frame, arrays, _global_random_state() if generator else None))
        elif event == "return" and self.calls and self.calls[-1][0] is frame:
            _, arrays, state = self.calls.pop()
            name = self.codes[code]
            for n, after, before in arrays:
                if not (before.shape == after.shape and np.array_equal(before, after, equal_nan=before.dtype.kind in "fc")):
                    self.changed.append((name, n))
            if state is not None and state != _global_random_state():
                self.global_random.append(name)

    def broken(self, checked: str) -> str | None:
        """What a call broke, said of the blank that broke it (a blank that ``checked`` calls before ``checked``,
        whose argument may have been changed through it), or None."""
        culprits = [name for name, _ in self.changed] + self.global_random
        if not culprits:
            return None
        name = next((n for n in culprits if n != checked), checked)
        arguments = list(dict.fromkeys(a for n, a in self.changed if n == name))
        said = changed_arguments_failure(name, arguments) if arguments else global_random_failure(name)
        return said if name == checked else f"{said} ({checked} calls {name}: fix {name} first.)"


def _global_random_state() -> tuple:
    """Where NumPy's global generator stands (its position, key and the Gaussian a legacy call keeps)."""
    state = np.random.get_state(legacy=False)
    return int(state["state"]["pos"]), state["state"]["key"].tobytes(), int(state["has_gauss"]), float(state["gauss"])


_watch: dict[str, _RuleWatch | None] = {"now": None}


def _before_cell(info: Any) -> None:
    found = _CHECK_CELL.search(getattr(info, "raw_cell", "") or "")
    _cell["checks"] = found.group(1) if found else None
    _cell["uses"] = []
    checked = _cell["checks"]
    if checked and not _grading():
        codes = {getattr(_current(name), "__code__", None): name for name in [checked, *_calls(checked)]}
        codes = {code: name for code, name in codes.items() if code is not None and NOT_WRITTEN not in code.co_consts}
        if codes:
            _watch["now"] = _RuleWatch(codes)
            sys.setprofile(_watch["now"])


def _after_cell(result: Any = None) -> None:
    if _watch["now"] is not None:
        sys.setprofile(None)
        _watch["now"] = None


def _explain_failure(shell: Any, etype: type, value: BaseException, tb: Any, tb_offset: int | None = None) -> list[str]:
    """IPython's handler for an exception that escapes a cell: the default traceback, or a better message.

    Another blank is blamed only when it may be the cause: the error was raised inside it (then it comes first),
    or it fails its own visible checks with a wrong result, not a crash (then this cell's own error comes first,
    and the other blank once after it). A message that already says which blank fails (NotWrittenYet,
    NotPassingYet) is shown as it is."""
    checked, required = _cell["checks"], list(_cell["uses"])
    if checked is None and _grading():
        shell.showtraceback((etype, value, tb), running_compiled_code=True)
        return []
    stub = _stub_that_raised(value, tb)
    if stub is not None:
        caller, unwritten = stub
        if checked is not None:
            _passed.pop(checked, None)
            _failed[checked] = (_current(checked), _not_written_message(caller, unwritten, "the check cell"), False, (),
                                False)
        stb = _not_written_message(caller, unwritten, "this cell").splitlines()
        shell._showtraceback(etype, value, stb)
        return stb
    # the blanks this cell uses: those it requires and, in a blank's check cell, the blanks that blank calls
    others = [n for n in dict.fromkeys(required + (_calls(checked) if checked else [])) if n != checked]
    calls, inside = _calls_through(tb, others)
    raised_in = calls[inside[-1]][0].f_code.co_name if inside else None
    if isinstance(value, (NotWrittenYet, NotPassingYet, RuleBroken)):
        blamed = []  # the message names the blank at fault
    elif raised_in is not None and _not_passing([raised_in]):
        blamed = [raised_in]  # raised inside another blank that fails its own checks: it alone
    else:
        # raised here, or inside a blank that passes its checks (a student review: a wrong observation_matrix
        # crashed kalman_gain inside run_rank4, and nothing named it): the failing blanks that may have given it,
        # by a wrong result (a blank whose own check saw it crash did not crash here)
        blamed = [n for n in _not_passing(others) if not _crashed(n)]
    cause_inside = raised_in is not None and blamed == [raised_in]

    def own(here: str) -> str | None:
        """What this cell's own error says, without blaming another blank (None: Python's traceback says it)."""
        message = explain(value, tb, ([checked] if checked else []) + others, here)
        if message is None and isinstance(value, NameError):
            message = _set_by_a_cell_that_failed(value, shell)
        if message is None and isinstance(value, (AssertionError, NotWrittenYet)) and not isinstance(value, NotPassingYet):
            # a check that fails, or a blank not written yet: its message, wrapped (Validate cuts longer lines mid-word)
            message = wrap(f"{etype.__name__}: {value}")
        return message

    def composed(here: str) -> str | None:
        """The message, for a reader who knows the cell that raised it as ``here``."""
        message = own(here)
        if not blamed:
            return message
        said = message or f"{etype.__name__}: {value}"
        blame = wrap(_blame(blamed, checked, cause_inside, here))
        # the certain cause first, and a failing blank before a wrong value that it may have made (the fairness review
        # of castaway-bob: run_rank4's check told a correct run_rank4 to build A from alpha, and only then that
        # transition_matrix failed its checks); a crash in this cell's own code before a blank that may have fed it
        return f"{blame}\n\n{said}" if cause_inside or isinstance(value, AssertionError) else f"{said}\n\n{blame}"

    message = composed("this cell")
    watch = _watch["now"] if checked is not None else None
    broken = watch.broken(checked) if watch is not None else None
    _after_cell()
    if broken is not None and not isinstance(value, (NotWrittenYet, NotPassingYet)):
        # the rule a call broke comes first: a write can change what the check compares with, or what it gave
        also = " That can also change what this check compares with." if watch.changed else ""
        rule = wrap(f"{etype.__name__}: {broken}{also}")
        message = f"{rule}\n\nWhat the check said after that:\n{message or wrap(f'{etype.__name__}: {value}')}"
    if checked is not None:
        _passed.pop(checked, None)
        crashed = raised_in is None and explain(value, tb, [checked]) is not None
        # validate() quotes it under the graded cell, where "this cell" would be the wrong one; a check that stopped
        # because another blank is not written yet says so there too (not "run the check cell", which was run)
        said = (f"{etype.__name__}: {str(value).replace('This cell needs', 'The check cell needs', 1)}"
                if isinstance(value, NotWrittenYet) else f"{etype.__name__}: {broken}" if broken is not None
                else own("the check cell") or f"{etype.__name__}: {value}")
        _failed[checked] = (_current(checked), said, crashed, tuple(blamed), cause_inside)
    if message is None:
        shell.showtraceback((etype, value, tb), running_compiled_code=True)
        return []
    stb = message.splitlines()
    shell._showtraceback(etype, value, stb)
    return stb


def _stub_that_raised(error: BaseException, tb: Any) -> tuple[str, str] | None:
    """(the blank the cell called, the blank whose stub raised ``error``) when a stub raised it, else None."""
    if not (type(error) is NotImplementedError and str(error) == NOT_WRITTEN):
        return None
    functions = [frame.f_code.co_name for frame, _ in traceback.walk_tb(tb)
                 if frame.f_globals.get("__name__") == "__main__" and not _in_cell(frame)]
    return (functions[0], functions[-1]) if functions else None


def _set_by_a_cell_that_failed(error: NameError, shell: Any) -> str | None:
    """For a name that a cell run earlier assigns (``history = run_particle_filter(...)``) but that is not
    defined, since that cell stopped with an error before it: a message that points at that cell. None when
    no cell run in this kernel assigns it (a typo, or a cell not run yet: Python's message says enough)."""
    name = getattr(error, "name", None)
    if not name:
        return None
    assigns = re.compile(rf"^[ \t]*(?:[\w\s,]*,\s*)?{re.escape(name)}\s*(?:,[\w\s,]*)?=(?!=).*$", re.MULTILINE)
    defines = re.compile(rf"^def\s+{re.escape(name)}\s*\(", re.MULTILINE)
    for source in reversed(shell.user_ns.get("In", [])[:-1]):
        if defines.search(source or ""):
            # a blank's cell that a SyntaxError stopped: nothing in it ran, so its function is not defined (a
            # student trial of reentry-pf: the check cell said only "NameError: name 'pf_step' is not defined")
            return wrap(f"NameError: name '{name}' is not defined. The cell with `def {name}(...)` was run, but it "
                        f"stopped with an error before {name} was defined: most often a SyntaxError (a missing "
                        "bracket, colon or comma, or a wrong indent), which stops the whole cell. Fix the error "
                        "that cell shows, run it again, then this one.")
        found = assigns.search(source or "")
        if found:
            line = " ".join(found.group(0).split())
            line = line if len(line) <= 60 else line[:57] + "..."
            return wrap(f"NameError: name '{name}' is not defined. A cell above sets it, at the line `{line}`, but "
                        f"that cell stopped with an error before {name} got its value. Run it again and fix its error "
                        "first: this cell needs what it makes.")
    return None


def _blame(blamed: list[str], checked: str | None, raised_inside: bool, here: str) -> str:
    """The sentence that blames other blanks that fail their own visible checks: as the cause (the error was
    raised inside one), or as a possible cause beside what this cell says."""
    w = _upstream(blamed)
    failing = f"{w['does']} not pass {w['its']} own visible checks yet"
    if raised_inside:
        subject = f"The error was raised inside {w['your']}, which {failing}"
    else:
        # the check cell itself, not the blank it checks, uses a blank that the checked one does not call
        user = checked if checked and set(blamed) <= set(_calls(checked)) else "this check" if checked else "this cell"
        subject = f"This may come from {w['your']}, which {user} uses: {w['they']} {failing}"
    says = "says" if len(blamed) == 1 else "say"
    # one step further back: the blanks that the blamed ones' own checks blamed (tracking_dynamics, when pf_step's
    # check failed because of it and this error was raised inside pf_step)
    behind = [n for b in blamed for n in _blamed_by_check(b) if n not in blamed and n != checked]
    further = (f" Its check in turn points at {_upstream(list(dict.fromkeys(behind)))['your']}: start there."
               if behind else "")
    return (f"{subject}. Make {w['it']} pass {w['its']} checks first ({w['its']} check {w['cell']} {says} what is "
            f"wrong), then run {here} again.{further}")


def _blamed_by_check(name: str) -> tuple[str, ...]:
    """The blanks that the last failing check of the blank ``name``, as it is defined now, blamed."""
    failed = _failed.get(name)
    return failed[3] if failed is not None and failed[0] is _current(name) else ()


def _calls(name: str) -> list[str]:
    """The blanks (functions with a visible-check record) that ``name`` calls, directly or through others."""
    known = set(_passed) | set(_failed)
    found: list[str] = []
    todo = [name]
    while todo:
        function = _current(todo.pop())
        for called in getattr(getattr(function, "__code__", None), "co_names", ()):
            if called in known and called != name and called not in found:
                found.append(called)
                todo.append(called)
    return found


def _hooks_installed() -> bool:
    return bool(getattr(_shell(), "_course_checks_installed", False))


def _install() -> None:
    shell = _shell()
    if shell is None or getattr(shell, "_course_checks_installed", False):
        return
    shell.events.register("pre_run_cell", _before_cell)
    shell.events.register("post_run_cell", _after_cell)
    shell.set_custom_exc((Exception,), _explain_failure)
    shell._course_checks_installed = True


_install()
