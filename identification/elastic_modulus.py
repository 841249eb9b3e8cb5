"""The one rule for the elastic modulus a result hands on (docs/methods.md §2.3a).

E is, in this order, given (``--E``), the record's handbook ``material.E_MPa``, measured with an
extensometer, or the handbook value of the material class the record's ``material`` names (a word
or a grade designation: EN/DIN, AISI/SAE, UNS, GOST; docs/materials.md) with its spread. The
slope of a crosshead diagram is *apparent* (frame, grips and toe are in it): it is reported as
apparent, named when it is far from any metal's, and never reaches a card or an FE model.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from flowcurve.errors import IdentificationError

DEFENSIBLE = ("given", "handbook", "measured", "stated", "class")  # in the order of the rule; "stated": a hand-written result.json's
SOURCE_TEXT = {
    "given": "given (--E)",
    "handbook": "handbook (the record's material.E_MPa)",
    "measured": "measured (extensometer)",
    "stated": "stated in result.json without its source (a result folder written by hand)",
    "class": "handbook value of the material class the record's material names (with its spread over the class's grades)",
    "apparent": "apparent (the crosshead diagram's slope: frame, grips and toe included, not the material's)",
    "none": "none (no elastic line, no handbook value)",
}
COMPRESSION_SOURCES = {"option": "given", "record": "handbook", "handbook": "handbook", "class": "class", "apparent": "apparent", "none": "none"}
GIVEN_E_REL_U = 0.05 / 3 ** 0.5  # a given or handbook E (not measured on the specimen) is within ±5 %, rectangular
METAL_E_RANGE_MPa = (40_000.0, 420_000.0)  # magnesium to tungsten: an apparent slope outside is no metal's elastic line
APPARENT_FAR = 0.3  # an apparent slope more than 30 % off the named class's E is not the material's
# handbook moduli of material classes, MPa: (E, its spread over the class's grades, ~1 standard error) — carbon and alloy
# steels 200–215 GPa, austenitic 193–200; aluminium alloys 68–73; titanium alloys 103–120; copper alloys 100–130;
# nickel alloys 195–215 (docs/materials.md). A class is named by a word or a grade designation in ``material``
# (:func:`material_class`).
CLASS_MODULI = {
    "steel": (200_000.0, 10_000.0, ("steel", "stainless", "сталь", "stahl", "acier")),
    "aluminium": (70_000.0, 3_000.0, ("aluminium", "aluminum", "alumin", "алюмин", "duralumin", "дюралюмин")),
    "titanium": (110_000.0, 6_000.0, ("titanium", "титан", "ti-6al-4v")),
    "copper": (120_000.0, 10_000.0, ("copper", "brass", "bronze", "медь", "латунь", "бронза")),
    "nickel": (205_000.0, 10_000.0, ("nickel", "inconel", "incoloy", "hastelloy", "monel", "nimonic", "никел")),
}
_KH = r"(?:kh|х|x)"  # GOST chromium: Latin transliteration Kh, Cyrillic Х (and a Latin X typed for it)
_GOST_LETTERS = r"(?:kh|yu|[хнмгстфвюрбадлцеп]|[nmgstfvrbadlcepk])"  # alloying letters of GOST 4543/5632 names
# grade designations per class: (system, pattern matched against a whole token of the material text)
GRADE_PATTERNS = {
    "steel": (
        ("EN material number", r"1\.[0-8]\d{3}"),
        ("UNS", r"[sgkjth]\d{5}"),
        ("EN/DIN name", r"x\d{1,3}(?:[a-z]{1,2})+\d+(?:-\d+){0,3}"),  # X5CrNi18-10, X2CrNiMo17-12-2
        ("EN/DIN name", r"\d{2,3}(?:cr|mn|mo|ni|si|v|w|b|s|al|ti|nb|pb)+\d{1,2}(?:-\d+)*[a-z]?"),  # 42CrMoS4, 16MnCr5, 100Cr6
        ("EN name", r"(?:c\d{2}[a-z]{0,2}|s\d{3}[a-z0-9+]{0,6}|e\d{3}|p\d{3}[a-z]{0,3}|b500[a-z]?)"),  # C45E, S355J2, E295, P265GH
        ("AISI/SAE", r"(?:aisi|sae)?-?(?:10|11|12|13|15|40|41|43|44|46|47|48|51|52|61|86|87|88|92|93|94|98)\d{2}[a-z]?h?"),
        ("AISI stainless", r"(?:aisi|ss)?-?(?:201|202|301|302|303|304|305|309|310|314|316|317|321|347|403|405|409|410|416|420|430|431|440)"
                           r"(?:l|h|ln|ti|s|se|f|a|b|c|n)?|17-4(?:ph)?|15-5(?:ph)?|2205|2507"),
        ("GOST", rf"\d{{1,3}}{_GOST_LETTERS}+(?:\d{{1,2}}{_GOST_LETTERS}*)*(?:-?[a-zа-я]{{1,3}})?"),  # 12Kh18N12M3TL, 40Kh, 09G2S, 12Х18Н10Т
        ("GOST", r"(?:ст|st)\.?\d(?:[a-zа-я]{1,3})?|(?:shkh|шх)\d{1,2}|[уu](?:7|8|10|12)a?|р6м5|r6m5"),  # Ст3сп, ШХ15, У8, Р6М5
        ("GOST carbon steel", r"0[58]|[1-6][05]|[1-6][05]g|[1-6][05]г"),  # 45, 20, 65G (alone: a GOST 1050 grade number)
    ),
    "aluminium": (
        ("EN material number", r"3\.[0-4]\d{3}"),
        ("EN AW / AA", r"(?:en-?aw|aa|al)-?[1-8]\d{3}[a-z]?(?:-[tho]\d*)?|[1-8]\d{3}-[tho]\d*|2014|2017|2024|5052|5083|5754|6060|6061|6063|6082|7020|7050|7075"),
        ("EN chemical", r"al(?:mg|si|zn|cu|mn)[a-z0-9.,]*"),  # AlMg3, AlSi1MgMn, AlZn5.5MgCu
        ("UNS", r"a9\d{4}"),
        ("GOST", r"(?:д|d)(?:1|16|19)[а-яa-z]{0,2}|(?:амг|amg)\d{0,2}|(?:ад|ad)(?:0|1|31|33|35)|(?:в|v)95|(?:ак|ak)\d{1,2}"),  # Д16Т, АМг6, АД31, В95
    ),
    "titanium": (
        ("EN material number", r"3\.7\d{3}"),
        ("name", r"ti-?6al-?4v(?:eli)?|tial6v4|ti-?gr(?:ade)?\.?-?\d{1,2}|cp-?ti"),
        ("UNS", r"r5\d{4}"),
        ("GOST", r"(?:вт|vt)\d{1,2}(?:-\d{1,2})?|(?:от|ot)4(?:-\d)?"),  # ВТ6, ВТ1-0, ОТ4
    ),
    "copper": (
        ("EN material number", r"2\.[01]\d{3}"),
        ("EN chemical", r"cu(?:zn|sn|al|ni|be|cr|-etp|-ofe?|-dhp)[a-z0-9.-]*"),  # CuZn37, CuSn8, Cu-ETP
        ("UNS", r"c\d{5}"),
        ("GOST", r"(?:лс|ls)\d{2}-\d|(?:бр|br)[а-яa-z]{1,4}[\d-]*"),  # ЛС59-1, БрБ2
    ),
    "nickel": (
        ("EN material number", r"2\.4\d{3}"),
        ("name", r"(?:alloy|in|ni)-?(?:600|601|617|625|718|738|825|x-?750)|nicr\d*[a-z0-9]*|nimonic\d*|c-?276|waspaloy|udimet\d*"),
        ("UNS", r"n\d{5}"),
        ("GOST", rf"{_KH}n\d{{2}}[a-zа-я0-9]*|хн\d{{2}}[а-я0-9]*|эи\d{{3}}|ei\d{{3}}|эп\d{{3}}|ep\d{{3}}"),  # ХН77ТЮР, ЭИ437
    ),
}
SYMBOLS = {"ti": "titanium", "al": "aluminium", "cu": "copper", "ni": "nickel"}  # a chemical symbol alone names the metal
NON_METALS = ("polymer", "plastic", "concrete", "wood", "rubber", "ceramic", "glass", "composite", "pmma", "peek", "nylon", "polyamide",
              "polycarbonate", "polyethylene", "polypropylene", "epoxy", "cfrp", "gfrp", "foam", "bone", "resin", "полимер", "пластмасс")
_COMPILED = {cls: tuple((system, re.compile(pattern)) for system, pattern in rules) for cls, rules in GRADE_PATTERNS.items()}


@dataclass(frozen=True)
class ModulusChoice:
    """The E the rule chose: value, standard uncertainty, class (given / handbook / measured / class / none) and where it came from."""

    E_MPa: float | None
    u_MPa: float
    source: str
    basis: str


def choose_modulus(*, given: float | None = None, handbook: float | None = None, measured: float | None = None,
                   measured_u_MPa: float | None = None, material: str | None = None) -> ModulusChoice:
    """The one rule: ``--E`` > the record's ``material.E_MPa`` > an extensometer's > the handbook
    value of the class ``material`` names (:func:`class_modulus`, with its spread as u) > none.
    A given or handbook E is taken as ±5 % rectangular; a measured one carries its standard error."""
    if _finite(given) is not None:
        return ModulusChoice(float(given), float(given) * GIVEN_E_REL_U, "given", "given (--E), ±5 % rectangular")
    if _finite(handbook) is not None:
        return ModulusChoice(float(handbook), float(handbook) * GIVEN_E_REL_U, "handbook", "the record's material.E_MPa, ±5 % rectangular")
    if _finite(measured) is not None:
        return ModulusChoice(float(measured), float(measured_u_MPa or 0.0), "measured", "measured (extensometer), its standard error")
    named = material_class(material)
    if named is not None:
        E, se, _ = CLASS_MODULI[named[0]]
        return ModulusChoice(E, se, "class", f"handbook E of {named[0]} ({named[1]} in material {material!r}): {E:.0f} ± {se:.0f} MPa")
    return ModulusChoice(None, 0.0, "none", "none: no --E, no material.E_MPa, no extensometer and no material class named")


def apparent_modulus_warning(apparent_MPa: float | None, material: str | None, *, what: str = "the first loading's slope") -> str | None:
    """A warning naming an apparent slope far from any metal's (:data:`METAL_E_RANGE_MPa`) or more
    than :data:`APPARENT_FAR` off the named class's handbook E; None when it is plausible."""
    E = _finite(apparent_MPa)
    if E is None:
        return None
    named = class_modulus(material)
    if named is not None and abs(E / named[1] - 1.0) > APPARENT_FAR:
        return (f"apparent modulus {E / 1000:.3g} GPa ({what}: frame, grips, toe or a stretch past yield in it) is far from the "
                f"{named[0]} class's {named[1] / 1000:.0f} GPa: not used; the class's handbook E strips the elastic strain")
    if named is None and not METAL_E_RANGE_MPa[0] <= E <= METAL_E_RANGE_MPa[1]:
        return (f"apparent modulus {E / 1000:.3g} GPa ({what}) is far from any metal's ({METAL_E_RANGE_MPa[0] / 1000:.0f}–"
                f"{METAL_E_RANGE_MPa[1] / 1000:.0f} GPa): the line may be a toe or a stretch past yield — give E (--E or "
                "material.E_MPa) or name the material's grade")
    return None


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


