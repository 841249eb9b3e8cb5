"""The one rule for the elastic modulus a result hands on (docs/methods.md §2.3a).

E is, in this order, given (``--E``), the record's handbook ``material.E_MPa``, or measured with
an extensometer. The slope of a crosshead diagram is *apparent* (frame, grips and toe are in it):
it is reported as apparent and never reaches a card or an FE model.
"""

from __future__ import annotations

import math

from flowcurve.errors import IdentificationError

DEFENSIBLE = ("given", "handbook", "measured", "stated")  # in the order of the rule; "stated": a hand-written result.json's
SOURCE_TEXT = {
    "given": "given (--E)",
    "handbook": "handbook (the record's material.E_MPa)",
    "measured": "measured (extensometer)",
    "stated": "stated in result.json without its source (a result folder written by hand)",
    "apparent": "apparent (the crosshead diagram's slope: frame, grips and toe included, not the material's)",
    "none": "none (no elastic line, no handbook value)",
}
COMPRESSION_SOURCES = {"option": "given", "record": "handbook", "handbook": "handbook", "apparent": "apparent", "none": "none"}
# handbook moduli of material classes, MPa: (E, its spread over the class's grades, ~1 standard error); a class is
# named by one of its words in the record's ``material`` (carbon and alloy steels 200–215 GPa, austenitic 193–200)
CLASS_MODULI = {
    "steel": (200_000.0, 10_000.0, ("steel", "stainless", "сталь")),
    "aluminium": (70_000.0, 3_000.0, ("aluminium", "aluminum", "alumin")),
    "titanium": (110_000.0, 6_000.0, ("titanium", "ti-6al-4v")),
    "copper": (120_000.0, 10_000.0, ("copper", "brass", "bronze")),
    "nickel": (205_000.0, 10_000.0, ("nickel", "inconel")),
}


def tension_E_source(modulus_source: str, strain_source: str) -> str:
    """given / handbook / measured / apparent from a tension result's ``modulus.source`` and strain source."""
    if modulus_source.startswith("option"):
        return "given"
    if modulus_source.startswith("handbook"):
        return "handbook"
    return "measured" if strain_source == "extensometer" else "apparent"


def material_modulus(given: float | None, handbook: float | None, measured: float | None) -> tuple[float | None, str]:
    """(E, source) by the rule: given, else handbook, else measured (extensometer); else (None, "none")."""
    for value, source in ((given, "given"), (handbook, "handbook"), (measured, "measured")):
        if _finite(value) is not None:
            return float(value), source
    return None, "none"


def result_material_E(result: dict) -> tuple[float | None, str]:
    """The E a result hands on and its class: a tension result's ``modulus.E_material_MPa`` when it
    has one, else its ``E_MPa`` with :func:`result_E_source` (an apparent one stays labelled apparent)."""
    modulus = result.get("modulus")
    if isinstance(modulus, dict) and modulus.get("E_material_source") in DEFENSIBLE:
        return _finite(modulus.get("E_material_MPa")), modulus["E_material_source"]
    return _finite(result.get("E_MPa")), result_E_source(result)


def result_E_source(result: dict) -> str:
    """The class of a result.json's ``E_MPa``: given, handbook, measured, apparent, none, or stated
    (a result.json that says nothing of where its E came from)."""
    if _finite(result.get("E_MPa")) is None:
        return "none"
    modulus = result.get("modulus")
    if isinstance(modulus, dict) and modulus.get("E_source") in SOURCE_TEXT:  # tension
        return modulus["E_source"]
    if "E_source" in result:  # compression (its modulus block, when there is one, is the line's fit)
        return COMPRESSION_SOURCES.get(str(result["E_source"]).split(" ")[0], "apparent")  # "record (material.E_MPa)"
    if isinstance(modulus, dict):  # tension written before modulus.E_source
        return tension_E_source(str(modulus.get("source", "")), str((result.get("methods") or {}).get("strain_source", "")))
    return "stated"


def class_modulus(material: str | None) -> tuple[str, float, float] | None:
    """(class, E MPa, its standard error MPa) of the material class one of whose words the
    ``material`` text names (:data:`CLASS_MODULI`); None when it names none or two classes."""
    text = str(material or "").lower()
    found = [(name, E, se) for name, (E, se, words) in CLASS_MODULI.items() if any(w in text for w in words)]
    return found[0] if len(found) == 1 else None


def modulus_for_model(record, result: dict, E_MPa: float | None = None, *, what: str = "the FE model") -> tuple[float, str]:
    """(E, source) for a model of ``record``: ``E_MPa`` (given), else ``material.E_MPa``, else the
    result's E when an extensometer measured it; else a one-line error asking for ``--E``."""
    if E_MPa is not None:
        return float(E_MPa), "given"
    handbook = record.positive("material.E_MPa")
    if handbook is not None:
        return float(handbook), "handbook"
    E, source = result_material_E(result)
    if source in DEFENSIBLE:
        return E, source
    seen = f"the record's {E:.0f} MPa is {SOURCE_TEXT[source]}" if E is not None else "the record gives none"
    raise IdentificationError(f"{record.source}: {what} needs the material's elastic modulus and {seen}: "
                              "give it with --E or as material.E_MPa in the record")


def series_modulus(moduli: list[tuple[str, float | None, str]]) -> dict:
    """The series' E from its members' (name, E, source): the mean over the members of the first
    defensible class present (given, handbook, measured); apparent values never, and then None.
    Returns fit.json's E_MPa, E_MPa_source and the apparent values for reference."""
    for cls in DEFENSIBLE:
        values = [(name, E) for name, E, source in moduli if source == cls and _finite(E) is not None]
        if values:
            mean = sum(E for _, E in values) / len(values)
            low, high = min(E for _, E in values), max(E for _, E in values)
            spread = f", {low:.0f}–{high:.0f} MPa" if high > low else ""
            return {"E_MPa": mean, "E_MPa_source": f"{SOURCE_TEXT[cls]}: mean of {len(values)} record(s){spread}"}
    apparent = {name: E for name, E, source in moduli if source == "apparent" and _finite(E) is not None}
    text = ("undetermined: " + (f"the records' moduli are apparent ({min(apparent.values()):.0f}–{max(apparent.values()):.0f} MPa, "
                                "crosshead slopes)" if apparent else "no record has a modulus")
            + "; give the material's E to 'flowcurve card' (--E) or as material.E_MPa in the records")
    return {"E_MPa": None, "E_MPa_source": text, **({"E_apparent_MPa": apparent} if apparent else {})}


def _finite(value) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) else None
