"""Coverage of the stated uncertainty (issue 43): does value ± U (k = 2) hold the truth?

Records of known truth, by kind, each identified through the product's public entry
(``identification.identify``); every stated budget of ``result["uncertainty"]`` (Rp0.2, Rm, E,
Ag, A, Z, μ, flow stress points, hardening constants) is compared with the truth of the
generator, computed here from the generating law and never from the product's uncertainty code:

- ``tension drawn``: tests/property/records.py (Johnson–Cook/Swift/Voce, extensometer or
  crosshead with the frame stiffness stated, toes, quanta, noise, early stops), drawn by
  numpy's generator with a fixed seed (hypothesis draws differ between its versions); truth from its closed forms.
- ``tension crosshead``: bench/modulus_methods.py's crosshead-only Voce records (frames 10.8–136
  N/µm not stated, seating toes, noise); truth the material's (an extensometer's) Rp0.2, Rm, Ag;
  E against the apparent modulus of specimen and frame where the result says its E is apparent.
- ``compression closed form``: tests/series/compression_series.py (Johnson–Cook with rate and
  temperature, frame, toe, noise, friction μ 0–0.2 with the CalculiX runs' force factor and barrel);
  truth the law at each point's own rate.
- ``CalculiX``: the vendored upsetting records of both model families (tests/fe/data, truth in
  their ``fe2.*`` header: the Johnson–Cook law and μ).
- ``CalculiX zoned friction``: the zoned records there (tests/fe/zoned_friction.py: the end face in two
  Coulomb zones, a lubricated or a dry centre): the friction law's form the correction's model form holds;
  truth the law (no one μ to judge).
- ``virtual rig``: cells of tests/scenarios/matrix.py on model time, fault drills included;
  truth the virtual material (rig/virtual/materials.py).

Truth of hardening constants: the same law fitted (least squares, here) to the noise-free
generating curve over the strain range the result reports, so a constant is judged as the
constant of that range. A cell (kind × quantity) fails when fewer than :data:`MIN_SHARE` of its
statements hold the truth, or, on the kinds whose instruments are simulated perfectly, when the
median of U's method share (U less its instrument terms: the simulation does not err with the
instruments the budget states; and less the conditions the records follow, :data:`INSTRUMENT_TERMS`,
:data:`OWN_FRICTION_MODEL`) is more than :data:`MAX_BLANKET` × the median |error| (a blanket U).

``python -m tests.coverage.campaign [--default]`` prints the markdown table (docs/test-report.md).
"""

from __future__ import annotations

import functools
import math
import random
import runpy
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
MIN_SHARE = 0.90
MAX_BLANKET = 5.0
DEFAULT_RECORDS = 40
FALLBACK_SEED = 43

# kinds whose instruments are simulated perfectly (no force/strain scale error): the blanket check applies
PERFECT = {"tension drawn", "tension crosshead", "compression closed form", "CalculiX", "CalculiX zoned friction"}


@dataclass
class Truth:
    """What the generator knows: scalars by result key, and curves."""

    values: dict = field(default_factory=dict)  # "Rp02_MPa", "Rm_MPa", "E_MPa", "Ag_pct", "A_pct", "friction_mu" (a tuple: equal truths)
    flow: Callable | None = None  # true plastic strain → true flow stress, MPa (the law the record was made with)
    E_apparent_MPa: float | None = None  # judged instead of E_MPa where the result says its E is apparent
    law: str | None = None  # the hardening law the record was made with: its constants are judged only on a fit of that law


@dataclass(frozen=True)
class Case:
    kind: str
    name: str
    make: Callable  # () → (Record, Truth) or (result dict, Truth) for a run that identifies itself

    def run(self) -> tuple[dict, Truth]:
        from flowcurve.identification.identify import identify

        made, truth = self.make()
        if isinstance(made, dict):
            return made, truth
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return dict(identify(made).result), truth


# -- truth from the generating laws --------------------------------------------------------


