"""A compression whose furnace heated the specimen on under load (the matrix's 300 C steel45 relay_stuck cell,
seed 196765774221528: 297–361 C under load, σ 1.8 % above the 300 C law early and 3.2 % below it late, 3 of 5
flow points outside U): its flow stresses are not the nominal temperature's and state no U."""

import numpy as np

from flowcurve.identification.identify import identify
from flowcurve.record.format import Record


def test_flow_stresses_recorded_off_the_nominal_temperature_are_not_certified(seed_like_record):
    record, _ = seed_like_record
    data = record.data.copy()
    meta = {**record.meta, "nominal_temperature_C": "300"}
    data["temperature_C"] = 300.0
    held = identify(Record(meta=meta, data=data, source="held.csv")).result
    data["temperature_C"] = np.linspace(298.0, 361.0, len(data))
    strayed = identify(Record(meta=meta, data=data, source="strayed.csv")).result
    for result, certified in ((held, True), (strayed, False)):
        unc = result["uncertainty"]
        budgets = [*unc["flow_stress_MPa"].values(), *unc["hardening"].values()]
        assert budgets and all((b["U"] is not None) == certified for b in budgets)
        assert unc["friction_mu"]["U"] is not None  # μ is the barrel's, not a temperature's
    assert any("not at the nominal 300 C" in w for w in strayed["warnings"])
