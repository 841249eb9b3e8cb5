"""The package's shape: one import name, and layers that point one way.

Data flows rig -> acquisition -> record -> identification -> reports; the application layer
(``flowcurve/`` itself: the CLI, the demo, the console) is the only place where layers meet.
These tests read the source with ``ast`` (nothing is imported), so a violation names the file
and line.
"""

from __future__ import annotations

import ast
import functools
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LAYER_FOLDERS = {"rig": "rig", "acquisition": "acquisition", "record": "record",
                 "identification": "identification", "reports": "reports"}
# what each layer may import besides itself and the shared flowcurve.errors / flowcurve.log
ALLOWED = {
    "rig": set(),
    "acquisition": {"rig", "record"},
    "record": set(),
    "identification": {"record"},
    "reports": {"identification", "record"},
}
SHARED = {"flowcurve", "flowcurve.errors", "flowcurve.log", "flowcurve.clock"}
OLD_NAMES = {"rig", "acquisition", "record", "identification", "reports"}


def _python_files(folder: Path):
    return sorted(p for p in folder.rglob("*.py") if "__pycache__" not in p.parts)


def _imports(path: Path, *, names: bool = False):
    """(line, imported module) for every import in a file, at module level or inside functions;
    with ``names``, ``from a.b import c`` gives ``a.b.c`` (a module or a name in a.b)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level and ROOT / "tests" not in path.parents:
                raise AssertionError(f"{path}:{node.lineno}: relative import; write flowcurve.<layer>.… in full")
            if names:
                for alias in node.names:
                    yield node.lineno, f"{node.module or ''}.{alias.name}"
            else:
                yield node.lineno, node.module or ""


def _layer_of(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "flowcurve" or len(parts) < 2:
        return None
    if parts[1] in LAYER_FOLDERS:
        return parts[1]
    return None


def test_no_bare_layer_import_anywhere():
    """`import rig` would pick up PyPI's rig or reports if one were installed beside flowcurve."""
    bad = []
    for folder in ["flowcurve", *LAYER_FOLDERS.values(), "tests", "bench", "examples"]:
        if not (ROOT / folder).is_dir():
            continue
        for path in _python_files(ROOT / folder):
            for line, module in _imports(path):
                if module.split(".")[0] in OLD_NAMES:
                    bad.append(f"{path.relative_to(ROOT)}:{line}: import {module}")
    assert not bad, "bare layer imports (use flowcurve.<layer>):\n" + "\n".join(bad)


@pytest.mark.parametrize("layer", sorted(LAYER_FOLDERS))
def test_layer_imports_point_one_way(layer):
    bad = []
    for path in _python_files(ROOT / LAYER_FOLDERS[layer]):
        for line, module in _imports(path):
            other = _layer_of(module)
            if module.startswith("flowcurve") and other is None and module not in SHARED:
                bad.append(f"{path.relative_to(ROOT)}:{line}: imports the application layer ({module})")
            elif other is not None and other != layer and other not in ALLOWED[layer]:
                bad.append(f"{path.relative_to(ROOT)}:{line}: {layer} imports {other} ({module})")
    assert not bad, "\n".join(bad)


def test_drivers_never_import_the_virtual_devices_and_twins_keep_their_own_codecs():
    """The virtual devices encode replies with code of their own: a codec bug shared by the
    driver and its twin would otherwise pass every test."""
    bad = []
    for path in _python_files(ROOT / "rig"):
        virtual = "virtual" in path.relative_to(ROOT / "rig").parts
        for line, module in _imports(path):
            if not virtual and module.startswith("flowcurve.rig.virtual"):
                bad.append(f"{path.relative_to(ROOT)}:{line}: a driver imports the virtual rig ({module})")
            if virtual and module.startswith(("flowcurve.rig.codecs", "flowcurve.rig.loadcell",
                                              "flowcurve.rig.encoder", "flowcurve.rig.furnace")):
                bad.append(f"{path.relative_to(ROOT)}:{line}: a virtual device uses driver code ({module})")
    assert not bad, "\n".join(bad)


@functools.lru_cache(maxsize=None)
def _product_modules() -> dict[str, Path]:
    """Every module of the product by its dotted name (a package by its ``__init__.py``), from
    pyproject's package-dir mapping; folders without ``__init__.py`` are no packages."""
    mapping = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]["package-dir"]
    modules = {}
    for package, folder in mapping.items():
        base = ROOT / folder
        for path in _python_files(base):
            parts = path.relative_to(base).with_suffix("").parts
            if not all((base.joinpath(*parts[:k]) / "__init__.py").is_file() for k in range(1, len(parts))):
                continue
            parts = parts[:-1] if parts[-1] == "__init__" else parts
            modules[".".join((package, *parts))] = path
    return modules


def _import_graph(modules: dict[str, Path]) -> dict[str, dict[str, str]]:
    """module -> {imported product module: "file:line" of the first such import}, module- and
    function-level imports alike (an import inside a function closes a circle when it runs)."""
    graph = {}
    for name, path in modules.items():
        out = graph.setdefault(name, {})
        for line, imported in _imports(path, names=True):
            parts = imported.split(".")
            target = next((".".join(parts[:k]) for k in range(len(parts), 0, -1) if ".".join(parts[:k]) in modules), None)
            if target is not None and target != name:
                out.setdefault(target, f"{path.relative_to(ROOT)}:{line}")
    return graph