def engineering_at_plastic(law: Callable, E_MPa: float, eps_p):
    """(e, s) on the uniform engineering curve at true plastic strain εp: e = exp(εp + σ/E) − 1, s = σ/(1 + e)."""
    sig = np.asarray(law(np.asarray(eps_p, dtype=float)), dtype=float)
    e = np.expm1(np.asarray(eps_p) + sig / E_MPa)
    return e, sig / (1.0 + e)


def rm_and_ag(law: Callable, E_MPa: float, upto: float = 0.6) -> tuple[float, float]:
    """(Rm MPa, Ag %) of the uniform curve: max s, and Ag = 100·(e_m − s_m/E) at that maximum."""
    ep = np.geomspace(1e-6, upto, 200_000)
    e, s = engineering_at_plastic(law, E_MPa, ep)
    i = int(np.argmax(s))
    return float(s[i]), float(100.0 * (e[i] - s[i] / E_MPa))


def fit_constants(flow: Callable, law: str, lo: float, hi: float) -> dict | None:
    """The result's law fitted (least squares on 400 points, within the bounds the
    product's fit states for each law: constants ≥ 0, 1e-4 ≤ n ≤ 5) to the true flow curve over [lo, hi]."""
    from scipy.optimize import curve_fit

    if not (hi > lo > 0):
        return None
    eps = np.linspace(lo, hi, 400)
    sig = np.asarray(flow(eps), dtype=float)
    if law == "johnson_cook":
        f, p0, keys = (lambda x, A, B, n: A + B * x ** n), (sig[0] * 0.8, sig[-1], 0.3), ("A_MPa", "B_MPa", "n")  # σ = A + Bεⁿ
        bounds = ([0.0, 0.0, 1e-4], [np.inf, np.inf, 5.0])
    elif law == "swift":
        f, p0, keys = (lambda x, K, e0, n: K * (e0 + x) ** n), (sig[-1], 0.01, 0.2), ("K_MPa", "eps0", "n")  # σ = K(ε0 + ε)ⁿ
        bounds = ([0.0, 1e-9, 1e-4], [np.inf, 10.0, 5.0])
    elif law == "voce":
        f, p0, keys = (lambda x, s0, Q, b: s0 + Q * (1 - np.exp(-b * x))), (sig[0], sig[-1] - sig[0], 10.0), ("sigma0_MPa", "Q_MPa", "b")  # σ = σ0 + Q(1 − e^(−bε))
        bounds = ([0.0, 0.0, 1e-6], [np.inf, np.inf, 1e5])
    else:
        return None
    try:
        p, _ = curve_fit(f, eps, sig, p0=p0, bounds=bounds, maxfev=20000)
    except (RuntimeError, ValueError):
        return None
    return dict(zip(keys, map(float, p)))


# -- the kinds ------------------------------------------------------------------------------


@functools.lru_cache(maxsize=None)
def _bench():
    return SimpleNamespace(**runpy.run_path(str(ROOT / "bench" / "modulus_methods.py")))


@functools.lru_cache(maxsize=None)
def _drawn_tension(i: int, seed: int):
    """Record ``i`` of tests/property/records.py drawn from numpy's generator (seed ``seed``, ``i``):
    the same population on every machine and hypothesis version."""
    from tests.property.records import seeded_tension_record

    return seeded_tension_record(seed * 100_003 + i)


def _drawn_case(i: int, n: int, seed: int):
    from tests.property.records import D0_MM

    record, t, desc = _drawn_tension(i, seed)
    law = lambda ep: t.law(np.maximum(np.asarray(ep) - t.hardening_start, 0.0))  # noqa: E731
    values = {"Rm_MPa": t.Rm_MPa, "E_MPa": t.E_MPa}
    if t.Rp02_MPa is not None:
        values["Rp02_MPa"] = t.Rp02_MPa
    if desc["early_stop"] is None and not desc["plateau"]:  # the force maximum is in the record: Ag at the record's own maximum
        # the generator's neck starts with a sample at the maximum's force (1.0 × s_max, 0.05/30 further): both are the maximum
        e, s = engineering_at_plastic(law, t.E_MPa, [t.uniform_plastic_strain])
        values["Ag_pct"] = (float(100.0 * (e[0] - s[0] / t.E_MPa)), float(100.0 * (e[0] + 0.05 / 30 - s[0] / t.E_MPa)))
        if "extensometer_mm" in record.data.columns:  # A: the extension at fracture less the elastic part
            d = record.data
            values["A_pct"] = float(100.0 * (d["crosshead_mm"].iloc[-1] / float(record.meta["specimen.l0_mm"])
                                             - d["force_N"].iloc[-1] / (math.pi * D0_MM**2 / 4) / t.E_MPa))
    return record, Truth(values=values, flow=law, law=desc["law"])


