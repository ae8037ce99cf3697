"""Types of the command-line options: each converts the option's text and checks it before any work.

Every converter parses the text and passes the value to the library's own check in
:mod:`intervalobs.validation`, so an option and the function argument it feeds are checked by the
same code. A bad value becomes an ``argparse`` error naming the option
(``intervalobs: error: argument --runs: expected an integer >= 1, got 0``), exit code 2.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
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


def _option(
    name: str, summary: str, check: Callable[[str, Any], T], parse: Callable[[str], Any] = str, kind: str = "str"
) -> Callable[[str], T]:
    """The converter ``name``: ``check`` applied to the parsed text, documented by ``summary`` and ``kind``."""

    def convert(text: str) -> T:
        return _convert(check, text, parse)

    convert.__name__ = convert.__qualname__ = name
    convert.__annotations__["return"] = kind  # what the signature shows (T is known only here)
    convert.__doc__ = (
        f"{summary}\n\nParameters\n----------\ntext : str\n    The option's text.\n\nReturns\n-------\n{kind}\n"
    )
    return convert


count = _option("count", "A count of at least 1 (``--runs``, ``--workers``).", as_count, int, "int")
seed = _option(
    "seed",
    "A random seed: an integer of at least 0 (``--seed``).",
    lambda name, value: as_count(name, value, minimum=0),
    int,
    "int",
)
fraction = _option(
    "fraction",
    "A fraction in [0, 1): a relative uncertainty level, 0.05 for ±5 % (``--levels``).",
    as_fraction,
    float,
    "float",
)
output_folder = _option(
    "output_folder",
    "A folder results can be written into, checked before anything is computed (``--out``).",
    as_output_folder,
    kind="pathlib.Path",
)
input_folder = _option(
    "input_folder",
    "An existing folder to read from (``--results``).",
    lambda name, value: as_input_path(name, value, "folder"),
    kind="pathlib.Path",
)
input_file = _option("input_file", "An existing file to read.", as_input_path, kind="pathlib.Path")


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
