"""The allowlist HTML sanitiser for everything a page renders from a submission.

``sanitise(html)`` keeps only the tags, attributes, classes, CSS properties and URLs listed here,
through nh3 (the Python binding of Rust's ammonia): no script, event handler, frame, object, form,
SVG, style sheet, ``<meta>`` or ``<base>`` survives, a link goes to http, https, mailto or an anchor
of the page, and an image is a PNG, JPEG or GIF held in the page (``data:``), so opening the page
asks nothing of another address. Width and height are whole numbers.

``sanitise(html, math=True)`` (the feedback pages, which load no script) also turns each formula
of the text into MathML (autograder.pipeline.mathml), the only MathML the page can hold: the first
pass drops every ``<math>`` of the markup with its content, and the last keeps the converter's
elements and attributes only (``mathml.TAGS``, ``mathml.ATTRIBUTES``).

MathJax, which formgrader's pages load, typesets TeX found in the page's text, and some of its macros make
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

from autograder.pipeline import mathml
from autograder.pipeline.mathml import TEX_WORD, TEX_WORDS

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

ZERO_WIDTH_SPACE = "\u200b"

def _cleaner_of(tags: frozenset[str], dropped: frozenset[str], attributes: dict[str, set[str]]) -> nh3.Cleaner:
    return nh3.Cleaner(
        tags=set(tags),
        clean_content_tags=set(dropped),
        attributes={tag: set(names) for tag, names in attributes.items()},
        allowed_classes={tag: set(names) for tag, names in CLASSES.items()},
        filter_style_properties=set(STYLE_PROPERTIES),
        url_schemes={"http", "https", "mailto", "data"},
        attribute_filter=lambda tag, name, value: _attribute(tag, name, value),
        strip_comments=True,
        link_rel=None,
    )


_cleaner = _cleaner_of(TAGS, DROPPED_WITH_CONTENT, ATTRIBUTES)
_math_cleaner = _cleaner_of(TAGS | mathml.TAGS, DROPPED_WITH_CONTENT - {"math"}, ATTRIBUTES | mathml.ATTRIBUTES)
"""The cleaner of a page whose TeX is MathML: its MathML comes from the converter alone, as the
first pass (``_cleaner``) drops every ``<math>`` of the markup with its content."""


def _attribute(tag: str, name: str, value: str) -> str | None:
    """An attribute's value if it is allowed (a link, an image held in the page, a whole number, a
    MathML attribute that mathml.attribute allows)."""
    if tag in mathml.TAGS:
        return mathml.attribute(name, value)
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
    """Rewrites the text of sanitised HTML with ``inert_tex``, or, with ``math``, each formula outside
    code as MathML (autograder.pipeline.mathml) and the rest with ``inert_tex``; tags are kept as written."""

    def __init__(self, math: bool) -> None:
        super().__init__(convert_charrefs=True)
        self.parts: list[str] = []
        self.math = math
        self.in_code = 0

    def handle_starttag(self, tag: str, attrs: list) -> None:
        self.parts.append(self.get_starttag_text() or "")
        self.in_code += tag in ("code", "pre")

    def handle_startendtag(self, tag: str, attrs: list) -> None:
        self.parts.append(self.get_starttag_text() or "")

    def handle_endtag(self, tag: str) -> None:
        self.parts.append(f"</{tag}>")
        if tag in ("code", "pre") and self.in_code:
            self.in_code -= 1

    def handle_data(self, data: str) -> None:
        pieces = mathml.formulas(data) if self.math and not self.in_code else [(data, None)]
        self.parts += [html.escape(inert_tex(text), quote=False) if markup is None else markup for text, markup in pieces]


def sanitise(markup: str, math: bool = False) -> str:
    """``markup`` with only the allowlisted HTML and TeX left (see the module's doc); with ``math``,
    its formulas as MathML, for a page that loads no MathJax."""
    parser = _TexInText(math)
    parser.feed(_cleaner.clean(markup))
    parser.close()
    return (_math_cleaner if math else _cleaner).clean("".join(parser.parts))


def sanitise_math(markup: str) -> str:
    """``sanitise(markup, math=True)``: the feedback template's ``kit_sanitise``."""
    return sanitise(markup, math=True)
