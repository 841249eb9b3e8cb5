"""``flowcurve run``, ``demo``, ``recover`` and ``annotate``.

``run tension|compression`` runs one test on the configured rig (``--config rig.toml``) or,
without a configuration, on the virtual rig in this process; ``demo`` runs a virtual
tension and a virtual compression test and identifies both; ``recover`` completes the
header of a record cut short; ``annotate`` adds post-test measurements to a record.
"""

from __future__ import annotations

import datetime as _dt
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from flowcurve.cli.choices import TEST_TYPES
from flowcurve.cli.specimen import add_geometry_options, add_modulus_option
from flowcurve.errors import EXIT_COMPLETE, EXIT_DATA_LOST, EXIT_STOPPED, DeviceError, FlowcurveError, RecordWriteError, SafetyError
from flowcurve.rig.virtual.responses import COMPRESSION_HELP, COMPRESSION_RESPONSES, TENSION_HELP, TENSION_RESPONSES
from flowcurve.services.run import DEFAULT_VIRTUAL_MATERIAL, RunRequest, parse_assignments, prepare, run_test

if TYPE_CHECKING:  # the acquisition and the record format import numpy: imported where a command runs, not for --help
    from flowcurve.acquisition.live import LiveView
    from flowcurve.acquisition.procedure import Outcome

def register(subparsers) -> None:
    """Add ``run``, ``recover``, ``annotate`` and ``demo`` to the subcommands."""
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
    """The parsed ``--fault`` options (FieldError naming a malformed one)."""
    from flowcurve.services.run import faults

    return faults(RunRequest("tension", fault=list(getattr(args, "fault", None) or [])))


def virtual_responses(args) -> dict[str, str]:
    """The virtual rig's responses the options ask for (fe where not given)."""
    return RunRequest("tension", compression_response=args.compression_response, tension_response=args.tension_response).responses()


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


def default_out(test: str) -> Path:
    """The default record path of a ``test``: records/TEST-YYYYmmdd-HHMMSS.csv."""
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


def run_request(args) -> RunRequest:
    """The typed request of ``flowcurve run``'s options."""
    return RunRequest(args.test, material=args.material, E_MPa=args.E_MPa, operator=args.operator, specimen_id=args.specimen_id,
                      temperature=args.temperature, soak=args.soak, speed=args.speed, d0=args.d0, l0=args.l0, lc=args.lc, h0=args.h0,
                      target=args.target, force_limit=args.force_limit, post=list(args.post), time_scale=args.time_scale,
                      fault=list(args.fault), compression_response=args.compression_response, tension_response=args.tension_response)


def unused_geometry(args) -> str:
    """What ``run`` ignores of the geometry given: the options another test type takes (--l0 and
    --lc on compression, --h0 on tension), in one line; "" when none."""
    from flowcurve.acquisition.procedure import TEST_GEOMETRY

    takes = {key.split("_")[0] for key in TEST_GEOMETRY[args.test]} | ({"lc"} if args.test == "tension" else set())
    ignored = [f"--{o}" for o in ("l0", "lc", "h0") if getattr(args, o, None) is not None and o not in takes]
    return f"{' and '.join(ignored)} ignored: a {args.test} specimen has no such length" if ignored else ""


def cmd_run(args) -> int:
    """``flowcurve run``: run a test on the rig or the virtual rig; the exit status."""
    from flowcurve.acquisition.live import LiveView

    view = LiveView(quiet=args.quiet)
    out_path = args.out or default_out(args.test)
    config = None
    if args.config is not None:
        given = [f"--{k.replace('_', '-')}" for k in ("compression_response", "tension_response") if getattr(args, k) is not None]
        given += ["--fault"] if args.fault else []
        if given:
            raise FlowcurveError(f"{' and '.join(given)}: the virtual rig in this process only; with --config the rig is the "
                                 "configured one (for 'flowcurve rig virtual' give the option there)")
        from flowcurve.rig.config import load_config

        config = load_config(args.config)
    interactive = _interactive(args)
    unused = unused_geometry(args)
    if unused:
        print(f"flowcurve: note: {unused}", file=sys.stderr)
    setup = prepare(run_request(args), config=config, ask=_ask if interactive else None)
    for warning in setup.warnings:
        print(f"flowcurve: warning: {warning}", file=sys.stderr)
    outcome = run_test(setup, out_path, config=config, view=view, interactive=interactive, stream=not args.poll)
    return report_outcome(outcome, view)


def cmd_recover(args) -> int:
    """``flowcurve recover``: close a record a crashed run left open; the exit status."""
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
    """``flowcurve annotate``: add post-test measurements to a record; the exit status."""
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
    """``flowcurve demo``: a series of virtual tests identified and fitted; the exit status."""
    from flowcurve.demo import run_demo

    return run_demo(args.out, material=args.material, quiet=args.quiet, faults=virtual_faults(args), **virtual_responses(args))
