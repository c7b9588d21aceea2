"""The allowlist HTML sanitiser for everything a page renders from a submission.

``sanitise(html)`` keeps only the tags, attributes, classes, CSS properties and URLs listed here,
through nh3 (the Python binding of Rust's ammonia): no script, event handler, frame, object, form,
SVG, style sheet, ``<meta>`` or ``<base>`` survives, a link goes to http, https, mailto or an anchor
of the page, and an image is a PNG, JPEG or GIF held in the page (``data:``), so opening the page
asks nothing of another address. Width and height are whole numbers.

MathJax, which the pages load, typesets TeX found in the page's text, and some of its macros make
links, classes, styles or ids, or load code (``\\href``, ``\\class``, ``\\style``, ``\\cssId``,
``\\require``, ``\\unicode``, ``\\data``, ``\\bbox``, and ``\\newcommand`` that would assemble one).
So in the text a zero-width space follows the backslash of every control word that is not on
``TEX_WORDS``: MathJax reads an unknown control symbol and the letters as text, and the text reads
the same. The pages' MathJax 2 also loads its own ``Safe`` extension; this does not depend on it.
"""

from __future__ import annotations

import html
import re
from html.parser import HTMLParser

import nh3
from pygments.token import STANDARD_TYPES

TAGS = frozenset({
    "a", "b", "blockquote", "br", "caption", "code", "dd", "del", "div", "dl", "dt", "em", "h1", "h2",
    "h3", "h4", "h5", "h6", "hr", "i", "img", "kbd", "li", "ol", "p", "pre", "s", "span", "strong",
    "sub", "sup", "table", "tbody", "td", "tfoot", "th", "thead", "tr", "ul",
})
"""What Markdown renders to; everything else goes, keeping its text."""
DROPPED_WITH_CONTENT = frozenset({
    "script", "style", "svg", "math", "template", "iframe", "object", "noscript", "noembed", "noframes",
    "textarea", "title", "select", "xmp",
})
"""Tags that go with everything inside them."""
ATTRIBUTES = {"a": {"href", "title"}, "img": {"src", "alt", "title", "width", "height"},
              "th": {"style"}, "td": {"style"}, "ol": {"start"}}
"""The attributes kept (class is filtered by CLASSES, style by STYLE_PROPERTIES)."""
STYLE_PROPERTIES = frozenset({"text-align"})
"""The CSS a table cell keeps (a Markdown table's column alignment)."""
CODE_CLASSES = frozenset({"highlight", "hl-python", "hl-python3", "hl-ipython3", "hl-text", "hl-bash", "hl-shell"})
CLASSES = {"div": CODE_CLASSES, "pre": CODE_CLASSES, "code": CODE_CLASSES,
           "span": frozenset(c for c in STANDARD_TYPES.values() if c), "a": frozenset({"anchor-link"})}
"""The classes kept: nbconvert's highlighted code (Pygments' token classes) and heading anchors."""
LINK = re.compile(r"(?:https?:|mailto:|#)", re.IGNORECASE)
IMAGE = re.compile(r"data:image/(?:png|jpeg|gif);base64,[A-Za-z0-9+/=\s]*", re.IGNORECASE)
NUMBER = re.compile(r"[0-9]{1,5}")

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
"""TeX control words the text keeps: math, no links, classes, styles, ids, loads or definitions."""
TEX_WORD = re.compile(r"\\(?:([A-Za-z]+)|.)", re.DOTALL)
ZERO_WIDTH_SPACE = "\u200b"

_cleaner = nh3.Cleaner(
    tags=set(TAGS),
    clean_content_tags=set(DROPPED_WITH_CONTENT),
    attributes={tag: set(names) for tag, names in ATTRIBUTES.items()},
    allowed_classes={tag: set(names) for tag, names in CLASSES.items()},
    filter_style_properties=set(STYLE_PROPERTIES),
    url_schemes={"http", "https", "mailto", "data"},
    attribute_filter=lambda tag, name, value: _attribute(tag, name, value),
    strip_comments=True,
    link_rel=None,
)


def _attribute(tag: str, name: str, value: str) -> str | None:
    """An attribute's value if it is allowed (a link, an image held in the page, a whole number)."""
    if name == "href":
        return value if LINK.match(value) else None
    if name == "src":
        return value if IMAGE.fullmatch(value) else None
    if name in ("width", "height", "start"):
        return value if NUMBER.fullmatch(value.strip()) else None
    return value


def inert_tex(text: str) -> str:
    """``text`` with a zero-width space after the backslash of each control word not on TEX_WORDS."""
    def word(match: re.Match) -> str:
        name = match.group(1)
        return match.group(0) if name is None or name in TEX_WORDS else "\\" + ZERO_WIDTH_SPACE + name
    return TEX_WORD.sub(word, text)


class _TexInText(HTMLParser):
    """Rewrites the text of sanitised HTML with ``inert_tex``; tags are kept as written."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.parts: list[str] = []

    def handle_starttag(self, tag: str, attrs: list) -> None:
        self.parts.append(self.get_starttag_text() or "")

    handle_startendtag = handle_starttag

    def handle_endtag(self, tag: str) -> None:
        self.parts.append(f"</{tag}>")

    def handle_data(self, data: str) -> None:
        self.parts.append(html.escape(inert_tex(data), quote=False))


def sanitise(markup: str) -> str:
    """``markup`` with only the allowlisted HTML and TeX left (see the module's doc)."""
    parser = _TexInText()
    parser.feed(_cleaner.clean(markup))
    parser.close()
    return _cleaner.clean("".join(parser.parts))
