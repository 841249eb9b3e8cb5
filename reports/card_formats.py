"""The card formats by name: the one place the CLI, the console and the report look them up.

A format is one :class:`CardFormat` entry of :data:`WRITERS`: its writer
``write(data: CardData, units: UnitSystem, options: CardOptions) -> str`` (a callable, or
``"module:function"`` imported when first used, so that this registry and ``flowcurve --help``
import no numpy), the file suffix of its cards and the name it is shown by. A new format is its
writer's module and one entry here (docs/extending.md).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any, Callable

Writer = Callable[[Any, Any, Any], str]  # (CardData, UnitSystem, CardOptions) -> card text


@dataclass(frozen=True)
class CardFormat:
    """One solver card format of the registry.

    Attributes
    ----------
    name : str
        The ``--format`` name.
    suffix : str
        Its files' suffix (no dot).
    display_name : str
        As printed (``LS-DYNA``).
    writer : callable or str
        ``writer(card, units, options) -> str``, or ``"module:function"``.
    contents : str
        What the card holds (the report's link).
    in_report : bool
        The series report writes and links this card.
    """

    name: str
    suffix: str
    display_name: str
    writer: Writer | str
    contents: str = ""
    in_report: bool = False

    @property
    def write(self) -> Writer:
        """The writer, imported on first use when it is named by ``"module:function"``."""
        if callable(self.writer):
            return self.writer
        module, _, func = str(self.writer).partition(":")
        return getattr(importlib.import_module(module), func)


_CARDS = "flowcurve.reports.cards"
WRITERS: dict[str, CardFormat] = {f.name: f for f in (
    CardFormat("lsdyna", "k", "LS-DYNA", f"{_CARDS}.lsdyna:lsdyna_card", "*MAT_JOHNSON_COOK and *MAT_PIECEWISE_LINEAR_PLASTICITY",
               in_report=True),
    CardFormat("abaqus", "inp", "Abaqus", f"{_CARDS}.abaqus:abaqus_card"),
    CardFormat("radioss", "rad", "OpenRadioss", f"{_CARDS}.radioss:radioss_card"),
    CardFormat("calculix", "inp", "CalculiX", f"{_CARDS}.calculix:calculix_card"),
    CardFormat("flow-table", "csv", "Flow-stress table (CSV)", f"{_CARDS}.flow_table:flow_table_card",
               "eps_p, strain rate, temperature, stress on every tested condition (forming codes)"),
)}
FORMATS = WRITERS.keys()  # a live view: a format registered later is among the CLI's choices too


def card_suffix(fmt: str, default: str = "txt") -> str:
    """The file suffix (no dot) of format ``fmt``'s cards; ``default`` for an unknown name."""
    entry = WRITERS.get(fmt)
    return entry.suffix if entry else default


def report_formats() -> list[CardFormat]:
    """The formats the series report writes and links (``in_report``), in registry order."""
    return [f for f in WRITERS.values() if f.in_report]
