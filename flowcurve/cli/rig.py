"""``flowcurve rig check`` and ``flowcurve rig virtual``.

'rig check --config rig.toml' talks to each configured device and prints its identity,
settings and one reading, or a diagnosis (port missing, silent — wrong baud, parity or
address?, garbled replies); exit code 0 when every device answered, 3 otherwise.
'rig virtual' starts the virtual rig on pseudo-terminals, prints each device's port and a
configuration file written for it (its [virtual] table states the bar simulated: --d0, --l0,
--lc, --h0 as 'run' takes them), and runs until Ctrl-C. 'rig recover-loadcell' brings an
amplifier left at an unknown baud rate back to the configured one.
"""

from __future__ import annotations

import math
import select
import signal
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from flowcurve.cli.acquisition import add_fault_option, add_virtual_response_options, unused_geometry, virtual_faults, virtual_responses
from flowcurve.cli.specimen import add_geometry_options
from flowcurve.errors import DeviceError, FlowcurveError
from flowcurve.rig.config import RigConfig, load_config, to_toml

CHECK_FAILED = 3


def register(subparsers) -> None:
    """Add ``rig`` (check, recover-loadcell, virtual) to the subcommands."""
    parser = subparsers.add_parser("rig", help="check the rig's devices, or start the virtual rig",
                                   description=__doc__.split("\n\n")[1])
    sub = parser.add_subparsers(dest="rig_command", metavar="ACTION")
    sub.required = True

    check = sub.add_parser("check", help="talk to each device and diagnose what does not answer")
    check.add_argument("--config", required=True, type=Path, help="rig configuration (TOML)")
    check.add_argument("--no-probe", dest="probe", action="store_false",
                       help="do not try other baud rates and parities on a silent device")
    check.set_defaults(func=run_check)

    recover = sub.add_parser("recover-loadcell",
                             help="bring an amplifier left at an unknown baud rate back to the configured one")
    recover.add_argument("--config", required=True, type=Path, help="rig configuration (TOML)")
    recover.set_defaults(func=run_recover_loadcell)

    virtual = sub.add_parser("virtual", help="run the virtual rig on pseudo-terminals until Ctrl-C")
    virtual.add_argument("--config", type=Path, default=None,
                         help="write the configuration for the virtual rig's ports to this file "
                              "(default: a file in a temporary folder)")
    virtual.add_argument("--material", default="12Kh18N12M3TL", help="virtual specimen material")
    virtual.add_argument("--test", choices=("tension", "compression"), default="tension")
    add_geometry_options(virtual.add_argument_group(
        "virtual specimen", "the bar the virtual rig simulates, as 'flowcurve run' takes it (give 'run --config' the same "
        "values; the configuration file states them in [virtual]); default the rig's own: tension d0 6, l0 30 (Lc l0), "
        "compression d0 5.989, h0 6.982"))
    virtual.add_argument("--temperature", type=float, default=None, metavar="C",
                         help="initial furnace temperature, C (default: ambient)")
    virtual.add_argument("--time-scale", type=float, default=1.0,
                         help="model seconds per wall-clock second (default 1)")
    virtual.add_argument("--checksum", action="store_true", help="DCON checksums on")
    virtual.add_argument("--speed", type=float, default=0.01, metavar="MM_PER_S",
                         help="the crosshead motor's speed, mm/s (default 0.01, what 'flowcurve run --config' asks for "
                              "by default): set it to the test's, as at the real machine's speed dial; interactively, "
                              "type a speed and Enter to change it")
    add_virtual_response_options(virtual)
    add_fault_option(virtual)
    virtual.add_argument("--motor-start-after", type=float, default=None, metavar="S",
                         help="start the virtual crosshead motor S wall-clock seconds after launch (for "
                              "scripts; 'kill -USR1 <pid>' toggles it too); interactively, press Enter here to "
                              "start and stop it, as the operator does at the real machine's motor switch")
    virtual.set_defaults(func=run_virtual)


