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


def parallel_length_refusal(lc_mm: float | None, l0_mm: float | None) -> str | None:
    """Why a parallel length ``lc_mm`` cannot go with the gauge length ``l0_mm`` (both mm; None:
    not given): shorter than l0, where the gauge marks lie. None when it can (or either is missing)."""
    if lc_mm is None or l0_mm is None or lc_mm >= l0_mm:
        return None
    return (f"--lc {lc_mm:g} mm is shorter than the gauge length l0 {l0_mm:g} mm: the gauge marks lie on the parallel "
            f"length (ISO 6892-1: Lc ≥ L0, round bars usually L0 + 2·d0); give the machined parallel length, or "
            f"nothing when it is l0")


def choice(field: str, option: str, value: str, allowed) -> str:
    """``value`` if it is one of ``allowed``, else FieldError in argparse's words."""
    if value not in allowed:
        raise FieldError(field, f"argument {option}: invalid choice: {value!r} (choose from {', '.join(map(repr, allowed))})")
    return value
