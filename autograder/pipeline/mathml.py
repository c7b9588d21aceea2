"""TeX in a page's text, as MathML that the browser lays out itself: no script, no network.

``mathml(tex, display)`` converts one formula with latex2mathml, or returns None, and then the page
shows the TeX as text. It converts only what is safe and quick to convert:

- a formula of at most ``MAX_TEX`` characters, groups nested at most ``MAX_DEPTH`` deep, whose
  every control word is on ``TEX_WORDS`` (so no ``\\href``, ``\\style``, ``\\class``, ``\\newcommand``,
  ``\\def``, ``\\rule``, ...), while the page's budget of ``PAGE_SECONDS`` lasts;
- into markup whose every element is on ``TAGS`` (``\\text{<img ...>}`` comes out of the converter as
  HTML inside ``<mtext>``: such a formula is shown as text), with no comment or declaration.

The sanitiser (autograder.pipeline.sanitise) cleans the result again with ``TAGS`` and ``ATTRIBUTES``
(through ``attribute``), whatever the converter made: no link, event handler, style, colour, size
or ``annotation-xml``, and lengths small enough that a formula cannot cover the page around it.
A conversion that fails for any reason is a formula shown as text; it never fails the page.
"""

from __future__ import annotations

import re
import time
from html.parser import HTMLParser

from latex2mathml.converter import convert

TEX_WORDS = frozenset("""
alpha beta gamma delta epsilon varepsilon zeta eta theta vartheta iota kappa lambda mu nu xi omicron
pi varpi rho varrho sigma varsigma tau upsilon phi varphi chi psi omega Gamma Delta Theta Lambda Xi Pi
Sigma Upsilon Phi Psi Omega ell hbar imath jmath aleph infty nabla partial emptyset varnothing
mathbf mathrm mathcal mathsf mathbb mathit mathtt mathfrak boldsymbol bm rm bf it sf tt cal
text textrm textbf textit texttt textsf mbox operatorname
hat widehat vec dot ddot bar overline underline tilde widetilde check breve acute grave mathring
overbrace underbrace overrightarrow overleftarrow overset underset stackrel
frac dfrac tfrac cfrac binom dbinom tbinom sqrt
sum prod coprod int iint iiint oint bigcup bigcap bigoplus bigotimes lim limsup liminf sup inf
max min arg argmax argmin det exp log ln lg sin cos tan cot sec csc arcsin arccos arctan sinh cosh
tanh coth deg dim ker hom gcd Pr mod bmod pmod
left right big Big bigg Bigg bigl bigr Bigl Bigr biggl biggr middle
begin end tag notag nonumber label displaystyle textstyle scriptstyle scriptscriptstyle limits nolimits
quad qquad hspace vspace enspace thinspace negthinspace hfill
cdot cdots ldots dots vdots ddots times div pm mp ast star circ bullet oplus ominus otimes oslash odot
wedge vee cap cup setminus sqcup uplus dagger ddagger amalg
le leq ge geq ne neq equiv approx sim simeq cong propto ll gg prec succ preceq succeq subset supset
subseteq supseteq in notin ni owns mid nmid parallel perp models vdash dashv doteq asymp bowtie
lt gt not neg lnot land lor forall exists nexists top bot angle triangle square
to gets leftarrow rightarrow Leftarrow Rightarrow leftrightarrow Leftrightarrow mapsto longrightarrow
longleftarrow Longrightarrow Longleftarrow longmapsto iff implies impliedby uparrow downarrow
Uparrow Downarrow updownarrow nearrow searrow swarrow nwarrow hookrightarrow hookleftarrow
rightharpoonup rightleftharpoons xrightarrow xleftarrow
langle rangle lvert rvert lVert rVert vert Vert lbrace rbrace lbrack rbrack lfloor rfloor lceil rceil
backslash prime colon
substack atop choose over pmatrix bmatrix matrix cases
color boxed
""".split())
"""TeX control words that only typeset math: no links, classes, styles, ids, loads or definitions."""
TEX_WORD = re.compile(r"\\(?:([A-Za-z]+)|.)", re.DOTALL)
TEX_SYMBOLS = frozenset("\\,;:!>{}|%&_$# ")
"""The control symbols a formula may hold (\\, spaces, escaped braces and signs): not the zero-width
space that the sanitiser puts after the backslash of a control word not on TEX_WORDS."""

