"""Sphinx configuration: markdown pages (MyST), the API reference (autodoc + numpydoc), benchmarks.

``make docs`` builds with ``-W`` (warnings are errors). The API pages are generated here on every
build from the package itself, so a new module appears in the reference without editing anything
under ``docs/``; they go to ``docs/api/`` (git-ignored). ``docs/benchmarks.md`` is written from the
benchmark JSON files by ``benchmarks/report.py`` and committed (so it reads on the repository too); the
build only checks that it is current and never writes a tracked file.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import runpy
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT / "src"))

import intervalobs  # noqa: E402

project = "intervalobs"
author = "the intervalobs developers"
copyright = "2026, the intervalobs developers"
release = version = intervalobs.__version__

extensions = [
    "myst_nb",  # MyST markdown pages (it includes myst_parser) and the notebooks, executed on every build
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax shipped with the pages: the math renders without a network
    "sphinx.ext.viewcode",
    "numpydoc",
]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "jupyter_execute", "**.ipynb_checkpoints"]

# Notebooks (docs/notebooks) are stored without outputs and executed on every build; an error fails it.
nb_execution_mode = "force"
nb_execution_raise_on_error = True
nb_execution_timeout = 600
root_doc = "index"

# MyST: GitHub-style markdown (the pages are also read on GitHub), anchors for ## headings.
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3


# autodoc + numpydoc: the docstrings are numpydoc; members are listed on the class page itself.
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # types are in the docstrings (and checked by tests/test_api_docs.py)
autodoc_default_options = {"show-inheritance": True}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
numpydoc_validation_checks: set[str] = set()  # validated by the test suite, not at build time

html_theme = "alabaster"
html_title = f"intervalobs {release}"
html_theme_options = {"description": "Sound interval observers", "fixed_sidebar": True}
html_sidebars = {"**": ["about.html", "navigation.html", "searchbox.html"]}


# ----------------------------------------------------------------------------------------------
# API reference: one page per public module, each object documented once, where it is defined.


def _public_modules() -> list[ModuleType]:
    modules = [intervalobs]
    for info in pkgutil.walk_packages(intervalobs.__path__, "intervalobs."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            modules.append(importlib.import_module(info.name))
    return sorted(modules, key=lambda m: m.__name__)


def _exported(module: ModuleType) -> list[str]:
    names = getattr(module, "__all__", None)
    if names is None:
        names = [
            n
            for n, obj in vars(module).items()
            if not n.startswith("_")
            and (inspect.isclass(obj) or inspect.isfunction(obj))
            and obj.__module__ == module.__name__
        ]
    # a name served by a module's __getattr__ has moved (it warns): it is documented at its new home
    return [n for n in names if not n.startswith("__") and n in vars(module)]


def _directive(module: ModuleType, name: str) -> str | None:
    """The autodoc directive for ``module.name`` if this module is where it is defined, else None."""
    obj = getattr(module, name)
    if inspect.isclass(obj) or inspect.isfunction(obj):
        if obj.__module__ != module.__name__:
            return None  # re-exported: documented on its defining module's page
        if inspect.isclass(obj) and issubclass(obj, BaseException):
            return f".. autoexception:: {module.__name__}.{name}\n"
        if inspect.isclass(obj):
            return f".. autoclass:: {module.__name__}.{name}\n   :members:\n"
        return f".. autofunction:: {module.__name__}.{name}\n"
    docs = _attribute_docs(module)
    if hasattr(module, "__path__") or ("", name) not in docs:
        return None  # data re-exported by a package, or without its own docstring (autodoc would show its type's)
    if callable(obj):  # a type alias such as tuple[...]: numpydoc would try to read a call signature
        body = "\n".join(f"   {line}" if line else "" for line in docs[("", name)])
        return f".. py:data:: {module.__name__}.{name}\n\n{body}\n"
    return f".. autodata:: {module.__name__}.{name}\n   :no-value:\n"


def _attribute_docs(module: ModuleType) -> dict[tuple[str, str], list[str]]:
    from sphinx.pycode import ModuleAnalyzer

    return dict(ModuleAnalyzer.for_module(module.__name__).find_attr_docs())


def _summary(obj: Any) -> str:
    doc = inspect.getdoc(obj) or ""
    return doc.strip().split("\n\n")[0].replace("\n", " ")


def _canonical(obj: Any, module: ModuleType, name: str) -> str:
    if inspect.isclass(obj) or inspect.isfunction(obj):
        return f"{obj.__module__}.{obj.__qualname__}"
    return f"{module.__name__}.{name}"


def _module_page(module: ModuleType) -> str:
    title = f"``{module.__name__}``"
    lines = [title, "=" * len(title), "", f".. automodule:: {module.__name__}", "   :no-members:", ""]
    reexported = []
    for name in _exported(module):
        directive = _directive(module, name)
        if directive is None:
            reexported.append(name)
        else:
            lines += [directive, ""]
    if reexported:
        lines += ["Re-exported here", "----------------", ""]
        for name in reexported:
            obj = getattr(module, name)
            role = "class" if inspect.isclass(obj) else ("func" if inspect.isfunction(obj) else "data")
            lines.append(f"- :{role}:`~{_canonical(obj, module, name)}`")
        lines.append("")
    return "\n".join(lines)


def _top_level_table() -> list[str]:
    lines = [".. list-table::", "   :widths: 30 70", ""]
    for name in intervalobs.__all__:
        if name.startswith("__"):
            continue
        obj = getattr(intervalobs, name)
        role = "class" if inspect.isclass(obj) else "func"
        lines += [f"   * - :{role}:`~{_canonical(obj, intervalobs, name)}`", f"     - {_summary(obj)}"]
    return lines


def write_api_pages() -> None:
    out = DOCS / "api"
    out.mkdir(exist_ok=True)
    modules = _public_modules()
    wanted = {f"{m.__name__}.rst" for m in modules} | {"index.rst"}
    for stale in out.glob("*.rst"):
        if stale.name not in wanted:
            stale.unlink()
    for module in modules:
        _write_if_changed(out / f"{module.__name__}.rst", _module_page(module))
    index = [
        "API reference",
        "=============",
        "",
        "Generated from the docstrings (numpydoc). Everything below is importable from the module",
        "whose page documents it; the names in the table are also importable from ``intervalobs``.",
        "",
        "Top-level exports",
        "-----------------",
        "",
        *_top_level_table(),
        "",
        "Modules",
        "-------",
        "",
        ".. toctree::",
        "   :maxdepth: 1",
        "",
        *[f"   {m.__name__}" for m in modules],
        "",
    ]
    _write_if_changed(out / "index.rst", "\n".join(index))


def _write_if_changed(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def check_benchmarks_page(app: Any) -> None:
    """Warn (an error under ``-W``) when docs/benchmarks.md is not what benchmarks/report.py makes of the JSON."""
    from sphinx.util import logging

    render = runpy.run_path(str(ROOT / "benchmarks" / "report.py"))["render"]
    if (DOCS / "benchmarks.md").read_text() != render():
        logging.getLogger(__name__).warning(
            "docs/benchmarks.md is stale: run `python benchmarks/report.py` and commit the page"
        )


def setup(app: Any) -> None:
    app.connect("builder-inited", check_benchmarks_page)


write_api_pages()
