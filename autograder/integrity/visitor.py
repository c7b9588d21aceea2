"""The scan's visitor: one cell's walk with every rule."""

from __future__ import annotations

from autograder.integrity.calls import CallRules
from autograder.integrity.names import NameRules
from autograder.integrity.strings import ClassAndStringRules


class Visitor(NameRules, CallRules, ClassAndStringRules):
    """Walks one cell's syntax tree and records a hit for each rule it breaks."""
