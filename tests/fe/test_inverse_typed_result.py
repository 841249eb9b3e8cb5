"""The inverse FE identifications return typed results (issue 44), and result.json is the file it was.

The compression and tension inverses run with CalculiX replaced by closed forms of the record
(test_inverse_numbers_unchanged.py's stand-ins; a few seconds in all). Each result.json, as
``Identification.write`` writes it, must equal the one the code of commit 377e6d0 wrote for the
same case (main before the typed blocks, when the inverse's result was a plain dict): key for key
in the same order, strings, booleans and nulls exactly, numbers to a relative 1e-12. The reference,
``data/inverse_result_json.json``, was written in an export of 377e6d0 (``git archive 377e6d0``)
with this file and test_inverse_numbers_unchanged.py copied in::

    FLOWCURVE_DEV_ROOT=<the export> python tests/fe/test_inverse_typed_result.py --write

Written again (``python tests/fe/<this file> --write`` on main) where a change outside the inverse moved its
inputs, each such change named in its commit: the compression strain zero of a handbook E (stop 51: only
the fe_table constants' standard errors), the tension scale (3.1) at the fracture (stop 51: the tension
stand-ins' K_l 0.991 → 1.002, and with it their inverse's fit). Stop 52: (3.1)'s a_u without post.du_mm read at the flat
maximum's mid-point less F·L(1 + a_u)²/(E·S0) (branch lcscale): the tension stand-ins' K_l, E and the inverse's fit move in
the fourth to fifth digit (E 79265 → 79261 MPa). And a hardening fit
whose Levenberg–Marquardt refit does not settle states the global stage's optimum (branch lawbest: a flat minimum's
end point was not reproducible): the tension auto case's per-law rms 5.05/5.05/0.46 → 4.46/4.30/0.24 % (JC, Swift, Voce),
its chosen Voce curve's first point 312.5 → 317.9 MPa.

Not compared: ``provenance`` (set by the command line, not here); the wall-clock times
(``wall_s``) and the record's file path, whose keys stay, in place, with a placeholder.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from flowcurve.identification.outcome import to_jsonable

sys.path.insert(0, str(Path(__file__).parent))
import test_inverse_numbers_unchanged as stand_ins  # noqa: E402  (the stand-in runs, shared with the numbers guard)

REFERENCE = Path(__file__).with_name("data") / "inverse_result_json.json"
REL_TOL = 1e-12
CLOCK_KEYS = {"wall_s"}  # a placeholder in place of their values
COMPRESSION = {  # name: (record, μ the force tells, μ the shape tells, law, fold-over strain, header keys dropped)
    "compression C2 johnson_cook": ("second_model_C2", 0.05, 0.05, "johnson_cook", None, ()),
    "compression C3 auto, fold-over, force and shape apart": ("second_model_C3", 0.03, 0.12, "auto", 0.4, ()),
    "compression C1 no dface": ("second_model_C1", 0.15, 0.15, "johnson_cook", None, ("post.dface_mm",)),
}
TENSION = {  # name: (force at fracture over Fm, law, post.dk_mm (None: the made-up record's), header keys dropped)
    "tension auto": (0.7, "auto", None, ()),
    "tension voce, dk 2.1": (0.6, "voce", "2.1", ()),
    "tension johnson_cook, no dk": (0.7, "johnson_cook", None, ("post.dk_mm",)),
}
UNTOLD = "compression C2 no dface, μ untold"


def _untold_fit(run, residuals_of, x0, lo, hi, *, n_residuals, **kw):
    """A solver fit's outcome that leaves μ undetermined (no Jacobian): test_inverse_untold.py's."""
    from flowcurve.identification.fe.solver_fit import SolverFit

    se = np.full(len(x0), 0.01)
    se[-1] = np.nan
    return SolverFit(x=np.asarray(x0, float), stderr=se, residuals=np.zeros(n_residuals), runs=9, solver_s=1.0, wall_s=1.0,
                     status=2, message="ftol", nfev=3, undetermined=(len(x0) - 1,))


def identification(case: str):
    """The Identification of one case."""
    if case in TENSION:
        *args, dropped = TENSION[case]
        return stand_ins.tension_identification(*args, dropped=dropped)
    if case == UNTOLD:
        import flowcurve.identification.fe.inverse as inverse

        patched = inverse.fit_with_solver
        inverse.fit_with_solver = _untold_fit
        try:
            return stand_ins.compression_identification("second_model_C2", 0.05, 0.05, "johnson_cook", None, dropped=("post.dface_mm",))
        finally:
            inverse.fit_with_solver = patched
    *args, dropped = COMPRESSION[case]
    return stand_ins.compression_identification(*args, dropped=dropped)


CASES = [*COMPRESSION, UNTOLD, *TENSION]


def _without_clock(value, key=""):
    """result.json's object with the clock's values and the record's path as placeholders, provenance left out."""
    if isinstance(value, dict):
        return {k: _without_clock(v, k) for k, v in value.items() if k != "provenance"}
    if isinstance(value, list):
        return [_without_clock(v) for v in value]
    return "<clock>" if key in CLOCK_KEYS else "<path>" if key == "path" and isinstance(value, str) else value


