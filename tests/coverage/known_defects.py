"""Known defects of the stated uncertainty (issue 43), one line per cell of the coverage table:
(kind, quantity) → what misses, as measured on 1f2f484 and, after the budgets' method shares merged, on main (``python -m tests.coverage.campaign --worst``);
the drawn tension records since they are drawn from numpy's generator (the same population on every machine).
tests/coverage/test_coverage.py marks these cells ``xfail(strict=True)``: a fix turns the cell red
until its line here is removed. The default selection does not judge these cells.
"""

KNOWN: dict[tuple[str, str], str] = {
    # over-wide: the method share of U is more than 5× the median error (never a blanket U)
    ("CalculiX", "flow stress"): "blanket: method share 7.4× the median error (μ term)",
    ("CalculiX", "johnson_cook A_MPa"): "blanket: method share 5.5× the median error",
    ("CalculiX", "johnson_cook B_MPa"): "blanket: method share 12× the median error",
    ("CalculiX", "johnson_cook n"): "blanket: method share 6.7× the median error",
    # misses: U too small for the method's error
    ("compression closed form", "friction_mu"): ("67 % held (worst 1.4 U at μ 0.2, 2.4 U before u(μ) was half the range): the records' barrel is "
                                                 "(3.18)'s, which CalculiX makes at μ ≈ 0.3 (second model S2: ΔR/h 0.0451 at μ 0.3, h0/d0 1.2, "
                                                 "ε 0.69; (3.18) at μ 0.2: 0.0449), so fe_table's 0.325 ± 0.089 holds the FE truth, not the "
                                                 "generator's 0.2 (docs/methods.md §4.9); a term spanning (3.19) would be a blanket on CalculiX (8.2×)"),
    ("compression closed form", "johnson_cook A_MPa"): "67 % held (worst 1.6 U)",
    ("compression closed form", "johnson_cook n"): "67 % held (worst 1.5 U)",
    ("tension drawn", "johnson_cook A_MPa"): "79 % held (worst 417 U: a stated U near 0 at the bound A = 0) and blanket 5.9×",
    ("tension drawn", "johnson_cook B_MPa"): "79 % held (worst 15 U)",
    ("tension drawn", "johnson_cook n"): "71 % held (worst 43 U)",
    ("virtual rig", "Rm_MPa"): "50 % held (worst 130 U: a furnace open-thermocouple drill)",
    ("virtual rig", "johnson_cook A_MPa"): "89 % held (worst 1.2 U)",
    ("virtual rig", "johnson_cook B_MPa"): "78 % held (worst 8.8 U)",
    ("virtual rig", "johnson_cook n"): "65 % held (worst 4.2 U)",
}

# cells within a few records of 90 % on the virtual rig, whose records are not bit-for-bit repeatable
# (its devices run in threads): xfail without strict, so a run that happens to hold is not red
BORDERLINE: set[tuple[str, str]] = {("virtual rig", "johnson_cook A_MPa")}
