"""The tension inverse FE without the solver: its flow-curve family against closed forms, and
the records it refuses before any run (no fracture, too short a necking range)."""

from __future__ import annotations

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.inverse import identify_inverse_fe
from flowcurve.identification.fe.inverse_tension import extended_curve
from flowcurve.identification.fe.synthetic import tension_record
from flowcurve.identification.fe.tension import TensionModel, TensionResult


def test_the_extension_starts_at_the_uniform_end_with_slope_H_and_saturates_at_sigma_u_plus_H_over_b():
    ue, us = np.array([0.0, 0.05, 0.2]), np.array([300.0, 450.0, 600.0])
    H, b = 580.0, 4.0
    assert extended_curve(0.1, ue, us, H, b) == pytest.approx(np.interp(0.1, ue, us))
    assert extended_curve(0.2, ue, us, H, b) == pytest.approx(600.0)
    h = 1e-7
    assert (extended_curve(0.2 + h, ue, us, H, b) - 600.0) / h == pytest.approx(H, rel=1e-5)  # dσ/dε_p at ε_pu
    assert extended_curve(50.0, ue, us, H, b) == pytest.approx(600.0 + H / b, rel=1e-12)  # σ_u + H/b
    # b → 0: linear hardening with slope H
    assert extended_curve(0.7, ue, us, H, 1e-9) == pytest.approx(600.0 + H * 0.5, rel=1e-6)


def _record(force_end_fraction: float):
    """A tension record of a made-up run (no solver): rises to Fm, then falls to a fraction of it."""
    m = TensionModel(6.0, 30.0, 6.0, (0.0, 1.0), (300.0, 900.0))
    t = np.linspace(0.01, 1.0, 300)
    e = 6.0 * t
    fm = 15000.0
    force = np.where(t < 0.02, fm * t / 0.02 * 0.6, 0.6 * fm + 0.4 * fm * np.sin(np.clip((t - 0.02) / 0.6, 0, 1) * np.pi / 2))
    force = np.where(t > 0.62, fm - (1.0 - force_end_fraction) * fm * (t - 0.62) / 0.38, force)
    run = TensionResult(m, t, e, force, np.full(t.size, 2.2), True, 0.0)
    return tension_record(run)


def test_a_record_without_fracture_is_refused_before_any_solver_run(monkeypatch):
    import flowcurve.identification.fe.inverse_tension as inv

    def no_solver(*a, **k):
        raise AssertionError("the solver must not run")

    monkeypatch.setattr(inv, "fit_with_solver", no_solver)
    rec = _record(0.95)
    rec.data.loc[rec.data.index[-5:], "force_N"] = rec.data["force_N"].iloc[-6]  # no break: the force stays up
    with pytest.raises(IdentificationError, match="reaches fracture"):
        identify_inverse_fe(rec)
