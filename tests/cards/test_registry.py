"""A card format is one registry entry: registered in a test (with no other edit) it is among
the card command's choices, names the console's card file and is written and linked by the report."""

from __future__ import annotations

import re
import warnings

import pytest

from flowcurve.cli import main
from flowcurve.reports.cards import registry
from flowcurve.reports.cards.registry import WRITERS, CardFormat, card_suffix
from flowcurve.reports.report import build_report

from .test_report import make_series


def toy_card(data, units, options) -> str:
    """A stand-in solver's card: the material and A in the deck's stress unit."""
    return f"** toy card of {data.material}\nA = {data.A_MPa}\n"


@pytest.fixture
def toy(monkeypatch):
    entry = CardFormat("toy", "toy", "Toy Solver", toy_card, "the toy keyword", in_report=True)
    monkeypatch.setitem(WRITERS, "toy", entry)
    return entry


def test_every_entry_carries_its_name_suffix_and_display_name():
    assert list(WRITERS) == ["lsdyna", "abaqus", "radioss", "calculix", "flow-table"]
    for name, entry in WRITERS.items():
        assert entry.name == name and entry.display_name and re.fullmatch(r"[a-z0-9]+", entry.suffix)
    assert [card_suffix(f) for f in WRITERS] == ["k", "inp", "rad", "inp", "csv"]
    assert card_suffix("nonesuch") == "txt"


def test_a_registered_format_is_among_the_card_commands_choices(toy, fit_file, tmp_path, capsys):
    out = tmp_path / "card.toy"
    assert main(["card", str(fit_file()), "--format", "toy", "-o", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == "** toy card of 12Kh18N12M3TL\nA = 105.0\n"
    with pytest.raises(SystemExit):
        main(["card", str(fit_file()), "--format", "nonesuch"])
    assert "'toy'" in capsys.readouterr().err  # argparse lists the choices


def test_a_registered_format_is_written_and_linked_by_the_report(toy, tmp_path):
    root = make_series(tmp_path / "series")
    out = tmp_path / "out"
    text = build_report(root, cards_dir=out / "cards", link_base=out, density_kg_per_m3=7820.0)
    href = re.search(r"<a href='(cards/[^']+\.toy)'>", text).group(1)
    assert (out / href).read_text(encoding="utf-8").startswith("** toy card of 12Kh18N12M3TL")
    assert "Toy Solver card (mm-s-t-N-MPa, the toy keyword): cards/" in text
    assert re.search(r"<a href='cards/[^']+-lsdyna-[^']+\.k'>", text)  # the LS-DYNA card still beside it
    assert "--format abaqus|radioss|calculix" in text  # the formats the report does not write, for 'flowcurve card'


def test_a_report_format_that_is_not_lsdyna_stands_alone(monkeypatch, tmp_path):
    """With LS-DYNA out of the report, nothing of it is written or named there."""
    monkeypatch.setitem(WRITERS, "lsdyna", CardFormat("lsdyna", "k", "LS-DYNA", WRITERS["lsdyna"].write))
    monkeypatch.setitem(WRITERS, "toy", CardFormat("toy", "toy", "Toy Solver", toy_card, in_report=True))
    root = make_series(tmp_path / "series")
    text = build_report(root, cards_dir=tmp_path / "cards", link_base=tmp_path)
    assert "LS-DYNA card" not in text and "Toy Solver card" in text
    assert [p.suffix for p in (tmp_path / "cards").iterdir()] == [".toy"]


def test_a_registered_format_names_the_consoles_card_file(toy, tmp_path):
    pytest.importorskip("starlette", reason="starlette is not installed (pip install -e .[test])")
    pytest.importorskip("httpx", reason="httpx is not installed (pip install -e .[test])")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from starlette.testclient import TestClient

    from flowcurve.console.server import Console, create_app
    from tests.console.conftest import identified_records

    client = TestClient(create_app(Console(tmp_path / "out", time_scale=60.0)), base_url="http://127.0.0.1:8080")
    names = identified_records(tmp_path / "out")
    r = client.post("/api/fit", json={"records": names, "format": "toy", "melt_temp": "1450", "fix_C": "0.01", "fix_m": "1"},
                    headers={"Content-Type": "application/json"})
    assert r.status_code == 200, r.text
    assert r.json()["card_name"] == "card-toy.toy"
    (card,) = (tmp_path / "out" / "fits").glob("fit-*/card-toy.toy")
    assert card.read_text(encoding="utf-8").startswith("** toy card of")
    assert registry.card_format("toy") is toy


def test_the_consoles_format_list_is_the_registrys(toy, tmp_path):
    """/api/info hands the page the registry's formats (the page's select is built from them, not written
    by hand): a registered format is among them with its display name, in registry order."""
    pytest.importorskip("starlette", reason="starlette is not installed (pip install -e .[test])")
    pytest.importorskip("httpx", reason="httpx is not installed (pip install -e .[test])")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from starlette.testclient import TestClient

    from flowcurve.console.server import Console, create_app

    client = TestClient(create_app(Console(tmp_path / "out", time_scale=60.0)), base_url="http://127.0.0.1:8080")
    formats = client.get("/api/info").json()["card_formats"]
    assert formats == [[name, entry.display_name] for name, entry in WRITERS.items()]
    assert ["toy", toy.display_name] in formats and formats[0] == ["lsdyna", "LS-DYNA"]
