"""Run an identified flow curve on a record's specimen in CalculiX and compare force–stroke.

The check the seed did in LS-DYNA (5.1 %), done with an open solver: the identified curve
(a ``result.json``'s hardening law, or the ``*ELASTIC``/``*PLASTIC`` rows of a CalculiX card)
and friction μ drive the upsetting model (:mod:`.upsetting`) on the record's d0, h0 to the
record's largest shortening; the record's frame-corrected force–stroke curve (the fast
identification's ``corrected_diagram``) is compared with the FE force at the same stroke.

The check runs a finer discretisation than the inverse FE fits with (:data:`VERIFY_LAYERS`
rim-layer elements, :data:`VERIFY_INCREMENTS` increments), and the inverse's own one beside it:
the gap between the two is the check's own discretisation error, reported with the deviation.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.elastic_modulus import DEFENSIBLE, SOURCE_TEXT, choose_modulus, result_material_E
from flowcurve.identification.fe.model.model_form import FOLD_OVER_BAND
from flowcurve.identification.fe.model.deck import PLASTIC_ROWS
from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting
from flowcurve.identification.laws.hardening import static_form, static_law_names

COMPARE_FROM_STRAIN = 0.02  # the toe and the elastic rise are left out of the deviation
# the check's discretisation: finer than the fit's (2 rim-layer elements, 50 increments), so that a curve is not judged
# on the model it was fitted with; where the side folds over, the two differ most (docs/methods.md §4a.5)
VERIFY_LAYERS, VERIFY_INCREMENTS = 4, 200
FIT_LAYERS, FIT_INCREMENTS = UpsettingModel.layers, UpsettingModel.increments


@dataclass
class FlowCurveSource:
    eps_p: np.ndarray
    stress_MPa: np.ndarray
    E_MPa: float | None
    mu: float | None
    what: str
    diagram_options: dict | None = None  # how the inverse read the record (its E, a fitted frame stiffness)
    E_source: str = ""  # where the curve's E came from (given, handbook, the class's, the card's *ELASTIC)


def _table_from_function(fn, eps_max: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    eps = np.concatenate([[0.0], np.geomspace(1e-4, eps_max, PLASTIC_ROWS)])
    return eps, np.asarray(fn(eps), dtype=float)


def curve_from_result(result: dict, source: str = "result.json") -> FlowCurveSource:
    """The hardening law of a ``result.json`` (law + unit-named constants) as a *PLASTIC table."""
    h = result.get("hardening") or {}
    try:
        law = static_form(str(h.get("law")))
    except IdentificationError:
        raise IdentificationError(f"{source}: no hardening law to verify ('hardening.law' is {h.get('law')!r}; expected one of {', '.join(static_law_names())})") from None
    try:
        params = {name: float(h[key]) for name, key in zip(law.names, law.keys)}
    except (KeyError, TypeError, ValueError):
        raise IdentificationError(f"{source}: hardening constants {', '.join(law.keys)} missing or not numbers") from None
    eps, sig = _table_from_function(lambda e: law.func(e, **params))
    E, E_source = result_material_E(result)  # by the one rule; an apparent slope is never the model's E
    E, E_text = (E, f"{source}: {SOURCE_TEXT[E_source]}") if E_source in DEFENSIBLE else (None, "")
    model = (result.get("inverse_fe") or {}).get("model") or {}
    if model.get("E_MPa") is not None:  # the inverse's model E (given, handbook, a class's handbook value)
        E, E_text = model["E_MPa"], f"{source}: the inverse's model E ({model.get('E_source', 'its source unstated')})"
    mu = result.get("friction_mu")
    return FlowCurveSource(eps, sig, E, None if mu is None else float(mu), f"{source}: {h['law']} {params}", model.get("diagram_options"), E_text)


def curve_from_card(text: str, source: str = "card") -> FlowCurveSource:
    """``*ELASTIC`` (E, ν) and the first temperature's ``*PLASTIC`` rows (σ, ε_p[, T]) of a CalculiX card."""
    E, rows, block = None, [], None
    for line_no, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("**"):
            continue
        if line.startswith("*"):
            block = line.split(",")[0].upper()
            if block == "*PLASTIC" and "HARDENING=JOHNSON" in line.upper().replace(" ", ""):
                raise IdentificationError(f"{source}, line {line_no}: *PLASTIC, HARDENING=JOHNSON COOK is misread by ccx 2.20; give a table")
            continue
        try:
            values = [float(v) for v in line.rstrip(",").split(",")]
        except ValueError:
            raise IdentificationError(f"{source}, line {line_no}: not a row of numbers: {line[:60]!r}") from None
        if block == "*ELASTIC" and E is None:
            E = values[0]
        elif block == "*PLASTIC":
            rows.append(values)
    if len(rows) < 2:
        raise IdentificationError(f"{source}: no *PLASTIC table (need at least 2 rows)")
    rows = np.array([r[:3] for r in rows if len(r) >= 2], dtype=object)
    first_t = rows[0][2] if len(rows[0]) > 2 else None
    table = np.array([[r[0], r[1]] for r in rows if (len(r) < 3 or r[2] == first_t)], dtype=float)
    sig, eps = table[:, 0], table[:, 1]
    if eps[0] != 0.0 or np.any(np.diff(eps) <= 0):
        raise IdentificationError(f"{source}: *PLASTIC strains must start at 0 and increase")
    if eps.size > 100:  # keep ccx's table short (docs/calculix.md)
        grid = np.concatenate([[0.0], np.geomspace(max(eps[1], 1e-5), eps[-1], PLASTIC_ROWS)])
        sig, eps = np.interp(grid, eps, sig), grid
    return FlowCurveSource(eps, sig, E, None, f"{source}: *PLASTIC, {eps.size} rows", E_source=f"{source}: *ELASTIC" if E is not None else "")


