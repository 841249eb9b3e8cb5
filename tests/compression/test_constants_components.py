"""The compression hardening constants' budgets name every share of their standard error (issue 43).

The stated standard error of A, B, n holds the fit's own and the method's shares in quadrature (μ,
the FE model form, the fit range: docs/methods.md §4.8). The budget in result.json states each
share as a component of its own ("method: …"), "fit (standard error)" the fit's own alone, and
its U is the U of one merged "fit (standard error)" (the budget before the shares were named).
"""

from __future__ import annotations

import math
import warnings

import pytest

from flowcurve.identification.quality import uncertainty as un

SHARES = ("method: friction μ", "method: FE model form", "method: fit range")


@pytest.fixture(scope="module")
def closed_form_result() -> dict:
    """A closed-form Johnson–Cook compression record at μ 0.1 (friction as the CalculiX runs make it), identified."""
    from flowcurve.identification.identify import identify
    from tests.series import compression_series as cs

    record, _ = cs.compression_record(20.0, 0.05, mu=0.1, seed=0, response="fe", reading_mm=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return dict(identify(record).result)


@pytest.mark.parametrize("key", ["A_MPa", "B_MPa", "n"])
def test_every_share_is_a_named_component(closed_form_result, key):
    names = [c["name"] for c in closed_form_result["uncertainty"]["hardening"][key]["components"]]
    for share in SHARES:
        assert sum(name.startswith(share) for name in names) == 1, names
    assert names[0] == "fit (standard error)"


@pytest.mark.parametrize("key", ["A_MPa", "B_MPa", "n"])
def test_the_components_sum_to_the_merged_budgets_U(closed_form_result, key):
    """Σ contribution² = u², and U is the U of the budget whose one "fit (standard error)" held every share."""
    hard, budget = closed_form_result["hardening"], closed_form_result["uncertainty"]["hardening"][key]
    assert math.fsum(c["contribution"] ** 2 for c in budget["components"]) == pytest.approx(budget["u"] ** 2, rel=1e-12)
    start = hard["start_uncertainty"]
    stress_rel_u = next((c["u"] for c in budget["components"] if c["name"].startswith("stress scale")), 0.0)
    merged = un.constant_budget(hard[key], hard[f"{key}_stderr"], stress_rel_u, budget["unit"],
                                zero_shift=start["constants_shift"].get(key.removesuffix("_MPa")),
                                lack_of_fit=start["constants_lack_of_fit"].get(key.removesuffix("_MPa")))
    assert len(merged["components"]) < len(budget["components"])
    assert budget["U"] == pytest.approx(merged["U"], rel=1e-12)


def test_the_fits_own_standard_error_is_what_the_shares_leave(closed_form_result):
    """"fit (standard error)"² = stated se² − the strain zero's shift² − Σ share²."""
    hard = closed_form_result["hardening"]
    comps = {c["name"]: c["u"] for c in closed_form_result["uncertainty"]["hardening"]["n"]["components"]}
    shares = [per["n"] for per in hard["stderr_shares"].values()]
    shift = hard["start_uncertainty"]["constants_shift"]["n"]
    expected = math.sqrt(hard["n_stderr"] ** 2 - shift ** 2 - sum(u * u for u in shares))
    assert comps["fit (standard error)"] == pytest.approx(expected, rel=1e-9)
    assert comps["fit (standard error)"] < min(shares)  # the fit's own is the smallest part here (the blanket's source was hidden in it)