def drawn_cases(n: int = 150, seed: int = 43) -> list[Case]:
    return [Case("tension drawn", f"drawn #{i} (seed {seed})", functools.partial(_drawn_case, i, n, seed)) for i in range(n)]


def _crosshead_case(kw: dict):
    from flowcurve.identification.laws.hardening import voce
    from tests.property.records import rp02_closed_form

    b = _bench()
    sy, Q, bb, E = 850.0, 150.0, 300.0, 205_000.0  # crosshead_tension's defaults
    record, E_app, _ = b.crosshead_tension(**kw)
    law = lambda ep: voce(ep, sy, Q, bb)  # noqa: E731
    Rm, Ag = rm_and_ag(law, E, upto=0.2)
    return record, Truth(values={"Rp02_MPa": rp02_closed_form(law, E, sy), "Rm_MPa": Rm, "Ag_pct": Ag, "E_MPa": E},
                         flow=law, E_apparent_MPa=E_app, law="voce")


def crosshead_cases(seeds: int = 3) -> list[Case]:
    out = []
    for s in range(seeds):
        for c in (10.8, 40.0, 136.0):
            for toe in (0.0, 0.05, 0.2):
                for frac in (0.1, 0.3):
                    kw = dict(frame_N_per_um=c, toe_mm=toe, toe_fraction=frac, seed=100 * s + len(out))
                    out.append(Case("tension crosshead", f"C{c:g} toe {toe:g}@{frac:g}Fm seed {kw['seed']}", functools.partial(_crosshead_case, kw)))
    return out


def _compression_case(T: float, rate: float, mu: float, seed: int):
    from tests.series import compression_series as cs

    record, t = cs.compression_record(T, rate, mu=mu, seed=seed, response=COMPRESSION_RESPONSE, reading_mm=0.01)
    eps_p, stress = t["eps_p"], t["stress_MPa"]
    flow = lambda ep: np.interp(ep, eps_p, stress)  # noqa: E731  # the law at each point's own rate
    # Rp0.2 of compression: the mean pressure at εp = 0.002, σ times the record's force factor at that height
    sig = float(flow(0.002))
    h = cs.H0_MM * math.exp(-(0.002 + sig / cs.E_MPa))
    rp = sig * float(cs.force_factor(mu, np.array([h]), COMPRESSION_RESPONSE)[0])
    return record, Truth(values={"friction_mu": mu, "Rp02_MPa": rp}, flow=flow, law="johnson_cook")


# the records' friction as CalculiX makes it at their μ (force factor and barrel), the relation the product's default
# fe_table reads; the seed's pair (slab pressure, (3.18) barrel) makes μ 0.2 a barrel of μ ≈ 0.3 (docs/methods.md §4.9)
COMPRESSION_RESPONSE = "fe"


def compression_cases(seeds: int = 2) -> list[Case]:
    return [Case("compression closed form", f"T{T:g} rate {r:g} mu {mu:g} seed {s}", functools.partial(_compression_case, T, r, mu, s))
            for s in range(seeds) for T in (20.0, 300.0, 600.0) for r in (0.005, 0.05) for mu in (0.0, 0.1, 0.2)]


def _calculix_case(path: Path):
    from flowcurve.record.importers import load_record

    record = load_record(path)
    A, B, n, mu = (float(record.meta[f"fe2.{k}"]) for k in ("A_MPa", "B_MPa", "n", "mu"))
    return record, Truth(values={"friction_mu": mu}, flow=lambda ep: A + B * np.asarray(ep) ** n, law="johnson_cook")  # σ = A + Bεⁿ


