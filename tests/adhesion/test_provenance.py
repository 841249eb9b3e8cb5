"""friction.json and the friction cards say which tables (SHA-256) and options they came from."""

from __future__ import annotations

import hashlib
import json

from flowcurve.cli import main
from .synthetic import TRUTH


def test_friction_json_and_cards_carry_the_tables_checksums(make_table, tmp_path, capsys):
    table, _ = make_table(contact="full", moment_noise_rel=0.002, radius_noise_um=0.2)
    source = table.sources[0]
    out = tmp_path / "out"
    assert main(["friction", source, "--mu-d", str(TRUTH.mu_d), "--out", str(out), "--card", "abaqus"]) == 0
    block = json.loads((out / "friction.json").read_text(encoding="utf-8"))["provenance"]
    with open(source, "rb") as f:
        sha = hashlib.sha256(f.read()).hexdigest()
    assert block["record_sha256"] == {source: sha}
    assert block["options"]["method"] == "simple" and block["options"]["mu_d"] == TRUTH.mu_d and "out" not in block["options"]
    card = (out / "friction_abaqus.inp").read_text(encoding="utf-8")
    assert f"** sha256 {sha}" in card
