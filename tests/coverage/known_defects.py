"""Known defects of the stated uncertainty (issue 43), one line per cell of the coverage table:
(kind, quantity) → what misses, as measured on 1f2f484 and, after the budgets' method shares merged, on main (``python -m tests.coverage.campaign --worst``);
the drawn tension records since they are drawn from numpy's generator (the same population on every machine).
tests/coverage/test_coverage.py marks these cells ``xfail(strict=True)``: a fix turns the cell red
until its line here is removed. The default selection does not judge these cells.
"""

KNOWN: dict[tuple[str, str], str] = {
    # over-wide: the method share of U is more than 5× the median error (never a blanket U)
    # ("CalculiX", "flow stress") held since the μ term spans μ's stated range (5.54× → 4.93×; 12.9× with Siebel's ∂σ/∂μ), until the correction's σ (below)
    # the CalculiX kind keeps the FE model form in the method share (its second-model records realise it: B's share is mostly that term)
    # the flow-stress points state the fe_table correction's own σ since it is one claim with true_curve.csv's rows
    # (correction_uncertainty_pct): on slab-barrel records (another friction model) 23 of 80 points missed without it,
    # 4 with it (tests/compression/test_flow_stress_correction_form.py); the CalculiX records' Coulomb contact does not
    # realise the friction law's form that σ holds (the same 0.12·μ as the constants' "FE model form" share)
    ("CalculiX", "flow stress"): "blanket: method share 23× the median error (4.9× before the correction's per-point σ)",
    ("CalculiX", "johnson_cook A_MPa"): "blanket: method share 6.1× the median error (5.5× before the constants-over-the-range term)",
    ("CalculiX", "johnson_cook B_MPa"): "blanket: method share 12× the median error",
    ("CalculiX", "johnson_cook n"): "blanket: method share 8.3× the median error (6.7× before the constants-over-the-range term)",
    # the zoned-friction records (tests/fe/zoned_friction.py: two Coulomb zones on the end face) realise the friction law's
    # form that the correction's 0.12·μ holds: there A and n hold (2.8×, 3.2×), flow stress up to 1.01 of the correction's σ
    # (C3D, εp 0.5) but its median error is far below it along the stroke, and B takes the uniform pattern's u·B
    ("CalculiX zoned friction", "flow stress"): "blanket: method share 7.0× the median error (its worst point at 1.01 of the correction's σ)",
    ("CalculiX zoned friction", "johnson_cook B_MPa"): "blanket: method share 10.7× the median error (the model form's uniform pattern moves B by u·B)",
    # the closed-form records make friction as CalculiX does at their stated μ since the μ 0.2 fix (docs/methods.md §4.9): μ and n
    # hold (67 → 100 %), and with the product now exact to the error of its readings the constants' U shows its size. The FE
    # model form (1.3–2.6 % of the force at μ 0.1–0.2) is a condition there since the budgets name their shares (campaign.py
    # OWN_FRICTION_MODEL: the records make friction by the very CalculiX runs); B holds (10.8× → 2.44×). What is left is the
    # fit range's refit (hardening.range_shift, A 4.1 MPa and n 0.0066 median at 1σ for errors of 1.1 MPa and 0.0032), the
    # strain zero's shift and μ's share (each A ≈ 1.6 MPa). Since a known slope's zero takes its own parts (docs/methods.md §2.11:
    # A's strain-zero share at most 83 → 2.6 MPa) A 9.0 → 8.15×, n 5.44 → 5.19×: what is left is the fit range's refit
    ("compression closed form", "johnson_cook A_MPa"): "blanket: method share 8.15× the median error 1.1 MPa (9.0× before the known slope's zero)",
    ("compression closed form", "johnson_cook n"): "blanket: method share 5.19× the median error 0.0032 (5.44× before the known slope's zero)",
    # tension drawn A and n hold since a constant on its bound states the k-interval of its unbounded value mapped through
    # the bound (A 18.6× → 4.2×, n 5.25× → 3.6×, 95 % held; docs/methods.md §2.12)
    # the virtual rig's n holds since the tension constants state the load cell's filter lag (92 → 97 % on two runs, A/B 97/94 →
    # 100 %; docs/methods.md §2.13): its misses were fast tests aborted at 1 mm, whose short range the rounded yield knee tilts
}

# cells within a few records of 90 % on the virtual rig, whose records are not bit-for-bit repeatable
# (its devices run in threads): xfail without strict, so a run that happens to hold is not red
BORDERLINE: set[tuple[str, str]] = set()
