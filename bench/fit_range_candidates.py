"""Candidates for the constants' fit-range share (docs/methods.md §4.8) measured on two record sets: the coverage
campaign's 36 closed-form compression records (their true curve departs from the static law by its own rate rise,
which the truth absorbs; friction made by the CalculiX runs the fe_table correction inverts) and the 16 slab-barrel
records of tests/compression/test_constants_uncertainty.py (the law exactly; slab friction and the (3.18) barrel,
another model than the correction's). Per record and constant: the error, the stated standard error, the present
share |fit over the first half − over the whole| ("range"), and two candidates in its place:
  "contribution": the range shift of the corrected curve less that of the curve corrected at μ = 0 (the correction's own);
  "projection": the constants' change when the law is fitted as σ = (A + B·εpⁿ)(1 + k·c), c = 1 − σ_corrected/σ_nominal
  (a shape error of the correction's own shape; 0 where the correction is nil);
  "span": the same with one such term per correction (fe_table, k_sigma, siebel, slab at μ̂): any friction model's shape;
  "rate": the range shift of the curve with the constant-speed rate rise's own shape divided out, σ/(1 + k·ε) with k
  from σ = (A + B·εpⁿ)(1 + k·ε) over the whole range (ε̇ = v/h grows as e^ε, so ln ε̇ by ε);
  "rate4": |constants of that four-constant law fitted over the first half − over the whole|.
Prints per record and a summary: the campaign's method share / median |error| (shares in quadrature, the FE model form
left out as the campaign does on this kind) and the slab records' count beyond 2.5 standard errors.
Run: PYTHONPATH=. python bench/fit_range_candidates.py"""

import itertools
import math
import statistics
import warnings

import numpy as np
from scipy.optimize import curve_fit

from flowcurve.identification.compression import friction as fr
from flowcurve.identification.compression import friction_result as frr
from flowcurve.identification.compression.values import _fit_points, plastic_strain
from flowcurve.identification.laws.hardening import fit_hardening

SEEN: list[dict] = []
_original = frr._constants_stderr


def _signed_range(eps, sig, law):
    first = eps <= eps.min() + 0.5 * np.ptp(eps)  # hardening.RANGE_SHARE_PART
    whole, part = fit_hardening(eps, sig, law), fit_hardening(eps[first], sig[first], law)
    return {k: part.params[k] - whole.params[k] for k in whole.params}, dict(whole.params)


def _spy(src, geo, nominal, friction, fit, i_yield, fit_range, law, friction_correction, E_used):
    shares = _original(src, geo, nominal, friction, fit, i_yield, fit_range, law, friction_correction, E_used)
    eps_tp, sig_t, _ = friction.corrected[friction_correction]
    idx = _fit_points(eps_tp, i_yield, fit_range)
    eps_fit, sig_fit = eps_tp[idx], sig_t[idx]
    eps_p0 = plastic_strain(nominal.strain, nominal.pressure, E_used) if E_used is not None else None
    elastic = None if E_used is None else (E_used, geo["nu"])
    eps_r, sig_r = fr.correct(friction_correction, nominal.strain, nominal.pressure, 0.0, nominal.d_n / 2.0, nominal.h, eps_p=eps_p0, elastic=elastic)
    ep_r = plastic_strain(eps_r, sig_r, E_used) if E_used is not None else eps_r
    corrected, whole = _signed_range(eps_fit, sig_fit, law)
    reference, _ = _signed_range(ep_r[idx], sig_r[idx], law)
    c = 1.0 - sig_fit / sig_r[idx]
    projection = {k: 0.0 for k in whole}
    if np.max(np.abs(c)) > 1e-3:  # a correction to project on
        model = lambda e, A, B, n, k: (A + B * e**n) * (1.0 + k * c)  # noqa: E731  # σ = (A + Bεⁿ)(1 + k·c)
        p, _ = curve_fit(model, eps_fit, sig_fit, p0=[whole["A"], whole["B"], whole["n"], 0.0], maxfev=20000)
        projection = dict(zip(("A", "B", "n"), (abs(p[0] - whole["A"]), abs(p[1] - whole["B"]), abs(p[2] - whole["n"]))))
    patterns = [q for q in (1.0 - friction.corrected[m][1][idx] / sig_r[idx] for m in fr.CORRECTIONS) if np.max(np.abs(q)) > 1e-3]
    span = {k: 0.0 for k in whole}
    if patterns:  # σ = (A + Bεⁿ)(1 + Σ k_m·c_m), c_m every correction's relative size at μ̂
        shapes = np.vstack(patterns)
        model = lambda e, A, B, n, *k: (A + B * e**n) * (1.0 + np.dot(np.asarray(k), shapes))  # noqa: E731
        p, _ = curve_fit(model, eps_fit, sig_fit, p0=[whole["A"], whole["B"], whole["n"]] + [0.0] * len(patterns), maxfev=40000)
        span = dict(zip(("A", "B", "n"), (abs(p[0] - whole["A"]), abs(p[1] - whole["B"]), abs(p[2] - whole["n"]))))
    rate, rate4 = _rate_shifts(eps_fit, sig_fit, friction.corrected[friction_correction][2][idx], whole, law)
    SEEN.append({"rate": rate, "rate4": rate4, "span": span, "range": {k: abs(v) for k, v in corrected.items()}, "contribution": {k: abs(corrected[k] - reference[k]) for k in corrected},
                 "projection": projection, "shares": {name: dict(v) for name, v in shares.items()}})
    return shares


