"""Issue 44: the public API of docs/api.md has numpydoc docstrings, and no public function lacks one.

Every entry of docs/api.md imports; a function's docstring has a ``Parameters`` section naming each
parameter of its signature (``*args``/``**kwargs`` may share one line) and a ``Returns`` section
(not asked of a function annotated ``-> None``); a class's has ``Parameters`` or ``Attributes``
naming each parameter of its constructor. Then, over the product's packages, every function or
method whose name has no leading underscore has a docstring (``ast``; a function nested in a
function is its detail, not public, and is not asked).
"""
from __future__ import annotations

import ast
import importlib
import inspect
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("flowcurve", "rig", "acquisition", "record", "identification", "reports")
ENTRY = re.compile(r"^- `([\w.]+)` — \S", re.M)


def api_entries() -> list[str]:
    return ENTRY.findall((ROOT / "docs" / "api.md").read_text(encoding="utf-8"))


def resolve(path: str):
    """The object at a dotted path: the longest importable module, then attributes."""
    parts = path.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for name in parts[cut:]:
            obj = getattr(obj, name)
        return obj
    raise ImportError(path)


def sections(doc: str) -> dict[str, list[str]]:
    """numpydoc sections of a cleaned docstring: title → its lines (the title underlined by dashes)."""
    lines = doc.splitlines()
    found, current = {}, None
    for i, line in enumerate(lines):
        if i + 1 < len(lines) and line.strip() and re.fullmatch(r"-{3,}", lines[i + 1].strip()):
            current = line.strip()
            found[current] = []
        elif current is not None and not re.fullmatch(r"-{3,}", line.strip()):
            found[current].append(line)
    return found


def documented_names(lines: list[str]) -> set[str]:
    """The names a Parameters/Attributes section describes: its unindented ``name : type`` lines."""
    names = set()
    for line in lines:
        if line and not line[0].isspace():
            for name in line.split(" : ")[0].split(","):
                names.add(name.strip().lstrip("*"))
    return names


def signature_names(obj) -> list[str]:
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    names = [p.name for p in sig.parameters.values() if p.name not in ("self", "cls")]
    if inspect.isclass(obj) and names == ["args", "kwargs"]:  # a Protocol's stand-in constructor
        return []
    return names


def returns_none(obj) -> bool:
    try:
        annotation = inspect.signature(obj).return_annotation
    except (TypeError, ValueError):
        return False
    return annotation in (None, "None")


def test_the_api_list_is_there():
    entries = api_entries()
    assert 40 <= len(entries) <= 60, f"{len(entries)} entries in docs/api.md"
    assert len(set(entries)) == len(entries), "an entry is listed twice"


@pytest.mark.parametrize("path", api_entries())
def test_api_entry_has_numpydoc_sections(path):
    obj = resolve(path)
    doc = inspect.getdoc(obj) if inspect.isclass(obj) else inspect.cleandoc(obj.__doc__ or "")
    assert doc and doc.splitlines()[0].strip(), f"{path}: no one-line summary"
    found = sections(doc)
    names = signature_names(obj)
    if inspect.isclass(obj):
        described = found.get("Parameters", []) + found.get("Attributes", [])
        assert "Parameters" in found or "Attributes" in found, f"{path}: no Parameters or Attributes section"
    else:
        described = found.get("Parameters", [])
        if names:
            assert "Parameters" in found, f"{path}: no Parameters section"
        if not returns_none(obj):
            assert "Returns" in found or "Yields" in found, f"{path}: no Returns section"
    missing = [n for n in names if n not in documented_names(described)]
    assert not missing, f"{path}: parameters not described: {', '.join(missing)}"


FUNCTIONS = (ast.FunctionDef, ast.AsyncFunctionDef)


def public_functions(tree: ast.Module):
    """Functions and methods reachable from outside their module: at module level or in a class
    (classes nested in classes too), their name without a leading underscore. A function defined
    inside another function is that function's detail, not public."""
    stack = list(tree.body)
    while stack:
        node = stack.pop()
        if isinstance(node, FUNCTIONS) and not node.name.startswith("_"):
            yield node
        elif isinstance(node, ast.ClassDef):
            stack.extend(node.body)
        elif isinstance(node, (ast.If, ast.Try)):  # definitions under "if TYPE_CHECKING:" or "try:"
            stack.extend(node.body + node.orelse + getattr(node, "finalbody", []) + [s for h in getattr(node, "handlers", []) for s in h.body])


def undocumented_public_functions() -> list[str]:
    missing = []
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
            missing += [f"{path.relative_to(ROOT)}:{node.lineno} {node.name}" for node in public_functions(tree)
                        if not ast.get_docstring(node)]
    return missing


def test_every_public_function_has_a_docstring():
    missing = undocumented_public_functions()
    assert not missing, f"{len(missing)} public functions without a docstring:\n" + "\n".join(missing)