MAX_TEX = 2000
"""Characters of one formula (the labs' longest has about 530)."""
FORMULA = re.compile(
    rf"(?<!\\)\$\$(?P<display>.{{1,{MAX_TEX}}}?)(?<!\\)\$\$"        # $$ display $$
    rf"|\\\[(?P<display2>.{{1,{MAX_TEX}}}?)\\\]"                     # \[ display \]
    rf"|\\\((?P<inline2>.{{1,{MAX_TEX}}}?)\\\)"                      # \( inline \)
    rf"|(?<![\\$])\$(?=[^\s$])(?P<inline>(?:[^$\\]|\\.){{1,{MAX_TEX}}}?)(?<=[^\s\\])\$"  # $inline$: $5 and $6 is no math
    rf"|(?P<environment>\\begin\{{(?P<name>[A-Za-z]{{1,20}}\*?)\}}.{{1,{MAX_TEX}}}?\\end\{{(?P=name)\}})",  # \begin{{align}}...
    re.DOTALL)
"""A formula in text, as nbconvert's Markdown leaves it and as MathJax found it, of at most MAX_TEX
characters (so that finding formulas takes time linear in the text, at worst MAX_TEX per character)."""
MAX_DEPTH = 20
"""Groups ({...}, \\left...\\right, \\begin...\\end) nested in one formula."""
MAX_TEXT = 20_000
"""The longest text whose formulas are converted (a lab's longest Markdown cell has about 4,800 characters): finding
formulas takes up to MAX_TEX steps per character, and 1 MB of text took 15 s in one search."""
PAGE_SECONDS = 10.0
"""Conversion time of one page (a lab's page takes about 0.2 s); later formulas are shown as text."""

TAGS = frozenset({
    "math", "mrow", "mi", "mn", "mo", "mtext", "mspace", "msub", "msup", "msubsup", "mfrac", "msqrt",
    "mroot", "mover", "munder", "munderover", "mtable", "mtr", "mtd", "mstyle", "mpadded", "mphantom",
    "menclose",
})
"""The MathML elements latex2mathml makes of TEX_WORDS."""
ATTRIBUTES = {
    "math": {"display"},
    "mi": {"mathvariant"}, "mn": {"mathvariant"}, "mtext": {"mathvariant"},
    "mo": {"mathvariant", "stretchy", "fence", "form", "accent", "movablelimits", "largeop", "separator",
           "minsize", "maxsize", "lspace", "rspace"},
    "mover": {"accent"}, "munder": {"accentunder"}, "mfrac": {"linethickness"},
    "mspace": {"width", "height", "depth", "linebreak"},
    "mpadded": {"width", "height", "depth", "lspace"},  # no voffset: nested, it lifted a formula over the page
    "mstyle": {"displaystyle", "scriptlevel"},
    "mtable": {"displaystyle", "rowspacing", "columnspacing", "columnalign"},
    "mtd": {"columnalign"}, "menclose": {"notation"},
}
"""The attributes kept: latex2mathml's, less colours (mathcolor, mathbackground) and sizes (mathsize)."""
LENGTHS = frozenset({"width", "height", "depth", "lspace", "rspace", "voffset", "minsize", "maxsize",
                     "linethickness", "rowspacing", "columnspacing"})
LENGTH = re.compile(r"(?:\+?(?:[0-9]?\.[0-9]+|[0-9])|-(?:0?\.[0-9]+|1))(?:em|ex|pt|px|width)?"
                    r"|(?:negative)?(?:thin|medium|thick)mathspace")
"""A length under 10 units, or a negative one under 1: a formula moves its own parts, not the page."""
WORDS = re.compile(r"[a-z-]+(?: [a-z-]+)*|[0-2]")
"""Any other value: keywords (true, prefix, bold-italic, box, left center) or a script level."""


def attribute(name: str, value: str) -> str | None:
    """A MathML attribute's value if it is allowed (see LENGTH and WORDS)."""
    if name in LENGTHS:
        return value if all(LENGTH.fullmatch(part) for part in value.split()) and value.strip() else None
    return value if WORDS.fullmatch(value) else None


