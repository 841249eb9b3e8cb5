"""A test on the rig: the typed request, its checks and the run, for ``flowcurve run`` and the console.

:class:`RunRequest` holds what ``flowcurve run`` takes as options (same names: ``d0``, ``speed`` …);
:func:`field_errors` lists every refused value at once (a form), :func:`prepare` checks in the
command's order and builds the :class:`RunSetup`, :func:`run_test` runs it on the virtual rig
in this process or on the configured rig.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from flowcurve.errors import FlowcurveError
from flowcurve.services import FieldError, measured, parallel_length_refusal

DEFAULT_VIRTUAL_MATERIAL = "steel45"
ROOM_TEMPERATURE_C = 20.0  # the record's nominal temperature without a set-point: a furnace heats above it
MAX_SOAK_S = 86_400.0  # a day
SOAK_DEFAULT_S = 60.0
# request field → run's option (the words of every message)
OPTIONS = {"E_MPa": "--E", "d0": "--d0", "l0": "--l0", "lc": "--lc", "h0": "--h0", "temperature": "--temperature", "soak": "--soak",
           "speed": "--speed", "target": "--target", "force_limit": "--force-limit", "time_scale": "--time-scale",
           "material": "--material", "post": "--post", "fault": "--fault"}
RANGE_OPTIONS = {k: OPTIONS[k] for k in ("temperature", "soak", "speed", "target", "force_limit", "d0", "l0", "lc", "h0")}


@dataclass
class RunRequest:
    """One test as ``flowcurve run`` and the console ask for it.

    Attributes
    ----------
    test : str
        "tension" or "compression".
    material, operator, specimen_id : str, optional
        Written to the record's header.
    E_MPa : float, optional
        The material's handbook Young's modulus, MPa.
    temperature, soak : float
        Heating set-point, °C (None: room temperature); soak time at it, s.
    speed, d0, l0, lc, h0, target, force_limit : float, optional
        Crosshead speed, mm/s; diameter, gauge length, parallel length (tension: the length the
        crosshead stretches, l0 when not given; ignored for compression) and height, mm; target
        displacement, mm; force limit, N.
    post : list of str
        Post-test measurements as KEY=VALUE (``post.lu_mm=55.2``).
    time_scale, fault, compression_response, tension_response : optional
        The virtual rig's time scale, fault drills (DEVICE:KIND…) and physics ("fe", "slab"; "fe", "bridgman").
    """

    test: str
    material: str | None = None
    E_MPa: float | None = None
    operator: str | None = None
    specimen_id: str | None = None
    temperature: float | None = None
    soak: float = SOAK_DEFAULT_S
    speed: float | None = None
    d0: float | None = None
    l0: float | None = None
    lc: float | None = None
    h0: float | None = None
    target: float | None = None
    force_limit: float | None = None
    post: list[str] = field(default_factory=list)
    time_scale: float | None = None
    fault: list[str] = field(default_factory=list)
    compression_response: str | None = None
    tension_response: str | None = None

    def responses(self) -> dict[str, str]:
        """The virtual rig's responses asked for (fe where not given)."""
        return {"compression_response": self.compression_response or "fe", "tension_response": self.tension_response or "fe"}


@dataclass
class RunSetup:
    """A checked test: the spec and, on the virtual rig, its material, time scale and drills."""

    __test__ = False

    spec: object  # acquisition.procedure.TestSpec
    virtual_material: str | None
    time_scale: float
    faults: tuple = ()  # rig.virtual.fault_spec.FaultSpec drills (virtual rig only)
    responses: dict = field(default_factory=dict)
    warnings: tuple[str, ...] = ()  # for the operator before the test (also events in the record)


def parse_assignments(items: list[str], *, numeric_prefix: str = "post.", known=None, option: str = "--set") -> dict[str, str | None]:
    """``["post.hk_mm=3.55", "operator=Ivanov"]`` → dict; post.* values must be numbers; a key the
    record format does not know (``known``: only these) is refused with the nearest known one."""
    from flowcurve.record.format import unknown_key_message

    out: dict[str, str | None] = {}
    for item in items:
        key, sep, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key or " " in key or ":" in key:
            raise FlowcurveError(f"'{item}': give KEY=VALUE, e.g. post.hk_mm=3.55")
        if key in ("flowcurve-record", "status"):
            raise FlowcurveError(f"'{key}' is managed by flowcurve and cannot be set")
        refused = unknown_key_message(key, known)
        if refused:
            raise FlowcurveError(f"{option} {item}: {refused} (nothing written)")
        if value and key.startswith(numeric_prefix):
            try:
                number = float(value)
            except ValueError:
                raise FlowcurveError(f"'{item}': {key} must be a number (mm, mm2)") from None
            if not (math.isfinite(number) and number > 0):
                raise FlowcurveError(f"'{item}': {key} must be > 0")
        out[key] = value or None
    return out