# the uniform-Coulomb records; zoned_*.csv (two Coulomb zones on the end face, tests/fe/zoned_friction.py) have no one μ
# for the μ budget to hold (their fe2.mu is a convention, the face's area mean): they are measured apart
# (bench/zoned_friction.py, tests/fe/test_zoned_friction.py, docs/methods.md §4a.7)
CALCULIX_RECORDS = ("second_model_*.csv", "other_settings_*.csv")


def calculix_cases() -> list[Case]:
    paths = sorted(p for pattern in CALCULIX_RECORDS for p in (ROOT / "tests" / "fe" / "data").glob(pattern))
    return [Case("CalculiX", p.stem, functools.partial(_calculix_case, p)) for p in paths]


def _zoned_case(path: Path):
    """A zoned-friction record (tests/fe/zoned_friction.py): truth the law; no μ judged (two Coulomb zones, no one μ)."""
    from flowcurve.record.importers import load_record

    record = load_record(path)
    A, B, n = (float(record.meta[f"fe2.{k}"]) for k in ("A_MPa", "B_MPa", "n"))
    return record, Truth(values={}, flow=lambda ep: A + B * np.asarray(ep) ** n, law="johnson_cook")  # σ = A + Bεⁿ


def zoned_cases() -> list[Case]:
    """The friction law's form realised: the end face in two Coulomb zones (lubricated or dry centre), CalculiX."""
    return [Case("CalculiX zoned friction", p.stem, functools.partial(_zoned_case, p))
            for p in sorted((ROOT / "tests" / "fe" / "data").glob("zoned_*.csv"))]


def _virtual_case(cell, workdir: Path):
    from tests.scenarios import matrix

    run = matrix.run_cell(cell, workdir)
    vr = run.virtual_run
    if run.result is None or vr is None:
        return {}, Truth()
    mat, rate, T = vr.material, vr.strain_rate_per_s, vr.temperature_C
    law = lambda ep: mat.flow_stress(np.asarray(ep, dtype=float), rate, T)  # noqa: E731
    values = {"E_MPa": mat.E_MPa}
    if cell.test == "tension":
        from tests.property.records import rp02_closed_form

        values["Rp02_MPa"] = rp02_closed_form(law, mat.E_MPa, None)  # e − s/E = 0.002 on the uniform curve
        # Rm: the uniform curve's maximum up to the fracture strain, where the rig breaks a specimen that has not necked
        # (12Kh18N12M3TL, ψ 30 %: ε_f 0.36 below its Considère strain, n 0.64)
        values["Rm_MPa"] = rm_and_ag(law, mat.E_MPa, upto=min(0.6, mat.fracture_strain_at(rate, T)))[0]
    else:
        values["friction_mu"] = vr.friction_mu
    return run.result, Truth(values=values, flow=law, law="johnson_cook")


def virtual_cases(n: int, seed: int) -> list[Case]:
    import tempfile

    from tests.scenarios import matrix

    cells = [c for c in matrix.all_cells() if c.temperature_C <= 600.0 and c.speed_mm_per_s >= 0.05]
    rng = random.Random(seed)
    chosen = rng.sample(cells, min(n, len(cells)))
    base = Path(tempfile.mkdtemp(prefix="flowcurve-coverage-"))
    return [Case("virtual rig", c.id, functools.partial(_virtual_case, c, base / f"{i:03d}")) for i, c in enumerate(chosen)]


def all_cases(seed: int = FALLBACK_SEED) -> list[Case]:
    """The whole campaign (≥ 300 records)."""
    return drawn_cases(150, seed) + crosshead_cases(3) + compression_cases(2) + calculix_cases() + zoned_cases() + virtual_cases(60, seed)


def default_cases(seed: int, n: int = DEFAULT_RECORDS) -> list[Case]:
    """About ``n`` records drawn with ``seed``, every kind present (the virtual rig with few: a cell costs seconds)."""
    rng = random.Random(seed)
    share = {"tension drawn": 12, "tension crosshead": 8, "compression closed form": 8, "CalculiX": 8, "CalculiX zoned friction": 2,
             "virtual rig": 4}
    pools = {"tension drawn": drawn_cases(150, FALLBACK_SEED), "tension crosshead": crosshead_cases(3),
             "compression closed form": compression_cases(2), "CalculiX": calculix_cases(), "CalculiX zoned friction": zoned_cases()}
    out = [c for kind, pool in pools.items() for c in rng.sample(pool, min(share[kind], len(pool)))]
    return out + virtual_cases(share["virtual rig"], seed)