class _Elements(HTMLParser):
    """The names of markup's elements in order (``tags``), and whether it holds only elements on TAGS and no
    comment, declaration or instruction (``clean``)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.clean = True
        self.tags: list[str] = []

    def handle_starttag(self, tag: str, attrs: list) -> None:
        self.clean &= tag in TAGS
        self.tags.append(tag)

    def handle_startendtag(self, tag: str, attrs: list) -> None:
        self.handle_starttag(tag, attrs)

    def handle_endtag(self, tag: str) -> None:
        self.handle_starttag(tag, [])

    def _foreign(self, *args) -> None:
        self.clean = False

    handle_comment = handle_decl = handle_pi = unknown_decl = _foreign


def _depth(tex: str) -> int:
    """How deep groups nest in ``tex`` (an unbalanced closing counts as 0)."""
    depth = deepest = 0
    for match in re.finditer(r"(?<!\\)[{}]|\\left\b|\\right\b|\\begin\b|\\end\b", tex):
        depth = max(depth + (1 if match.group(0) in ("{", "\\left", "\\begin") else -1), 0)
        deepest = max(deepest, depth)
    return deepest


def convertible(tex: str) -> bool:
    """Whether ``tex`` is short, shallow and uses only TEX_WORDS and TEX_SYMBOLS."""
    return (len(tex) <= MAX_TEX and _depth(tex) <= MAX_DEPTH
            and all(match.group(1) in TEX_WORDS if match.group(1) else match.group(0)[1:] in TEX_SYMBOLS
                    for match in TEX_WORD.finditer(tex)))


class _Budget:
    """The conversion time left to the page being rendered."""

    seconds = PAGE_SECONDS


_budget = _Budget()


def start_page() -> None:
    """Give the next page its own PAGE_SECONDS (the feedback's preprocessor calls it per notebook)."""
    _budget.seconds = PAGE_SECONDS


TEXT_COMMAND = re.compile(r"\\(?:text[a-z]*|mbox|operatorname|tag)(?![A-Za-z])")
"""The control words whose argument latex2mathml copies into ``<mtext>`` as it is, markup included (\\tag too: the
re-attack of issue 36's review)."""
MARKUP = re.compile(r"<")
"""What opens a tag in the converter's output (a formula's own < is made &lt; outside such an argument)."""


def mathml(tex: str, display: bool) -> str | None:
    """``tex`` as MathML (block if ``display``), or None to show it as text."""
    # an argument of \text copied as it is can close the <mtext> and open elements of its own, with attributes
    # that move them over the page (an adversarial review of issue 36: <mpadded voffset> over the score)
    if not convertible(tex) or (TEXT_COMMAND.search(tex) and MARKUP.search(tex)):
        return None
    mode = "block" if display else "inline"
    try:
        markup = convert(tex, display=mode)
        check = _parsed(markup)
        # a < that made elements: some command copied its argument as markup (in math, < and \lt are one <mo>)
        if "<" in tex and check.tags != _parsed(convert(tex.replace("<", r"\lt "), display=mode)).tags:
            return None
    except Exception:  # noqa: BLE001 (latex2mathml, and the check of what it made, raise many kinds: show the TeX)
        return None
    return markup if check.clean else None


def _parsed(markup: str) -> _Elements:
    check = _Elements()
    check.feed(markup)
    check.close()
    return check


def formulas(text: str) -> list[tuple[str, str | None]]:
    """``text`` cut into (piece, its MathML or None): each formula that converts, and the text between.
    Finding and converting formulas spends the page's budget; once it is spent, the rest is text."""
    pieces: list[tuple[str, str | None]] = []
    end, start = 0, time.monotonic()
    try:
        # one search can take MAX_TEX steps per character, which the budget, checked between matches, cannot stop
        for match in FORMULA.finditer(text) if _budget.seconds > 0 and len(text) <= MAX_TEXT else ():
            if time.monotonic() - start > _budget.seconds:
                break
            kind, tex = next((kind, tex) for kind, tex in match.groupdict().items() if tex is not None)
            markup = mathml(tex, display=kind not in ("inline", "inline2"))
            if markup is not None:
                pieces += [(text[end:match.start()], None), (match.group(0), markup)]
                end = match.end()
    finally:
        _budget.seconds -= time.monotonic() - start
    pieces.append((text[end:], None))
    return [(piece, markup) for piece, markup in pieces if piece]
