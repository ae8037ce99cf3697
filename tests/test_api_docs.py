"""The package checks itself: docstrings, type hints, version and packaging of the public API.

The public API is walked automatically (:mod:`public_api`): everything exported by
``intervalobs.__init__``, the ``__all__`` of every public module (or its public classes and
functions when it has no ``__all__``), and the public methods and properties of those classes.
A new module is checked from the moment it exists.

Docstrings are validated with numpydoc's own validator (:func:`numpydoc.validate.validate`), not a
parser of ours. The error codes enforced are listed in :data:`CHECKED`; the others are left out on
purpose: SA01/EX01/ES01 (no See Also / Examples / extended summary: useful, not mandatory),
RT02/RT03 (``Returns`` may give only a type), PR07 (a parameter may be documented by its type and
shape alone, e.g. ``C : numpy.ndarray, shape (p, n)`` for a matrix named as in the paper),
SS05/SS06/PR08/PR09/GL01–GL03 (wording and layout).

Every docstring (modules and documented module constants included) must also render: it is passed
through numpydoc's Sphinx output and parsed by docutils, so what would break ``make docs`` (Sphinx
with ``-W``) already fails ``make test``. Type hints of every public function and method are required
as well (mypy with disallow_untyped_defs checks them too; this test keeps the rule whatever mypy's settings).
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.metadata
import inspect
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path
from typing import Any

import docutils.core
import docutils.nodes
import numpydoc.validate
import pytest
from docutils.parsers.rst import Directive, directives, roles
from numpydoc.docscrape_sphinx import get_doc_object
from sphinx.pycode import ModuleAnalyzer

import intervalobs
from public_api import public_modules, public_objects, signature_of

ROOT = Path(__file__).resolve().parents[1]

CHECKED = {
    "GL06": "a section name numpydoc does not know (typo, or a heading that will not render)",
    "GL07": "sections in the wrong order",
    "GL08": "the object has no docstring",
    "SS01": "no one-line summary",
    "PR01": "a parameter of the signature is not documented",
    "PR02": "a documented parameter is not in the signature",
    "PR03": "parameters documented in a different order than the signature",
    "PR04": "a documented parameter has no type",
    "PR06": "a type spelled 'integer'/'boolean'/'string' instead of int/bool/str",
    "PR10": "'name: type' without a space before the colon (numpydoc reads it as a name)",
    "RT01": "a function that returns a value has no Returns section",
    "YD01": "a generator has no Yields section",
}


class _Validator(numpydoc.validate.Validator):
    """numpydoc's validator with two adjustments.

    - A dataclass's fields are both its attributes and its constructor parameters: when its docstring
      has no ``Parameters`` section, the ``Attributes`` section is checked against the signature
      instead (so every field must still be documented, in order, with a type).
    - ``Validator.source_file_def_line`` looks for the first ``def``/``class`` line of the object's
      source and raises ``StopIteration`` for a package ``__init__`` made only of imports (numpydoc 1.11).
    """

    def __init__(self, obj_name: str) -> None:
        super().__init__(numpydoc.validate.get_doc_object(numpydoc.validate.Validator._load_obj(obj_name)))

    def _parameter_sections(self, sections: list[str]) -> list[str]:
        if dataclasses.is_dataclass(self.obj) and inspect.isclass(self.obj) and not self.doc["Parameters"]:
            return ["Attributes" if section == "Parameters" else section for section in sections]
        return sections

    @property
    def doc_parameters(self) -> dict[str, Any]:
        return self._doc_parameters(self._parameter_sections(["Parameters"]))

    @property
    def doc_all_parameters(self) -> dict[str, Any]:
        return self._doc_parameters(self._parameter_sections(["Parameters", "Other Parameters"]))

    @property
    def source_file_def_line(self) -> int | None:
        if inspect.ismodule(self.code_obj):
            return None
        return super().source_file_def_line


def _errors(name: str) -> list[str]:
    result: dict[str, Any] = numpydoc.validate.validate(name, validator_cls=_Validator)
    return [f"{code}: {message}" for code, message in result["errors"] if code in CHECKED]


def test_the_walk_finds_the_public_api():
    names = public_objects()
    for expected in (
        "intervalobs.observers.interval_observer.IntervalObserver",
        "intervalobs.observers.interval_observer.IntervalObserver.design",
        "intervalobs.simulate.simulate",
        "intervalobs.systems.dimensions.ModelDimensions.n",
    ):
        assert expected in names
    exported = {n for n in intervalobs.__all__ if n != "__version__"}
    assert exported <= {name.rsplit(".", 1)[-1] for name in names}


@pytest.mark.parametrize("name", list(public_modules()), ids=str)
def test_module_docstring(name):
    errors = _errors(name)
    assert not errors, f"{name}:\n  " + "\n  ".join(errors)


@pytest.mark.parametrize("name", list(public_objects()), ids=str)
def test_numpydoc_docstring(name):
    errors = _errors(name)
    assert not errors, f"{name}:\n  " + "\n  ".join(errors)


# -- rendering: what `make docs` (sphinx -W) would reject, caught by `make test` already -------------
# Each docstring goes through numpydoc's Sphinx rendering and is parsed by docutils; any warning or
# error (an undefined ``|substitution|`` from an unquoted ``|x|``, an unclosed ``*emphasis*`` from
# ``*args`` or ``2**n`` outside double backticks, bad indentation) fails the test. Sphinx roles and
# directives are accepted without checking their targets; LaTeX is left to MathJax.


class _AnyDirective(Directive):
    has_content = True
    optional_arguments = 10
    final_argument_whitespace = True
    option_spec = None

    def run(self) -> list[docutils.nodes.Node]:
        return []


class _AnyOptions(dict):
    def __contains__(self, key: object) -> bool:
        return True

    def __getitem__(self, key: str) -> Any:
        return directives.unchanged


_AnyDirective.option_spec = _AnyOptions()
for _role in ("class", "func", "meth", "mod", "attr", "data", "exc", "obj", "ref", "doc", "term", "any", "math"):
    roles.register_generic_role(_role, docutils.nodes.literal)
for _directive in (
    "math",
    "seealso",
    "autosummary",
    "index",
    "versionadded",
    "versionchanged",
    "deprecated",
    "plot",
    "only",
):
    directives.register_directive(_directive, _AnyDirective)


def _render_problems(rst: str) -> list[str]:
    doctree = docutils.core.publish_doctree(
        rst, settings_overrides={"report_level": 2, "halt_level": 5, "warning_stream": False}
    )
    # parse-time messages are in the tree; transform-time ones (undefined substitutions) are kept aside
    messages = [*doctree.findall(docutils.nodes.system_message), *doctree.transform_messages]
    return [f"line {msg.get('line', '?')}: {msg.astext()}" for msg in messages if msg["level"] >= 2]


@functools.cache
def _docstrings() -> dict[str, str]:
    """Rendered docstrings of the public API, modules and documented module data included."""
    found: dict[str, str] = {}
    for name, module in public_modules().items():
        found[name] = str(get_doc_object(module, what="module"))
        if not hasattr(module, "__path__"):
            for (scope, attr), lines in ModuleAnalyzer.for_module(name).find_attr_docs().items():
                if not scope:
                    found[f"{name}.{attr}"] = "\n".join(lines)
    for name, obj in public_objects().items():
        target = obj.fget if isinstance(obj, property) else obj
        found[name] = str(get_doc_object(target, config={"show_class_members": False}))
    return dict(sorted(found.items()))


@pytest.mark.parametrize("name", list(_docstrings()), ids=str)
def test_docstring_renders(name):
    problems = _render_problems(_docstrings()[name])
    assert not problems, f"{name} does not render (sphinx -W would fail):\n  " + "\n  ".join(problems)


def _unannotated(obj: Any) -> list[str]:
    if isinstance(obj, property):
        obj = obj.fget
    if inspect.isclass(obj):
        init = vars(obj).get("__init__")
        if init is None:  # constructor inherited (checked where it is defined) or dataclass-made
            return []
        obj = init
    missing = []
    signature = signature_of(obj)
    for param in signature.parameters.values():
        if param.annotation is inspect.Parameter.empty and param.name not in ("self", "cls"):
            missing.append(param.name)
    if signature.return_annotation is inspect.Signature.empty:
        missing.append("return")
    return missing


@pytest.mark.parametrize("name", list(public_objects()), ids=str)
def test_type_hints(name):
    missing = _unannotated(public_objects()[name])
    assert not missing, f"{name}: no type hint for {missing}"


def test_version_is_the_installed_distribution_version():
    assert re.fullmatch(r"\d+\.\d+\.\d+([.-]?\w+)?", intervalobs.__version__)
    assert intervalobs.__version__ == importlib.metadata.version("intervalobs")


def test_cli_version_matches():
    exe = shutil.which("intervalobs", path=str(Path(sys.executable).parent))
    command = [exe] if exe else [sys.executable, "-m", "intervalobs.cli"]
    out = subprocess.run([*command, "--version"], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == f"intervalobs {intervalobs.__version__}"


def test_changelog_license_and_py_typed():
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["project"]["license"] == "BSD-3-Clause"
    assert (ROOT / "LICENSE").read_text().startswith("BSD 3-Clause License")
    assert "py.typed" in pyproject["tool"]["setuptools"]["package-data"]["intervalobs"]
    assert (ROOT / "src" / "intervalobs" / "py.typed").is_file()
    changelog = (ROOT / "CHANGELOG.md").read_text()
    assert f"## [{intervalobs.__version__}]" in changelog, "CHANGELOG.md has no section for the current version"


@pytest.mark.slow
def test_wheel_ships_py_typed_license_and_version(tmp_path):
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w", str(tmp_path), str(ROOT)], check=True
    )
    (wheel,) = tmp_path.glob("intervalobs-*.whl")
    files = zipfile.ZipFile(wheel).namelist()
    assert "intervalobs/py.typed" in files
    assert any(f.endswith(".dist-info/licenses/LICENSE") or f.endswith(".dist-info/LICENSE") for f in files)
    assert wheel.name.startswith(f"intervalobs-{intervalobs.__version__}-")
