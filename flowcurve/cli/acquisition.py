"""``flowcurve run``, ``demo``, ``recover`` and ``annotate``.

``run tension|compression`` runs one test on the configured rig (``--config rig.toml``) or,
without a configuration, on the virtual rig in this process; ``demo`` runs a virtual
tension and a virtual compression test and identifies both; ``recover`` completes the
header of a record cut short; ``annotate`` adds post-test measurements to a record.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from flowcurve.cli.choices import TEST_TYPES
from flowcurve.cli.specimen import add_geometry_options, add_modulus_option, check_specimen_options, measurement
from flowcurve.errors import EXIT_COMPLETE, EXIT_DATA_LOST, EXIT_STOPPED, DeviceError, FlowcurveError, RecordError, RecordWriteError, SafetyError
from flowcurve.rig.virtual.responses import COMPRESSION_HELP, COMPRESSION_RESPONSES, TENSION_HELP, TENSION_RESPONSES

if TYPE_CHECKING:  # the acquisition and the record format import numpy: imported where a command runs, not for --help
    from flowcurve.acquisition.live import LiveView
    from flowcurve.acquisition.procedure import Outcome, TestSpec

DEFAULT_VIRTUAL_MATERIAL = "steel45"


def register(subparsers) -> None:
    run = subparsers.add_parser("run", help="run a tension or compression test and record it", description="Run a test on the rig (--config) or on the virtual rig (no --config), record it crash-safely, show it live.")
    run.add_argument("test", choices=TEST_TYPES, help="test type")
    run.add_argument("--config", type=Path, help="rig configuration (TOML); without it the virtual rig runs in this process")
    run.add_argument("--out", type=Path, help="record file (default records/<test>-<date-time>.csv)")
    run.add_argument("--material", help="material name (virtual rig: also the virtual specimen's material, default steel45)")
    add_modulus_option(run, "the handbook value, written into the record as material.E_MPa (compression identification strips elastic strain with it; the virtual rig knows its own)")
    run.add_argument("--operator", default=None, help="operator name")
    run.add_argument("--specimen-id", default=None, help="specimen identifier")
    run.add_argument("--temperature", type=float, metavar="C", help="heat to this set-point, C, and soak before loading")
    run.add_argument("--soak", type=float, default=60.0, metavar="S", help="soak time at the set-point, test seconds (default 60)")
    run.add_argument("--speed", type=float, metavar="MM_PER_S", help="crosshead speed, mm/s (default 0.01; the demo-like 0.05 on the virtual rig)")
    add_geometry_options(run)
    run.add_argument("--target", type=float, metavar="MM", help="stop at this crosshead displacement, mm")
    run.add_argument("--force-limit", type=float, metavar="N", help="stop at this force, N (default 98 %% of the frame capacity)")
    run.add_argument("--post", action="append", default=[], metavar="KEY=VALUE", help="post-test measurement, e.g. post.hk_mm=3.55 (repeatable)")
    run.add_argument("--quiet", action="store_true", help="no live view, no prompts (for scripts)")
    run.add_argument("--time-scale", type=float, default=None, metavar="X", help="virtual rig: model seconds per wall second (in this process: default 15; with --config: what 'flowcurve rig virtual --time-scale' runs at)")
    run.add_argument("--poll", action="store_true", help="poll the load cell (MSV?) instead of streaming (MSV?0)")
    add_virtual_response_options(run, " (the virtual rig in this process only; recorded in the header)")
    add_fault_option(run, " (the virtual rig in this process; with --config give it to 'flowcurve rig virtual')")
    run.set_defaults(func=cmd_run)

    demo = subparsers.add_parser("demo", help="a virtual tension and compression test, recorded and identified", description="Run a virtual tension test and a virtual compression test (time-scaled), identify both, and compare with the virtual material's true constants.")
    demo.add_argument("--out", type=Path, default=Path("flowcurve-demo"), help="output folder (default ./flowcurve-demo)")
    demo.add_argument("--material", default=DEFAULT_VIRTUAL_MATERIAL, help="virtual material (default steel45)")
    demo.add_argument("--quiet", action="store_true", help="only the summary")
    add_virtual_response_options(demo, " (recorded in the header)")
    add_fault_option(demo, " (in both tests)")
    demo.set_defaults(func=cmd_demo)

    rec = subparsers.add_parser("recover", help="complete the header of a record cut short (power cut, kill -9)")
    rec.add_argument("record", type=Path)
    rec.set_defaults(func=cmd_recover)

    ann = subparsers.add_parser("annotate", help="add or change metadata of a record (post-test measurements)")
    ann.add_argument("record", type=Path)
    ann.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", required=True, help="e.g. --set post.hk_mm=3.55 (repeatable; empty value removes the key)")
    ann.set_defaults(func=cmd_annotate)


# -- helpers ----------------------------------------------------------------------------------


def add_virtual_response_options(parser, note: str = "") -> None:
    """``--compression-response fe|slab`` and ``--tension-response fe|bridgman``: the virtual rig's physics."""
    parser.add_argument("--compression-response", choices=COMPRESSION_RESPONSES, help=COMPRESSION_HELP + note)
    parser.add_argument("--tension-response", choices=TENSION_RESPONSES, help=TENSION_HELP + note)


