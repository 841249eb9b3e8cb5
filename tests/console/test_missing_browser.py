"""The browser tests without a browser: skipped with the reason on a developer's machine,
failed in CI, whether Chromium (a fixture's skip) or selenium (the file's import) is missing."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
BROWSER_TESTS = "tests/console/test_browser.py"


def _pytest(tmp_path: Path, *, ci: bool, missing: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("CI", "PYTEST_ADDOPTS")}
    env["PATH"] = str(tmp_path / "empty-bin")  # no chromium, no chromedriver on it
    (tmp_path / "empty-bin").mkdir(exist_ok=True)
    if missing == "selenium":  # a selenium that fails to import, ahead of the installed one
        fake = tmp_path / "fake" / "selenium"
        fake.mkdir(parents=True, exist_ok=True)
        (fake / "__init__.py").write_text("raise ModuleNotFoundError(\"No module named 'selenium'\", name='selenium')\n")
        env["PYTHONPATH"] = os.pathsep.join([str(fake.parent)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    if ci:
        env["CI"] = "true"
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", BROWSER_TESTS],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("missing, reason", [
    ("chromium", "chromium / chromedriver is not installed (apt-get install chromium chromium-driver)"),
    ("selenium", "selenium is not installed"),
])
def test_without_a_browser_the_browser_tests_skip_with_the_reason_and_fail_in_ci(tmp_path, missing, reason):
    here = _pytest(tmp_path, ci=False, missing=missing)
    assert here.returncode in (pytest.ExitCode.OK, pytest.ExitCode.NO_TESTS_COLLECTED), here.stdout + here.stderr  # the file alone, skipped whole
    assert "skipped" in here.stdout and "passed" not in here.stdout and "failed" not in here.stdout, here.stdout
    assert reason in here.stdout

    ci = _pytest(tmp_path, ci=True, missing=missing)
    assert ci.returncode not in (pytest.ExitCode.OK, pytest.ExitCode.NO_TESTS_COLLECTED), ci.stdout + ci.stderr
    assert f"in CI this must be present: Skipped: {reason}" in ci.stdout or f"in CI this must be present: {reason}" in ci.stdout, ci.stdout
    assert "passed" not in ci.stdout
