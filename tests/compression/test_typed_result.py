"""The typed compression result: optional keys only when they apply, the same text as result.json."""

import json
from pathlib import Path

from flowcurve.identification.identify import identify
from flowcurve.identification.results import CompressionResult
from flowcurve.record.format import read_record

EXAMPLE = Path(__file__).parents[2] / "examples" / "data" / "compression-steel45.csv"


def test_compression_result_serialises_with_its_optional_keys(tmp_path):
    ident = identify(read_record(EXAMPLE))
    res = ident.result
    assert isinstance(res, CompressionResult)
    assert "modulus" in res and res["modulus"]["source"] == res.modulus["source"]
    assert "E_apparent_stderr_MPa" not in res  # the handbook modulus: no apparent one
    assert res["hardening"]["correction"] == res.hardening.correction == res.friction_correction
    ident.write(tmp_path)
    assert (tmp_path / "result.json").read_text(encoding="utf-8") == res.to_json()
    assert list(json.loads(res.to_json()))[-1] == "modulus"
