"""The card formats by name: the one place the CLI, the console and the report look them up.

A format is one :class:`CardFormat` entry of :data:`WRITERS`: its writer
``write(data: CardData, units: UnitSystem, options: CardOptions) -> str``, the file suffix of
its cards and the name it is shown by. A new format is its writer's module and one entry here
(docs/extending.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from flowcurve.reports.cards.abaqus import abaqus_card
from flowcurve.reports.cards.calculix import calculix_card
from flowcurve.reports.cards.data import CardData, CardOptions
from flowcurve.reports.cards.fields import CardError
from flowcurve.reports.cards.lsdyna import lsdyna_card
from flowcurve.reports.cards.radioss import radioss_card
from flowcurve.reports.units import UnitSystem, get_unit_system

Writer = Callable[[CardData, UnitSystem, CardOptions], str]


@dataclass(frozen=True)
class CardFormat:
    """One solver format: ``name`` (``--format``), ``suffix`` of its files (no dot),
    ``display_name`` (``LS-DYNA``), ``write`` the writer; ``contents`` says what the card holds
    (in the report's link); ``in_report``: the series report writes and links this card."""

    name: str
    suffix: str
    display_name: str
    write: Writer
    contents: str = ""
    in_report: bool = False


WRITERS: dict[str, CardFormat] = {f.name: f for f in (
    CardFormat("lsdyna", "k", "LS-DYNA", lsdyna_card, "*MAT_JOHNSON_COOK and *MAT_PIECEWISE_LINEAR_PLASTICITY", in_report=True),
    CardFormat("abaqus", "inp", "Abaqus", abaqus_card),
    CardFormat("radioss", "rad", "OpenRadioss", radioss_card),
    CardFormat("calculix", "inp", "CalculiX", calculix_card),
)}
FORMATS = WRITERS.keys()  # a live view: a format registered later is among the CLI's choices too


def card_format(fmt: str) -> CardFormat:
    """The registry entry of format ``fmt``; CardError naming the known ones."""
    try:
        return WRITERS[fmt]
    except KeyError:
        raise CardError(f"unknown card format {fmt!r} (choose one of: {', '.join(FORMATS)})") from None


def card_suffix(fmt: str, default: str = "txt") -> str:
    """The file suffix (no dot) of format ``fmt``'s cards; ``default`` for an unknown name."""
    entry = WRITERS.get(fmt)
    return entry.suffix if entry else default


def report_formats() -> list[CardFormat]:
    """The formats the series report writes and links (``in_report``), in registry order."""
    return [f for f in WRITERS.values() if f.in_report]


def write_card(card: CardData, fmt: str, units: str | UnitSystem, **options) -> str:
    """The card text in solver format ``fmt`` and unit system ``units``; ``options`` are the
    fields of :class:`CardOptions` (None keeps a default)."""
    entry = card_format(fmt)
    system = get_unit_system(units) if isinstance(units, str) else units
    return entry.write(card, system, CardOptions.from_keywords(**options))
