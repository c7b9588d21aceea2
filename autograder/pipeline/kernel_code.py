"""The code the grader runs silently in a grading kernel: installing the kernel's server, and serving
one blank for a hidden test.

The kernel never imports ``autograder``: the grader sends it the source of the wire
(autograder/kernel/wire.py) and of the server (autograder/kernel/server.py), which become the modules
``_kit_grading.wire`` and ``_kit_grading`` in the kernel's ``sys.modules``.
"""

from __future__ import annotations

from pathlib import Path

from autograder.kernel import server, wire
from autograder.pipeline.hidden_blocks import HiddenTest

MODULE_NAME = "_kit_grading"
"""The kernel's server's name in the kernel's ``sys.modules``; its wire is ``_kit_grading.wire``."""


def kernel_setup_code() -> str:
    """Code that the grader runs silently in each new grading kernel: it defines the wire, then the
    server (which imports the wire relatively, as ``.wire``), each sent as source and put in
    ``sys.modules`` before it runs, and binds no name in the notebook."""
    modules = ((f"{MODULE_NAME}.wire", Path(wire.__file__).read_text()),
               (MODULE_NAME, Path(server.__file__).read_text()))
    return ("(lambda sys, types: [(lambda m: (setattr(m, '__package__', " f"{MODULE_NAME!r}" "), "
            "sys.modules.__setitem__(name, m), "
            f"exec(compile(source, {wire.FILENAME!r}, 'exec'), m.__dict__)))(types.ModuleType(name)) "
            f"for name, source in {modules!r}])"
            "(__import__('sys'), __import__('types'))")


def serve_code(path: str, test: HiddenTest) -> str:
    """Code that the grader runs silently in the kernel for one hidden test: serve the student's function."""
    return f"__import__('sys').modules[{MODULE_NAME!r}].serve({path!r}, {test.blank!r})"
