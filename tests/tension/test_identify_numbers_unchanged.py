"""Speed-ups of identify change no number: result.json against a stored reference.

The reference (``data/identify_reference.json``) was written by the code of commit 38e31b7,
before the speed work of issue 43, with::

    git checkout 38e31b7 && python tests/tension/test_identify_numbers_unchanged.py --write

The long cases were written again at the (3.1) change of branch klscale: the bench's record
stated Lu as L0 plus its *loaded* elongation at the end, and (3.1) now sets Lu − L0 against the
elongation at the fracture less the elastic recovery there, so its K_l moved 0.99996 → 1.0077 and
every strain-dependent value with it (Agt 19.73 → 19.89 %); the 42CrMoS4 cases (extensometer) are unchanged.
Written again (long cases only) on branch lcscale, twice: (3.1)'s a_u without post.du_mm moved from
the argmax sample to the flat maximum's mid-point less F·L(1 + a_u)²/(E·S0) (the bench's a_u 0.1994 →
0.1936 at 54k, K_l 1.00771 → 1.00763); then the bench's record states Lu as the caliper reads it on
the unloaded pieces (its loaded elongation less the uniform part's elastic give-back, 0.097 mm), so
like is set against like and K_l reads 0.99996 (54k and 540k) — the truth 1 of a record whose
crosshead less F/C is its specimen's elongation — and Agt 19.886 → 19.734 % (54k).
Written again (all cases) when A read off the curve without post.lu_mm came to state its terms
(result.json methods.A_from_curve, for A's new budget): the 42CrMoS4 cases gained that key and nothing
else moved; the long cases (Lu given) are byte-identical.
The long cases again when the bench's record came to state its parallel length (Lc = L0, its crosshead
stretches L0; a crosshead record without it now states the unknown length in its strain scale): the
keys specimen.parallel_length_mm and methods.strain_length_stated and the conformity's wording, no number.

Every leaf of result.json is compared: strings, booleans and nulls exactly, numbers to a
relative 1e-9 (float summation order may change; nothing else may).
"""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = Path(__file__).with_name("data") / "identify_reference.json"
DATA = ROOT / "tests" / "data" / "42CrMoS4" / "original_data"
SPECIMENS = ("46NT71", "46NT73", "46NT75", "46NT81")
LONG_ROWS = {"long_54k": 54_000, "long_540k": 540_000}  # the bench's record, a tenth and full length
REL_TOL = 1e-9


def _bench():
    spec = importlib.util.spec_from_file_location("identify_long_record", ROOT / "bench" / "identify_long_record.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def result_of(case: str, tmp: Path) -> dict:
    """result.json (as written) of one case: a 42CrMoS4 specimen or the bench's long record."""
    from flowcurve.identification.identify import identify
    from flowcurve.identification.outcome import to_jsonable
    from flowcurve.record.format import write_record
    from flowcurve.record.importers import load_record

    if case in LONG_ROWS:
        path = tmp / f"{case}.csv"
        write_record(path, _bench().synthetic_tension(LONG_ROWS[case]))
    else:
        path = DATA / f"{case}.csv"
    result = json.loads(json.dumps(to_jsonable(identify(load_record(path)).result), allow_nan=False))
    result["record"].pop("path")  # where the file was written, not a result
    return result


def differences(new, ref, where: str = "") -> list[str]:
    """Paths where new and ref differ (numbers beyond REL_TOL, anything else at all)."""
    if isinstance(ref, dict) and isinstance(new, dict):
        out = [f"{where}/{k}: missing" for k in ref.keys() - new.keys()]
        out += [f"{where}/{k}: new key" for k in new.keys() - ref.keys()]
        for k in ref.keys() & new.keys():
            out += differences(new[k], ref[k], f"{where}/{k}")
        return out
    if isinstance(ref, list) and isinstance(new, list):
        if len(ref) != len(new):
            return [f"{where}: length {len(new)} != {len(ref)}"]
        return [d for i, (a, b) in enumerate(zip(new, ref)) for d in differences(a, b, f"{where}[{i}]")]
    numbers = (int, float)
    if isinstance(ref, numbers) and isinstance(new, numbers) and not isinstance(ref, bool) and not isinstance(new, bool):
        return [] if math.isclose(new, ref, rel_tol=REL_TOL, abs_tol=0.0) else [f"{where}: {new!r} != {ref!r}"]
    return [] if new == ref and type(new) is type(ref) else [f"{where}: {new!r} != {ref!r}"]


def _cases():
    return [pytest.param(c, marks=pytest.mark.slow) if c == "long_540k" else c for c in (*SPECIMENS, *LONG_ROWS)]


@pytest.mark.parametrize("case", _cases())
def test_result_json_unchanged(case, tmp_path):
    reference = json.loads(REFERENCE.read_text(encoding="utf-8"))
    diff = differences(result_of(case, tmp_path), reference[case])
    assert not diff, f"{case}: {len(diff)} fields changed: " + "; ".join(diff[:10])


def test_comparison_catches_a_change():
    ref = {"a": 1.0, "b": [1, "x"], "c": None}
    assert differences(ref, ref) == []
    assert differences({"a": 1.0 + 1e-12, "b": [1, "x"], "c": None}, ref) == []
    assert differences({"a": 1.0 + 1e-8, "b": [1, "x"], "c": None}, ref)
    assert differences({"a": 1.0, "b": [1, "y"], "c": None}, ref)
    assert differences({"a": 1.0, "b": [1, "x"], "c": 0.0}, ref)


if __name__ == "__main__" and sys.argv[1:] == ["--write"]:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        out = {case: result_of(case, Path(tmp)) for case in (*SPECIMENS, *LONG_ROWS)}
    REFERENCE.parent.mkdir(exist_ok=True)
    REFERENCE.write_text(json.dumps(out, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    print(f"wrote {REFERENCE}")
