"""The wheel holds one import name, ``flowcurve``, and works beside PyPI-like packages named
``rig`` and ``reports`` (issue 9). Everything is built locally, without network."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CONFIG = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
PACKAGE_DIRS = CONFIG["tool"]["setuptools"]["package-dir"]  # import name → folder


def _build_wheel(source: Path, out: Path) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index",
                            "-q", "-w", str(out), str(source)], capture_output=True, text=True)
    assert built.returncode == 0, ("building the wheel failed (the test extra brings setuptools>=70.1, which "
                                   "builds wheels by itself: pip install -e '.[test]'):\n" + built.stderr[-3000:])
    (wheel,) = out.glob("*.whl")
    return wheel


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The flowcurve wheel, built from a copy of the sources (the work tree stays clean)."""
    source = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", CONFIG["project"]["readme"]):
        shutil.copy2(ROOT / name, source / name)
    for folder in set(PACKAGE_DIRS.values()):
        shutil.copytree(ROOT / folder, source / folder, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return _build_wheel(source, tmp_path_factory.mktemp("dist"))


def test_the_wheel_holds_flowcurve_alone(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names} == {"flowcurve", f"flowcurve-{CONFIG['project']['version']}.dist-info"}
    # every module of every layer folder is in it, under flowcurve/
    for package, folder in PACKAGE_DIRS.items():
        for path in (ROOT / folder).rglob("*.py"):
            if "__pycache__" in path.parts:
                continue
            inside = "/".join((*package.split("."), *path.relative_to(ROOT / folder).parts))
            assert inside in names, f"{path.relative_to(ROOT)} is missing from the wheel (as {inside})"
    assert "flowcurve/rig/example-rig.toml" in names  # package data travels too
    for data in ("flowcurve/rig/virtual/data/upsetting_response.npz", "flowcurve/rig/virtual/data/upsetting_response.json",
                 "flowcurve/identification/fe/model/data/upsetting_table.npz"):
        assert data in names  # the FE tables the virtual rig and the identification read


def _dummy_wheel(tmp_path: Path, name: str) -> Path:
    """A PyPI-like project named ``name`` with a top-level package of that name."""
    project = tmp_path / f"dummy-{name}"
    (project / name).mkdir(parents=True)
    (project / name / "__init__.py").write_text(f'WHO = "the other {name}"\n')
    (project / "pyproject.toml").write_text(
        '[build-system]\nrequires = ["setuptools"]\nbuild-backend = "setuptools.build_meta"\n'
        f'[project]\nname = "{name}"\nversion = "9.9"\n[tool.setuptools]\npackages = ["{name}"]\n')
    return _build_wheel(project, tmp_path / f"dist-{name}")


def _sub_commands() -> list[list[str]]:
    import argparse

    from flowcurve.cli import build_parser

    def walk(parser, prefix):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    yield [*prefix, name]
                    yield from walk(sub, [*prefix, name])

    return [[], *walk(build_parser(), [])]


@pytest.mark.slow
def test_installed_beside_packages_named_rig_and_reports_every_command_answers(wheel, tmp_path, request):
    if "slow" not in (request.config.option.markexpr or ""):
        pytest.skip("20-30 s (a venv, three installs, a dozen processes): run with -m slow")
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=False)
    python = env_dir / "bin" / "python"
    dummies = [_dummy_wheel(tmp_path, "rig"), _dummy_wheel(tmp_path, "reports")]
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-index", "--no-deps", "-q",
                    *map(str, dummies), str(wheel)], check=True, capture_output=True, text=True)
    # flowcurve's dependencies (numpy, pandas, ...) from this interpreter's site-packages, after the venv's own
    site = subprocess.run([str(python), "-c", "import site; print(site.getsitepackages()[0])"],
                          check=True, capture_output=True, text=True).stdout.strip()
    outer_sites = [p for p in sys.path if p.endswith("site-packages")]  # this venv's and its base's
    Path(site, "dependencies.pth").write_text("\n".join(outer_sites) + "\n")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    check = ("import rig, reports, flowcurve, flowcurve.rig.codecs.aed, flowcurve.reports.cards; "
             "from flowcurve.rig.virtual.fe_response import UpsettingResponse; UpsettingResponse.load(); "  # its package data
             "print(rig.WHO, reports.WHO, flowcurve.__file__)")
    out = subprocess.run([str(python), "-c", check], cwd=tmp_path, env=env, check=True, capture_output=True, text=True).stdout
    assert out.startswith("the other rig the other reports ") and str(env_dir) in out
    for words in _sub_commands():
        run = subprocess.run([str(env_dir / "bin" / "flowcurve"), *words, "--help"], cwd=tmp_path, env=env,
                             capture_output=True, text=True)
        assert run.returncode == 0 and run.stdout.startswith("usage: flowcurve"), (words, run.stderr[-2000:])
    # and a command that does real work with the installed package: identify a shipped record, with plots
    record = ROOT / "examples" / "data" / "46NT71.csv"
    run = subprocess.run([str(env_dir / "bin" / "flowcurve"), "identify", str(record), "--out", "results"], cwd=tmp_path,
                         env={**env, "MPLBACKEND": "Agg"}, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    assert (tmp_path / "results" / "46NT71" / "result.json").is_file()
    assert list((tmp_path / "results" / "46NT71").glob("*.png"))