def run_post_keys(test: str) -> tuple[str, ...]:
    """The post-test keys ``run --post`` takes for ``test``."""
    from flowcurve.acquisition.procedure import POST_KEYS

    extra = {"tension": ("post.sk_mm2",), "compression": ("post.smax_mm2", "post.dtop_mm")}
    return POST_KEYS[test] + extra[test]


def out_of_range(req, config=None) -> dict[str, str]:
    """What is wrong with each given value (field → text after the option's name) that the rig
    cannot do or take: the [frame] speed range, travel, largest specimen and capacity, the
    furnace's range. ``config`` None: the virtual rig, which has the configuration's defaults."""
    from flowcurve.rig.config import FrameConfig, FurnaceConfig, setpoint_refusal

    frame = config.frame if config is not None else FrameConfig()
    furnace = config.furnace if config is not None else FurnaceConfig(port="virtual")
    longest = (0.0, frame.max_specimen_length_mm, "mm", "the longest specimen that fits, [frame] max_specimen_length_mm")
    limits = {  # field → (low, high, unit, where the high end comes from); a low of 0 is checked as > 0 elsewhere
        "speed": (frame.min_speed_mm_per_s, frame.max_speed_mm_per_s, "mm/s", "the machine's speed range, [frame] min_speed_mm_per_s and max_speed_mm_per_s"),
        "target": (0.0, frame.travel_mm, "mm", "the crosshead travel, [frame] travel_mm"),
        "force_limit": (0.0, frame.max_force_N, "N", "the machine's capacity, [frame] max_force_N"),
        "d0": (0.0, frame.max_specimen_diameter_mm, "mm", "the largest diameter the grips and platens take, [frame] max_specimen_diameter_mm"),
        "l0": longest, "lc": longest, "h0": longest,
        "soak": (0.0, MAX_SOAK_S, "s", "a day"),
    }
    problems = {}
    for dest, (lo, hi, unit, why) in limits.items():
        value = getattr(req, dest, None)
        if value is None or not math.isfinite(value) or (lo <= value <= hi and value > 0):
            continue
        span = f"between {lo:g} and {hi:g} {unit}" if lo > 0 else f"more than 0 and at most {hi:g} {unit}"
        problems[dest] = f"must be {span} ({why}), got {value:g}"
    temperature = getattr(req, "temperature", None)
    if temperature is not None and furnace is None:
        problems["temperature"] = f"this rig has no furnace: leave it out for a test at room temperature, got {temperature:g}"
    elif temperature is not None and not ROOM_TEMPERATURE_C < temperature < furnace.max_temperature_C:
        problems["temperature"] = (f"must be above {ROOM_TEMPERATURE_C:g} C (room; leave it out for a test at room temperature) and below "
                                   f"{furnace.max_temperature_C:g} C (the furnace's [furnace] max_temperature_C), got {temperature:g}")
    elif temperature is not None and (refusal := setpoint_refusal(temperature, furnace.max_temperature_C, furnace.setpoint_margin_C)):
        problems["temperature"] = refusal
    return problems


def check_ranges(req, config=None) -> None:
    """FieldError naming each value outside the rig's ranges (:func:`out_of_range`), in one line."""
    problems = out_of_range(req, config)
    if problems:
        raise FieldError.of({dest: f"{RANGE_OPTIONS[dest]} {text}" for dest, text in problems.items()})


def field_errors(req: RunRequest, *, virtual: bool, config=None) -> dict[str, str]:
    """Every refused value of ``req`` at once (field → run's message): numbers not > 0, values
    outside the rig's ranges (``config``; None on the virtual rig), malformed fault drills."""
    errors: dict[str, str] = {}
    for name in ("d0", "l0", "lc", "h0", "soak", "speed", "target", "force_limit", "E_MPa"):
        try:
            measured(name, OPTIONS[name], getattr(req, name))
        except FieldError as exc:
            errors.update(exc.errors)
    for name, text in out_of_range(req, None if virtual else config).items():
        errors[name] = f"{OPTIONS[name]} {text}"  # the range says more than "a positive number"
    if req.test == "tension" and "lc" not in errors and "l0" not in errors:
        refusal = parallel_length_refusal(req.lc, req.l0)  # l0 not given: build_spec checks against the one it takes
        if refusal:
            errors["lc"] = refusal
    if virtual:
        try:
            faults(req)
        except FieldError as exc:
            errors.update(exc.errors)
    return errors


