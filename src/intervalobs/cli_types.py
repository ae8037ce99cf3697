"""Types of the command-line options: each converts the option's text and checks it before any work.

Every converter parses the text and passes the value to the library's own check in
:mod:`intervalobs.validation`, so an option and the function argument it feeds are checked by the
same code. A bad value becomes an ``argparse`` error naming the option
(``intervalobs: error: argument --runs: expected an integer >= 1, got 0``), exit code 2.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

from .errors import IntervalObserverError
from .validation import as_choice, as_count, as_fraction, as_input_path, as_output_folder

__all__ = ["choice", "count", "fraction", "input_file", "input_folder", "output_folder", "seed"]

T = TypeVar("T")


def _convert(check: Callable[[str, Any], T], text: str, parse: Callable[[str], Any] = str) -> T:
    """``check("", parse(text))``, or ``check("", text)`` when the text does not parse (the check then
    reports the text); an :class:`~intervalobs.errors.IntervalObserverError` becomes argparse's error."""
    try:
        value = parse(text)
    except ValueError:
        value = text
    try:
        return check("", value)
    except IntervalObserverError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def count(text: str) -> int:
    """A count of at least 1 (``--runs``, ``--workers``).

    Parameters
    ----------
    text : str
        The option's text.

    Returns
    -------
    int
    """
    return _convert(as_count, text, int)


def seed(text: str) -> int:
    """A random seed: an integer of at least 0 (``--seed``).

    Parameters
    ----------
    text : str
        The option's text.

    Returns
    -------
    int
    """
    return _convert(lambda name, value: as_count(name, value, minimum=0), text, int)


def fraction(text: str) -> float:
    """A fraction in [0, 1): a relative uncertainty level, 0.05 for ±5 % (``--levels``).

    Parameters
    ----------
    text : str
        The option's text.

    Returns
    -------
    float
    """
    return _convert(as_fraction, text, float)


def output_folder(text: str) -> Path:
    """A folder results can be written into, checked before anything is computed (``--out``).

    Parameters
    ----------
    text : str
        The option's text.

    Returns
    -------
    pathlib.Path
    """
    return _convert(as_output_folder, text)


def input_folder(text: str) -> Path:
    """An existing folder to read from (``--results``).

    Parameters
    ----------
    text : str
        The option's text.

    Returns
    -------
    pathlib.Path
    """
    return _convert(lambda name, value: as_input_path(name, value, "folder"), text)


def input_file(text: str) -> Path:
    """An existing file to read.

    Parameters
    ----------
    text : str
        The option's text.

    Returns
    -------
    pathlib.Path
    """
    return _convert(as_input_path, text)


def choice(choices: Sequence[str]) -> Callable[[str], str]:
    """A converter accepting one of ``choices`` (an example's name).

    Parameters
    ----------
    choices : sequence of str
        The accepted values.

    Returns
    -------
    callable
        ``convert(text) -> text``, for ``argparse``'s ``type=``.
    """

    def one_of(text: str) -> str:
        return _convert(lambda name, value: as_choice(name, value, choices), text)

    return one_of
