"""The set-up form: browser fields → a :class:`~flowcurve.services.run.RunRequest` → a checked test.

The form's values become the request ``flowcurve run`` builds from its options and go through
the same service (:mod:`flowcurve.services.run`): a value the command line refuses is refused
here with the same words, shown beside the field the service's FieldError names.
"""

from __future__ import annotations

import math
import re

from flowcurve.acquisition.procedure import POST_KEYS, TEST_GEOMETRY
from flowcurve.errors import FlowcurveError
from flowcurve.services import FieldError
from flowcurve.services.run import SOAK_DEFAULT_S, RunRequest, RunSetup, field_errors, parse_assignments, prepare

# form field → (run option, unit) for the numeric fields; the form uses the option's dest as name
NUMERIC_FIELDS = {
    "E_MPa": ("--E", "MPa"),
    "d0": ("--d0", "mm"),
    "l0": ("--l0", "mm"),
    "lc": ("--lc", "mm"),  # tension, optional: the parallel length, l0 when empty
    "h0": ("--h0", "mm"),
    "temperature": ("--temperature", "C"),
    "soak": ("--soak", "s"),
    "speed": ("--speed", "mm/s"),
    "target": ("--target", "mm"),
    "force_limit": ("--force-limit", "N"),
}
TEXT_FIELDS = ("material", "operator", "specimen_id")
FAULT_FIELD = "fault"  # virtual rig only: run's --fault drills, DEVICE:KIND[:VALUE][@SECONDS], several split by spaces or commas
# each field as the form labels it (static/index.html): an error beside a field names it so
LABELS = {"E_MPa": "Handbook E, MPa", "d0": "d0, mm", "l0": "l0, mm", "lc": "Parallel length Lc, mm", "h0": "h0, mm", "temperature": "Temperature, °C",
          "soak": "Soak, s", "speed": "Speed, mm/s", "target": "Target, mm", "force_limit": "Force limit, N",
          FAULT_FIELD: "Fault drill"}


class FormError(FieldError):
    """Values the form refuses: ``errors`` maps a form field's name to its message."""

    def __init__(self, errors: dict[str, str]):
        (field, message), *rest = errors.items()
        super().__init__(field, message, more=dict(rest))
        self.args = ("; ".join(f"{k}: {v}" for k, v in errors.items()),)

    def __str__(self) -> str:
        return self.args[0]


def _number(field: str, text) -> float | None:
    if text is None or (isinstance(text, str) and not text.strip()):
        return None
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise FormError({field: f"{NUMERIC_FIELDS[field][0]}: not a number: {text!r}"}) from None
    if not math.isfinite(value):
        raise FormError({field: f"{NUMERIC_FIELDS[field][0]}: not a finite number: {text!r}"})
    return value


def run_request(form: dict, errors: dict[str, str]) -> RunRequest:
    """The request ``flowcurve run`` would build from these values; bad numbers go to ``errors``."""
    test = str(form.get("test") or "")
    if test not in TEST_GEOMETRY:
        errors["test"] = f"test type must be one of {', '.join(TEST_GEOMETRY)}"
    values: dict[str, object] = {}
    for field in NUMERIC_FIELDS:
        try:
            values[field] = _number(field, form.get(field))
        except FormError as exc:
            errors.update(exc.errors)
            values[field] = None
    if values["soak"] is None:
        values["soak"] = SOAK_DEFAULT_S
    text = {k: (str(form.get(k) or "").strip() or None) for k in TEXT_FIELDS}
    drills = [t for t in re.split(r"[\s,]+", str(form.get(FAULT_FIELD) or "")) if t]  # several split by spaces or commas
    return RunRequest(test, fault=drills, **text, **values)


def labelled(field: str, message: str) -> str:
    """The service's message with the field's option (``--d0 …``) named as the form labels it."""
    option = NUMERIC_FIELDS[field][0] if field in NUMERIC_FIELDS else "--fault" if field == FAULT_FIELD else None
    return message.replace(option, LABELS[field], 1) if option else message


def validate(form: dict, *, virtual: bool, time_scale: float | None, config=None) -> RunSetup:
    """Check the form as ``run`` checks its options, the rig's ranges included (``config``, None
    on the virtual rig); a :class:`FormError` lists every bad field, each named by its label."""
    errors: dict[str, str] = {}
    request = run_request(form, errors)
    request.time_scale = time_scale
    if request.fault and not virtual:
        errors[FAULT_FIELD] = f"{LABELS[FAULT_FIELD]}: fault drills run on the virtual rig only; this console drives a configured rig"
    errors.update(field_errors(request, virtual=virtual, config=config))  # a number not read is None there: no second message
    if errors:
        raise FormError({field: labelled(field, message) for field, message in errors.items()})
    try:
        return prepare(request, virtual=virtual, config=None if virtual else config)
    except FieldError as exc:
        raise FormError({field: labelled(field, message) for field, message in exc.errors.items()}) from None
    except FlowcurveError as exc:  # not a field's: the test as a whole
        raise FormError({"form": str(exc)}) from None


def post_values(test: str, form: dict) -> dict[str, float]:
    """Post-test measurements from the form (``post.hk_mm`` …), checked like ``annotate --set``."""
    errors: dict[str, str] = {}
    out: dict[str, float] = {}
    for key in POST_KEYS[test]:
        text = str(form.get(key) or "").strip()
        if not text:
            continue
        try:
            parsed = parse_assignments([f"{key}={text}"])
        except FlowcurveError as exc:
            errors[key] = str(exc)
            continue
        out[key] = float(parsed[key])
    if errors:
        raise FormError(errors)
    return out
