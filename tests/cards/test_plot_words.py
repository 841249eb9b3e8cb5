"""The report's figures: words in the legends, one label style, the extrapolated part of a fit marked."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.figure  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from flowcurve.identification.outcome import Identification  # noqa: E402
from flowcurve.reports.plots import draw_corrections, draw_stress_strain  # noqa: E402


@pytest.fixture
def drawn(monkeypatch):
    """The texts (legends, axis labels, titles) and lines of every figure a draw function saves."""
    seen = []

    def capture(fig, path, **kw):
        texts, lines = [], []
        for ax in fig.axes:
            legend = ax.get_legend()
            texts += [t.get_text() for t in legend.get_texts()] if legend else []
            texts += [ax.get_xlabel(), ax.get_ylabel(), ax.get_title()]
            lines += [(line.get_label(), line.get_linestyle(), np.asarray(line.get_xdata(), dtype=float)) for line in ax.lines]
        seen.append((texts, lines))

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", capture)
    return seen


def _compression(fit_to: float, fitted: tuple[float, float]) -> Identification:
    eps = np.linspace(0.0, 0.6, 100)
    curves = {f"true_{m}": pd.DataFrame({"true_plastic_strain": eps, "true_stress_MPa": 400 + k * 10 + 300 * eps ** 0.4})
              for k, m in enumerate(("fe_table", "k_sigma", "siebel", "slab"))}
    grid = np.linspace(0.0, fit_to, 200)
    curves["fit"] = pd.DataFrame({"true_plastic_strain": grid, "true_stress_MPa": 400 + 300 * grid ** 0.4})
    result = {"test": "compression", "friction_correction": "fe_table",
              "hardening": {"law": "johnson_cook", "A_MPa": 400.0, "B_MPa": 300.0, "n": 0.4, "strain_range": list(fitted)},
              "record": {"name": "c1", "material": "steel45", "nominal_temperature_C": 20.0}}
    return Identification(result=result, true_curve=curves["true_fe_table"], curves=curves)


def test_a_fit_drawn_past_its_range_is_dashed_and_labelled(drawn, tmp_path):
    draw_stress_strain(_compression(0.8, (0.05, 0.6)), tmp_path / "s.png")
    texts, lines = drawn[0]
    dashed = [(label, x) for label, style, x in lines if style == "--"]
    assert len(dashed) == 1 and "extrapolated beyond the fitted εp 0.05–0.6" in dashed[0][0]
    beyond = dashed[0][1][np.isfinite(dashed[0][1])]
    assert beyond.min() > 0.6 and beyond.max() == pytest.approx(0.8)
    solid = next(x for label, style, x in lines if label.startswith("Johnson–Cook fit"))
    assert np.nanmin(solid) >= 0.05 and np.nanmax(solid) <= 0.6  # not drawn below the fitted range either


def test_legends_speak_words_and_labels_share_one_style(drawn, tmp_path):
    ident = _compression(0.6, (0.0, 0.6))
    draw_stress_strain(ident, tmp_path / "s.png")
    draw_corrections(ident, tmp_path / "c.png")
    texts = [t for figure_texts, _ in drawn for t in figure_texts]
    assert "selected true curve (CalculiX force-factor table)" in texts
    assert any(t.startswith("Johnson–Cook fit: A = 400 MPa") for t in texts)
    assert "other correction: Siebel" in texts and "K_σ/K_ε factors" in texts
    assert not any(code in t for t in texts for code in ("johnson_cook", "fe_table", "true fe", "k sigma", "k_sigma"))
    assert "true stress, MPa" in texts and "true stress (MPa)" not in texts
    assert not [label for _, lines in drawn for label, style, _ in lines if style == "--" and "extrapolated" in label]