def faults(req: RunRequest) -> tuple:
    """The parsed fault drills (FieldError ``fault`` naming a malformed one)."""
    from flowcurve.rig.virtual.fault_spec import parse_faults

    try:
        return parse_faults(req.fault)
    except FlowcurveError as exc:
        raise FieldError("fault", str(exc)) from None


def build_spec(req: RunRequest, geometry_default: dict[str, float] | None = None, ask: Callable | None = None):
    """The TestSpec of ``req`` (geometry in mm); ``ask(prompt, default, cast)`` asks for what is
    missing (the command line when interactive), else a missing geometry is a FieldError. A given
    parallel length (tension) joins the geometry; it must be at least l0 (FieldError ``lc``)."""
    from flowcurve.acquisition.procedure import TEST_GEOMETRY, StopCriteria, TestSpec

    for name in ("d0", "l0", "lc", "h0", "E_MPa", "speed", "target", "force_limit", "soak"):
        measured(name, OPTIONS[name], getattr(req, name))
    geometry: dict[str, float] = {}
    for key in TEST_GEOMETRY[req.test]:
        opt = key.split("_")[0]
        value = getattr(req, opt)
        if value is None and geometry_default:
            value = geometry_default.get(key)
        if value is None and ask:
            value = ask(f"specimen {opt} [mm]", None, float)
        if value is None:
            raise FieldError(opt, f"specimen geometry missing: give --{opt} (mm)")
        geometry[key] = float(value)
    if req.test == "tension" and req.lc is not None:  # compression has no parallel length: ignored, as --l0 is
        refusal = parallel_length_refusal(req.lc, geometry["l0_mm"])
        if refusal:
            raise FieldError("lc", refusal)
        geometry["parallel_length_mm"] = float(req.lc)
    material = req.material or (ask("material", "unknown") if ask else "unknown")
    operator = req.operator if req.operator is not None else (ask("operator", "") if ask else "")
    try:
        post = parse_assignments(req.post, known=run_post_keys(req.test), option="--post")
    except FlowcurveError as exc:
        raise FieldError("post", str(exc)) from None
    return TestSpec(
        test=req.test, material=material or "unknown", operator=operator or "", specimen_id=req.specimen_id or "",
        geometry_mm=geometry, temperature_C=req.temperature, speed_mm_per_s=req.speed, soak_s=req.soak,
        stop=StopCriteria(target_displacement_mm=req.target, force_limit_N=req.force_limit),
        post={k: float(v) for k, v in post.items() if v is not None},
        extra_meta={"material.E_MPa": repr(float(req.E_MPa))} if req.E_MPa else {},
    )


def virtual_bar(test: str) -> dict[str, float]:
    """The virtual rig's own bar of a ``test`` (mm, the record's geometry keys: d0 with l0 or h0):
    what it simulates where no geometry is given."""
    from flowcurve.rig.virtual.physics import Specimen

    base = Specimen.tension() if test == "tension" else Specimen.compression()
    return {"d0_mm": base.d0_mm, "l0_mm" if test == "tension" else "h0_mm": base.length0_mm}


def virtual_specimen_geometry(req: RunRequest) -> dict[str, float]:
    """The geometry (mm, the record's keys) of the bar the virtual rig makes of ``req``'s d0, l0,
    lc, h0 — its own bar's where one is not given — checked as ``run`` on the virtual rig checks it
    (:func:`check_ranges` with the frame's defaults, then :func:`build_spec`: FieldError naming the
    option, e.g. an Lc shorter than l0). For ``flowcurve rig virtual``, whose bar is the one
    ``run`` would make in its own process of the same options."""
    check_ranges(req)
    return build_spec(req, virtual_bar(req.test)).geometry_mm


