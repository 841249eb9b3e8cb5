"""The specimen of a record, parsed once: its geometry and the measurements after the test.

``record.specimen`` (:attr:`flowcurve.record.format.Record.specimen`) reads the header's
``specimen.*`` and ``post.*`` keys of the record's test (docs/record-format.md) into a frozen
:class:`Specimen`; the identification takes its numbers and derived areas from it instead of
parsing header text again. Bad or missing values raise the record's own errors (file, key, value).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from flowcurve.errors import MissingValueError, RecordError

# field name → header key, per test; REQUIRED names those every identification of the test needs
_COMMON = {"d0_mm": "specimen.d0_mm"}
TEST_KEYS: dict[str, dict[str, str]] = {
    "tension": {**_COMMON, "l0_mm": "specimen.l0_mm", "extensometer_gauge_mm": "specimen.extensometer_gauge_mm",
                "parallel_length_mm": "specimen.parallel_length_mm", "s0_stated_mm2": "specimen.s0_mm2",
                "notch_radius_mm": "specimen.notch_radius_mm", "lu_mm": "post.lu_mm", "dk_mm": "post.dk_mm",
                "du_mm": "post.du_mm", "sk_mm2": "post.sk_mm2", "neck_radius_mm": "post.neck_radius_mm"},
    "compression": {**_COMMON, "h0_mm": "specimen.h0_mm", "extensometer_gauge_mm": "specimen.extensometer_gauge_mm",
                    "hk_mm": "post.hk_mm", "dmax_mm": "post.dmax_mm", "smax_mm2": "post.smax_mm2",
                    "dtop_mm": "post.dtop_mm", "dface_mm": "post.dface_mm"},
}
REQUIRED = {"tension": ("d0_mm", "l0_mm"), "compression": ("d0_mm", "h0_mm")}
# the header keys a specimen is read from, for the record's cache to tell when its header changed
ALL_KEYS = ("test",) + tuple(dict.fromkeys(k for keys in TEST_KEYS.values() for k in keys.values()))


def circle_area_mm2(d_mm):
    """Area of a round section of diameter ``d_mm`` (a number or an array), mm²: S = π·d²/4."""
    return math.pi * d_mm**2 / 4.0  # S = π·d²/4


@dataclass(frozen=True)
class Specimen:
    """A round specimen's geometry (mm) and its post-test measurements (mm, mm²; None when not given).

    Tension: d0, l0 (gauge), Le (extensometer gauge), parallel length, stated S0, notch radius;
    after fracture Lu, dk, du, Sk, neck radius. Compression: d0, h0; after the test hk, dmax, Smax,
    dtop, dface. The record format has no flat specimens: ``kind`` is always ``"round"``.
    """

    test: str
    source: str
    d0_mm: float
    l0_mm: float | None = None
    h0_mm: float | None = None
    extensometer_gauge_mm: float | None = None
    parallel_length_mm: float | None = None
    s0_stated_mm2: float | None = None  # specimen.s0_mm2 (INSTRON imports)
    notch_radius_mm: float | None = None
    lu_mm: float | None = None
    dk_mm: float | None = None
    du_mm: float | None = None
    sk_mm2: float | None = None
    neck_radius_mm: float | None = None
    hk_mm: float | None = None
    dmax_mm: float | None = None
    smax_mm2: float | None = None
    dtop_mm: float | None = None
    dface_mm: float | None = None
    kind: str = "round"

    @classmethod
    def from_record(cls, record) -> Specimen:
        """Read the specimen keys of a :class:`~flowcurve.record.format.Record`'s test once (the record model
        imports this module, so it is not imported back); the record's errors for a value that is
        not a positive number (file, key, value) or a required one missing (d0 and l0 or h0)."""
        test = record.test
        values = {name: record.positive(key, required=name in REQUIRED[test]) for name, key in TEST_KEYS[test].items()}
        lc, l0 = values.get("parallel_length_mm"), values.get("l0_mm")
        if lc is not None and l0 is not None and lc < l0:  # the gauge marks lie on the parallel length: a slip, not a bar
            raise RecordError(record.source, f"metadata '{TEST_KEYS[test]['parallel_length_mm']}' = {lc:g} mm is shorter than "
                              f"'{TEST_KEYS[test]['l0_mm']}' = {l0:g} mm: the gauge marks lie on the parallel length (ISO 6892-1: "
                              "Lc ≥ L0); give the machined one (identify --lc) or remove it (Lc is then l0)")
        return cls(test=test, source=record.source, **values)

    @property
    def area0_mm2(self) -> float:
        """Initial cross-section from d0, mm²: S0 = π·d0²/4."""
        return circle_area_mm2(self.d0_mm)

    @property
    def s0_mm2(self) -> float:
        """Initial cross-section of a tension test, mm²: the stated ``specimen.s0_mm2``, else π·d0²/4."""
        return self.s0_stated_mm2 if self.s0_stated_mm2 is not None else self.area0_mm2

    @property
    def gauge_mm(self) -> float:
        """The length the nominal strain refers to: l0 (tension) or h0 (compression), mm."""
        return self.l0_mm if self.test == "tension" else self.h0_mm

    @property
    def uniform_plastic_elongation(self) -> float | None:
        """The uniform part's plastic elongation from its diameter after fracture du, at constant volume:
        a_u = (d0/du)² − 1; None without du."""
        return (self.d0_mm / self.du_mm) ** 2 - 1.0 if self.du_mm is not None else None

    @property
    def fracture_area_mm2(self) -> float | None:
        """Section after fracture, mm²: the stated Sk, else π·dk²/4; None without either."""
        if self.sk_mm2 is not None:
            return self.sk_mm2
        return circle_area_mm2(self.dk_mm) if self.dk_mm is not None else None

    @property
    def fracture_area_source(self) -> str | None:
        """The header key the section after fracture comes from (``post.sk_mm2``, ``post.dk_mm``), or None."""
        return "post.sk_mm2" if self.sk_mm2 is not None else "post.dk_mm" if self.dk_mm is not None else None

    def required(self, name: str) -> float:
        """The value of field ``name`` (e.g. ``"hk_mm"``); the record's missing-value error when not given."""
        value = getattr(self, name)
        if value is None:
            raise MissingValueError(self.source, (TEST_KEYS[self.test][name],))
        return value