def add_fault_option(parser, note: str = "") -> None:
    """``--fault DEVICE:KIND[:VALUE][@SECONDS]`` (repeatable): a fault drill on the virtual rig."""
    from flowcurve.rig.virtual.fault_spec import help_text  # pure and light

    parser.add_argument("--fault", action="append", default=[], metavar="DEVICE:KIND[:VALUE][@SECONDS]",
                        help=help_text().replace("%", "%%") + note)


def virtual_faults(args) -> tuple:
    """The parsed ``--fault`` options (ConfigError naming a malformed one)."""
    from flowcurve.rig.virtual.fault_spec import parse_faults

    return parse_faults(getattr(args, "fault", None))


def virtual_responses(args) -> dict[str, str]:
    """The virtual rig's responses the options ask for (fe where not given)."""
    return {"compression_response": args.compression_response or "fe", "tension_response": args.tension_response or "fe"}


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
    """The post-test keys ``run --post`` takes for ``test``: the record format's and the areas."""
    from flowcurve.acquisition.procedure import POST_KEYS

    return POST_KEYS[test] + {"tension": ("post.sk_mm2",), "compression": ("post.smax_mm2", "post.dtop_mm")}[test]


def _positive(name: str, value: float | None) -> None:
    if value is not None:
        measurement(name, value)


ROOM_TEMPERATURE_C = 20.0  # the record's nominal temperature without a set-point: a furnace heats above it
MAX_SOAK_S = 86_400.0  # a day
RANGE_OPTIONS = {"temperature": "--temperature", "soak": "--soak", "speed": "--speed", "target": "--target",
                 "force_limit": "--force-limit", "d0": "--d0", "l0": "--l0", "h0": "--h0"}