def load_curve(path: str | Path) -> FlowCurveSource:
    """The flow curve of a result folder or CSV at ``path``."""
    from flowcurve.identification.outcome import read_json_object

    p = Path(path)
    if p.is_dir():
        p = p / "result.json"
    if p.suffix.lower() == ".json":
        return curve_from_result(read_json_object(p, IdentificationError, "result file"), str(p))
    try:
        return curve_from_card(p.read_text(encoding="utf-8", errors="replace"), str(p))
    except FileNotFoundError:
        raise IdentificationError(f"{p}: no such result or card") from None


def record_force_stroke(record, **options):
    """(specimen shortening mm, force N) of the record's loading branch, frame-corrected and
    scaled to the measured height change by the fast identification (``options``: its E_MPa,
    frame_stiffness_N_per_um)."""
    from flowcurve.identification.compression.identify import identify_compression

    ident = identify_compression(record, **options)
    d = ident.curves["corrected_diagram"]
    return d["specimen_displacement_mm"].to_numpy(), d["force_N"].to_numpy(), ident


def _simulate_with_retries(model_with, timeout_s: float):
    """(run, settings) of ``model_with(**settings)``: the model's own settings first, then the
    table's retries (:data:`.make_table.RETRY_SETTINGS`, as the inverse FE) — where the side folds
    onto the platen a run stops at a strain that moves with the stick slope and the increments."""
    from flowcurve.identification.fe.model.ccx import SolverError
    from flowcurve.identification.fe.make_table import RETRY_SETTINGS

    for k, settings in enumerate(({}, *RETRY_SETTINGS)):
        try:
            return simulate_upsetting(model_with(**settings), timeout_s=timeout_s), settings
        except SolverError:
            if k == len(RETRY_SETTINGS):
                raise


def _deviation(stroke, force, strain, sel, run) -> dict:
    """The record's force against a run's at the record's strokes (%), over the compared range and before the band
    where the model's force error grows (the inverse's σ there, docs/methods.md §4a.3)."""
    s_fe = np.concatenate([[0.0], run.stroke_mm])
    f_fe = np.concatenate([[0.0], run.force_N])
    f_at = np.interp(stroke[sel], s_fe, f_fe)
    dev = (force[sel] - f_at) / f_at * 100.0
    fold = run.fold_over_strain
    steady_to = None if fold is None else fold - FOLD_OVER_BAND
    before = strain[sel] < steady_to if steady_to is not None else np.ones(dev.size, bool)
    return {"fe_force_N": f_at, "deviation_pct": dev, "fold_over_strain": fold, "before_fold_over_to_strain": steady_to,
            "max_force_deviation_pct": float(np.max(np.abs(dev))),
            "max_force_deviation_before_fold_over_pct": float(np.max(np.abs(dev[before]))) if before.any() else None}


def verify_modulus(curve: FlowCurveSource, record) -> tuple[float, str]:
    """(E, where it came from) for the check's model by the one rule (:mod:`..elastic_modulus`): the
    curve's own (a card's *ELASTIC, a result's given/handbook/class E), else the record's
    material.E_MPa, else the handbook E of the class its material names; else a one-line error."""
    if curve.E_MPa is not None:
        return float(curve.E_MPa), curve.E_source or "the curve's"
    choice = choose_modulus(handbook=record.positive("material.E_MPa"), material=record.meta.get("material"))
    if choice.E_MPa is None:
        raise IdentificationError(f"{record.source}: verify needs the material's elastic modulus: the curve gives none, the record has no "
                                  "material.E_MPa and its material names no class (steel, aluminium, titanium, copper, nickel or a grade); "
                                  "give E in the card's *ELASTIC or as material.E_MPa")
    return choice.E_MPa, f"{record.source}: {choice.basis}"


