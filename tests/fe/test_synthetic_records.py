"""Quick checks (no solver) of how FE runs become records, against closed forms: the crosshead
moves at the set speed (so the elastic line takes the time the frame's compliance gives it),
the toe closes as the force reaches its toe force, and a small first increment reaches the deck."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowcurve.identification.fe.synthetic import upsetting_record
from flowcurve.identification.fe.model.upsetting import UpsettingModel, UpsettingResult, upsetting_deck

E, D0, H0 = 200_000.0, 6.0, 9.0
AREA = math.pi * D0**2 / 4.0


def elastic_plastic_run(sigma_y=400.0, stroke_end=3.0, points=300) -> UpsettingResult:
    """A homogeneous, frictionless, perfectly plastic upsetting history in closed form:
    elastic to σ_y at the stroke h0·σ_y/E, then F = σ_y·A0·h0/h (volume constancy)."""
    model = UpsettingModel.from_law(D0, H0, H0 - stroke_end, 0.0, lambda e: np.full_like(np.asarray(e, float), sigma_y), E_MPa=E)
    stroke = np.linspace(stroke_end / points, stroke_end, points)
    h = H0 - stroke
    yield_stroke = H0 * sigma_y / E
    force = np.where(stroke < yield_stroke, stroke / H0 * E * AREA, sigma_y * AREA * H0 / h)
    d = D0 * np.sqrt(H0 / h)
    return UpsettingResult(model, stroke / stroke_end, stroke, h, force, d, d, True, 0.0, False)


@pytest.mark.parametrize("speed_mm_per_s, stiffness", [(0.18, 136.0), (0.018, 40.0)])
def test_the_crosshead_moves_at_the_set_speed(speed_mm_per_s, stiffness):
    rec = upsetting_record(elastic_plastic_run(), speed_mm_per_s=speed_mm_per_s, stiffness_N_per_um=stiffness, rate_hz=10.0,
                           noise_N=0.0, step_mm=1e-9, toe_mm=0.0)
    t, x, f = (rec.data[c].to_numpy() for c in ("time_s", "crosshead_mm", "force_N"))
    loading = np.arange(f.size) <= np.argmax(np.abs(f))
    np.testing.assert_allclose(-x[loading], speed_mm_per_s * t[loading], rtol=1e-6, atol=1e-6)
    # the elastic line: crosshead = F·(h0/(E·A0) + 1/C) → its samples = that travel / (speed/rate)
    f_y = 400.0 * AREA
    travel = f_y * (H0 / (E * AREA) + 1.0 / (stiffness * 1000.0))
    on_line = int(np.sum(np.abs(f[loading]) < 0.999 * f_y))
    assert on_line == pytest.approx(travel / speed_mm_per_s * 10.0, abs=1.5)


def test_the_toe_closes_at_its_force():
    """The toe is a soft contact in series: toe = toe_mm·√(F/F_toe) up to F_toe, then closed."""
    toe_mm, toe_force = 0.03, 300.0
    rec = upsetting_record(elastic_plastic_run(), speed_mm_per_s=0.01, rate_hz=50.0, noise_N=0.0, step_mm=1e-9,
                           toe_mm=toe_mm, toe_force_N=toe_force, stiffness_N_per_um=136.0)
    x, f = -rec.data["crosshead_mm"].to_numpy(), -rec.data["force_N"].to_numpy()
    elastic = H0 / (E * AREA) + 1.0 / 136_000.0  # mm/N of specimen and frame
    early = (f > 1.0) & (f < 0.5 * 400.0 * AREA) & (np.arange(f.size) < np.argmax(f))  # the first loading
    expected = f[early] * elastic + toe_mm * np.sqrt(np.clip(f[early] / toe_force, 0.0, 1.0))
    np.testing.assert_allclose(x[early], expected, atol=2e-6)


def test_a_small_first_increment_reaches_the_deck():
    law = lambda e: 300.0 + 0.0 * np.asarray(e, float)  # noqa: E731
    static = lambda m: upsetting_deck(m).split("*STATIC\n")[1].splitlines()[0].split(",")  # noqa: E731
    plain = UpsettingModel.from_law(D0, H0, 5.0, 0.1, law, increments=50)
    fine_start = UpsettingModel.from_law(D0, H0, 5.0, 0.1, law, increments=50, first_increment=1.0 / 3000)
    assert float(static(plain)[0]) == pytest.approx(1 / 50) and float(static(plain)[3]) == pytest.approx(1 / 50)
    first, _, smallest, largest = map(float, static(fine_start))
    assert first == pytest.approx(1 / 3000) and largest == pytest.approx(1 / 50) and smallest <= first