def out_of_range(args, config=None) -> dict[str, str]:
    """What is wrong with each given value (``args`` dest → text after the option's name) that the
    rig cannot do or take: the [frame] speed range, travel, largest specimen and capacity, the
    furnace's range. ``config`` None: the virtual rig, which has the configuration's defaults."""
    from flowcurve.rig.config import FrameConfig, FurnaceConfig, setpoint_refusal

    frame = config.frame if config is not None else FrameConfig()
    furnace = config.furnace if config is not None else FurnaceConfig(port="virtual")
    longest = (0.0, frame.max_specimen_length_mm, "mm", "the longest specimen that fits, [frame] max_specimen_length_mm")
    limits = {  # dest → (low, high, unit, where the high end comes from); a low of 0 is checked as > 0 elsewhere
        "speed": (frame.min_speed_mm_per_s, frame.max_speed_mm_per_s, "mm/s", "the machine's speed range, [frame] min_speed_mm_per_s and max_speed_mm_per_s"),
        "target": (0.0, frame.travel_mm, "mm", "the crosshead travel, [frame] travel_mm"),
        "force_limit": (0.0, frame.max_force_N, "N", "the machine's capacity, [frame] max_force_N"),
        "d0": (0.0, frame.max_specimen_diameter_mm, "mm", "the largest diameter the grips and platens take, [frame] max_specimen_diameter_mm"),
        "l0": longest, "h0": longest,
        "soak": (0.0, MAX_SOAK_S, "s", "a day"),
    }
    problems = {}
    for dest, (lo, hi, unit, why) in limits.items():
        value = getattr(args, dest, None)
        if value is None or not math.isfinite(value) or (lo <= value <= hi and value > 0):
            continue
        span = f"between {lo:g} and {hi:g} {unit}" if lo > 0 else f"more than 0 and at most {hi:g} {unit}"
        problems[dest] = f"must be {span} ({why}), got {value:g}"
    temperature = getattr(args, "temperature", None)
    if temperature is not None and furnace is None:
        problems["temperature"] = f"this rig has no furnace: leave it out for a test at room temperature, got {temperature:g}"
    elif temperature is not None and not ROOM_TEMPERATURE_C < temperature < furnace.max_temperature_C:
        problems["temperature"] = (f"must be above {ROOM_TEMPERATURE_C:g} C (room; leave it out for a test at room temperature) and below "
                                   f"{furnace.max_temperature_C:g} C (the furnace's [furnace] max_temperature_C), got {temperature:g}")
    elif temperature is not None and (refusal := setpoint_refusal(temperature, furnace.max_temperature_C, furnace.setpoint_margin_C)):
        problems["temperature"] = refusal
    return problems


def check_ranges(args, config=None) -> None:
    """``run``'s one-line error naming each option outside the rig's ranges (:func:`out_of_range`)."""
    problems = out_of_range(args, config)
    if problems:
        raise FlowcurveError("; ".join(f"{RANGE_OPTIONS[dest]} {text}" for dest, text in problems.items()))


def _interactive(args) -> bool:
    return not args.quiet and sys.stdin.isatty()


def _ask(prompt: str, default=None, cast=str):
    text = input(f"{prompt}{f' [{default}]' if default is not None else ''}: ").strip()
    if not text:
        return default
    try:
        return cast(text)
    except ValueError:
        raise FlowcurveError(f"{prompt}: not a number: {text!r}") from None


def build_spec(args, geometry_default: dict[str, float] | None = None) -> TestSpec:
    """The TestSpec from options (and prompts when interactive) — geometry in mm."""
    from flowcurve.acquisition.procedure import TEST_GEOMETRY, ProcedureError, StopCriteria, TestSpec

    check_specimen_options(args)
    for name in ("speed", "target", "force_limit", "soak"):
        _positive(name.replace("_", "-"), getattr(args, name, None))
    interactive = _interactive(args)
    geometry: dict[str, float] = {}
    for key in TEST_GEOMETRY[args.test]:
        opt = key.split("_")[0]
        value = getattr(args, opt)
        if value is None and geometry_default:
            value = geometry_default.get(key)
        if value is None and interactive:
            value = _ask(f"specimen {opt} [mm]", None, float)
        if value is None:
            raise ProcedureError(f"specimen geometry missing: give --{opt} (mm)")
        geometry[key] = float(value)
    material = args.material or (_ask("material", "unknown") if interactive else "unknown")
    operator = args.operator if args.operator is not None else (_ask("operator", "") if interactive else "")
    post = {k: float(v) for k, v in parse_assignments(args.post, known=run_post_keys(args.test), option="--post").items() if v is not None}
    return TestSpec(
        test=args.test,
        material=material or "unknown",
        operator=operator or "",
        specimen_id=args.specimen_id or "",
        geometry_mm=geometry,
        temperature_C=args.temperature,
        speed_mm_per_s=args.speed,
        soak_s=args.soak,
        stop=StopCriteria(target_displacement_mm=args.target, force_limit_N=args.force_limit),
        post=post,
        extra_meta={"material.E_MPa": repr(float(args.E_MPa))} if args.E_MPa else {},
    )


