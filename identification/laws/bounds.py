"""Whether a fitted constant sits on a bound of its law: one rule for the fit's warnings and the budgets.

A bounded optimiser stops a hair inside a bound, so "on the bound" is a tolerance; an absolute one
(10⁻⁹ MPa) misses A = 5·10⁻⁹ MPa, so the tolerance is relative to the constant's own scale: the
change that moves the law by its own size.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np

BOUND_REL_TOL = 1e-6  # a constant within this part of its own scale from a finite bound sits on it (the optimisers stop short)


def central_jacobian(func: Callable, params: Mapping[str, float], eps: np.ndarray) -> np.ndarray:
    """∂f/∂p_k at the points by central differences (unconstrained: a constant on its bound moves both ways)."""
    # ∂f/∂p ≈ (f(p + h) − f(p − h)) / 2h, h = 10⁻⁶·max(|p|, 10⁻³)
    cols = []
    for k in params:
        h = 1e-6 * max(abs(params[k]), 1e-3)
        cols.append((func(eps, **{**params, k: params[k] + h}) - func(eps, **{**params, k: params[k] - h})) / (2.0 * h))
    return np.column_stack(cols)


def constant_scales(func: Callable, params: Mapping[str, float], eps) -> dict[str, float]:
    """Each constant's own scale: the change that moves the law by its own size, max|f| / max|∂f/∂p_k|
    (A of Johnson–Cook: the stress level; n: about 1/|ln ε|). Inputs: the law, its constants, the strains."""
    eps = np.asarray(eps, dtype=float).ravel()
    eps = eps[np.isfinite(eps)]
    with np.errstate(all="ignore"):
        level = float(np.nanmax(np.abs(func(eps, **params)))) if eps.size else 0.0
        J = central_jacobian(func, params, eps) if eps.size else np.zeros((0, len(params)))
    out = {}
    for i, k in enumerate(params):
        top = float(np.nanmax(np.abs(J[:, i]))) if J.size else 0.0
        out[k] = level / top if top > 0 and math.isfinite(level / top) else 0.0
    return out


def constants_on_bound(func: Callable, params: Mapping[str, float], bounds: Mapping[str, tuple[float, float]], eps) -> dict[str, float]:
    """The constants sitting on a finite bound, name → +1 (lower: inward is up) or −1 (upper): those whose
    move onto the bound changes the law by at most :data:`BOUND_REL_TOL` of its level at the strains ``eps``
    (A = 5·10⁻⁹ MPa on 0 moves a 500 MPa curve by 5·10⁻⁹ MPa; a constant the curve hardly feels but that lies
    far from its bound moves it by much more, whatever its linearised scale)."""
    # on ⇔ max|f(p; p_k = bound) − f(p)| ≤ tol·max|f(p)|
    eps = np.asarray(eps, dtype=float).ravel()
    eps = eps[np.isfinite(eps)]
    if not eps.size:
        return {}
    with np.errstate(all="ignore"):
        base = func(eps, **params)
        level = float(np.nanmax(np.abs(base)))
        out = {}
        for k, v in params.items():
            lo, hi = bounds.get(k, (-math.inf, math.inf))
            for bound, inward in ((lo, 1.0), (hi, -1.0)):
                if not math.isfinite(bound) or abs(v - bound) > 0.5 * (hi - lo):
                    continue
                moved = float(np.nanmax(np.abs(func(eps, **{**params, k: bound}) - base)))
                if math.isfinite(moved) and moved <= BOUND_REL_TOL * level:
                    out[k] = inward
                    break
    return out


def sides(on_bound: Mapping[str, float]) -> dict[str, str]:
    """:func:`constants_on_bound`'s name → ±1 as name → "lower" / "upper"."""
    return {k: "lower" if inward > 0 else "upper" for k, inward in on_bound.items()}


def bound_sides(func: Callable, params: Mapping[str, float], bounds: Mapping[str, tuple[float, float]], eps) -> dict[str, str]:
    """:func:`constants_on_bound` as name → "lower" / "upper"."""
    return sides(constants_on_bound(func, params, bounds, eps))
