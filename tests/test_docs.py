"""The repository stands on its own: docstrings cite docs/methods.md (not a file outside the
repository), and every section they cite exists there."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ["flowcurve", "rig", "acquisition", "record", "identification", "reports", "examples", "bench", "docs", "tests"]


def _sources():
    for folder in FOLDERS:
        for path in sorted((ROOT / folder).rglob("*")):
            if path.suffix in (".py", ".md") and "__pycache__" not in path.parts:
                yield path


def methods_sections() -> set[str]:
    text = (ROOT / "docs" / "methods.md").read_text(encoding="utf-8")
    return set(re.findall(r"^## (\d+)\.", text, re.M)) | set(re.findall(r"\*\*§(\d+\.\d+)", text))


def test_every_cited_section_of_the_methods_reference_exists():
    sections = methods_sections()
    assert {"2.1", "3.2", "4.2", "5"} <= sections  # the parser finds headings and numbered items
    missing = []
    for path in _sources():
        for line_no, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for cited in re.findall(r"docs/methods\.md((?:[ ,]*§\d+(?:\.\d+)?(?:[–-]§\d+(?:\.\d+)?)?)+)", line):
                for number in re.findall(r"§(\d+(?:\.\d+)?)", cited):
                    if number not in sections:
                        missing.append(f"{path.relative_to(ROOT)}:{line_no}: §{number}")
    assert not missing, "cited sections missing from docs/methods.md: " + ", ".join(missing)


def test_no_citation_of_the_methods_file_outside_the_repository():
    bad = [f"{p.relative_to(ROOT)}" for p in _sources() if p.name != "test_docs.py"
           and re.search(r"(?<![/\w])METHODS\.md", p.read_text(encoding="utf-8"))]
    assert not bad, "cite docs/methods.md instead of METHODS.md: " + ", ".join(bad)


OUTSIDE_FILES = {"CALCULIX.md": "docs/calculix.md", "PROTOCOLS.md": "docs/protocols.md"}


def test_no_citation_of_the_other_reference_files_outside_the_repository():
    bad = [f"{p.relative_to(ROOT)}: {name} (cite {inside})" for p in _sources() if p.name != "test_docs.py"
           for name, inside in OUTSIDE_FILES.items() if re.search(rf"(?<![/\w]){re.escape(name)}", p.read_text(encoding="utf-8"))]
    assert not bad, "citations of files outside the repository: " + ", ".join(bad)


def test_nothing_reads_the_shared_folder_beside_the_checkout():
    """The validation records are in tests/data/ (a fresh clone with nothing beside it runs every test)."""
    pattern = re.compile(r"FLOWCURVE_SHARED|shared/validation|/work/shared|\"shared\"")
    bad = [f"{p.relative_to(ROOT)}:{n}" for p in _sources() if p.name != "test_docs.py"
           for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1) if pattern.search(line)]
    assert not bad, "paths outside the repository: " + ", ".join(bad)


def test_every_cited_docs_file_exists():
    missing = sorted({f"{p.relative_to(ROOT)}: {cited}" for p in [*_sources(), ROOT / "README.md"]
                      for cited in re.findall(r"docs/[\w.-]+\.md", p.read_text(encoding="utf-8")) if not (ROOT / cited).exists()})
    assert not missing, "cited docs files missing: " + ", ".join(missing)
