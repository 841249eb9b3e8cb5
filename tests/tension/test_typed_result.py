"""The typed result: fields are the keys of result.json, and it still reads like the dict it replaced."""

import json

import pytest

from flowcurve.identification.identify import identify
from flowcurve.identification.results import TensionHardening, TensionResult


def test_tension_result_is_typed_and_serialises_to_result_json(synthetic, tmp_path):
    record, _ = synthetic()
    ident = identify(record)
    res = ident.result
    assert isinstance(res, TensionResult) and isinstance(res.hardening, TensionHardening)
    assert res.hardening.fit(0.1) == pytest.approx(res["hardening"]["A_MPa"] + res["hardening"]["B_MPa"] * 0.1 ** res["hardening"]["n"])
    ident.write(tmp_path)
    written = (tmp_path / "result.json").read_text(encoding="utf-8")
    assert written == res.to_json()
    assert list(json.loads(written)) == list(res) == list(res.as_dict())
    assert list(res)[0] == "test" and list(res)[-1] == "record"
    # the transition aid: mapping access, assignment to its own keys only
    assert res["Rm_MPa"] == res.Rm_MPa and res.get("no_such_key") is None and "E_MPa" in res
    res["warnings"] = res["warnings"] + ["x"]
    assert res.warnings[-1] == "x"
    with pytest.raises(KeyError):
        res["no_such_key"] = 1
    with pytest.raises(TypeError):
        del res["E_MPa"]
