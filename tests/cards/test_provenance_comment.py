"""Every card's comment carries fit.json's provenance: versions, each record's SHA-256, options, date."""

from __future__ import annotations

import hashlib

import pytest

from flowcurve.reports.cards import FORMATS, load_card_data, write_card

SHA = {"c20_v1": hashlib.sha256(b"c20_v1 bytes").hexdigest(), "c20_v2": hashlib.sha256(b"c20_v2 bytes").hexdigest(),
       "c400_v1": None}
BLOCK = {"flowcurve_version": "0.1.0", "code_sha256": "ab12" * 16, "record_sha256": SHA,
         "options": {"melt_temp": 1400.0, "method": "global"}, "date_utc": "2026-11-26T11:40:00Z", "ccx_version": "ccx 2.20"}


@pytest.mark.parametrize("fmt", FORMATS)
def test_the_card_names_every_record_checksum_and_the_options(fit_file, fmt):
    card = write_card(load_card_data(fit_file(provenance=BLOCK)), fmt, "mm-s-t-N-MPa")
    head = card[: card.index("A = ") if "A = " in card else 4000]
    for name, sha in SHA.items():
        assert f"sha256 {sha or 'not recorded'}" in head and name in head  # the 64 hex digits whole, on one line
    assert "2026-11-26T11:40:00Z" in head and "ccx 2.20" in head and "code ab12ab12ab12" in head
    assert '{"melt_temp": 1400.0, "method": "global"}' in head


def test_a_fit_file_from_before_provenance_says_so(fit_file):
    card = write_card(load_card_data(fit_file()), "calculix", "mm-s-t-N-MPa")
    assert "provenance: fit file carries none" in card


def test_the_constants_carry_the_fits_total_uncertainty_where_it_states_one(fit_file, tmp_path):
    """A series fit states each constant's total standard uncertainty (fit and curve shape, fit.json
    total_uncertainty): the card's comment prints that, not the fit's standard error alone, and says what ± is."""
    plain = write_card(load_card_data(fit_file()), "lsdyna", "mm-s-t-N-MPa").replace("\n$   ", " ")
    total = write_card(load_card_data(fit_file(total_uncertainty={"A_MPa": 12.5, "B_MPa": 40.0, "n": 0.02, "C": None, "m": None})),
                       "lsdyna", "mm-s-t-N-MPa").replace("\n$   ", " ")
    assert "A = 105 +/- 2.1 MPa" in plain and "B = 1392 +/- 35 MPa" in plain
    assert "A = 105 +/- 12 MPa" in total and "B = 1392 +/- 40 MPa" in total and "n = 0.642 +/- 0.02" in total
    flat = total
    assert "standard uncertainty (k = 1)" in flat