# -- rig check ------------------------------------------------------------------------
def diagnose(exc: Exception, port: str) -> str:
    """One line saying what a device failure most likely means."""
    text = str(exc)
    if "cannot open port" in text:
        reason = text.rsplit(": ", 1)[-1]
        if "No such file" in reason:
            return f"port missing: {port} does not exist — is the adapter plugged in, is the name right?"
        if "ermission" in reason:
            return f"no permission to open {port} — is the user in the dialout group?"
        return f"cannot open {port}: {reason} — is another program using it?"
    if "disappeared" in text:
        return f"port {port} disappeared during the check — cable or USB adapter unplugged?"
    if "no answer" in text:
        return f"silent: {text.split(': ', 1)[-1]} — wrong baud rate, parity or address? powered?"
    if "garbled" in text or "incomplete answer" in text:
        return f"garbled replies: {text.split(': ', 1)[-1]} — wrong baud rate or parity, or another device on this port?"
    return text.split(": ", 1)[-1] if isinstance(exc, DeviceError) else text


def check_device(section, out, opener=None) -> None:
    """Open the device a rig file's ``section`` names and print what it says of itself
    (its driver's ``check_lines``: rig/roles.py)."""
    with section.create(opener=opener) as device:
        for line in device.check_lines(section):
            out(line)


SECTIONS = (("loadcell", "load cell"), ("encoder", "crosshead encoder"), ("furnace", "furnace"))


PROBE_TIMEOUT_S = 0.1


def probe_line(key: str, section, opener=None) -> str | None:
    """For a silent or garbled device: the first other baud rate / parity it answers at."""
    from flowcurve.rig.config import BAUDS
    from flowcurve.rig.roles import driver_class

    parities = driver_class(section.role, section.model).probe_parities
    for baud in sorted(BAUDS, key=lambda b: abs(b - section.baud)):
        for parity in parities:
            if (baud, parity) == (section.baud, section.parity):
                continue
            trial = replace(section, baud=baud, parity=parity, timeout_s=PROBE_TIMEOUT_S)
            device = trial.create(opener=opener)
            try:
                with device:
                    device.answers()
            except FlowcurveError:
                continue
            return f"it answers at {baud} baud, parity {parity}: set baud = {baud}, parity = \"{parity}\" in [{key}]"
    return None


def check_rig(config: RigConfig, out=print, *, probe: bool = True, opener=None) -> int:
    """Check every configured device; returns how many failed.

    ``probe``: when a device is silent or garbled, try the other line settings.
    ``opener`` replaces :func:`serial.serial_for_url` (tests).
    """
    failed = 0
    for key, label in SECTIONS:
        section = getattr(config, key)
        if section is None:
            out(f"{label}: not configured")
            continue
        out(f"{label} on {section.port}:")
        try:
            check_device(section, out, opener)
        except FlowcurveError as exc:
            failed += 1
            out(f"  FAILED: {diagnose(exc, section.port)}")
            text = str(exc)
            if probe and ("no answer" in text or "garbled" in text or "incomplete" in text):
                found = probe_line(key, section, opener)
                out(f"  probe: {found}" if found else
                    "  probe: no answer at any other baud rate or parity either — address, cable, power?")
        else:
            out("  ok")
    return failed


def run_check(args) -> int:
    """``flowcurve rig check``: every configured device checked; the exit status."""
    config = load_config(args.config)
    failed = check_rig(config, probe=args.probe)
    if failed:
        print(f"{failed} device(s) failed the check", file=sys.stderr)
        return CHECK_FAILED
    return 0


def run_recover_loadcell(args) -> int:
    """``flowcurve rig recover-loadcell``: resend the configured baud rate at every rate and parity, then identify the cell."""
    section = load_config(args.config).loadcell
    print(f"load cell on {section.port}: sending ';S98;BDR{section.baud},...;' at every baud rate "
          f"and parity, then IDN? at {section.baud} baud, parity {section.parity}")
    with section.create() as cell:
        idn = cell.recover_line()
    print(f"  answers: {idn['manufacturer']} {idn['model']}, serial {idn['serial']} — "
          f"send TDD1 to keep the rate over a power cycle")
    return 0


