"""The package's layers (docs/design.md, "Layers"): a module imports only from layers below its own.

Read from the source with :mod:`ast`, so a new upward import fails here before it makes a cycle.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "intervalobs"

LAYERS: dict[str, int] = {
    "errors": 0,
    "references": 0,
    "_docstrings": 0,
    "interval": 1,
    "complex_interval": 1,
    "validation": 1,
    "recursion": 1,
    "_tables": 1,
    "inclusion": 2,
    "zonotope": 2,
    "cli_types": 2,
    "interval_dual": 3,
    "estimate": 4,
    "plotting": 4,
    "systems": 5,
    "lp": 5,
    "simulate": 6,
    "design": 6,
    "diagnosis": 8,
    "examples": 8,
    "observers": 7,
    "tightness": 8,
    "front_door": 8,
    "records": 9,
    "reproduce": 9,
    "__init__": 10,
    "cli": 11,
}
"""Layer of each top-level module or subpackage of ``intervalobs`` (as in docs/design.md)."""

SAME_LAYER = {("estimate", "plotting"), ("plotting", "estimate")}
"""The one pair of one layer that imports each other: an Estimate draws itself, figures take an Estimate."""


def _internal_imports(path: Path) -> set[str]:
    """Top-level names of ``intervalobs`` that a module imports (relative imports)."""
    parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
    package = parts[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = package[: len(package) - (node.level - 1)]
            if node.module:
                found.add((base + node.module.split("."))[0])
            else:
                for alias in node.names:
                    name = [*base, alias.name][0]
                    module = PACKAGE / name
                    found.add(name if module.with_suffix(".py").exists() or module.is_dir() else "__init__")
    return found


MODULES = sorted(PACKAGE.rglob("*.py"))


def test_every_module_has_a_layer() -> None:
    tops = {p.relative_to(PACKAGE).with_suffix("").parts[0] for p in MODULES}
    assert tops <= set(LAYERS), f"add to LAYERS and docs/design.md: {sorted(tops - set(LAYERS))}"


@pytest.mark.parametrize("path", MODULES, ids=[str(p.relative_to(PACKAGE)) for p in MODULES])
def test_imports_only_from_lower_layers(path: Path) -> None:
    own = path.relative_to(PACKAGE).with_suffix("").parts[0]
    for target in _internal_imports(path) - {own}:
        upward = LAYERS[target] > LAYERS[own]
        sideways = LAYERS[target] == LAYERS[own] and (own, target) not in SAME_LAYER
        assert not (upward or sideways), f"{own} (layer {LAYERS[own]}) imports {target} (layer {LAYERS[target]})"


def _imports_highspy(path: Path) -> bool:
    """Whether a module imports ``highspy`` (or a part of it) anywhere, inside functions too."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import) and any(alias.name.split(".")[0] == "highspy" for alias in node.names):
            return True
        if isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").split(".")[0] == "highspy":
            return True
    return False


def test_only_the_lp_layer_imports_highspy() -> None:
    outside = [str(p.relative_to(PACKAGE)) for p in MODULES if p.relative_to(PACKAGE).parts[0] != "lp"]
    assert [name for name in outside if _imports_highspy(PACKAGE / name)] == []
    assert _imports_highspy(PACKAGE / "lp" / "certified.py")  # the check finds what it looks for