def default_out(test: str) -> Path:
    return Path("records") / f"{test}-{_dt.datetime.now():%Y%m%d-%H%M%S}.csv"


def report_outcome(out: Outcome, view: LiveView) -> int:
    """Print where the record went and why it ended; the exit code."""
    from flowcurve.acquisition.procedure import POST_KEYS
    from flowcurve.record.format import read_record

    line = f"record: {out.path} ({out.samples} samples, {out.duration_s:.1f} s test time, max force {out.max_force_N / 1000:.2f} kN) — {out.status}: {out.reason}"
    print(line)
    if out.post:
        print("post-test measurements: " + ", ".join(f"{k}={v:g}" for k, v in out.post.items()))
    elif out.status == "complete":
        print(f"no post-test measurements yet: flowcurve annotate {out.path} --set {POST_KEYS[read_record(out.path).test][0]}=...")
    if out.error is not None:
        print(f"flowcurve: error: {out.error}{advice(out.error)} (the record keeps everything up to the fault"
              f"{'; ' + out.losses if out.losses else ''})", file=sys.stderr)
        return out.error.exit_code
    if out.losses:
        print(f"flowcurve: warning: {out.losses} — declared in the record's events (data_loss)", file=sys.stderr)
        return EXIT_DATA_LOST if out.status == "complete" else EXIT_STOPPED
    return EXIT_COMPLETE if out.status == "complete" else EXIT_STOPPED


def advice(error: FlowcurveError) -> str:
    """What to do about a device that failed a test (empty when the message says it already)."""
    text = str(error)
    if not isinstance(error, DeviceError) or " — " in text:
        return ""
    if "disappeared" in text or "Input/output error" in text or "No such file" in text:
        return " — the port vanished: reconnect the cable or USB adapter, then 'flowcurve rig check'"
    if "garbled" in text or "incomplete" in text:
        return " — check the cable, baud rate and parity ('flowcurve rig check' probes them)"
    if "no answer" in text or "no data" in text or "silent" in text:
        return " — check the device's power and cable, then 'flowcurve rig check'"
    if isinstance(error, SafetyError):
        return " — the heater is off; let the furnace cool before opening it"
    return " — 'flowcurve rig check' diagnoses the device"


# -- commands ---------------------------------------------------------------------------------


def cmd_run(args) -> int:
    from flowcurve.acquisition.live import LiveView

    view = LiveView(quiet=args.quiet)
    out_path = args.out or default_out(args.test)
    if args.config is not None:
        given = [f"--{k.replace('_', '-')}" for k in ("compression_response", "tension_response") if getattr(args, k) is not None]
        given += ["--fault"] if args.fault else []
        if given:
            raise FlowcurveError(f"{' and '.join(given)}: the virtual rig in this process only; with --config the rig is the "
                                 "configured one (for 'flowcurve rig virtual' give the option there)")
        return _run_configured(args, view, out_path)
    return _run_virtual(args, view, out_path)


def configured_spec(args, config=None) -> tuple[TestSpec, float]:
    """A test on the configured rig as ``run`` sets it up: (spec, time scale)."""
    scale = 1.0 if args.time_scale is None else args.time_scale
    _positive("time-scale", scale)
    if args.speed is None:
        args.speed = 0.01
    check_ranges(args, config)
    return build_spec(args), scale


def _run_configured(args, view: LiveView, out_path: Path) -> int:
    from flowcurve.acquisition.procedure import Procedure
    from flowcurve.acquisition.session import DriverRig
    from flowcurve.rig.config import load_config

    config = load_config(args.config)
    spec, scale = configured_spec(args, config)
    with DriverRig(config, time_scale=scale, stream=not args.poll) as rig:
        proc = Procedure(rig, spec, out_path, view=view, interactive=_interactive(args))
        return report_outcome(proc.run(), view)


