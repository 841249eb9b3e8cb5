"""record.specimen: the specimen parsed once from the header, its areas against closed forms, the
record's errors for bad or missing values, and the area formula kept in one place in the product."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import pandas as pd
import pytest

from flowcurve.errors import MissingValueError, RecordError
from flowcurve.record.format import Record
from flowcurve.record.specimen import Specimen, circle_area_mm2

ROOT = Path(__file__).resolve().parents[2]
# the packages that read records; the virtual rig (rig/virtual/physics.py) keeps its own area, the truth the
# identification is tested against is computed apart from it
READERS = ("flowcurve", "record", "identification", "reports")
DATA = pd.DataFrame({"time_s": [0.0, 1.0], "force_N": [0.0, 1.0], "crosshead_mm": [0.0, 0.1]})


def _record(**meta) -> Record:
    return Record(meta={k.replace("__", "."): v for k, v in meta.items()}, data=DATA, source="T1.csv")


def test_a_round_tension_specimen_is_read_with_its_post_test_measurements():
    spec = _record(test="tension", specimen__d0_mm="6.0", specimen__l0_mm="30", specimen__extensometer_gauge_mm="25",
                   post__lu_mm="36.2", post__dk_mm="3.9", post__neck_radius_mm="2.5").specimen
    assert (spec.kind, spec.test, spec.d0_mm, spec.l0_mm, spec.gauge_mm) == ("round", "tension", 6.0, 30.0, 30.0)
    assert (spec.extensometer_gauge_mm, spec.lu_mm, spec.dk_mm, spec.neck_radius_mm, spec.sk_mm2, spec.h0_mm) == (25.0, 36.2, 3.9, 2.5, None, None)
    assert spec.area0_mm2 == pytest.approx(9.0 * math.pi, rel=1e-15)  # (d0/2)²·π, d0 = 6
    assert spec.s0_mm2 == spec.area0_mm2  # no stated S0
    assert spec.fracture_area_mm2 == pytest.approx(1.95**2 * math.pi, rel=1e-15)
    assert spec.fracture_area_source == "post.dk_mm"


def test_a_stated_section_wins_over_the_diameters_own():
    spec = _record(test="tension", specimen__d0_mm="5", specimen__l0_mm="25", specimen__s0_mm2="19.5", post__dk_mm="3", post__sk_mm2="7.2").specimen
    assert (spec.s0_mm2, spec.area0_mm2) == (19.5, pytest.approx(6.25 * math.pi))  # tension takes S0; the diameter's area stays π·d0²/4
    assert (spec.fracture_area_mm2, spec.fracture_area_source) == (7.2, "post.sk_mm2")
    bare = _record(test="tension", specimen__d0_mm="5", specimen__l0_mm="25").specimen
    assert (bare.fracture_area_mm2, bare.fracture_area_source) == (None, None)


def test_a_compression_specimen_reads_its_own_keys_only():
    spec = _record(test="compression", specimen__d0_mm="10", specimen__h0_mm="15", post__hk_mm="9.1",
                   post__dmax_mm="12.4", post__dface_mm="10.9", post__dk_mm="not a number").specimen
    assert (spec.d0_mm, spec.h0_mm, spec.gauge_mm, spec.hk_mm, spec.dmax_mm, spec.dface_mm, spec.smax_mm2) == (10.0, 15.0, 15.0, 9.1, 12.4, 10.9, None)
    assert spec.dk_mm is None  # a tension key on a compression record is not read (nor refused)
    assert spec.area0_mm2 == pytest.approx(25.0 * math.pi, rel=1e-15)
    assert spec.required("hk_mm") == 9.1


def test_circle_area_is_vectorized():
    import numpy as np

    assert circle_area_mm2(np.array([2.0, 4.0])) == pytest.approx([math.pi, 4.0 * math.pi], rel=1e-15)


@pytest.mark.parametrize("meta, message", [
    ({"test": "tension", "specimen.l0_mm": "30"}, "required metadata 'specimen.d0_mm' is missing"),
    ({"test": "tension", "specimen.d0_mm": "6"}, "required metadata 'specimen.l0_mm' is missing"),
    ({"test": "compression", "specimen.d0_mm": "6"}, "required metadata 'specimen.h0_mm' is missing"),
    ({"test": "tension", "specimen.d0_mm": "6,0", "specimen.l0_mm": "30"}, "metadata 'specimen.d0_mm' is not a number"),
    ({"test": "tension", "specimen.d0_mm": "-6", "specimen.l0_mm": "30"}, "metadata 'specimen.d0_mm' must be > 0, got -6"),
    ({"test": "tension", "specimen.d0_mm": "6", "specimen.l0_mm": "30", "post.dk_mm": "inf"}, "metadata 'post.dk_mm' is not finite"),
    ({"test": "compression", "specimen.d0_mm": "6", "specimen.h0_mm": "9", "post.hk_mm": "0"}, "metadata 'post.hk_mm' must be > 0, got 0"),
])
def test_bad_or_missing_values_get_the_records_one_line_error(meta, message):
    with pytest.raises(RecordError) as err:
        Record(meta=meta, data=DATA, source="T1.csv").specimen
    assert message in str(err.value) and str(err.value).startswith("T1.csv")


def test_a_required_post_measurement_not_given_is_named():
    spec = _record(test="compression", specimen__d0_mm="6", specimen__h0_mm="9").specimen
    with pytest.raises(MissingValueError, match=r"required metadata 'post.hk_mm' is missing"):
        spec.required("hk_mm")


def test_the_specimen_is_parsed_once_and_again_when_the_header_changes():
    record = _record(test="tension", specimen__d0_mm="6", specimen__l0_mm="30")
    first = record.specimen
    assert record.specimen is first
    record.meta["post.dk_mm"] = "4"  # an override after the first read is not lost to the cache
    assert record.specimen is not first and record.specimen.dk_mm == 4.0
    with pytest.raises(Exception):
        first.d0_mm = 7.0  # frozen
    assert Specimen.from_record(record) == record.specimen


def _is_pi(node: ast.AST) -> bool:
    return isinstance(node, ast.Attribute) and node.attr == "pi" or isinstance(node, ast.Name) and node.id == "pi"


def _squared(node: ast.AST) -> bool:
    return (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow) and isinstance(node.right, ast.Constant) and node.right.value == 2
            or isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult) and ast.dump(node.left) == ast.dump(node.right))


def circle_areas(tree: ast.AST) -> list[int]:
    """Lines of π·d²/4 (or π·d·d/4, d²·π/4) in a module: a product by π of a square, divided by 4."""
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div) and isinstance(node.right, ast.Constant) and node.right.value == 4:
            top = node.left
            if isinstance(top, ast.BinOp) and isinstance(top.op, ast.Mult) and (
                    _is_pi(top.left) and _squared(top.right) or _is_pi(top.right) and _squared(top.left)
                    or isinstance(top.left, ast.BinOp) and isinstance(top.left.op, ast.Mult) and _is_pi(top.left.left)
                    and ast.dump(top.left.right) == ast.dump(top.right)):  # π·d·d, parsed (π·d)·d
                lines.append(node.lineno)
    return lines


def header_parses(tree: ast.AST) -> list[int]:
    """Lines that read a ``specimen.*`` or ``post.*`` header key as a number off a record."""
    return [node.lineno for node in ast.walk(tree)
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in ("positive", "number")
            and node.args and isinstance(node.args[0], ast.Constant) and str(node.args[0].value).startswith(("specimen.", "post."))]


def _product_hits(find) -> list[str]:
    hits = []
    for path in sorted(p for pkg in READERS for p in (ROOT / pkg).rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        hits += [f"{path.relative_to(ROOT)}:{line}" for line in find(tree)]
    return hits


def test_the_finders_find_what_they_name():
    tree = ast.parse("a = math.pi * d0**2 / 4.0\nb = np.pi * d * d / 4\nc = d**2 * pi / 4\nd = math.pi * r**2\n"
                     "e = record.positive('specimen.d0_mm', required=True)\nf = record.number('post.hk_mm')\ng = record.number('material.nu')")
    assert circle_areas(tree) == [1, 2, 3]
    assert header_parses(tree) == [5, 6]


def test_the_circle_area_is_written_once_in_the_product():
    assert _product_hits(circle_areas) == ["record/specimen.py:" + str(_line_of("record/specimen.py", "return math.pi * d_mm**2 / 4.0"))]


def test_no_specimen_key_is_parsed_outside_the_record_package():
    assert [h for h in _product_hits(header_parses) if not h.startswith("record/")] == []


def _line_of(rel: str, text: str) -> int:
    return next(i for i, line in enumerate((ROOT / rel).read_text(encoding="utf-8").splitlines(), 1) if text in line)
