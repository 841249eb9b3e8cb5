"""Material cards for FE solvers, written from a series fit (``fit.json``).

One module per concern: :mod:`.data` (what a card carries, read from ``fit.json``, and the
options that shape a deck), :mod:`.tables` (the tabulated curves every format shares),
:mod:`.fields` (fixed-width and free-format fields, ASCII comment blocks), one module per
solver (:mod:`.lsdyna`, :mod:`.abaqus`, :mod:`.radioss`, :mod:`.calculix`) and
:mod:`.registry` (format name -> :class:`~.registry.CardFormat`: writer, suffix, display name). Unit systems: :mod:`flowcurve.reports.units`.
Every card opens with a comment block: the source records, the identification method, the
unit system, and the range the constants were identified on, with the warning that
extrapolation beyond it is the user's risk.
"""

from flowcurve.reports.cards.data import (CONSTANTS, MAX_TABLE_ROWS, CardData, CardOptions, FlowCurve, card_data_from_fit,
                                          header_lines, load_card_data)
from flowcurve.reports.cards.fields import CardError, comment_block, fixed
from flowcurve.reports.cards.registry import FORMATS, WRITERS, CardFormat, card_format, card_suffix, report_formats, write_card

__all__ = ["CONSTANTS", "FORMATS", "MAX_TABLE_ROWS", "WRITERS", "CardData", "CardError", "CardFormat", "CardOptions", "FlowCurve",
           "card_data_from_fit", "card_format", "card_suffix", "report_formats", "comment_block", "fixed", "header_lines", "load_card_data", "write_card"]
