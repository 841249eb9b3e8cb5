"""Writing a card of a registered format (:mod:`flowcurve.reports.card_formats` holds the registry)."""

from __future__ import annotations

from flowcurve.reports.card_formats import FORMATS, WRITERS, CardFormat, Writer, card_suffix, report_formats  # noqa: F401  (re-exported)
from flowcurve.reports.cards.data import CardData, CardOptions
from flowcurve.reports.cards.fields import CardError
from flowcurve.reports.units import UnitSystem, get_unit_system


def card_format(fmt: str) -> CardFormat:
    """The registry entry of format ``fmt``; CardError naming the known ones."""
    try:
        return WRITERS[fmt]
    except KeyError:
        raise CardError(f"unknown card format {fmt!r} (choose one of: {', '.join(FORMATS)})") from None


def write_card(card: CardData, fmt: str, units: str | UnitSystem, **options) -> str:
    """The card text of ``card`` in solver format ``fmt`` and unit system ``units``.

    Parameters
    ----------
    card : CardData
        The law, curves and constants (:func:`card_data_from_fit`).
    fmt : str
        A registered format (:data:`FORMATS`).
    units : str or UnitSystem
        The unit system (``mm-s-t-N-MPa`` …).
    **options
        Fields of :class:`CardOptions` (None keeps a default).

    Returns
    -------
    str
        The card.

    Raises
    ------
    CardError
        An unknown format, or a value the format cannot write.
    """
    entry = card_format(fmt)
    system = get_unit_system(units) if isinstance(units, str) else units
    return entry.write(card, system, CardOptions.from_keywords(**options))
