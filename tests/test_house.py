"""The house rules of issue 44: no module over 800 lines, no function over 100, at most 5 over 60.

Measured with ``ast`` over the product's packages (not tests/ or bench/); a function's length is
``end_lineno - lineno + 1`` of its ``def`` (decorators excluded), nested functions counted on their own.
"""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("flowcurve", "rig", "acquisition", "record", "identification", "reports")
MAX_MODULE_LINES = 800
MAX_FUNCTION_LINES = 100
LONG_FUNCTION_LINES = 60
MAX_LONG_FUNCTIONS = 5


def product_modules() -> list[Path]:
    """Every .py file of the product's packages, sorted."""
    return sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def function_lengths(path: Path) -> list[tuple[int, str]]:
    """(lines, 'path:line name') of every function and method in one module, nested ones included."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    where = path.relative_to(ROOT)
    return [(node.end_lineno - node.lineno + 1, f"{where}:{node.lineno} {node.name}")
            for node in ast.walk(tree) if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]


def test_the_product_is_found():
    modules = product_modules()
    assert len(modules) > 50, f"only {len(modules)} modules under {ROOT}: the packages moved?"


def test_no_module_over_800_lines():
    long = [f"{p.relative_to(ROOT)}: {n} lines" for p in product_modules()
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES]
    assert not long, f"modules over {MAX_MODULE_LINES} lines:\n" + "\n".join(long)


def test_no_function_over_100_lines():
    long = sorted((f for p in product_modules() for f in function_lengths(p) if f[0] > MAX_FUNCTION_LINES), reverse=True)
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines:\n" + "\n".join(f"{n:4d}  {w}" for n, w in long)


def test_at_most_5_functions_over_60_lines():
    long = sorted((f for p in product_modules() for f in function_lengths(p) if f[0] > LONG_FUNCTION_LINES), reverse=True)
    assert len(long) <= MAX_LONG_FUNCTIONS, (
        f"{len(long)} functions over {LONG_FUNCTION_LINES} lines (at most {MAX_LONG_FUNCTIONS}):\n"
        + "\n".join(f"{n:4d}  {w}" for n, w in long))