def campaign_seed() -> int:
    """The scenario matrix's seed: fixed per commit, ``FLOWCURVE_MATRIX_SEED`` draws another."""
    from tests.scenarios.matrix import matrix_seed

    return matrix_seed()


# -- the judge ------------------------------------------------------------------------------


# budget components that are the instruments' (classes, resolutions, gauge lengths) or the test conditions' (the
# testing rate anywhere within the method's allowed range: the records are made at one known rate, so the truth is the
# value at that rate) or the machine's (the crosshead compliance model's spread, measured on real extensometer pairs: the
# records simulate a machine that follows the model): the rest is the method's share
INSTRUMENT_TERMS = ("force", "diameter", "strain scale", "stress scale", "initial height", "gauge length", "original gauge length",
                    "extensometer", "extension", "shortening", "smallest diameter", "method: testing rate",
                    "method: crosshead compliance")


# the FE model form of the friction correction (the spread between the product's upsetting model and other defensible
# ones, 0.12·μ of the force, identification/fe/model/model_form.py) is a condition where the records make friction by the
# product's own model: the closed-form records and the virtual rig take their force factor and barrel from the very
# CalculiX runs the fe_table correction reads (tests/series/compression_series.py, rig/virtual/fe_response.py), so the
# truth is the value on a specimen that follows that model — as the compliance term's machine follows its model. On the
# CalculiX kind the second model's records (tests/fe/second_model.py) realise it: there it stays in the method share.
OWN_FRICTION_MODEL = {"compression closed form", "virtual rig"}
MODEL_FORM_TERMS = ("method: fe model form",)


def method_share_U(budget: dict, kind: str = "") -> float:
    """U less its instrument and test-condition terms (and the FE model form on :data:`OWN_FRICTION_MODEL`'s kinds):
    k·√(Σ contribution² of the method's components) (GUM root sum of squares)."""
    conditions = INSTRUMENT_TERMS + (MODEL_FORM_TERMS if kind in OWN_FRICTION_MODEL else ())
    comps = [c for c in budget.get("components") or [] if not str(c.get("name", "")).lower().startswith(conditions)]
    k = float(budget.get("k") or 2.0)
    return k * math.sqrt(sum(float(c.get("contribution") or 0.0) ** 2 for c in comps))


def judge(case: Case, result: dict, truth: Truth) -> list[dict]:
    """One row per stated budget with a truth: quantity, value, U, its method share, truth, error, held."""
    unc = result.get("uncertainty") or {}
    rows = []

    def row(quantity, budget, true):
        if not isinstance(budget, dict) or budget.get("U") is None or budget.get("value") is None or true is None:
            return
        value, U = float(budget["value"]), float(budget["U"])
        if isinstance(true, tuple):  # a truth the generator makes twice (equal maxima): the nearer one
            true = min(true, key=lambda x: abs(value - x))
        rows.append(dict(kind=case.kind, record=case.name, quantity=quantity, value=value, U=U, U_method=method_share_U(budget, case.kind),
                         truth=float(true), error=abs(value - true), held=abs(value - true) <= U))

    for key in ("Rp02_MPa", "Rm_MPa", "Ag_pct", "A_pct", "Z_pct", "friction_mu"):
        if key in unc:
            row(key, unc[key], truth.values.get(key))
    if "E_MPa" in unc:
        apparent = str((result.get("modulus") or {}).get("E_source") or "") == "apparent"
        row("E_MPa", unc["E_MPa"], truth.E_apparent_MPa if apparent and truth.E_apparent_MPa else truth.values.get("E_MPa"))
    for at, budget in (unc.get("flow_stress_MPa") or {}).items():
        if truth.flow is not None:
            row("flow stress", budget, float(truth.flow(float(at))))
    hard = result.get("hardening") or {}
    rng = hard.get("fit_range") or hard.get("strain_range")
    if truth.flow is not None and unc.get("hardening") and rng and hard.get("law") == truth.law:
        fitted = fit_constants(truth.flow, str(hard.get("law")), max(float(rng[0]), 1e-4), float(rng[1]))
        for key, budget in unc["hardening"].items():
            if fitted and key in fitted:
                row(f"{hard.get('law')} {key}", budget, fitted[key])
    return rows


