"""The user's language: no paper-internal references in error messages or in the user pages.

Error messages (the strings of every ``raise`` in the package) and the user pages (README.md and
docs/*.md, except docs/paper-notes.md, which maps the papers to the code, and docs/design.md, which
records decisions with their sources) say what a condition means for the user's system; the paper
and equation belong in a docstring's References section.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "intervalobs"
PAPER_TERMS = ("seed 00", "Seed 00", "Theorem", "Hypothesis", "H-matrix", "U2'g")
"""Paper-internal names: the papers' file numbers, their theorem and hypothesis numbers, their symbols."""
PAGES = [
    ROOT / "README.md",
    *(p for p in sorted((ROOT / "docs").glob("*.md")) if p.name not in ("paper-notes.md", "design.md")),
]


def _messages(path: Path) -> list[tuple[int, str]]:
    """(line, text) of the string parts of every ``raise`` of a module."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Raise) and node.exc is not None:
            parts = [n.value for n in ast.walk(node.exc) if isinstance(n, ast.Constant) and isinstance(n.value, str)]
            found.append((node.lineno, " ".join(parts)))
    return found


@pytest.mark.parametrize("path", sorted(PACKAGE.rglob("*.py")), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_error_messages_speak_of_the_system_not_the_paper(path: Path) -> None:
    for line, text in _messages(path):
        terms = [term for term in PAPER_TERMS if term in text]
        assert not terms, f"{path.relative_to(ROOT)}:{line}: error message names {terms}: say what it means instead"


@pytest.mark.parametrize("path", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_user_pages_speak_of_the_system_not_the_paper(path: Path) -> None:
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        terms = [term for term in PAPER_TERMS if term in line]
        assert not terms, f"{path.relative_to(ROOT)}:{number} names {terms}: {line.strip()[:80]}"


def test_the_scan_finds_a_paper_reference() -> None:
    assert [term for term in PAPER_TERMS if term in 'raise AssumptionError("Hypothesis 6 (seed 000)")'] == [
        "seed 00",
        "Hypothesis",
    ]


BUILTIN_ERRORS = {"TypeError", "ValueError", "RuntimeError", "KeyError", "IndexError", "OSError", "Exception"}
"""Builtins the package never raises itself: it raises the named error of :mod:`intervalobs.errors`
that subclasses the builtin (``AttributeError`` stays in a module's ``__getattr__``, ``NotImplementedError``
in an abstract method)."""


def _raised_builtins(source: str) -> list[tuple[int, str]]:
    """(line, name) of every ``raise`` of a builtin error in a module's source."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Raise) and node.exc is not None:
            call = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
            if isinstance(call, ast.Name) and call.id in BUILTIN_ERRORS:
                found.append((node.lineno, call.id))
    return found


@pytest.mark.parametrize("path", sorted(PACKAGE.rglob("*.py")), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_errors_are_the_library_s_named_errors(path: Path) -> None:
    raised = _raised_builtins(path.read_text(encoding="utf-8"))
    assert not raised, f"{path.relative_to(ROOT)}: raises {raised}: use the named error of intervalobs.errors"


def test_the_scan_finds_a_builtin_error() -> None:
    assert _raised_builtins("raise ValueError('x')\nraise DataError('y')\nraise TypeError") == [
        (1, "ValueError"),
        (3, "TypeError"),
    ]
