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


NAMES = {"d0_mm": "d0", "l0_mm": "l0", "parallel_length_mm": "Lc", "h0_mm": "h0"}  # in run's option words


def _stated(geometry_mm: dict) -> dict:
    """The lengths that make a bar: the parallel length is l0 where none is stated."""
    g = dict(geometry_mm)
    if "l0_mm" in g:
        g.setdefault("parallel_length_mm", g["l0_mm"])
    return g


def virtual_geometry_mismatch(test: str, geometry_mm: dict, rig_test: str, rig_geometry_mm: dict,
                              rig: str = "the virtual rig") -> str | None:
    """Where a test's geometry (mm, the record's keys) differs from the bar a virtual rig in its
    own process simulates (its configuration's ``[virtual]``; ``rig`` names it), in one line naming
    both values; None when they agree. The record would state the test's geometry over the rig's
    bar's numbers."""
    if test != rig_test:
        return f"{rig} simulates a {rig_test} specimen, not a {test} one ({geometry_words(_stated(rig_geometry_mm))})"
    ours, theirs = _stated(geometry_mm), _stated(rig_geometry_mm)
    differ = [key for key in NAMES if key in ours and key in theirs and not math.isclose(ours[key], theirs[key], rel_tol=1e-9)]
    if not differ:
        return None
    return (f"{rig} simulates another specimen than this test states: " +
            ", ".join(f"{NAMES[k]} {ours[k]:g} mm here, {theirs[k]:g} mm on the rig" for k in differ) +
            " — the record would give this geometry to the rig's bar's forces and travel; restart 'flowcurve rig virtual' "
            "with this geometry, or give run the rig's")


def geometry_words(geometry_mm: dict) -> str:
    """``d0 6 mm, l0 30 mm, Lc 42 mm``: a geometry (mm, the record's keys) in run's option words."""
    return ", ".join(f"{NAMES[k]} {v:g} mm" for k, v in geometry_mm.items() if k in NAMES)