# -- rig virtual ----------------------------------------------------------------------
def run_virtual(args) -> int:
    """``flowcurve rig virtual``: serve the virtual rig's devices on ports until stopped; the exit status."""
    from flowcurve.rig.virtual.rig import VirtualRig  # the virtual-rig engineer's twins

    for option, value in (("--time-scale", args.time_scale), ("--speed", args.speed)):
        if not (value > 0 and math.isfinite(value)):
            raise FlowcurveError(f"{option} must be a positive number, got {value}")
    responses = virtual_responses(args)
    faults = virtual_faults(args)
    specimen = virtual_specimen(args)
    with VirtualRig(args.material, test=args.test, specimen=specimen, temperature_C=args.temperature, speed_mm_per_s=args.speed,
                    time_scale=args.time_scale, checksum=args.checksum, **responses) as rig:
        path = args.config
        if path is None:
            path = Path(tempfile.mkdtemp(prefix="flowcurve-virtual-rig-")) / "flowcurve.rig.toml"
        path.write_text(to_toml(rig.config()))
        for fault in faults:
            rig.schedule(fault)
        for name, port in rig.ports.items():
            print(f"{name:9s} {port}")
        for fault in faults:
            print(f"fault: {fault.describe()} " + ("from now" if fault.at_s is None else "after the crosshead starts"))
        print(f"{args.test} response: {responses[args.test + '_response']}")
        print(f"specimen: {specimen_line(specimen)} (give 'flowcurve run --config' the same)")
        print(f"crosshead speed: {args.speed:g} mm/s (time scale {args.time_scale:g}: give 'flowcurve run' the same --speed and --time-scale)")
        print(f"configuration: {path}")
        print(f"try: flowcurve rig check --config {path}")
        previous = signal.signal(signal.SIGTERM, _stop_on_sigterm)  # kill/systemd: stop cleanly too
        signal.signal(signal.SIGUSR1, _toggle_motor)  # scripts: 'kill -USR1 <pid>' is the motor switch
        interactive = sys.stdin is not None and sys.stdin.isatty()
        try:  # Ctrl-C may come as soon as the line below is out
            print("running; " + ("Enter starts/stops the crosshead motor, a speed and Enter sets it (mm/s), " if interactive else "")
                  + "Ctrl-C stops", flush=True)
            _serve_motor(rig, interactive, args.motor_start_after)
        except KeyboardInterrupt:
            print("virtual rig stopped")
        finally:
            signal.signal(signal.SIGTERM, previous)
    return 0


def virtual_specimen(args):
    """The bar ``rig virtual``'s options ask for (rig.virtual.physics.Specimen), made as ``run``
    makes it on the virtual rig in its own process: the same options, checks and defaults
    (services.run.virtual_specimen_geometry; FieldError in one line, e.g. an Lc shorter than l0)."""
    from flowcurve.rig.virtual.physics import Specimen
    from flowcurve.services.run import RunRequest, virtual_specimen_geometry

    unused = unused_geometry(args)
    if unused:
        print(f"flowcurve: note: {unused}", file=sys.stderr)
    request = RunRequest(args.test, d0=args.d0, l0=args.l0, lc=args.lc, h0=args.h0)
    return Specimen.from_geometry(args.test, virtual_specimen_geometry(request))


def specimen_line(specimen) -> str:
    """``tension bar d0 6 mm, l0 30 mm, Lc 42 mm`` (in run's option names)."""
    from flowcurve.acquisition.specimen_geometry import geometry_words

    return f"{specimen.test} {'bar' if specimen.test == 'tension' else 'cylinder'} {geometry_words(specimen.geometry_mm)}"


