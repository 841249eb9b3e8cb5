"""The static laws (identification/laws/: Hollomon, Ludwik, Swift, Voce, Hockett–Sherby,
Swift–Voce): each evaluated against a value computed here by hand, each fit recovering the
constants that made a curve (noise-free and with 0.3 % noise), ``best`` picking the law that
made the curve, and a constant on its bound named."""

import math

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.base import get_law
from flowcurve.identification.laws.hardening import choose_law, fit_hardening, static_law_names

EPS = np.linspace(0.01, 0.5, 80)

# (law, constants, (εp, σ in MPa computed by hand with math))
HAND = [
    ("hollomon", dict(K=800.0, n=0.2), (0.1, 800 * 0.1**0.2)),
    ("ludwik", dict(sigma0=200.0, K=500.0, n=0.4), (0.1, 200 + 500 * 0.1**0.4)),
    ("swift", dict(K=900.0, eps0=0.01, n=0.25), (0.1, 900 * 0.11**0.25)),
    ("voce", dict(sigma0=250.0, Q=200.0, b=15.0), (0.1, 250 + 200 * (1 - math.exp(-1.5)))),
    ("hockett_sherby", dict(sigma_s=700.0, sigma0=250.0, N=4.0, p=0.7), (0.1, 700 - 450 * math.exp(-4 * 0.1**0.7))),
    ("swift_voce", dict(alpha=0.6, K=900.0, eps0=0.01, n=0.25, sigma0=250.0, Q=200.0, b=15.0),
     (0.1, 0.6 * 900 * 0.11**0.25 + 0.4 * (250 + 200 * (1 - math.exp(-1.5))))),
]


@pytest.mark.parametrize("name, values, point", HAND, ids=[h[0] for h in HAND])
def test_each_static_law_equals_its_hand_computed_value(name, values, point):
    law = get_law(name)
    assert not law.rate_dependent and not law.temperature_dependent
    assert law.stress(point[0], **values) == pytest.approx(point[1], rel=1e-12)
    assert name in static_law_names()


# noise-free: every constant within 0.1 %; 0.3 % noise: within the tolerance given (the
# correlated pairs move most: Ludwik's σ0 with n, Swift's ε0, set by the first points, 6 %)
RECOVER = [(h[0], h[1], tol) for h, tol in zip(HAND[:5], (0.01, 0.05, 0.1, 0.02, 0.05))]


@pytest.mark.parametrize("name, truth, noisy_tol", RECOVER, ids=[r[0] for r in RECOVER])
def test_each_static_fit_recovers_the_constants_that_made_the_curve(name, truth, noisy_tol):
    exact = get_law(name).stress(EPS, **truth)
    clean = fit_hardening(EPS, exact, name)
    assert clean.params == pytest.approx(truth, rel=1e-3)
    noisy = fit_hardening(EPS, exact * (1 + 0.003 * np.random.default_rng(7).standard_normal(EPS.size)), name)
    assert noisy.params == pytest.approx(truth, rel=noisy_tol)
    assert noisy.rms_error_pct < 0.5 and not noisy.warnings


def _swift_voce_identifiable(v):
    """What one curve determines of Swift–Voce: α·K, (1 − α)·σ0, (1 − α)·Q, ε0, n, b (α trades with
    the three moduli: any α with rescaled K, σ0, Q is the same curve)."""
    return {"aK": v["alpha"] * v["K"], "s0": (1 - v["alpha"]) * v["sigma0"], "Q": (1 - v["alpha"]) * v["Q"],
            "eps0": v["eps0"], "n": v["n"], "b": v["b"]}


def test_the_swift_voce_fit_recovers_what_one_curve_determines():
    truth = HAND[5][1]
    exact = get_law("swift_voce").stress(EPS, **truth)
    clean = fit_hardening(EPS, exact, "swift_voce")
    assert _swift_voce_identifiable(clean.params) == pytest.approx(_swift_voce_identifiable(truth), rel=1e-3)
    noisy = fit_hardening(EPS, exact * (1 + 0.003 * np.random.default_rng(7).standard_normal(EPS.size)), "swift_voce")
    assert np.max(np.abs(noisy(EPS) / exact - 1)) < 0.005  # the curve within 0.5 %; the constants are not all determined


@pytest.mark.parametrize("maker", ["swift", "voce", "hockett_sherby"])
def test_best_picks_the_law_that_made_the_curve_and_says_by_how_much(maker):
    truth = {h[0]: h[1] for h in HAND}[maker]
    sig = get_law(maker).stress(EPS, **truth) * (1 + 0.002 * np.random.default_rng(3).standard_normal(EPS.size))
    won = choose_law(EPS, sig)
    choice = won.law_choice
    assert won.law == choice["chosen"] == maker, choice
    assert choice["next"] != maker and choice["delta_aic_to_next"] == pytest.approx(choice["aic"][choice["next"]] - choice["aic"][maker])
    # below the next, or (a law nesting it fitting the noise) within 2 with fewer constants
    assert choice["delta_aic_to_next"] > 0 or (choice["delta_aic_to_next"] > -2
                                               and len(get_law(choice["next"]).parameters) > len(get_law(maker).parameters))
    assert set(choice["aic"]) >= {"johnson_cook", "hollomon", "swift", "voce", "hockett_sherby", "swift_voce"}
    assert "ludwik" not in choice["aic"]  # johnson_cook's static part is Ludwik's form: one form, one AIC
    assert won.as_dict()["law_choice"] == choice


