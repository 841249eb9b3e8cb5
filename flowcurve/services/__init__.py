"""The application's services: what ``flowcurve`` and the console both do, called with typed requests.

``services.run`` (a test on the rig), ``services.identify`` (records → results), ``services.fit``
(series fit, card and report). The CLI parses argv into a request and prints what the service
returns; the console builds the same request from its form. A value a request refuses raises
:class:`FieldError` naming the request's field, so a form shows it beside that field.
"""

from __future__ import annotations

from flowcurve.errors import FlowcurveError


class FieldError(FlowcurveError):
    """Values of a request refused: ``errors`` maps each field (the request's attribute) to its
    message; ``field`` and ``message`` are the first. ``str()`` is the messages joined by "; "."""

    def __init__(self, field: str, message: str, *, more: dict[str, str] | None = None):
        self.errors = {field: message, **(more or {})}
        self.field, self.message = field, message
        super().__init__("; ".join(self.errors.values()))

    @classmethod
    def of(cls, errors: dict[str, str]) -> FieldError:
        """One FieldError holding every ``field → message`` of ``errors`` (not empty)."""
        (field, message), *rest = errors.items()
        return cls(field, message, more=dict(rest))


def measured(field: str, option: str, value: float | None) -> float | None:
    """A given number option (dimension, speed, modulus) finite and > 0, or FieldError naming
    ``field`` in the option's words (``--d0 must be a positive number …``); None passes."""
    from flowcurve.record.format import MAX_MAGNITUDE, MIN_POSITIVE

    if value is not None and not MIN_POSITIVE <= value <= MAX_MAGNITUDE:  # NaN fails too
        raise FieldError(field, f"{option} must be a positive number of at most {MAX_MAGNITUDE:g}, got {value!r}")
    return value


def choice(field: str, option: str, value: str, allowed) -> str:
    """``value`` if it is one of ``allowed``, else FieldError in argparse's words."""
    if value not in allowed:
        raise FieldError(field, f"argument {option}: invalid choice: {value!r} (choose from {', '.join(map(repr, allowed))})")
    return value