def _rate_shifts(eps_p, sig, eps_t, whole, law):
    """("rate", "rate4") of the docstring: the refits with the rate rise's shape (1 + k·ε) free."""
    model = lambda e, A, B, n, k, t=eps_t: (A + B * e**n) * (1.0 + k * t)  # noqa: E731  # σ = (A + Bεpⁿ)(1 + kε)
    p, _ = curve_fit(model, eps_p, sig, p0=[whole["A"], whole["B"], whole["n"], 0.0], maxfev=20000)
    shifted, _ = _signed_range(eps_p, sig / (1.0 + p[3] * eps_t), law)
    first = eps_p <= eps_p.min() + 0.5 * np.ptp(eps_p)
    q, _ = curve_fit(lambda e, A, B, n, k: model(e, A, B, n, k, eps_t[first]), eps_p[first], sig[first], p0=list(p), maxfev=20000)
    return {k: abs(v) for k, v in shifted.items()}, dict(zip(("A", "B", "n"), (abs(q[i] - p[i]) for i in range(3))))


frr._constants_stderr = _spy
KEYS = {"A": "A_MPa", "n": "n"}


def _campaign():
    from tests.coverage import campaign as cp

    rows = []
    for case in cp.compression_cases():
        result, truth = case.run()
        h = result["hardening"]
        lo, hi = (float(v) for v in (h.get("fit_range") or h.get("strain_range")))
        true = cp.fit_constants(truth.flow, "johnson_cook", max(lo, 1e-4), hi)
        zero = h["start_uncertainty"]["constants_shift"]
        rows.append({"name": case.name, **SEEN[-1], "err": {k: abs(h[key] - true[key]) for k, key in KEYS.items()},
                     "se": {k: h[f"{key}_stderr"] for k, key in KEYS.items()}, "zero": zero})
    return rows


def _slab():
    from tests.compression.toe_records import make_toe_compression
    from flowcurve.identification.compression.identify import identify_compression

    laws = {"seed": {"A": 105.0, "B": 1392.0, "n": 0.642}, "steel45": {"A": 410.0, "B": 280.0, "n": 0.47}, "linear": {"A": 300.0, "B": 250.0, "n": 1.0}}
    cases = [(name, mu, d0, h0) for name, mu, (d0, h0) in itertools.product(("seed", "steel45"), (0.05, 0.11, 0.2), ((8.0, 6.0), (6.0, 9.0)))]
    cases += [("linear", mu, 6.0, 9.0) for mu in (0.05, 0.11, 0.2)] + [("seed", 0.11, 5.989, 6.982)]
    rows = []
    for name, mu, d0, h0 in cases:
        law = laws[name]
        record, _ = make_toe_compression(law=law, mu=mu, d0=d0, h0=h0, rate_hz=2.0, toe_mm=0.05, speed=0.005, handbook_E=True, noise_N=5.0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            h = identify_compression(record).result["hardening"]
        rows.append({"name": f"{name}-mu{mu}-h0d0_{h0 / d0:.2f}", **SEEN[-1], "err": {k: abs(h[key] - law[k]) for k, key in KEYS.items()},
                     "se": {k: h[f"{key}_stderr"] for k, key in KEYS.items()}})
    return rows


def _with(row, k, term):
    """The row's stated standard error with the fit-range share replaced by ``term``."""
    share = next((v.get(k, 0.0) for name, v in row["shares"].items() if name.startswith("fit range")), 0.0)
    return math.sqrt(max(row["se"][k] ** 2 - share**2, 0.0) + term**2)


def main() -> None:
    campaign, slab = _campaign(), _slab()
    for title, rows in (("campaign", campaign), ("slab-barrel", slab)):
        print(f"== {title}")
        for r in rows:
            print(f"{r['name']:28s} " + " | ".join(f"{k} err {r['err'][k]:.3g} se {r['se'][k]:.3g} range {r['range'][k]:.3g} "
                                                   f"contribution {r['contribution'][k]:.3g} projection {r['projection'][k]:.3g} span {r['span'][k]:.3g} "
                                                   f"rate {r['rate'][k]:.3g} rate4 {r['rate4'][k]:.3g}" for k in KEYS))
    for k in KEYS:
        errors = statistics.median(r["err"][k] for r in campaign)
        for cand in ("range", "contribution", "projection", "span", "rate", "rate4"):
            method = [2.0 * math.sqrt(sum(v.get(k, 0.0) ** 2 for name, v in r["shares"].items() if not name.startswith(("fit range", "FE model form")))
                                      + r["zero"].get(k, 0.0) ** 2 + r[cand][k] ** 2) for r in campaign]
            beyond = [r["name"] for r in slab if r["err"][k] > 2.5 * _with(r, k, r[cand][k])]
            print(f"{k} {cand:12s}: campaign method share (shares + strain zero) / median |error| {statistics.median(method) / errors:.2f}; "
                  f"slab-barrel beyond 2.5 se: {len(beyond)} {beyond}")


if __name__ == "__main__":
    main()
