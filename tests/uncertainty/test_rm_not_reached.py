"""A tension test stopped before its force maximum (a fault drill's abort, a stop on the rise) has no Rm:
its largest force is a lower bound, and the budget says it is not certifiable instead of stating a U
(issue 43: the virtual rig's aborted drills printed Rm 30 % low ± 1 %)."""

import numpy as np
import pandas as pd

from flowcurve.identification.quality.assurance import force_maximum_not_reached
from flowcurve.record.format import Record


def _record(force_N, stop_reason):
    t = np.arange(force_N.size) * 0.1
    meta = {"test": "tension", "specimen.d0_mm": "6", "specimen.l0_mm": "30", "stop_reason": stop_reason}
    return Record(meta=meta, data=pd.DataFrame({"time_s": t, "force_N": force_N, "crosshead_mm": t * 0.05}), source="drill")


def _rising_then(after, noise_N=10.0, seed=0):
    """A work-hardening force (Fm 20 kN at the 400th sample of a uniform curve), cut as ``after`` says, with noise."""
    x = np.linspace(0.0, 1.0, 400)
    force = 20_000.0 * (1.0 - (1.0 - x) ** 2)  # rises to its maximum at x = 1
    force = np.concatenate([force, after])
    return force + np.random.default_rng(seed).normal(0.0, noise_N, force.size)


def test_a_test_stopped_on_the_rise_has_no_rm():
    x = np.linspace(0.0, 1.0, 400)[:250]
    force = 20_000.0 * (1.0 - (1.0 - x) ** 2) + np.random.default_rng(1).normal(0.0, 10.0, x.size)
    why = force_maximum_not_reached(_record(force, "load cell: stream ('MSV?0') silent for 1.3 s"))
    assert why and "before the force maximum" in why and "silent" in why


def test_a_test_stopped_after_the_maximum_keeps_rm():
    """Necking had begun (the force fell 3 % from Fm, far above its noise) when the fault stopped it: Fm is the test's."""
    necking = 20_000.0 * (1.0 - 0.03 * np.linspace(0.0, 1.0, 60))
    assert force_maximum_not_reached(_record(_rising_then(necking), "crosshead encoder: no answer for 2.0 s")) is None


def test_a_broken_specimen_keeps_rm():
    broken = np.array([19_500.0, 200.0, 50.0])
    assert force_maximum_not_reached(_record(_rising_then(broken), "fracture")) is None


def test_a_fall_within_the_noise_is_not_a_maximum():
    """A force held at its maximum, only its noise (±10 N) after the largest sample: the maximum is not passed."""
    flat = np.full(200, 20_000.0)
    assert force_maximum_not_reached(_record(_rising_then(flat, noise_N=10.0), "target displacement 5 mm reached"))


def test_identification_marks_rm_and_ag_not_certifiable():
    """Through identify: a drawn tension record cut at 60 % of its force rise, its stop reason a fault's."""
    import warnings

    from flowcurve.identification.identify import identify
    from tests.property.records import seeded_tension_record

    record, truth, _ = seeded_tension_record(4_300_300)
    force = np.abs(record.data["force_N"].to_numpy())
    cut = int(np.argmax(force >= 0.98 * force.max()))  # on the rise, before Fm
    data = record.data.iloc[:cut].reset_index(drop=True)
    meta = {k: v for k, v in record.meta.items() if not k.startswith("post.")} | {"stop_reason": "load cell: cannot open port"}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = identify(Record(meta=meta, data=data, source="cut")).result
    rm = result["uncertainty"]["Rm_MPa"]
    assert rm["certifiable"] is False and rm["U"] is None and "before the force maximum" in rm["note"]
    assert result["Rm_MPa"] < truth.Rm_MPa  # the lower bound the note says
    assert any("Rm is not certifiable" in w for w in result["warnings"])