def virtual_spec(args, view: LiveView) -> tuple[TestSpec, str, float]:
    """A test on the in-process virtual rig as ``run`` sets it up: (spec, virtual material, time scale)."""
    from flowcurve.rig.virtual.materials import get_material
    from flowcurve.rig.virtual.physics import Specimen

    scale = 15.0 if args.time_scale is None else args.time_scale
    _positive("time-scale", scale)
    if args.speed is None:
        args.speed = 0.05
    name = args.material or DEFAULT_VIRTUAL_MATERIAL
    try:
        name = get_material(name).name  # the virtual specimen is made of what the record will say
    except FlowcurveError as exc:
        raise FlowcurveError(f"--material: {str(exc).split(': ', 1)[-1]} — the virtual rig makes its specimen of the "
                             "material the record names") from None
    base = Specimen.tension() if args.test == "tension" else Specimen.compression()
    geometry = {"d0_mm": base.d0_mm, "l0_mm" if args.test == "tension" else "h0_mm": base.length0_mm}
    args.material = args.material or name
    check_ranges(args)
    return build_spec(args, geometry), name, scale


def _run_virtual(args, view: LiveView, out_path: Path) -> int:
    from flowcurve.acquisition.session import run_virtual_test

    faults = virtual_faults(args)
    spec, name, scale = virtual_spec(args, view)
    run = run_virtual_test(spec, out_path, material=name, time_scale=scale, view=view, interactive=_interactive(args), stream=not args.poll,
                           faults=faults, **virtual_responses(args))
    return report_outcome(run.outcome, view)


def cmd_recover(args) -> int:
    from flowcurve.record.format import read_record, recover_record

    before = read_record(args.record)
    if not before.truncated and before.meta.get("status") != "recording":
        print(f"{args.record}: complete already (status {before.meta.get('status', '?')}), nothing to recover")
        return 0
    try:
        path, rec = recover_record(args.record)
    except OSError as exc:  # a full disk (or a read-only one): the record is rewritten through a copy
        import shutil

        size = args.record.stat().st_size
        free = shutil.disk_usage(args.record.parent.resolve()).free
        raise RecordWriteError(f"{args.record}: cannot recover in place ({exc.strerror or exc}): it needs about "
                               f"{size // 1024 + 1} KiB free next to the record ({free // 1024} KiB free) — free space, or "
                               f"copy the record to another disk and run 'flowcurve recover' there; the record is unchanged") from None
    last = float(rec.data["time_s"].iloc[-1])
    print(f"{path}: recovered — {len(rec.data)} samples up to {last:.1f} s, {len(rec.events)} events; status {rec.meta['status']} ({rec.meta.get('abort_reason', '')})")
    return 0


def cmd_annotate(args) -> int:
    from flowcurve.acquisition.procedure import POST_KEYS, missing_post_keys, post_prompts
    from flowcurve.record.format import amend_record, read_record

    updates = parse_assignments(args.set)
    read_record(args.record)  # a clear error before touching a file that is not a record
    amend_record(args.record, updates)
    rec = read_record(args.record)
    for key, value in updates.items():
        print(f"{key} = {rec.meta.get(key, '(removed)')}")
    test = rec.meta.get("test", "")
    geometry = {k: rec.number(f"specimen.{k}") for k in ("d0_mm", "h0_mm")}
    missing = missing_post_keys(test, geometry, rec.meta) if test in POST_KEYS else []
    if missing:
        print(f"still missing: {', '.join(missing)}")
    if "post.dface_mm" in missing:
        print(f"  {post_prompts(test, geometry)['post.dface_mm']}: give --set post.dface_mm=...")
    return 0


def cmd_demo(args) -> int:
    from flowcurve.demo import run_demo

    return run_demo(args.out, material=args.material, quiet=args.quiet, faults=virtual_faults(args), **virtual_responses(args))
