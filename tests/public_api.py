"""The public API of intervalobs, found by walking the package (used by the self-checking tests).

Public means: every module of the package whose dotted name has no component starting with ``_``;
in each, the names in its ``__all__`` (or, without ``__all__``, every class and function it defines
whose name does not start with ``_``); of each public class, the methods, class/static methods and
properties it defines itself whose names do not start with ``_`` (plus ``__call__``). Objects
re-exported from other packages (NumPy, SciPy, ...) are skipped. New modules are picked up
automatically, so the checks apply to them from the start.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import pkgutil
from collections.abc import Callable
from types import ModuleType
from typing import Any

import intervalobs

PACKAGE = "intervalobs"


def _is_public_module(name: str) -> bool:
    return not any(part.startswith("_") for part in name.split("."))


@functools.cache
def public_modules() -> dict[str, ModuleType]:
    """Every public module of the package by dotted name, the package itself included."""
    modules: dict[str, ModuleType] = {PACKAGE: intervalobs}
    for info in pkgutil.walk_packages(intervalobs.__path__, f"{PACKAGE}."):
        if _is_public_module(info.name):
            modules[info.name] = importlib.import_module(info.name)
    return dict(sorted(modules.items()))


def _own(obj: Any) -> bool:
    module = getattr(obj, "__module__", None) or ""
    return module == PACKAGE or module.startswith(f"{PACKAGE}.")


def _module_names(module: ModuleType) -> list[str]:
    names = getattr(module, "__all__", None)
    if names is not None:
        return list(names)
    return [
        name
        for name, obj in vars(module).items()
        if not name.startswith("_")
        and (inspect.isclass(obj) or inspect.isfunction(obj))
        and obj.__module__ == module.__name__
    ]


def _members(cls: type) -> dict[str, Any]:
    """Public members a class defines itself (raw descriptors: property, classmethod, function)."""
    found = {}
    for name, raw in vars(cls).items():
        if name.startswith("_") and name != "__call__":
            continue
        if isinstance(raw, (classmethod, staticmethod, property, functools.cached_property)) or inspect.isfunction(raw):
            found[name] = raw
    return found


@functools.cache
def public_objects() -> dict[str, Any]:
    """Public classes, functions, methods and properties by importable dotted name.

    Methods and properties map to the raw class attribute (a ``property`` object, a bound
    classmethod, a plain function), which numpydoc and ``inspect`` both accept.
    """
    objects: dict[str, Any] = {}
    for module in public_modules().values():
        for name in _module_names(module):
            if name not in vars(module):  # a moved name, served with a FutureWarning: checked at its new home
                continue
            obj = vars(module)[name]
            if not (inspect.isclass(obj) or inspect.isfunction(obj)) or not _own(obj):
                continue
            qualified = f"{obj.__module__}.{obj.__qualname__}"
            objects[qualified] = obj
            if inspect.isclass(obj):
                for member, raw in _members(obj).items():
                    bound = isinstance(raw, (classmethod, staticmethod))
                    objects[f"{qualified}.{member}"] = getattr(obj, member) if bound else raw
    return dict(sorted(objects.items()))


def public_callables() -> dict[str, Callable[..., Any]]:
    """Public functions, methods and classes (their constructor), without properties."""
    return {name: obj for name, obj in public_objects().items() if callable(obj)}


def signature_of(obj: Callable[..., Any]) -> inspect.Signature:
    """Signature of a function or a class constructor; ``self``/``cls`` are dropped."""
    if inspect.isclass(obj):
        return inspect.signature(obj)
    signature = inspect.signature(obj)
    params = list(signature.parameters.values())
    if params and params[0].name in ("self", "cls") and inspect.isfunction(obj) and "." in obj.__qualname__:
        params = params[1:]
    return signature.replace(parameters=params)
