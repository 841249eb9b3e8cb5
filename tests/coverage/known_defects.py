"""Known defects of the stated uncertainty (issue 43), one line per cell of the coverage table:
(kind, quantity) → what misses, as measured on 1f2f484 and, after the budgets' method shares merged, on main (``python -m tests.coverage.campaign --worst``);
the drawn tension records since they are drawn from numpy's generator (the same population on every machine).
tests/coverage/test_coverage.py marks these cells ``xfail(strict=True)``: a fix turns the cell red
until its line here is removed. The default selection does not judge these cells.
"""

KNOWN: dict[tuple[str, str], str] = {
    # over-wide: the method share of U is more than 5× the median error (never a blanket U)
    ("CalculiX", "flow stress"): "blanket: method share 7.4× the median error (μ term)",
    ("CalculiX", "johnson_cook A_MPa"): "blanket: method share 6.1× the median error (5.5× before the constants-over-the-range term)",
    ("CalculiX", "johnson_cook B_MPa"): "blanket: method share 12× the median error",
    ("CalculiX", "johnson_cook n"): "blanket: method share 8.3× the median error (6.7× before the constants-over-the-range term)",
    # misses: U too small for the method's error
    ("compression closed form", "friction_mu"): ("67 % held (worst 1.4 U at μ 0.2, 2.4 U before u(μ) was half the range): the records' barrel is "
                                                 "(3.18)'s, which CalculiX makes at μ ≈ 0.3 (second model S2: ΔR/h 0.0451 at μ 0.3, h0/d0 1.2, "
                                                 "ε 0.69; (3.18) at μ 0.2: 0.0449), so fe_table's 0.325 ± 0.089 holds the FE truth, not the "
                                                 "generator's 0.2 (docs/methods.md §4.9); a term spanning (3.19) would be a blanket on CalculiX (8.2×)"),
    ("compression closed form", "johnson_cook n"): "67 % held: every μ 0.2 record reads n 0.13 high (the friction correction), U 0.10–0.13 (worst 1.4 U)",
    ("tension drawn", "johnson_cook A_MPa"): ("95 % held since the constants-over-the-range term (79 % before); blanket 19× (5.9× before): the strain "
                                              "zero's shift along the A–B–n valley, and A = 0 on its bound whose truth is 0 too (error ~0) gets the distance it could move"),
    ("tension drawn", "johnson_cook n"): "95 % held since the constants-over-the-range term (71 % before); blanket 5.25× (limit 5)",
    ("virtual rig", "Rm_MPa"): "50 % held (worst 130 U: a furnace open-thermocouple drill)",
    ("virtual rig", "johnson_cook n"): "65 % held before the constants-over-the-range term, 92 % after (borderline: 3 misses of 37)",
}

# cells within a few records of 90 % on the virtual rig, whose records are not bit-for-bit repeatable
# (its devices run in threads): xfail without strict, so a run that happens to hold is not red
BORDERLINE: set[tuple[str, str]] = {("virtual rig", "johnson_cook n")}