def run_cases(cases: list[Case]) -> tuple[list[dict], list[str]]:
    """(rows, refusals): every case run and judged; a refusal (a one-line error of the product) is listed, not judged."""
    from flowcurve.errors import FlowcurveError

    rows, refused = [], []
    for case in cases:
        try:
            result, truth = case.run()
        except FlowcurveError as exc:
            refused.append(f"{case.kind} {case.name}: {str(exc).splitlines()[0]}")
            continue
        rows += judge(case, result, truth)
    return rows, refused


def table(rows: list[dict]) -> list[dict]:
    """Per kind × quantity: n, share held, median U, median |error|, U/error, the method share's ratio, the verdict.

    A blanket: on a perfect-instrument kind, the median method share of U over 5× the median |error|
    (the instrument terms are stated for instruments the simulation does not err with)."""
    cells = {}
    for r in rows:
        cells.setdefault((r["kind"], r["quantity"]), []).append(r)
    out = []
    for (kind, q), rs in sorted(cells.items()):
        share = sum(r["held"] for r in rs) / len(rs)
        mU, mE, mM = (float(np.median([r[k] for r in rs])) for k in ("U", "error", "U_method"))
        blanket = kind in PERFECT and mM > MAX_BLANKET * mE
        worst = max(rs, key=lambda r: r["error"] / r["U"] if r["U"] > 0 else math.inf)
        out.append(dict(kind=kind, quantity=q, n=len(rs), share=share, median_U=mU, median_error=mE,
                        ratio=mU / mE if mE > 0 else math.inf, method_ratio=mM / mE if mE > 0 else (0.0 if mM == 0 else math.inf),
                        ok=share >= MIN_SHARE and not blanket, blanket=blanket,
                        worst=worst["error"] / worst["U"] if worst["U"] > 0 else math.inf, worst_record=worst["record"]))
    return out


def markdown(cells: list[dict]) -> str:
    lines = ["| kind | quantity | n | held at k = 2 | median U | median \\|error\\| | U / error | method share / error | worst \\|error\\|/U | verdict |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---|"]
    for c in cells:
        words = ([] if c["share"] >= MIN_SHARE else ["misses"]) + (["blanket"] if c["blanket"] else [])
        lines.append(f"| {c['kind']} | {c['quantity']} | {c['n']} | {100 * c['share']:.0f} % | {c['median_U']:.4g} | {c['median_error']:.3g} | "
                     f"{c['ratio']:.3g} | {c['method_ratio']:.3g} | {c['worst']:.3g} | {', '.join(words) or 'holds'} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    import argparse
    import time

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--default", action="store_true", help="only the default selection's ~40 records")
    p.add_argument("--seed", type=int, default=None)
    p.add_argument("--worst", action="store_true", help="name the worst record of every failing cell")
    a = p.parse_args(argv)
    seed = a.seed if a.seed is not None else (campaign_seed() if a.default else FALLBACK_SEED)
    t0 = time.perf_counter()
    cases = default_cases(seed) if a.default else all_cases(seed)
    rows, refused = run_cases(cases)
    cells = table(rows)
    print(f"{len(cases)} records, {len(rows)} statements judged, {len(refused)} refused, seed {seed}, "
          f"{time.perf_counter() - t0:.0f} s\n")
    print(markdown(cells))
    print(f"\n{len(refused)} records refused with a one-line error (not judged):")
    for r in refused:
        print(f"- {r}")
    if a.worst:
        for c in cells:
            if not c["ok"]:
                print(f"- worst of {c['kind']} | {c['quantity']}: {c['worst_record']} ({c['worst']:.3g} U)")
    return 0 if all(c["ok"] for c in cells) else 1


if __name__ == "__main__":
    raise SystemExit(main())
