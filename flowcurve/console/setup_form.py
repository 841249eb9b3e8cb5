"""The set-up form: browser fields → the ``run`` command's options → a :class:`TestSpec`.

The form's values become the same ``argparse`` namespace ``flowcurve run`` builds, and go
through the same checks (``flowcurve.cli.acquisition``): a value the command line refuses
is refused here with the same words, shown beside its field.
"""

from __future__ import annotations

import argparse
import math
import re
from dataclasses import dataclass

from flowcurve.acquisition.procedure import POST_KEYS, TEST_GEOMETRY, TestSpec
from flowcurve.errors import FlowcurveError

# form field → (run option, unit) for the numeric fields; the form uses the option's dest as name
NUMERIC_FIELDS = {
    "E_MPa": ("--E", "MPa"),
    "d0": ("--d0", "mm"),
    "l0": ("--l0", "mm"),
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
LABELS = {"E_MPa": "Handbook E, MPa", "d0": "d0, mm", "l0": "l0, mm", "h0": "h0, mm", "temperature": "Temperature, °C",
          "soak": "Soak, s", "speed": "Speed, mm/s", "target": "Target, mm", "force_limit": "Force limit, N",
          FAULT_FIELD: "Fault drill"}
SOAK_DEFAULT_S = 60.0  # run's --soak default


class FormError(FlowcurveError):
    """Values the form refuses: ``errors`` maps a field name to its message."""

    def __init__(self, errors: dict[str, str]):
        self.errors = errors
        super().__init__("; ".join(f"{k}: {v}" for k, v in errors.items()))


@dataclass
class TestSetup:
    """A validated test: the spec and, on the virtual rig, its material and time scale."""

    __test__ = False

    spec: TestSpec
    virtual_material: str | None
    time_scale: float
    faults: tuple = ()  # rig.virtual.fault_spec.FaultSpec drills (virtual rig only)


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


def run_namespace(form: dict, errors: dict[str, str]) -> argparse.Namespace:
    """The namespace ``flowcurve run`` would parse from these values; bad numbers go to ``errors``."""
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
    return argparse.Namespace(test=test, quiet=True, post=[], time_scale=None, poll=False, **text, **values)


def field_of(message: str) -> str:
    """The form field an error message of the ``run`` checks names (``--d0 …`` → d0)."""
    for field, (option, _unit) in NUMERIC_FIELDS.items():
        if re.search(rf"(?<![\w-]){re.escape(option)}(?![\w-])", message):
            return field
    if "set-point" in message or "heating" in message:
        return "temperature"
    if "speed" in message:
        return "speed"
    return "form"


def labelled(field: str, message: str) -> str:
    """``run``'s message with the field's option (``--d0 …``) named as the form labels it."""
    if field in NUMERIC_FIELDS:
        return re.sub(rf"(?<![\w-]){re.escape(NUMERIC_FIELDS[field][0])}(?![\w-])", LABELS[field], message, count=1)
    return message


def fault_drills(form: dict, *, virtual: bool, errors: dict[str, str]) -> tuple:
    """The form's fault drills parsed as ``run --fault`` parses them (several split by spaces or
    commas); a bad one, or any on a configured rig, goes to ``errors`` under the field's name."""
    from flowcurve.rig.virtual.fault_spec import parse_faults

    texts = [t for t in re.split(r"[\s,]+", str(form.get(FAULT_FIELD) or "")) if t]
    if texts and not virtual:
        errors[FAULT_FIELD] = f"{LABELS[FAULT_FIELD]}: fault drills run on the virtual rig only; this console drives a configured rig"
        return ()
    try:
        return parse_faults(texts)
    except FlowcurveError as exc:  # parse_fault's words: the form and the devices, kinds or values allowed
        errors[FAULT_FIELD] = str(exc).replace("--fault", LABELS[FAULT_FIELD], 1)
        return ()


def validate(form: dict, *, virtual: bool, time_scale: float | None, config=None) -> TestSetup:
    """Check the form as ``run`` checks its options, the rig's ranges included (``config``, None
    on the virtual rig); a :class:`FormError` lists every bad field, each named by its label."""
    from flowcurve.acquisition.live import LiveView
    from flowcurve.cli.acquisition import _positive, configured_spec, out_of_range, virtual_spec

    errors: dict[str, str] = {}
    args = run_namespace(form, errors)
    faults = fault_drills(form, virtual=virtual, errors=errors)
    for field, (option, _unit) in NUMERIC_FIELDS.items():
        if field in errors or field in ("E_MPa", "temperature"):
            continue
        try:
            _positive(option[2:], getattr(args, field))  # run's own rule, run's own words
        except FlowcurveError as exc:
            errors[field] = str(exc)
    if args.E_MPa is not None and not args.E_MPa > 0 and "E_MPa" not in errors:
        errors["E_MPa"] = f"--E must be a positive number, got {args.E_MPa:g}"
    for field, text in out_of_range(args, None if virtual else config).items():
        errors[field] = f"{NUMERIC_FIELDS[field][0]} {text}"  # the range says more than "a positive number"
    if errors:
        raise FormError({field: labelled(field, message) for field, message in errors.items()})
    args.time_scale = time_scale
    try:
        if virtual:
            spec, material, scale = virtual_spec(args, LiveView(quiet=True))
        else:
            (spec, scale), material = configured_spec(args, config), None
        spec.check()
    except FlowcurveError as exc:
        field = field_of(str(exc))
        raise FormError({field: labelled(field, str(exc))}) from None
    return TestSetup(spec, material, scale, faults)


def post_values(test: str, form: dict) -> dict[str, float]:
    """Post-test measurements from the form (``post.hk_mm`` …), checked like ``annotate --set``."""
    from flowcurve.cli.acquisition import parse_assignments

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
