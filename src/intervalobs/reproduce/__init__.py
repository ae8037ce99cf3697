"""Reproductions of the papers' examples, one module each, found automatically.

A reproduction module defines a module-level ``EXAMPLE = Example(...)``; :func:`registry` imports every
module of this package and collects them, so adding a paper never edits a shared list.
"""

from __future__ import annotations

import importlib
import pkgutil

from .contract import Example, write_reproduction

__all__ = ["Example", "registry", "write_reproduction"]


def registry() -> dict[str, Example]:
    """All reproducible examples by name, in the order of their seed file, then name.

    Returns
    -------
    dict of str to Example
        Every ``EXAMPLE`` defined by a module of :mod:`intervalobs.reproduce`.
    """
    found: list[Example] = []
    for info in pkgutil.iter_modules(__path__):
        if info.name == "contract":
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        example = getattr(module, "EXAMPLE", None)
        if isinstance(example, Example):
            found.append(example)
    found.sort(key=lambda e: (e.seed_file, e.name))
    return {e.name: e for e in found}