def material_class(material: str | None) -> tuple[str, str] | None:
    """(class, how it was told) of the metal the ``material`` text names — by a word of
    :data:`CLASS_MODULI` or a grade designation of :data:`GRADE_PATTERNS` (EN/DIN, AISI/SAE, UNS,
    GOST); None when it names none, two classes or a non-metal (:data:`NON_METALS`)."""
    text = re.sub(r"\b(en|alloy|grade|gr\.?)\s+(aw|\d)", r"\1-\2", str(material or "").lower())  # "EN AW 6061", "Alloy 625": one token
    if not text.strip() or any(w in text for w in NON_METALS):
        return None
    found: dict[str, str] = {}
    for name, (_, _, words) in CLASS_MODULI.items():
        word = next((w for w in words if w in text), None)
        if word:
            found.setdefault(name, f"the word '{word}'")
    for token in (t.strip(".-") for t in re.split(r"[\s,;/()\[\]]+", text)):
        if token in SYMBOLS:
            found.setdefault(SYMBOLS[token], f"the symbol '{token}'")
        for name, rules in _COMPILED.items():
            system = next((system for system, rx in rules if rx.fullmatch(token)), None)
            if system:
                found.setdefault(name, f"{system} grade '{token}'")
    return next(iter(found.items())) if len(found) == 1 else None


def class_modulus(material: str | None) -> tuple[str, float, float] | None:
    """(class, E MPa, its standard error MPa) of the material class the ``material`` text names
    (:func:`material_class`); None when it names none, two classes or a non-metal."""
    named = material_class(material)
    if named is None:
        return None
    E, se, _ = CLASS_MODULI[named[0]]
    return named[0], E, se


def modulus_for_model(record, result: dict, E_MPa: float | None = None, *, what: str = "the FE model") -> tuple[float, str]:
    """(E, source) for a model of ``record``: ``E_MPa`` (given), else ``material.E_MPa``, else the
    result's E when an extensometer measured it; else a one-line error asking for ``--E``."""
    if E_MPa is not None:
        return float(E_MPa), "given"
    handbook = record.positive("material.E_MPa")
    if handbook is not None:
        return float(handbook), "handbook"
    E, source = result_material_E(result)
    if source in DEFENSIBLE and source != "class":  # a class's handbook E: the caller takes it with its spread (fe.machine)
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
