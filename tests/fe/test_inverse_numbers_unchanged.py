"""The split of the inverse FE (issue 44) changes no number: results against a stored reference.

CalculiX is replaced by closed forms of the record (as in test_force_shape.py and
test_time_limit.py), so the whole chain runs in seconds: the compression inverse on two vendored
records, the tension inverse on two made-up records, and ``fit_with_solver`` alone. The reference
(``data/inverse_reference.json``) was written by the code of commit 01c1793, before the split: this
file copied into an export of that commit (``git archive 01c1793``) and run there with::

    FLOWCURVE_DEV_ROOT=<the export> python tests/fe/test_inverse_numbers_unchanged.py --write

Written again (``python tests/fe/<this file> --write`` on main) where a change outside the inverse moved its
inputs, each such change named in its commit: the compression strain zero of a handbook E (stop 51: only
the fe_table constants' standard errors), the tension scale (3.1) at the fracture (stop 51: the tension
stand-ins' K_l 0.991 → 1.002, and with it their inverse's fit). Stop 52: (3.1)'s a_u without post.du_mm read at the flat
maximum's mid-point less F·L(1 + a_u)²/(E·S0) (branch lcscale): the tension stand-ins' K_l, At and the inverse's fit move in the
fourth to fifth digit (At 20.0382 → 20.0392 %). And a hardening fit
whose Levenberg–Marquardt refit does not settle states the global stage's optimum (branch lawbest: a flat minimum's
end point was not reproducible): the tension auto case's per-law rms 5.05/5.05/0.46 → 4.46/4.30/0.24 % (JC, Swift, Voce),
its chosen Voce curve's first point 312.5 → 317.9 MPa.

Every leaf is compared: strings, booleans and nulls exactly, numbers to a relative 1e-9; the wall
and solver times and the record's path are left out.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = Path(__file__).with_name("data") / "inverse_reference.json"
DATA = Path(__file__).with_name("data")
REL_TOL = 1e-9
LEFT_OUT = {"wall_s", "solver_s", "provenance", "path"}
COMPRESSION = [("second_model_C2", 0.05, 0.05, "johnson_cook", None), ("second_model_C3", 0.03, 0.12, "auto", 0.4)]
TENSION = [(0.7, "auto", None), (0.6, "voce", "2.1")]
DMAX_PER_MU, DFACE_PER_MU = 1.5, -3.0  # mm per unit μ: the bulge grows with μ, the original end face shrinks
FORCE_PER_MU = 0.5  # relative force per unit μ at the end of the stroke, growing as t³ (the law takes up 1, t, t²)


def _entry_points():
    """(identify_inverse_fe for both tests, TensionModel, TensionResult) where they are, before or after the split."""
    try:
        from flowcurve.identification.fe.model.tension import TensionModel, TensionResult
        from flowcurve.identification.identify import identify_inverse_fe
    except ImportError:  # 01c1793, the reference's code
        from flowcurve.identification.fe.inverse import identify_inverse_fe
        from flowcurve.identification.fe.tension import TensionModel, TensionResult
    return identify_inverse_fe, TensionModel, TensionResult


def _plain(value):
    from flowcurve.identification.outcome import to_jsonable

    value = to_jsonable(value)
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items() if k not in LEFT_OUT}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return "nan" if isinstance(value, float) and math.isnan(value) else value


def _identification(ident, curves) -> dict:
    out = _plain(ident.result)
    out["curves"] = {k: _plain(ident.curves[k].to_dict(orient="list")) for k in curves}
    out["true_curve"] = _plain(ident.true_curve.to_dict(orient="list"))
    return out


def linear_runs(state: dict):
    """(capture, run): stand-ins for ``verify.record_force_stroke`` (the real one, its stroke, force and header kept
    in ``state``) and the compression inverse's ``_run``: the record's own force times 1 + (the law's constants'
    relative change)·(1, t, t²) + 0.5·t³·(μ − state["mu_force"]) + a fixed 0.05 % misfit, dmax and dface moved by
    +1.5 and −3 mm per unit (μ − state["mu_shape"]), the side folding over from state["fold_over"] (None: not)."""
    import flowcurve.identification.fe.inverse as inv
    import flowcurve.identification.fe.verify as verify

    real = verify.record_force_stroke

    def capture(record, **kw):
        out = real(record, **kw)
        state["stroke"], state["force"], state["meta"] = np.asarray(out[0], float), np.asarray(out[1], float), record.meta
        return out

    def run(problem, x):
        x = np.asarray(x, float)
        x0 = state.setdefault("x0", x.copy())
        s, f = state["stroke"], state["force"]
        t = s / s.max()
        rel = x[:-1] / x0[:-1] - 1.0
        factor = 1.0 + rel[0] + rel[1] * t + rel[2] * t**2 + FORCE_PER_MU * t**3 * (x[-1] - state["mu_force"]) + 5e-4 * np.cos(40.0 * t)
        dmu, meta = x[-1] - state["mu_shape"], state["meta"]
        return inv._Run(s, f * factor, float(meta["post.dmax_mm"]) + DMAX_PER_MU * dmu, float(meta.get("post.dface_mm", "nan")) + DFACE_PER_MU * dmu,
                        wall_s=0.0, cached=True, fold_over_strain=state.get("fold_over"))

    return capture, run


def compression_identification(name, mu_force, mu_shape, law, fold_over, *, dropped=()):
    """The compression inverse's Identification on a vendored record (its ``dropped`` header keys left out) with
    :func:`linear_runs` for CalculiX."""
    import flowcurve.identification.fe.inverse as inv
    import flowcurve.identification.fe.verify as verify
    from flowcurve.record.format import read_record

    identify_inverse_fe = _entry_points()[0]
    record = read_record(DATA / f"{name}.csv")
    for key in dropped:
        del record.meta[key]
    patched = verify.record_force_stroke, inv._run
    verify.record_force_stroke, inv._run = linear_runs({"mu_force": mu_force, "mu_shape": mu_shape, "fold_over": fold_over})
    try:
        return identify_inverse_fe(record, law=law, workers=1, time_limit_s=None)
    finally:
        verify.record_force_stroke, inv._run = patched


def _compression(name, mu_force, mu_shape, law, fold_over) -> dict:
    """The compression inverse on a vendored record with :func:`linear_runs` for CalculiX."""
    return _identification(compression_identification(name, mu_force, mu_shape, law, fold_over), ["inverse_fe_force"])


def tension_identification(force_end_fraction, law, dk, *, dropped=()):
    """The tension inverse's Identification on a made-up record (test_inverse_tension_inputs.py's; its ``dropped`` header keys
    left out), each run its corrected force scaled by 1 + (H/H* − 1)·u + 10·(δ − δ*)·u² and a neck radius moving with δ
    (test_time_limit.py's)."""
    import flowcurve.identification.fe.inverse_tension as invt
    from flowcurve.identification.fe.synthetic import tension_record
    from flowcurve.identification.tension.identify import identify_tension

    identify_inverse_fe, TensionModel, TensionResult = _entry_points()
    t = np.linspace(0.01, 1.0, 300)
    fm = 15000.0
    force = np.where(t < 0.02, fm * t / 0.02 * 0.6, 0.6 * fm + 0.4 * fm * np.sin(np.clip((t - 0.02) / 0.6, 0, 1) * np.pi / 2))
    force = np.where(t > 0.62, fm - (1.0 - force_end_fraction) * fm * (t - 0.62) / 0.38, force)
    record = tension_record(TensionResult(TensionModel(6.0, 30.0, 6.0, (0.0, 1.0), (300.0, 900.0)), t, 6.0 * t, force,
                                          np.full(t.size, 2.2), True, 0.0))
    if dk is not None:
        record.meta["post.dk_mm"] = dk
    for key in dropped:
        del record.meta[key]
    diagram = identify_tension(record).curves["corrected_diagram"]
    elong, f_c = diagram["elongation_mm"].to_numpy(), diagram["force_N"].to_numpy()
    state, patched = {}, invt._run

    def run(problem, x):
        target = state.setdefault("target", (1.2 * float(x[0]), 0.008))
        u = elong / elong.max()
        factor = 1.0 + (x[0] / target[0] - 1.0) * u + 10.0 * (x[3] - target[1]) * u**2
        return invt._Run(elong, f_c * factor, np.full(elong.size, 2.2) - 0.3 * (x[3] - 0.008), 1.0, False)

    invt._run = run
    try:
        return identify_inverse_fe(record, law=law, workers=1, time_limit_s=None)
    finally:
        invt._run = patched


def _tension(force_end_fraction, law, dk) -> dict:
    """The tension inverse on a made-up record with :func:`tension_identification`'s stand-in runs."""
    return _identification(tension_identification(force_end_fraction, law, dk), ["inverse_fe_force", "fit"])


def _fit(kind: str) -> dict:
    """``fit_with_solver`` alone on an exponential whose runs fail beyond a rate of 2.5."""
    from flowcurve.identification.fe.solver_fit import fit_with_solver

    class Out:
        def __init__(self, y):
            self.y, self.wall_s, self.cached, self.retried = y, 0.5, False, False

    T = np.linspace(0.0, 1.0, 40)
    target = 2.0 * np.exp(-1.3 * T)

    def run(x):
        return None if x[1] > 2.5 else Out(x[0] * np.exp(-x[1] * T) + 0.01 * np.sin(9 * T))

    options = {"failed start": {"other_starts": [[1.0, 1.0]]},
               "best start, known row": {"best_start": True, "other_starts": [[1.0, 0.5], [3.0, 2.0]],
                                         "row_sigma": np.r_[np.full(39, np.nan), 0.1], "correlated": True}}[kind]
    sol = fit_with_solver(run, lambda out: out.y - target, np.array([1.5, 2.6 if kind == "failed start" else 0.8]), [0.1, 0.0], [5.0, 5.0],
                          n_residuals=T.size, steps=lambda x: np.full(2, 1e-4), x_scale=np.ones(2), workers=1, **options)
    return _plain({k: getattr(sol, k) for k in ("x", "stderr", "residuals", "runs", "status", "message", "nfev", "undetermined",
                                                 "jac", "covariance", "failed_runs", "retried_runs", "cut")})


CASES = {**{f"compression {c[0]} {c[3]}": (_compression, c) for c in COMPRESSION},
         **{f"tension {c[0]} {c[1]} dk={c[2]}": (_tension, c) for c in TENSION},
         **{f"fit {k}": (_fit, (k,)) for k in ("failed start", "best start, known row")}}


def _differences(got, want, where="") -> list[str]:
    if isinstance(want, dict) and isinstance(got, dict):
        out = [f"{where}.{k}: missing" for k in want.keys() - got.keys()] + [f"{where}.{k}: new" for k in got.keys() - want.keys()]
        return out + [d for k in want.keys() & got.keys() for d in _differences(got[k], want[k], f"{where}.{k}")]
    if isinstance(want, list) and isinstance(got, list) and len(want) == len(got):
        return [d for i, (g, w) in enumerate(zip(got, want)) for d in _differences(g, w, f"{where}[{i}]")]
    numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (got, want))
    if numbers and math.isclose(got, want, rel_tol=REL_TOL, abs_tol=0.0) or got == want:
        return []
    return [f"{where}: {got!r} (reference {want!r})"]


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_inverse_gives_the_numbers_it_gave_before_the_split(case):
    func, args = CASES[case]
    differences = _differences(func(*args), json.loads(REFERENCE.read_text(encoding="utf-8"))[case])
    assert not differences, f"{len(differences)} fields changed:\n" + "\n".join(differences[:20])


if __name__ == "__main__" and "--write" in sys.argv:
    REFERENCE.write_text(json.dumps({case: func(*args) for case, (func, args) in CASES.items()}, indent=0, sort_keys=True) + "\n",
                         encoding="utf-8")
    print(f"wrote {REFERENCE}")
