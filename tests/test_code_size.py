"""The package stays small enough to read (issue 34; STYLE.md, "A function fits in one screen").

Measured from the source with :mod:`ast`: no function outside ``reproduce/`` over
:data:`FUNCTION_LINES` lines, no estimator module over :data:`OBSERVER_MODULE_LINES` lines, ``highspy``
imported only by the LP layer, and a short, sorted top-level namespace.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import intervalobs

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "intervalobs"
MODULES = sorted(PACKAGE.rglob("*.py"))
IDS = [str(p.relative_to(PACKAGE)) for p in MODULES]

FUNCTION_LINES = 120
"""Most lines of a function or method (``end_lineno - lineno + 1``, docstring included) outside ``reproduce/``."""
OBSERVER_MODULE_LINES = 800
"""Most lines of a module under ``observers/``."""
TOP_LEVEL_NAMES = 45
"""Most names in ``intervalobs.__all__``."""


def _tree(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"))


def _top(path: Path) -> str:
    """The top-level module or subpackage of ``intervalobs`` that ``path`` belongs to."""
    return path.relative_to(PACKAGE).parts[0].removesuffix(".py")


def long_functions(path: Path, limit: int = FUNCTION_LINES) -> list[str]:
    """``name (lines)`` of every function or method of ``path`` longer than ``limit`` lines."""
    found = []
    for node in ast.walk(_tree(path)):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            lines = (node.end_lineno or node.lineno) - node.lineno + 1
            if lines > limit:
                found.append(f"{node.name} ({lines})")
    return found


def highspy_imports(path: Path) -> list[int]:
    """Line numbers where ``path`` imports ``highspy`` (``import highspy…`` or ``from highspy… import``)."""
    lines = []
    for node in ast.walk(_tree(path)):
        if isinstance(node, ast.Import) and any(a.name.split(".")[0] == "highspy" for a in node.names):
            lines.append(node.lineno)
        elif isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").split(".")[0] == "highspy":
            lines.append(node.lineno)
    return lines


@pytest.mark.parametrize("path", MODULES, ids=IDS)
def test_no_function_outside_the_reproductions_is_over_120_lines(path: Path) -> None:
    if _top(path) == "reproduce":
        pytest.skip("the reproductions are scripts of the papers' examples")
    assert long_functions(path) == [], "split into functions named for what they do"


@pytest.mark.parametrize("path", [p for p in MODULES if _top(p) == "observers"], ids=lambda p: p.name)
def test_no_estimator_module_is_over_800_lines(path: Path) -> None:
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= OBSERVER_MODULE_LINES, f"{path.name}: {lines} lines; one concept a module"


@pytest.mark.parametrize("path", MODULES, ids=IDS)
def test_only_the_lp_layer_imports_highspy(path: Path) -> None:
    if _top(path) != "lp":
        assert highspy_imports(path) == [], "solver calls belong in intervalobs.lp"


def test_the_top_level_namespace_is_short_and_sorted() -> None:
    names = list(intervalobs.__all__)
    assert len(names) <= TOP_LEVEL_NAMES
    # ruff's RUF022 order: CONSTANT_CASE, then CamelCase, then the rest
    assert names == sorted(names, key=lambda s: (0 if s.isupper() else 1 if s[0].isupper() else 2, s))


def test_the_top_level_namespace_has_no_per_paper_blocks() -> None:
    """``__all__`` is one sorted list: no comment lines that group its names (by paper or otherwise)."""
    source = (PACKAGE / "__init__.py").read_text(encoding="utf-8")
    node = next(
        n
        for n in ast.parse(source).body
        if isinstance(n, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in n.targets)
    )
    lines = source.splitlines()[node.lineno - 1 : node.end_lineno]
    assert [line for line in lines if line.strip().startswith("#")] == []


def test_the_measures_see_what_they_measure(tmp_path: Path) -> None:
    """The helpers find a long function, a nested one and both forms of a highspy import."""
    body = "\n".join(f"    x{i} = {i}" for i in range(FUNCTION_LINES))
    source = f"def long():\n{body}\n\nclass A:\n    def short(self):\n        import highspy\n"
    source += "        from highspy._core import HighsStatus\n"
    path = tmp_path / "sample.py"
    path.write_text(source, encoding="utf-8")
    assert long_functions(path) == [f"long ({FUNCTION_LINES + 1})"]
    assert highspy_imports(path) == [FUNCTION_LINES + 5, FUNCTION_LINES + 6]