def verify_compression(curve: FlowCurveSource, record, *, mu: float | None = None, increments: int = VERIFY_INCREMENTS,
                       layers: int = VERIFY_LAYERS, timeout_s: float = 900.0) -> dict:
    """FE force–stroke of ``curve`` on ``record``'s specimen vs the record; deviations in %.

    The run at ``layers``/``increments`` is the check; unless that is the fit's own discretisation, the fit's is run too
    and ``discretisation`` gives their largest force gap (%), the check's own model error."""
    if record.test != "compression":
        raise IdentificationError(f"{record.source}: verify runs upsetting (compression) records; this is a {record.test} record")
    stroke, force, ident = record_force_stroke(record, **(curve.diagram_options or {}))
    d0, h0 = record.specimen.d0_mm, record.specimen.h0_mm
    mu = mu if mu is not None else curve.mu if curve.mu is not None else ident.result["friction_mu"]
    E, E_source = verify_modulus(curve, record)
    s_end = float(np.max(stroke))
    strain = -np.log(1.0 - stroke / h0)
    sel = strain >= COMPARE_FROM_STRAIN
    if sel.sum() < 3:
        raise IdentificationError(f"{record.source}: too little of the record beyond {COMPARE_FROM_STRAIN:g} strain to compare")

    def run_at(n_layers: int, n_increments: int):
        """Run the curve at ``n_layers`` rim layers and ``n_increments`` increments."""
        return _simulate_with_retries(
            lambda **settings: UpsettingModel(d0, h0, h0 - s_end, float(mu), tuple(map(float, curve.eps_p)), tuple(map(float, curve.stress_MPa)),
                                              E_MPa=float(E), **{"layers": n_layers, "increments": n_increments, **settings}).realising(),
            timeout_s)  # the curve as the specimen's

    run, retry = run_at(layers, increments)
    check = _deviation(stroke, force, strain, sel, run)
    discretisation = None
    if (layers, increments) != (FIT_LAYERS, FIT_INCREMENTS):
        fit_run, fit_retry = run_at(FIT_LAYERS, FIT_INCREMENTS)
        fit = _deviation(stroke, force, strain, sel, fit_run)
        gap = (fit["fe_force_N"] - check["fe_force_N"]) / check["fe_force_N"] * 100.0
        discretisation = {
            "layers": FIT_LAYERS, "increments": FIT_INCREMENTS, "solver_retry": fit_retry or None,
            "max_force_gap_pct": float(np.max(np.abs(gap))),  # the fit's model against the check's, the curve and μ the same
            "max_force_deviation_pct": fit["max_force_deviation_pct"],
            "max_force_deviation_before_fold_over_pct": fit["max_force_deviation_before_fold_over_pct"],
            "fold_over_strain": fit["fold_over_strain"], "solver_wall_s": fit_run.wall_s}
    dev = check["deviation_pct"]
    post_dmax = record.specimen.dmax_mm
    return {
        "record": record.source, "curve": curve.what, "mu": float(mu), "E_MPa": float(E), "E_source": E_source,
        "d0_mm": d0, "h0_mm": h0, "stroke_end_mm": s_end,
        "model": {"layers": layers, "increments": increments},
        "max_force_deviation_pct": check["max_force_deviation_pct"],
        "fold_over_strain": check["fold_over_strain"], "before_fold_over_to_strain": check["before_fold_over_to_strain"],
        "max_force_deviation_before_fold_over_pct": check["max_force_deviation_before_fold_over_pct"],
        "rms_force_deviation_pct": float(np.sqrt(np.mean(dev**2))),
        "final_force_deviation_pct": float(dev[-1]),
        "discretisation": discretisation,
        "fe_dmax_mm": float(run.dmax_mm[-1]), "record_dmax_mm": post_dmax,
        "dmax_deviation_mm": None if post_dmax is None else float(post_dmax - run.dmax_mm[-1]),
        "compared_from_strain": COMPARE_FROM_STRAIN, "solver_wall_s": run.wall_s, "solver_cached": run.cached,
        "solver_retry": retry or None,  # the settings that carried a run the model's own stopped (None: its own)
        "curves": {"stroke_mm": stroke[sel], "record_force_N": force[sel], "fe_force_N": check["fe_force_N"], "deviation_pct": dev},
    }