def written(ident, folder: Path) -> dict:
    """result.json as ``Identification.write`` writes it, read back in its order."""
    return json.loads((ident.write(folder) / "result.json").read_text(encoding="utf-8"))


def _differences(got, want, where="") -> list[str]:
    if isinstance(want, dict) and isinstance(got, dict):
        if list(got) != list(want):
            return [f"{where}: keys {list(got)} (reference {list(want)})"]
        return [d for k in want for d in _differences(got[k], want[k], f"{where}.{k}")]
    if isinstance(want, list) and isinstance(got, list) and len(want) == len(got):
        return [d for i, (g, w) in enumerate(zip(got, want)) for d in _differences(g, w, f"{where}[{i}]")]
    numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (got, want))
    if numbers and type(got) is type(want) and math.isclose(got, want, rel_tol=REL_TOL, abs_tol=0.0) or (got == want and type(got) is type(want)):
        return []
    return [f"{where}: {got!r} (reference {want!r})"]


@pytest.mark.parametrize("case", CASES)
def test_result_json_is_the_file_it_was_before_the_typed_blocks(case, tmp_path):
    want = json.loads(REFERENCE.read_text(encoding="utf-8"))[case]
    differences = _differences(_without_clock(written(identification(case), tmp_path)), want)
    assert not differences, f"{len(differences)} differences:\n" + "\n".join(differences[:20])


@pytest.mark.parametrize("case", ["compression C2 johnson_cook", UNTOLD, "tension voce, dk 2.1"])
def test_the_inverse_returns_the_typed_result_and_its_mapping_is_its_json(case, tmp_path):
    """The result stays a CompressionResult or TensionResult; its inverse_fe block, budget and hardening are typed; the
    mapping access, as_dict() and to_json() give what Identification.write writes."""
    from flowcurve.identification.fe.force_shape import MuBySide
    from flowcurve.identification.laws.hardening import HardeningFit
    from flowcurve.identification.results import (CompressionBudget, CompressionInverseFE, CompressionResult, InverseBudget,
                                                  InverseHardening, TensionInverseFE, TensionInverseHardening, TensionResult)

    ident = identification(case)
    result = ident.result
    if case in TENSION:
        assert type(result) is TensionResult and type(result.inverse_fe) is TensionInverseFE
        assert type(result.inverse_fe.budget) is InverseBudget
        assert type(result.hardening) is TensionInverseHardening and isinstance(result.hardening.fit, HardeningFit)
    else:
        assert type(result) is CompressionResult and type(result.inverse_fe) is CompressionInverseFE
        assert type(result.inverse_fe.budget) is CompressionBudget and type(result.hardening) is InverseHardening
        # the fit's Jacobian tells what the force and the shape alone say of μ; the untold stand-in has none
        assert isinstance(result.inverse_fe.by_side, MuBySide) is (case != UNTOLD)
        assert ("mu_force_alone" in result["inverse_fe"]) is (case != UNTOLD)
    assert result["inverse_fe"] == result.inverse_fe.as_dict() and result["hardening"] == result.hardening.as_dict()
    text = (ident.write(tmp_path) / "result.json").read_text(encoding="utf-8")
    assert result.to_json() == text
    assert json.loads(text) == json.loads(json.dumps(to_jsonable(result.as_dict()), allow_nan=False))


def test_the_compression_inverse_hardening_is_its_law_in_closed_form():
    """InverseHardening(ε_p) is Johnson–Cook's A + B·ε_p^n with the constants result.json gives, and the true curve is it."""
    ident = identification("compression C2 johnson_cook")
    h = to_jsonable(ident.result)["hardening"]
    eps = ident.true_curve["true_plastic_strain"].to_numpy()
    closed_form = h["A_MPa"] + h["B_MPa"] * eps ** h["n"]  # σ = A + B·ε_p^n
    np.testing.assert_allclose(ident.result.hardening(eps), closed_form, rtol=1e-12)
    np.testing.assert_allclose(ident.true_curve["true_stress_MPa"].to_numpy(), closed_form, rtol=1e-12)


def test_readers_of_the_typed_result_work(tmp_path):
    """The command line's summary and the plots read the typed inverse results as they read the dicts."""
    from flowcurve.cli.identification import summary_lines
    from flowcurve.reports.plots import add_plots

    for case, said in (("compression C3 auto, fold-over, force and shape apart", "inverse FE: μ"), ("tension voce, dk 2.1", "inverse FE beyond")):
        ident = identification(case)
        assert any(said in line for line in summary_lines(ident.result)), case
        add_plots(ident)
        folder = ident.write(tmp_path / case.split()[0])
        assert ident.plots and all((folder / f"{name}.png").stat().st_size > 0 for name in ident.plots)


if __name__ == "__main__" and "--write" in sys.argv:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        cases = {case: _without_clock(written(identification(case), Path(tmp) / str(i))) for i, case in enumerate(CASES)}
    REFERENCE.write_text(json.dumps(cases, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    print(f"wrote {REFERENCE}")