def _report_rig(rig, seen: dict) -> None:
    """Lines for what the virtual rig's operator would notice: a fault switching on, the furnace
    module's watchdog timing out (with the heater relay's state: a stuck relay stays on)."""
    for t, spec in rig.faults_applied[seen.setdefault("faults", 0):]:
        print(f"fault on: {spec.describe()} (model time {t:.1f} s)", flush=True)
    seen["faults"] = len(rig.faults_applied)
    furnace = rig.devices["furnace"]
    tripped = bool(furnace.watchdog_status & 0x04)
    if tripped and not seen.get("tripped"):
        relay = "ON (stuck)" if rig.model.furnace.relay_on else "off"
        print(f"furnace module: host watchdog timed out (model time {rig.now():.1f} s) — heater output off, "
              f"relay {relay}", flush=True)
    seen["tripped"] = tripped


def post_test_lines(rig, reason: str) -> list[str]:
    """What the operator measures on the specimen when a test ends (the twin's values), ready for
    the prompts of 'flowcurve run' or 'flowcurve annotate'."""
    post = rig.post_test_measurements()
    sets = " ".join(f"--set {k}={v}" for k, v in post.items())
    unbroken = rig.model.test == "tension" and not rig.model.fractured
    return [f"test ended ({reason}, model time {rig.model.time_s:.1f} s); post-test measurements of the specimen"
            + (" (unbroken: no fracture values)" if unbroken else "") + ":",
            *(f"  {k} = {v}" for k, v in post.items()),
            f"  (give them at the prompts of 'flowcurve run', or: flowcurve annotate RECORD {sets})"]


def _report_end(rig, seen: dict) -> None:
    """When the crosshead stops after moving (fracture, stroke limit, the motor switched off): the
    post-test measurements, once per stop."""
    with rig.lock:
        model = rig.sync()
        moving, last = model.moving, model.events[-1][1] if model.events else "crosshead_stop"
    if seen.get("moving") and not moving:
        reason = {"fracture": "fracture", "stroke_limit": "stroke limit", "crosshead_stop": "motor stopped"}.get(last, last)
        print("\n".join(post_test_lines(rig, reason)), flush=True)
    seen["moving"] = moving


def _set_speed(rig, text: str) -> bool:
    """A typed speed (mm/s) for the motor; False when the line is not a number."""
    try:
        speed = float(text)
    except ValueError:
        return False
    try:
        rig.set_speed(speed)
    except FlowcurveError as exc:
        print(f"speed not changed: {str(exc).split(': ', 1)[-1]}", flush=True)
        return True
    print(f"crosshead speed set to {speed:g} mm/s", flush=True)
    return True


def _serve_motor(rig, interactive: bool, start_after_s: float | None) -> None:
    """The operator's motor switch: Enter toggles the crosshead, or it starts after a delay; a
    number and Enter sets its speed. The post-test measurements are printed whenever it stops."""
    started_at = time.monotonic()
    running = False
    seen: dict = {}
    while True:
        _report_rig(rig, seen)
        _report_end(rig, seen)
        running = running and rig.model.moving  # a fracture or the stroke limit stopped it: Enter starts it again
        if start_after_s is not None and not running and time.monotonic() - started_at >= start_after_s:
            rig.start_crosshead()
            running, start_after_s = True, None
            print("crosshead motor started", flush=True)
        if _MOTOR_TOGGLES:
            _MOTOR_TOGGLES.pop()
            (rig.stop_crosshead if running else rig.start_crosshead)()
            running = not running
            print(f"crosshead motor {'started' if running else 'stopped'}", flush=True)
        elif interactive and select.select([sys.stdin], [], [], 0.5)[0]:
            if _set_speed(rig, sys.stdin.readline().strip()):
                continue
            (rig.stop_crosshead if running else rig.start_crosshead)()
            running = not running
            print(f"crosshead motor {'started' if running else 'stopped'}", flush=True)
        elif not interactive:
            time.sleep(0.05)


_MOTOR_TOGGLES: list[int] = []


def _toggle_motor(signum, frame):
    _MOTOR_TOGGLES.append(signum)


def _stop_on_sigterm(signum, frame):
    raise KeyboardInterrupt
