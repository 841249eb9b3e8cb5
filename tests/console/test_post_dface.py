"""The console's post-test form asks for the original end face (post.dface_mm) on a compression
specimen with h0/d0 ≥ 1.6: its prompt says why, and /api/post without it is refused with the
reason beside the field; given, it is written into the record (issue 37). A short specimen still
takes the form without it."""

from __future__ import annotations

import pytest

pytest.importorskip("hypothesis", reason="hypothesis is not installed (pip install -e .[test])")

from flowcurve.record.format import read_record  # noqa: E402

from .test_fuzz import _completed, _console_with  # noqa: E402

JSON = {"Content-Type": "application/json"}


def test_tall_compression_asks_for_the_end_face(tmp_path_factory):
    with _console_with(tmp_path_factory, {"test": "compression", "d0": "6", "h0": "10", "target": "0.5", "specimen_id": "tall"},
                       _completed) as fuzzed:
        client = fuzzed.client
        record = fuzzed.console.runner.current.record
        before = read_record(record).meta  # the virtual rig measured hk and dmax; a real one leaves them to the form
        test = client.get("/api/status").json()["test"]
        assert "needed" in test["post_prompts"]["post.dface_mm"] and "optional" not in test["post_prompts"]["post.dface_mm"]
        r = client.post("/api/post", json={"post.hk_mm": "9.6", "post.dmax_mm": "6.1"}, headers=JSON)
        assert r.status_code == 400 and "h0/d0 1.67" in r.json()["fields"]["post.dface_mm"]
        assert read_record(record).meta == before  # refused whole: nothing written
        r = client.post("/api/post", json={"post.hk_mm": "9.6", "post.dmax_mm": "6.1", "post.dface_mm": "6.05"}, headers=JSON)
        assert r.status_code == 200, r.text
        assert float(read_record(record).meta["post.dface_mm"]) == 6.05


def test_short_compression_keeps_the_end_face_optional(tmp_path_factory):
    with _console_with(tmp_path_factory, {"test": "compression", "target": "0.5", "specimen_id": "short"}, _completed) as fuzzed:
        assert "optional" in fuzzed.client.get("/api/status").json()["test"]["post_prompts"]["post.dface_mm"]
        r = fuzzed.client.post("/api/post", json={"post.hk_mm": "6.5", "post.dmax_mm": "6.1"}, headers=JSON)
        assert r.status_code == 200, r.text