def prepare(req: RunRequest, *, virtual: bool | None = None, config=None, ask: Callable | None = None) -> RunSetup:
    """Check ``req`` in ``run``'s order and set the test up.

    On a configured rig (``config``): its ranges, time scale 1 and 0.01 mm/s by default; on the
    virtual rig in this process: time scale 15, 0.05 mm/s and the virtual specimen's geometry
    where none is given.

    Parameters
    ----------
    req : RunRequest
        The test as asked.
    virtual : bool, optional
        Run on the virtual rig (default: when there is no ``config``).
    config : RigConfig, optional
        The rig's configuration (:func:`flowcurve.rig.config.load_config`).
    ask : callable, optional
        ``ask(prompt, default, cast)`` asks the operator for what is missing; None: nothing asked.

    Returns
    -------
    RunSetup
        The checked TestSpec and, on the virtual rig, its material, time scale and drills.

    Raises
    ------
    FieldError
        Naming each refused field.
    """
    warnings: tuple[str, ...] = ()
    if not (config is None if virtual is None else virtual):
        scale = 1.0 if req.time_scale is None else req.time_scale
        measured("time_scale", OPTIONS["time_scale"], scale)
        req.speed = 0.01 if req.speed is None else req.speed
        check_ranges(req, config)
        spec, material, drills, responses = build_spec(req, ask=ask), None, (), {}
        mismatch = virtual_mismatch(spec, config)
        if mismatch:
            spec.opening_events.append(("geometry_mismatch", mismatch))
            warnings = (mismatch,)
    else:
        from flowcurve.rig.virtual.materials import get_material

        drills = faults(req)
        scale = 15.0 if req.time_scale is None else req.time_scale
        measured("time_scale", OPTIONS["time_scale"], scale)
        req.speed = 0.05 if req.speed is None else req.speed
        try:
            material = get_material(req.material or DEFAULT_VIRTUAL_MATERIAL).name  # the specimen is made of what the record says
        except FlowcurveError as exc:
            raise FieldError("material", f"--material: {str(exc).split(': ', 1)[-1]} — the virtual rig makes its specimen of the "
                             "material the record names") from None
        req.material = req.material or material
        check_ranges(req)
        spec, responses = build_spec(req, virtual_bar(req.test), ask=ask), req.responses()
    spec.check()
    return RunSetup(spec, material, scale, drills, responses, warnings)


def virtual_mismatch(spec, config) -> str | None:
    """Where ``spec``'s geometry differs from the bar the virtual rig in its own process simulates
    (``config``'s ``[virtual]``, which ``flowcurve rig virtual`` writes): one line naming both
    values, with the configuration file; None when they agree or the rig is not a virtual one."""
    from flowcurve.acquisition.specimen_geometry import virtual_geometry_mismatch

    virtual = getattr(config, "virtual", None)
    if virtual is None:
        return None
    return virtual_geometry_mismatch(spec.test, spec.geometry_mm, virtual.test, virtual.geometry_mm,
                                     f"the virtual rig ({config.source} [virtual])")


def run_test(setup: RunSetup, record: Path, *, config=None, view=None, interactive: bool = False, stream: bool = True,
             stop_requested=None, on_rig: Callable | None = None, open_rig: Callable | None = None):
    """Run a prepared test into a record file.

    Parameters
    ----------
    setup : RunSetup
        From :func:`prepare`.
    record : Path
        The record file written as the test runs.
    config : RigConfig, optional
        The configured rig; None with ``open_rig`` None: the virtual rig in this process.
    view : LiveView, optional
        What shows the test live (the terminal, the console).
    interactive, stream : bool
        Ask the operator at the terminal; stream the load cell (else poll it).
    stop_requested : callable, optional
        Another thread's stop button: an operator-stop reason or None.
    on_rig, open_rig : callable, optional
        ``on_rig(rig)`` sees the rig once open; ``open_rig(time_scale)`` a context manager giving
        the rig (default :class:`flowcurve.acquisition.session.DriverRig`).

    Returns
    -------
    Outcome
        The procedure's outcome: path, status, reason, samples, duration, maximum force.
    """
    if config is None and open_rig is None:
        from flowcurve.acquisition.session import run_virtual_test

        return run_virtual_test(setup.spec, record, material=setup.virtual_material, time_scale=setup.time_scale, view=view,
                                interactive=interactive, stream=stream, faults=setup.faults, **setup.responses,
                                **({"rig_setup": on_rig} if on_rig else {}),
                                **({"stop_requested": stop_requested} if stop_requested else {})).outcome
    from flowcurve.acquisition.procedure import Procedure
    from flowcurve.acquisition.session import DriverRig

    opened = open_rig(setup.time_scale) if open_rig else DriverRig(config, time_scale=setup.time_scale, stream=stream)
    with opened as rig:
        if on_rig is not None:
            on_rig(rig)
        return Procedure(rig, setup.spec, record, view=view, interactive=interactive,
                         **({"stop_requested": stop_requested} if stop_requested else {})).run()
