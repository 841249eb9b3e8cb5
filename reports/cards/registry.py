"""The card writers by format name: the one place the CLI and the report look them up.

Each writer is ``writer(data: CardData, units: UnitSystem, options: CardOptions) -> str``.
"""

from __future__ import annotations

from typing import Callable

from flowcurve.reports.cards.abaqus import abaqus_card
from flowcurve.reports.cards.calculix import calculix_card
from flowcurve.reports.cards.data import CardData, CardOptions
from flowcurve.reports.cards.fields import CardError
from flowcurve.reports.cards.lsdyna import lsdyna_card
from flowcurve.reports.cards.radioss import radioss_card
from flowcurve.reports.units import UnitSystem, get_unit_system

Writer = Callable[[CardData, UnitSystem, CardOptions], str]

WRITERS: dict[str, Writer] = {
    "lsdyna": lsdyna_card,
    "abaqus": abaqus_card,
    "radioss": radioss_card,
    "calculix": calculix_card,
}
FORMATS = tuple(WRITERS)


def write_card(card: CardData, fmt: str, units: str | UnitSystem, **options) -> str:
    """The card text in solver format ``fmt`` and unit system ``units``; ``options`` are the
    fields of :class:`CardOptions` (None keeps a default)."""
    try:
        writer = WRITERS[fmt]
    except KeyError:
        raise CardError(f"unknown card format {fmt!r} (choose one of: {', '.join(FORMATS)})") from None
    system = get_unit_system(units) if isinstance(units, str) else units
    return writer(card, system, CardOptions.from_keywords(**options))