def test_a_constant_on_its_bound_is_named_as_such():
    # a Voce curve has no Swift part: Swift–Voce's α·K goes to 0 on K's lower bound, and no
    # constant claims a standard error (α trades with K, σ0 and Q: the curve does not fix them)
    sig = get_law("voce").stress(EPS, sigma0=250.0, Q=200.0, b=15.0)
    fit = fit_hardening(EPS, sig, "swift_voce")
    assert fit.params["K"] == pytest.approx(0.0, abs=1e-6)
    assert any(w.startswith("swift_voce K_MPa = ") and "sits on its lower bound" in w for w in fit.warnings), fit.warnings
    assert fit.as_dict()["K_MPa_stderr"] is None


def test_a_rate_or_temperature_law_on_one_record_is_refused_naming_fit():
    for name in ("zerilli_armstrong_bcc", "zerilli_armstrong_fcc", "hyperbolic_sine"):
        with pytest.raises(IdentificationError, match=f"one record cannot identify it.*flowcurve fit --law {name}"):
            fit_hardening(EPS, 300 + 100 * EPS, name)
    with pytest.raises(IdentificationError, match="did you mean 'hollomon'"):
        fit_hardening(EPS, 300 + 100 * EPS, "holomon")


def test_undetermined_names_the_constants_whose_interval_holds_zero():
    from flowcurve.identification.laws.hardening import static_form, undetermined

    spec = static_form("voce")
    values = {"sigma0": 250.0, "Q": 200.0, "b": 15.0}
    assert undetermined(spec, values, {"sigma0": 2.0, "Q": 3.0, "b": 0.5}) == []
    assert undetermined(spec, values, {"sigma0": 2.0, "Q": 250.0, "b": None}) == ["Q_MPa", "b"]
    # a constant on its bound: lmfit states no errors at all, which says nothing of the others (46NTAV's JC: A on 0,
    # B 1415 ± 2.7 MPa and n 0.039 ± 0.0025 once the errors are taken without it)
    assert undetermined(spec, {**values, "sigma0": 0.0}, {"sigma0": None, "Q": None, "b": None}, on_bound={"sigma0"}) == []
    assert undetermined(spec, {**values, "sigma0": 0.0}, {"sigma0": None, "Q": 250.0, "b": None}, on_bound={"sigma0"}) == ["Q_MPa"]
    assert undetermined(spec, {**values, "sigma0": 0.0}, {"sigma0": None, "Q": None, "b": None}) == ["sigma0_MPa", "Q_MPa", "b"]


def test_law_choice_text_claims_no_support_only_beyond_ten():
    from flowcurve.identification.laws.hardening import law_choice_text

    base = {"chosen": "swift", "next": "voce", "lowest_aic": "swift", "undetermined": {}}
    assert "essentially no support" in law_choice_text({**base, "delta_aic_to_next": 12.0})
    assert "less support, not none" in law_choice_text({**base, "delta_aic_to_next": 5.0})
    text = law_choice_text({**base, "delta_aic_to_next": 1.0})
    assert "support" not in text and "AIC 1.0 below the next (voce)" in text


def test_a_constant_a_hair_off_its_bound_is_warned_on_it_by_the_budgets_rule():
    """The fit's warning and the budget's one-sided interval read one rule (laws.bounds): a power law less a
    constant wants A < 0, and A's lower bound 0 holds it (whether the optimiser stops at 0 or 1e-9 off it)."""
    from flowcurve.identification.laws.bounds import bound_sides
    from flowcurve.identification.laws.hardening import fit_hardening, johnson_cook_static, static_form

    eps = np.linspace(0.005, 0.4, 60)
    fit = fit_hardening(eps, johnson_cook_static(eps, 0.0, 900.0, 0.3) - 40.0)
    assert fit.on_bound == {"A": "lower"}
    assert any("A_MPa" in w and "lower bound" in w for w in fit.warnings)
    assert fit.undetermined == []  # B and n with A held: the linearised errors lmfit does not state at a bound, each under its value
    law = static_form("johnson_cook")
    assert bound_sides(law.func, {**fit.params, "A": 5e-9}, law.bounds, eps) == {"A": "lower"}  # 10⁻⁹ MPa absolute missed it
    assert bound_sides(law.func, {**fit.params, "A": 0.5}, law.bounds, eps) == {}
