"""Shared parameter descriptions (:mod:`intervalobs._docstrings`): placed whole, indented, never left behind."""

from __future__ import annotations

import inspect
from pathlib import Path

import pytest

from intervalobs._docstrings import DESCRIPTIONS, shared_docs
from public_api import public_objects


def test_a_placeholder_line_becomes_the_description_at_its_indentation() -> None:
    def f(system: object, bounds: object) -> None:
        """Summary, 5 % of it kept as written.

        Parameters
        ----------
        %(lti_system_bounds)s
        """

    shared_docs(f)
    assert "5 % of it" in (f.__doc__ or "")
    expected = "\n".join("        " + line for line in DESCRIPTIONS["lti_system_bounds"].splitlines())
    assert expected in (f.__doc__ or "")
    assert "%(" not in (f.__doc__ or "")


def test_an_unknown_name_fails_at_decoration() -> None:
    def f() -> None:
        """Summary.

        %(no_such_description)s
        """

    with pytest.raises(KeyError, match="no_such_description"):
        shared_docs(f)


def test_no_public_docstring_keeps_a_placeholder() -> None:
    left = [name for name, obj in public_objects().items() if "%(" in (inspect.getdoc(obj) or "")]
    assert left == []


def test_every_shared_description_is_used() -> None:
    package = Path(__file__).resolve().parents[1] / "src" / "intervalobs"
    source = "\n".join(path.read_text(encoding="utf-8") for path in package.rglob("*.py"))
    assert [name for name in DESCRIPTIONS if f"%({name})s" not in source] == []
