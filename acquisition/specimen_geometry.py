"""A test spec's specimen geometry, checked before anything moves (:meth:`TestSpec.check`)."""

from __future__ import annotations

import math

OPTIONAL_GEOMETRY = {"tension": ("parallel_length_mm",), "compression": ()}  # the parallel length Lc: l0 when not given


def geometry_problem(test: str, required, geometry_mm: dict) -> str | None:
    """What is wrong with ``geometry_mm`` (key → mm) of a ``test`` that needs the keys ``required``:
    one missing or not > 0, a key the test has no such length for, a parallel length shorter than
    l0 (the gauge marks lie on it) — one line naming the option; None when nothing is."""
    for key in required:
        v = geometry_mm.get(key)
        if v is None or not (v > 0 and math.isfinite(v)):
            return f"specimen geometry '{key}' is missing or not > 0 (give --{key.split('_')[0]})"
    unknown = set(geometry_mm) - set(required) - set(OPTIONAL_GEOMETRY.get(test, ()))
    if unknown:
        return f"specimen geometry {', '.join(sorted(unknown))}: not a {test} specimen's"
    lc = geometry_mm.get("parallel_length_mm")
    if lc is not None and not (math.isfinite(lc) and lc >= geometry_mm["l0_mm"]):
        return f"specimen parallel length {lc:g} mm must be at least l0 {geometry_mm['l0_mm']:g} mm (the gauge marks lie on it; give --lc ≥ --l0)"
    return None