def _circles(graph: dict[str, dict[str, str]]) -> list[str]:
    """The strongly connected components of more than one node (Tarjan), each with the imports inside it."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                edges = [f"  {a} -> {b} ({where})" for a in sorted(component) for b, where in sorted(graph.get(a, {}).items()) if b in component]
                found.append(" <-> ".join(sorted(component)) + "\n" + "\n".join(edges))

    for v in list(graph):
        if v not in index:
            visit(v)
    return found


def _layer_of_module(module: str) -> str:
    """The layer a product module belongs to: rig … reports, or flowcurve (the application)."""
    return _layer_of(module) or "flowcurve"


def _package_node(module: str, modules: dict[str, Path]) -> str:
    """A module's node in the package graph: its sub-package (identification.fe, identification.fe.model,
    rig.virtual, flowcurve.cli …), or the module itself in a layer's own folder (flowcurve.identification.tension.identify)."""
    package = module if modules[module].name == "__init__.py" else module.rpartition(".")[0]
    return module if package == "flowcurve" or package in {f"flowcurve.{layer}" for layer in LAYER_FOLDERS} else package


@functools.lru_cache(maxsize=None)
def _product_graph() -> dict[str, dict[str, str]]:
    return _import_graph(_product_modules())


def test_no_import_circle_between_modules():
    """No module imports, at any depth, one that imports it back: a circle ties the modules into one
    (none can be read, tested or moved alone) and a function-level import that closes it only hides it."""
    circles = _circles(_product_graph())
    assert not circles, "import circles between modules:\n" + "\n".join(circles)


def _package_graph(layer: str) -> dict[str, dict[str, str]]:
    """The import graph of one layer with each sub-package one node (the layer's own modules stay nodes)."""
    modules = _product_modules()
    graph: dict[str, dict[str, str]] = {}
    for a, targets in _product_graph().items():
        if _layer_of_module(a) != layer:
            continue
        for b, where in targets.items():
            na, nb = _package_node(a, modules), _package_node(b, modules)
            if _layer_of_module(b) == layer and na != nb:
                graph.setdefault(na, {}).setdefault(nb, where)
    return graph


def _console_imports_the_cli() -> bool:
    return any(b.startswith("flowcurve.cli") for a, bs in _product_graph().items()
               if a.startswith("flowcurve.console") for b in bs)


@pytest.mark.parametrize("layer", [*sorted(LAYER_FOLDERS), pytest.param("flowcurve", marks=pytest.mark.xfail(
    _console_imports_the_cli(), strict=True, reason="the console imports the CLI, which starts the console (issue 44: the "
    "console never imports the CLI); runs as a plain test once the console imports nothing of it"))])
def test_no_import_circle_between_packages(layer):
    """Within a layer, the sub-packages and the layer's own modules point one way: e.g.
    identification.fe (inverse FE, verify) above the corrections (friction, compression) above
    identification.fe.model (decks, table, model form). Across layers test_layer_imports_point_one_way
    holds, so together no package circle exists in the product."""
    circles = _circles(_package_graph(layer))
    assert not circles, f"import circles between packages of {layer}:\n" + "\n".join(circles)


def test_every_package_folder_is_in_the_wheel():
    """pyproject lists the packages by hand (package-dir mapping); a forgotten one would be
    missing from the wheel while the editable install still found it."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]
    mapping = config["package-dir"]
    listed = set(config["packages"])
    on_disk = set()
    for package, folder in mapping.items():
        base = ROOT / folder
        for init in base.rglob("__init__.py"):
            rel = init.parent.relative_to(base)
            if "__pycache__" in rel.parts:
                continue
            on_disk.add(".".join((package, *rel.parts)) if rel.parts else package)
    assert on_disk - listed == set(), f"package folders missing from pyproject's packages: {sorted(on_disk - listed)}"
    assert listed - on_disk == set(), f"pyproject lists packages with no folder: {sorted(listed - on_disk)}"
    assert {p.split(".")[0] for p in listed} == {"flowcurve"}


def _imports_of_package(folder: Path, package: str) -> list[str]:
    """Every import (module- and function-level) of ``package`` or below in ``folder``'s files."""
    return [f"{path.relative_to(folder.parent)}:{line}: imports {module}" for path in _python_files(folder)
            for line, module in _imports(path) if module == package or module.startswith(package + ".")]


@pytest.mark.parametrize("folder", ["console", "services"])
def test_the_console_and_the_services_import_nothing_of_the_cli(folder):
    """The console builds the services' typed requests from its forms; it never parses argv with
    the CLI's parser or borrows the CLI's helpers (issue 44). The services sit below both."""
    bad = _imports_of_package(ROOT / "flowcurve" / folder, "flowcurve.cli")
    assert not bad, "\n".join(bad)


def test_the_services_import_nothing_of_the_console():
    bad = _imports_of_package(ROOT / "flowcurve" / "services", "flowcurve.console")
    assert not bad, "\n".join(bad)


def test_the_import_finder_sees_function_level_imports(tmp_path):
    """An import inside a function counts: the console's old ``from flowcurve.cli import build_parser``
    sat in a method."""
    (tmp_path / "m.py").write_text("def f():\n    from flowcurve.cli.reports import run_card\n", encoding="utf-8")
    assert _imports_of_package(tmp_path, "flowcurve.cli") == [f"{tmp_path.name}/m.py:2: imports flowcurve.cli.reports"]
