"""The scenario matrix of the whole chain (issue 31): axes, fault table, one cell run from
``flowcurve run`` to ``flowcurve identify`` in-process on model time, and its invariants.

A cell is test type × temperature × crosshead speed × load-cell rate × virtual material ×
fault. It runs the product's own entry points (``flowcurve.cli.main``) with the virtual rig
in this process on a :class:`flowcurve.clock.ModelClock`: the bench around the command line
(:func:`run_cell`) only puts the rig on the model clock, sets the load-cell rate through the
rig configuration (``loadcell_rate_code``), starts the furnace at the set-point and injects
the fault — what an operator cannot do from the command line yet.

**Time.** The virtual devices keep their rates in host time (the AED streams ``ICR`` values
per host second; the encoder is polled 50 times per host second), and the rig's model runs
``time_scale`` model seconds per host second. Every cell runs at
``time_scale = SAMPLING_SPEED_MM_PER_S / speed``, so the record holds ``rate / 1 mm/s`` samples
per millimetre of crosshead at every speed — what the real rig would give at 1 mm/s, sparser
than any speed of the matrix: a 2 Hz cell is a tension test of about ten samples. This keeps
every cell to a few host seconds; the physics (strain rate v/l0, temperature) is the speed's
own. A heated cell runs at most at :data:`HEATED_MAX_TIME_SCALE` (issue 29 #11: beyond it the
furnace controller's minimum on-time does not fit its 2 s control period and the furnace cools
off the set-point), so its record is denser. Compression stops at the operator's target
:data:`COMPRESSION_TARGET_MM`.

**Furnace.** The furnace starts at the set-point (a furnace already hot from the previous
specimen) and the soak is short (:data:`SOAK_S`): heating from room temperature at 30 °C/min
would cost each cell half an hour of model time at ``time_scale`` 1, and the heating phase has
tests of its own (tests/acquisition/test_faults.py).

**Faults** (:data:`FAULTS`): one line per kind and device; a new kind is one more line. Each is
injected :func:`fault_time_s` model seconds after the crosshead starts (1 mm of crosshead, the
plastic range of every specimen here).

**Invariants** (:func:`violations`): no internal error in ``run`` or ``identify``; every fault
that was injected named (its device) in the record's events and in what the operator saw;
heater off at the end; samples lost ≤ what the events declare; the identified flow curve within
3 % of the virtual material over the measured range it reports (the hardening's ``fit_range``),
or a warning/quality mark that says why not, or a clean one-line refusal. identify's "the record
declares rig faults" warning is no such excuse: it comes with every fault (issue 42).

**Numbers that survived a fault** (:func:`survived`, issue 42): a fault cell is judged against
the same cell without its fault (:func:`reference`, run once per fault-free cell and cached):
the force at every recorded crosshead position from :data:`FORCE_FROM_MM` within
:data:`FORCE_TOL` of the reference's (plus half the reference's own step between the samples
around it: its sampling resolution), and, for a record the fault did not abort, the last
crosshead within :data:`LAST_CROSSHEAD_TOL_MM` and Fm within :data:`FM_TOL` (or their sampling
steps; an Fm that is the force at a target stop is judged as force and stop); Rm and Rp0.2 from
identify within :data:`RM_TOL` / :data:`RP02_TOL` unless a warning names that value; the flow curve within 3 % of the material (or, where the reference itself is
off, within 1 % of the reference's deviation) unless the hardening is marked.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import io
import itertools
import json
import os
import random
import re
import subprocess
import threading
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

TESTS = ("tension", "compression")
TEMPERATURES_C = (20.0, 300.0, 600.0, 850.0)
SPEEDS_MM_PER_S = (0.005, 0.05, 0.5)
RATES_HZ = (2.0, 12.0, 50.0, 100.0)  # the AED's ICR rates (rig/codecs/aed.py ICR_RATES_PER_S)
MAX_TEMPERATURE_C = 900.0  # the rig configuration's furnace max_temperature_C: every set-point below it
SAMPLING_SPEED_MM_PER_S = 1.0  # see "Time" above
HEATED_MAX_TIME_SCALE = 50.0  # issue 29 #11: faster, the furnace controller cannot hold 850 C (its on-time rule)
COMPRESSION_TARGET_MM = 3.0  # the operator's target: ε ≈ 0.6 on the 6.98 mm specimen, short of the stroke limit
SOAK_S = 5.0
FAULT_AT_MM = 1.0  # the fault comes this much crosshead travel after the start
CURVE_TOLERANCE_PCT = 3.0
LOSS_SLACK_FRAMES = 2  # a frame on the wire at each end of the record's span
FORCE_FROM_MM = 0.5  # issue 42: the force against the crosshead is compared from here (past seating and the elastic rise)
FORCE_TOL = 0.01
LAST_CROSSHEAD_TOL_MM = 0.05
FM_TOL = 0.003
RM_TOL = 0.01
RP02_TOL = 0.02  # a proof stress moves with the modulus fit's window: twice Rm's
TEMPERATURE_COLUMN = "temperature_C"  # the record's thermocouple channel
TEMPERATURE_MARK = re.compile(r"recorded temperature under load ranges|temperature was not recorded over")  # identify: the curve mixes or loses temperatures
CHANGES_THE_SPECIMEN = ("relay_stuck",)  # the furnace heats on: the specimen is hotter, its force truly lower (the record's temperature says so)
CURVE_OVER_REFERENCE_PCT = 1.0  # where the fault-free cell's own curve is beyond 3 %, the faulty one may add this much
DEFAULT_CELLS = 40
FALLBACK_SEED = 31

# warnings that do not say why a flow curve is off (what is missing past fracture, alternatives that failed)
NOT_ABOUT_THE_CURVE = re.compile(r"without a fracture: A is not reported|no post\.dk_mm or post\.sk_mm2|"
                                 r"three-point \w+ fit failed|has a yield point")

RIG_FAULTS_WARNING = re.compile(r"the record declares rig faults")  # with every fault: it excuses nothing (issue 42)
VALUE_MARK = {"Rm_MPa": re.compile(r"\bRm\b|maximum force|\bFm\b"), "Rp02_MPa": re.compile(r"Rp0\.?2|proof stress|yield")}

START_ONLY = re.compile(r"the curve's start \(εp < [^)]*\) rests on the strain zero")  # methods §2.11: excuses εp < X only

DEVICE_NAMES = {"loadcell": "load cell", "encoder": "crosshead encoder", "furnace": "furnace"}


def materials() -> tuple[str, ...]:
    from flowcurve.rig.virtual.materials import MATERIALS

    return tuple(MATERIALS)


@dataclass(frozen=True)
class Fault:
    """One row of the fault table: ``DEVICE:KIND[:VALUE]`` as ``--fault`` spells it."""

    device: str
    kind: str
    value: float | None = None
    args: tuple[tuple[str, float], ...] = ()  # keyword arguments of VirtualRig.inject

    @property
    def label(self) -> str:
        return "none" if not self.device else ":".join([self.device, self.kind] + ([f"{self.value:g}"] if self.value is not None else []))


NO_FAULT = Fault("", "none")

# The fault axis: every kind of rig/virtual/faults.py on every device it applies to.
WIRE_FAULT_ARGS = {"silence": None, "drop": ("fraction", 0.05), "garble": ("fraction", 0.05), "delay": ("seconds", 0.5),
                   "unplug": None}  # the one keyword each wire fault takes in VirtualRig.inject, with the matrix's value


def _wire_fault(device: str, kind: str) -> Fault:
    arg = WIRE_FAULT_ARGS[kind]
    return Fault(device, kind) if arg is None else Fault(device, kind, arg[1], (arg,))


# kinds the matrix schedules as an operator does, ``--fault DEVICE:KIND@SECONDS`` on `flowcurve run` (their default VALUE)
SCHEDULED_KINDS = ("corrupt", "spike", "jump", "wrong_address")

FAULTS: tuple[Fault, ...] = (
    NO_FAULT,
    *(_wire_fault(device, kind) for device in ("loadcell", "encoder", "furnace") for kind in WIRE_FAULT_ARGS),
    Fault("furnace", "open_thermocouple"),
    Fault("furnace", "relay_stuck"),
    *(Fault(device, "corrupt") for device in ("loadcell", "encoder", "furnace")),
    Fault("loadcell", "spike"),  # +900 N (its default): under the rate rules' 1 % of capacity, judged by the signal's noise
    Fault("encoder", "jump"),
    Fault("furnace", "wrong_address"),
)


@dataclass(frozen=True)
class Cell:
    test: str
    temperature_C: float
    speed_mm_per_s: float
    rate_Hz: float
    material: str
    fault: Fault

    @property
    def id(self) -> str:
        return (f"{self.test}-{self.temperature_C:g}C-{self.speed_mm_per_s:g}mmps-{self.rate_Hz:g}Hz-"
                f"{self.material}-{self.fault.label}")

    @property
    def time_scale(self) -> float:
        scale = SAMPLING_SPEED_MM_PER_S / self.speed_mm_per_s
        return min(scale, HEATED_MAX_TIME_SCALE) if self.temperature_C > 20.0 else scale

    @property
    def rate_code(self) -> int:
        from flowcurve.rig.codecs.aed import ICR_RATES_PER_S

        return ICR_RATES_PER_S.index(self.rate_Hz)


def all_cells() -> list[Cell]:
    """The whole matrix, in a fixed order."""
    return [Cell(*axes) for axes in itertools.product(TESTS, TEMPERATURES_C, SPEEDS_MM_PER_S, RATES_HZ, materials(), FAULTS)]


def matrix_seed() -> int:
    """``FLOWCURVE_MATRIX_SEED`` if set; else the hash of the last commit that changed the code
    (fixed per commit; a commit of prose or of the known-defect list alone keeps the draw, so the
    cells a defect was found on stay drawn); else :data:`FALLBACK_SEED` (no git)."""
    given = os.environ.get("FLOWCURVE_MATRIX_SEED", "").strip()
    if given:
        return int(given, 0)
    try:
        head = subprocess.run(["git", "log", "-1", "--format=%H", "--", ":/", ":(exclude,top)*.md",
                               ":(exclude,top)tests/scenarios/known_defects.py"], cwd=Path(__file__).parent,
                              capture_output=True, text=True, timeout=10, check=True).stdout.strip()
        return int(head[:12], 16)
    except (OSError, subprocess.SubprocessError, ValueError):
        return FALLBACK_SEED


def default_selection(cells: list[Cell], seed: int, n: int = DEFAULT_CELLS) -> list[Cell]:
    """``n`` cells drawn with ``seed``, every value of every axis present at least once
    (a fault-free cell included): the first cells cycle through each axis, the rest are random."""
    rng = random.Random(seed)
    axes = [TESTS, TEMPERATURES_C, SPEEDS_MM_PER_S, RATES_HZ, materials(), FAULTS]
    longest = max(len(a) for a in axes)
    shuffled = [rng.sample(list(a), len(a)) for a in axes]
    chosen = [Cell(*(s[i % len(s)] for s in shuffled)) for i in range(longest)]
    rest = [c for c in cells if c not in chosen]
    chosen += rng.sample(rest, max(0, n - len(chosen)))
    return chosen


def cells_from_env() -> list[str] | None:
    """``FLOWCURVE_MATRIX_CELLS=id,id`` re-runs exactly those cells."""
    text = os.environ.get("FLOWCURVE_MATRIX_CELLS", "").strip()
    return [c.strip() for c in text.split(",") if c.strip()] or None


def fault_time_s(cell: Cell) -> float:
    """Model seconds after the crosshead start at which the fault is injected."""
    return FAULT_AT_MM / cell.speed_mm_per_s


# -- one cell ---------------------------------------------------------------------------------


@dataclass
class CellRun:
    """What one cell produced: exit codes, captured output, the record, the truth."""

    cell: Cell
    run_code: int | None = None
    run_out: str = ""
    run_err: str = ""
    run_exception: str | None = None  # a traceback escaping `flowcurve run`
    identify_code: int | None = None
    identify_out: str = ""
    identify_err: str = ""
    identify_exception: str | None = None
    record_path: Path | None = None
    result: dict | None = None
    virtual_run: object = None  # acquisition.session.VirtualRun
    injected_at_s: float | None = None  # model time of the injection, None if the test ended first
    frames_sent_at: list = field(default_factory=list)  # host times of the stream frames that left the amplifier intact
    procedure_t0: float | None = None  # host time of the procedure's test clock zero
    heater_do: int | None = None  # the furnace module's digital outputs at the end
    relay_on: bool | None = None
    replies_hit: int | None = None  # replies the fault's drop or garble fraction took (None: not such a fault)
    hit_at: list = field(default_factory=list)  # host times of those hits (a hit after the record's last row is no loss of it)
    notes: list[str] = field(default_factory=list)
    run_wall_s: float = 0.0
    identify_wall_s: float = 0.0


def _capture(argv: list[str]) -> tuple[int | None, str, str, str | None]:
    from flowcurve.cli import main

    out, err = io.StringIO(), io.StringIO()
    code, exc = None, None
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as e:  # argparse
            code = e.code if isinstance(e.code, int) else 2
        except BaseException:  # an internal error: the traceback an operator would see
            exc = traceback.format_exc()
    return code, out.getvalue(), err.getvalue(), exc


def run_cell(cell: Cell, workdir: Path) -> CellRun:
    """Run ``flowcurve run`` and ``flowcurve identify`` for ``cell`` in this process."""
    import flowcurve.acquisition.session as session
    from flowcurve.clock import ModelClock

    workdir.mkdir(parents=True, exist_ok=True)
    out = CellRun(cell, record_path=workdir / f"{cell.test}.csv")
    clock = ModelClock()
    done = threading.Event()
    heated = cell.temperature_C > 20.0

    rigs = []

    def setup(vr):
        rigs.append(vr)
        _count_frames_sent(vr.devices["loadcell"], out.frames_sent_at)
        if cell.fault.kind in ("drop", "garble"):
            _note_hits(vr.devices[cell.fault.device], out.hit_at)
        if cell.fault is NO_FAULT or not cell.fault.device or cell.fault.kind in SCHEDULED_KINDS:
            return
        start = vr.start_crosshead

        def start_and_arm(*args, **kwargs):  # the procedure sends its speed (DriverRig.start_crosshead)
            start(*args, **kwargs)
            injector = threading.Thread(target=inject, args=(vr,), daemon=True, name="matrix-fault")
            clock.enlist(injector)
            injector.start()

        vr.start_crosshead = start_and_arm

    def inject(vr):
        if clock.wait(done, fault_time_s(cell) / cell.time_scale):
            return  # the test ended first
        try:
            vr.inject(cell.fault.device, cell.fault.kind, **dict(cell.fault.args))
            out.injected_at_s = vr.now()
        except Exception as exc:  # noqa: BLE001 - the bench's own failure, reported as a note
            out.notes.append(f"injection failed: {type(exc).__name__}: {exc}")

    real = session.run_virtual_test
    set_clock = session.DriverRig.set_clock

    def set_and_note_clock(rig, test_clock):
        out.procedure_t0 = test_clock.__self__._t0  # the Procedure's bound clock: time_s = (host − t0)·scale
        set_clock(rig, test_clock)

    def on_the_bench(*args, **kwargs):
        overrides = {"loadcell_rate_code": cell.rate_code, "furnace_max_temperature_C": MAX_TEMPERATURE_C}
        try:
            run = real(*args, clock=clock, link="inprocess", rig_setup=setup, config_overrides=overrides,
                       initial_temperature_C=cell.temperature_C if heated else None, **kwargs)
        finally:
            done.set()
            clock.notify()
        out.virtual_run = run
        return run

    argv = ["run", cell.test, "--quiet", "--time-scale", f"{cell.time_scale:g}", "--out", str(out.record_path),
            "--material", cell.material, "--speed", f"{cell.speed_mm_per_s:g}", "--operator", "matrix",
            "--specimen-id", cell.id]
    if cell.test == "compression":
        argv += ["--target", f"{COMPRESSION_TARGET_MM:g}"]
    if heated:
        argv += ["--temperature", f"{cell.temperature_C:g}", "--soak", f"{SOAK_S:g}"]
    if cell.fault.kind in SCHEDULED_KINDS:
        argv += ["--fault", f"{cell.fault.label}@{fault_time_s(cell):g}"]
    session.run_virtual_test = on_the_bench
    session.DriverRig.set_clock = set_and_note_clock
    t0 = time.monotonic()
    try:
        out.run_code, out.run_out, out.run_err, out.run_exception = _capture(argv)
    finally:
        session.run_virtual_test = real
        session.DriverRig.set_clock = set_clock
        done.set()
        out.run_wall_s = time.monotonic() - t0
    vr = rigs[0] if rigs else None
    if vr is not None:  # the virtual furnace module's outputs and the relay, as the test left them
        module = vr.devices["furnace"]
        out.heater_do, out.relay_on = module.do, vr.model.furnace.relay_on
        if cell.fault.kind in ("drop", "garble"):
            out.replies_hit = vr.devices[cell.fault.device].faults.replies_hit
        if cell.fault.kind in SCHEDULED_KINDS and vr.faults_applied:
            out.injected_at_s = vr.faults_applied[0][0]  # model time the rig switched it on
    if out.record_path.exists():
        os.environ["FLOWCURVE_DEBUG"] = "1"  # an internal error raises here instead of one line
        try:
            res_dir = workdir / "results"
            out.identify_code, out.identify_out, out.identify_err, out.identify_exception = _capture(
                ["identify", str(out.record_path), "--out", str(res_dir), "--no-plots"])
        finally:
            del os.environ["FLOWCURVE_DEBUG"]
            out.identify_wall_s = time.monotonic() - t0 - out.run_wall_s
        result_json = res_dir / out.record_path.stem / "result.json"
        if out.identify_code == 0 and result_json.exists():
            out.result = json.loads(result_json.read_text())
    return out


def _count_frames_sent(aed, times: list) -> None:
    """Note the host time of every stream frame the virtual amplifier sends that its wire
    faults let through intact (a dropped or garbled frame is lost to the host)."""
    on_tick, apply = aed.on_tick, aed.faults.apply
    ticking = []

    def counting_tick(now):
        ticking.append(now)
        try:
            on_tick(now)
        finally:
            ticking.clear()

    def counting_apply(reply):
        sent = apply(reply)
        if ticking and sent is not None and len(sent) == len(reply):
            times.append(ticking[0])
        return sent

    aed.on_tick, aed.faults.apply = counting_tick, counting_apply


def _note_hits(device, times: list) -> None:
    """Note the host time of every reply the device's drop or garble fault takes."""
    faults = device.faults
    apply = faults.apply

    def noting_apply(reply):
        before = faults.replies_hit
        sent = apply(reply)
        if faults.replies_hit > before:
            times.append(device.clock.now())
        return sent

    faults.apply = noting_apply


def hits_within(r: CellRun, rec) -> int | None:
    """Replies the fault took up to the record's last row (host time); None when unknown."""
    if r.replies_hit is None:
        return None
    if r.procedure_t0 is None or rec.data.empty:
        return r.replies_hit
    end = r.procedure_t0 + rec.data["time_s"].to_numpy()[-1] / r.cell.time_scale
    return sum(1 for t in r.hit_at if t <= end + 1e-9)


# -- invariants -------------------------------------------------------------------------------


def declared_loss(events) -> int:
    """Samples the record's events say were lost: the integers before 'sample(s)'/'frame(s)'
    in events that speak of losing, dropping or missing them."""
    total = 0
    for e in events:
        text = f"{e.name} {e.text}"
        if re.search(r"lost|dropp|missing|discard|skipp", text, re.I):
            total += sum(int(n) for n in re.findall(r"(\d+)\s+(?:\w+\s+)?(?:samples?|frames?|values?)", text))
    return total


def frames_sent_within(r: CellRun, rec) -> int | None:
    """Intact stream frames the amplifier sent between the record's first and last row (host
    time); None when the record has no rows or the test clock's zero is unknown."""
    if r.procedure_t0 is None or rec.data.empty:
        return None
    t = rec.data["time_s"].to_numpy()
    lo, hi = (r.procedure_t0 + t[0] / r.cell.time_scale, r.procedure_t0 + t[-1] / r.cell.time_scale)
    sent = np.asarray(r.frames_sent_at)
    return int(np.count_nonzero((sent >= lo - 1e-9) & (sent <= hi + 1e-9)))


def curve_deviation_pct(result: dict, cell_run: CellRun, from_eps_p: float = 0.0) -> tuple[float, tuple[float, float]] | None:
    """Max |σ_fit/σ_true − 1| in % over the hardening's measured range (``fit_range``, else
    ``strain_range``) from ``from_eps_p`` on; None when the result has no static Johnson-Cook-like
    law to compare."""
    from flowcurve.identification.laws.hardening import johnson_cook_static

    hard = result.get("hardening") or {}
    rng = hard.get("fit_range") or hard.get("strain_range")
    run = cell_run.virtual_run
    if not rng or run is None or not {"A_MPa", "B_MPa", "n"} <= set(hard):
        return None
    lo, hi = max(float(rng[0]), 0.002, from_eps_p), float(rng[1])
    if not hi > lo:
        return None
    eps = np.linspace(lo, hi, 200)
    fitted = johnson_cook_static(eps, hard["A_MPa"], hard["B_MPa"], hard["n"])
    truth = run.material.flow_stress(eps, run.strain_rate_per_s, run.temperature_C)
    return float(100.0 * np.max(np.abs(fitted / truth - 1.0))), (lo, hi)


def violations(r: CellRun, reference: "Truth | None" = None) -> list[tuple[str, str]]:
    """The invariants this cell breaks: [(class, detail)] — empty when it passes; a fault cell
    given its fault-free ``reference`` is also judged on the numbers that survived."""
    from flowcurve.errors import RecordError
    from flowcurve.record.format import read_record

    bad: list[tuple[str, str]] = []
    cell = r.cell
    if r.run_exception:
        bad.append(("internal error in run", _last_line(r.run_exception)))
    if "internal error" in r.run_err:
        bad.append(("internal error in run", _first(r.run_err, "internal error")))
    if r.identify_exception:
        bad.append(("internal error in identify", _last_line(r.identify_exception)))
    if "internal error" in r.identify_err:
        bad.append(("internal error in identify", _first(r.identify_err, "internal error")))
    if r.notes:
        bad.append(("bench", "; ".join(r.notes)))
    if r.record_path is None or not r.record_path.exists():
        bad.append(("no record", r.run_err.strip()[-200:]))
        return bad
    try:
        rec = read_record(r.record_path)
    except RecordError as exc:
        if "no samples" in str(exc):  # the test ended before loading: the cause is what the operator was told
            bad.append(("the test ended before loading", _first(r.run_err, "error") or str(exc)))
        else:
            bad.append(("record unreadable", f"{type(exc).__name__}: {exc}"))
        return bad
    if r.heater_do not in (0, None):
        bad.append(("heater on at the end", f"furnace DO {r.heater_do}"))
    if r.relay_on and cell.fault.kind != "relay_stuck":
        bad.append(("heater on at the end", "furnace relay on"))
    seen_by_operator = r.run_out + r.run_err
    # a 5 % fault may take no reply before the record's end in a short test: nothing to name
    if r.injected_at_s is not None and hits_within(r, rec) != 0:
        name = DEVICE_NAMES[cell.fault.device]
        texts = " ".join(f"{e.name} {e.text}" for e in rec.events) + " " + " ".join(
            str(rec.meta.get(k, "")) for k in ("abort_reason", "stop_reason"))
        if name not in texts:
            bad.append(("fault not in the record's events", f"{cell.fault.label} at {r.injected_at_s:.1f} s; "
                        f"status {rec.meta.get('status')}, stop: {rec.meta.get('stop_reason', '')[:80]}"))
        if name not in seen_by_operator:
            bad.append(("fault not shown to the operator", f"{cell.fault.label}: {_last_line(r.run_out)[:100]}"))
    rows = len(rec.data)
    sent = frames_sent_within(r, rec)
    declared = declared_loss(rec.events)
    if sent is not None and sent - rows > declared + LOSS_SLACK_FRAMES:
        bad.append(("samples lost beyond what the events declare",
                    f"{sent} frames sent within the record's span, {rows} rows, {declared} declared lost"))
    bad += unmarked_post_test(r.result, rec)
    judged = reference is not None and cell.fault is not NO_FAULT and cell.fault.kind not in CHANGES_THE_SPECIMEN
    tolerance = max(CURVE_TOLERANCE_PCT, (reference.curve_dev_pct or 0.0) + CURVE_OVER_REFERENCE_PCT) if judged else CURVE_TOLERANCE_PCT
    bad += _curve_violations(r, rec, tolerance)
    if judged:
        bad += survived(r, rec, reference)
    return bad


HEATED_WHERE_IT_STOOD = re.compile(r"heater does not switch off|over-temperature")  # the furnace heated the specimen after the stop
POST_TEST_MARK = re.compile(r"post-test measurements")


def unmarked_post_test(result: dict | None, rec) -> list[tuple[str, str]]:
    """A record whose specimen was heated after its last row (a stuck relay found by the furnace's
    watch, an over-temperature), its post-test measurements taken after that, identified without
    a word of it: the specimen flowed on under the stop's load (the 20 C relay_stuck cell: hk 0.8 %
    short, the curve 3.4 % low, marked good)."""
    if not result or rec.data.empty or not any(k.startswith("post.") for k in rec.meta):
        return []
    last = float(np.nanmax(rec.data["time_s"].to_numpy(dtype=float)))
    late = [e for e in rec.events if e.name == "fault" and e.time_s > last and HEATED_WHERE_IT_STOOD.search(e.text)]
    if not late or any(POST_TEST_MARK.search(w) for w in result.get("warnings") or []):
        return []
    return [("post-test measurements after a heating fault, unmarked", f"{late[0].text[:80]} at {late[0].time_s:.1f} s, "
             f"the last row at {last:.1f} s; hardening quality {(result.get('hardening') or {}).get('quality')}")]


# -- the numbers that survived a fault (issue 42) ---------------------------------------------------


@dataclass(frozen=True)
class Truth:
    """What the fault-free run of a cell gave: |force| against |crosshead| (rows in order of
    crosshead), the last crosshead, Fm and its sampling step, identify's Rm and Rp0.2, the
    flow curve's deviation from the material."""

    x_mm: np.ndarray
    force_N: np.ndarray
    last_x_mm: float | None
    last_step_mm: float
    fm_N: float
    fm_step: float  # relative: how far Fm's neighbours are below it (the sampling's resolution of Fm)
    loaded_to_mm: float  # the last crosshead with at least half Fm (before a fracture's fall)
    step_mm: float  # the median crosshead step between rows
    values: dict  # Rm_MPa, Rp02_MPa when identified
    curve_dev_pct: float | None
    temperature_C: np.ndarray | None = None  # the recorded temperature of each row (NaN where none)
    material: str | None = None  # the virtual material: how its force moves with the temperature


_REFERENCES: dict[str, Truth | None] = {}


def truth_of(r: CellRun) -> Truth | None:
    """The :class:`Truth` of a fault-free run; None when it has no readable record."""
    from flowcurve.errors import RecordError
    from flowcurve.record.format import read_record

    try:
        rec = read_record(r.record_path)
    except (RecordError, OSError, TypeError):
        return None
    x, f = _rows(rec)
    dev = curve_deviation_pct(r.result, r) if r.result else None
    truth = truth_from_rows(x, f, rec.meta.get("status") == "complete", r.result, dev[0] if dev else None)
    return None if truth is None else dataclasses.replace(truth, temperature_C=_row_temperatures(rec), material=r.cell.material)


def truth_from_rows(x: np.ndarray, f: np.ndarray, complete: bool, result: dict | None, curve_dev_pct: float | None) -> Truth | None:
    """A :class:`Truth` from a fault-free run's |crosshead| and |force| rows and identify's result."""
    if x.size < 2:
        return None
    i = int(np.argmax(f))
    neighbours = f[max(i - 1, 0):i + 2]
    fm_step = float((f[i] - np.min(neighbours)) / f[i]) if f[i] > 0 else 0.0
    values = {k: float(result[k]) for k in VALUE_MARK if result and isinstance(result.get(k), (int, float))}
    loaded = float(x[np.flatnonzero(f >= 0.5 * f[i])[-1]])
    moved = np.diff(x)[np.diff(x) > 0]  # an encoder's count spans several rows: the step is the one between counts
    step = float(np.median(moved)) if moved.size else 0.0
    return Truth(x, f, float(x[-1]) if complete else None, float(x[-1] - x[-2]), float(f[i]), fm_step, loaded, step,
                 values, curve_dev_pct)


def _rows_with_both(rec) -> np.ndarray:
    """The rows that hold both a crosshead and a force reading."""
    return np.isfinite(rec.column("crosshead_mm")) & np.isfinite(rec.column("force_N"))


def _rows(rec) -> tuple[np.ndarray, np.ndarray]:
    """|crosshead| and |force| of the rows with both, in record order (the crosshead only advances)."""
    ok = _rows_with_both(rec)
    return np.abs(rec.column("crosshead_mm"))[ok], np.abs(rec.column("force_N"))[ok]


def _row_temperatures(rec) -> np.ndarray:
    """The recorded temperature of :func:`_rows`' rows (NaN where a row has none, or the record no column)."""
    ok = _rows_with_both(rec)
    return rec.column(TEMPERATURE_COLUMN)[ok] if rec.has(TEMPERATURE_COLUMN) else np.full(int(np.sum(ok)), np.nan)


def temperature_ratio(material: str | None, run_C, reference_C) -> np.ndarray:
    """The virtual material's force at the run's recorded temperature over that at the fault-free
    run's, row by row: Johnson–Cook's (1 − T*^m) at each (the rate's factor is the same in both); 1
    where either temperature is unknown. A furnace fault that lets the specimen run 3 °C hotter within
    the standard's tolerance changes the specimen, not the numbers' truth."""
    # r = (1 − T*_run^m) / (1 − T*_ref^m)
    run, ref = np.broadcast_arrays(np.asarray(run_C, dtype=float), np.asarray(reference_C, dtype=float))
    if material is None:
        return np.ones(run.shape)
    from flowcurve.rig.virtual.materials import get_material

    m = get_material(material)
    known = np.isfinite(run) & np.isfinite(ref)
    out = np.ones(run.shape)
    out[known] = m.rate_temperature_factor(0.0, run[known]) / m.rate_temperature_factor(0.0, ref[known])
    return out


def reference(cell: Cell, workdir: Path) -> Truth | None:
    """The fault-free run of ``cell``'s other axes: run once per process, then cached."""
    ref = dataclasses.replace(cell, fault=NO_FAULT)
    if ref.id not in _REFERENCES:
        remember(run_cell(ref, workdir / "reference"))
    return _REFERENCES[ref.id]


def remember(r: CellRun) -> None:
    """Keep a fault-free run's truth for the fault cells that share its other axes."""
    if r.cell.fault is NO_FAULT:
        _REFERENCES[r.cell.id] = truth_of(r)


def claim_holds(result: dict, key: str, truth: float) -> bool:
    """Whether the result's claim on ``key`` holds the fault-free truth: its value within its stated U
    of it, or no claim at all (the budget stated not certifiable). A value beyond the tolerance that its
    own U holds is an honest number, not one the fault moved unseen."""
    budget = (result.get("uncertainty") or {}).get(key)
    if not isinstance(budget, dict):
        return False
    if budget.get("certifiable") is False:
        return True
    value, U = budget.get("value"), budget.get("U")
    return isinstance(value, (int, float)) and isinstance(U, (int, float)) and abs(value - truth) <= U


def survived(r: CellRun, rec, ref: Truth) -> list[tuple[str, str]]:
    """The numbers beyond the fault-free truth's tolerance: [(class, detail)]. None when identify says
    the recorded temperature under load left the nominal one: the specimen truly changed (the record's
    temperature column shows it), the fault-free run is another test, and every value is marked; or,
    where identify refused the record (an aborted run without its post-test measurements), when the
    record itself says so (the same rule, identify's temperature_warnings on the record: a furnace that
    stopped answering leaves the rows after it without a temperature, not its last reading repeated)."""
    from flowcurve.identification.identify import temperature_warnings

    warnings = (r.result.get("warnings") or []) if r.result else temperature_warnings(rec)
    if any(TEMPERATURE_MARK.search(w) for w in warnings):
        return []
    bad = []
    x, f = _rows(rec)
    # the fault-free run's force at the run's own recorded temperature (the specimen is what it was)
    at_temperature = np.ones(x.shape)
    run_C = _row_temperatures(rec) if ref.temperature_C is not None else None
    if run_C is not None and x.size:
        order = np.argsort(ref.x_mm, kind="stable")
        at_temperature = temperature_ratio(ref.material, run_C, np.interp(x, ref.x_mm[order], ref.temperature_C[order]))
    # the reference's force at each recorded crosshead position: |F − F_ref(x)| ≤ tol·F_ref + half its step there,
    # short of either run's end by two steps (the fracture's fall, the crosshead standing at a stop)
    end = min(ref.loaded_to_mm, float(x[-1]) if x.size else 0.0) - 2 * ref.step_mm
    keep = (x >= FORCE_FROM_MM) & (x <= end)
    if np.any(keep):
        xs, fs = x[keep], f[keep]
        order = np.argsort(ref.x_mm, kind="stable")
        rx, rf = ref.x_mm[order], ref.force_N[order]
        j = np.clip(np.searchsorted(rx, xs), 1, rx.size - 1)
        f_ref = np.interp(xs, rx, rf) * at_temperature[keep]
        slack = FORCE_TOL * f_ref + 0.5 * np.abs(rf[j] - rf[j - 1])
        off = np.abs(fs - f_ref) - slack
        if np.max(off) > 0:
            k = int(np.argmax(off))
            rising = xs <= ref.x_mm[int(np.argmax(ref.force_N))]  # up to Fm: the hardening, no fracture step
            before_fm = f"; up to Fm {100 * np.max(np.abs(fs[rising] / f_ref[rising] - 1)):.1f} %" if np.any(rising) else ""
            bad.append(("force against the crosshead beyond the fault-free run's",
                        f"{100 * (fs[k] / f_ref[k] - 1):+.1f} % at {xs[k]:.2f} mm ({int(np.sum(off > 0))} of {xs.size} rows{before_fm})"))
    if rec.meta.get("status") == "complete" and ref.last_x_mm is not None and x.size:
        if abs(x[-1] - ref.last_x_mm) > max(LAST_CROSSHEAD_TOL_MM, abs(ref.last_step_mm)):
            bad.append(("last crosshead beyond the fault-free run's", f"{x[-1]:.3f} mm for {ref.last_x_mm:.3f}"))
        fm = float(np.max(f))
        fm_ref = ref.fm_N
        if run_C is not None:  # each Fm at its own run's temperature there
            fm_ref *= float(temperature_ratio(ref.material, run_C[int(np.argmax(f))], ref.temperature_C[int(np.argmax(ref.force_N))]))
        # rising to a target: Fm is the stop's force, where either run stopped (the force against the crosshead judges it)
        fm_at_stop = (ref.x_mm[int(np.argmax(ref.force_N))] >= ref.x_mm[-1] - 2 * ref.step_mm
                      or x[int(np.argmax(f))] >= x[-1] - 2 * ref.step_mm)
        if not fm_at_stop and abs(fm / fm_ref - 1) > max(FM_TOL, ref.fm_step):
            bad.append(("Fm beyond the fault-free run's", f"{fm:.0f} N for {fm_ref:.0f} ({100 * (fm / fm_ref - 1):+.2f} %)"))
    if r.result and rec.meta.get("status") == "complete":
        warnings = [w for w in (r.result.get("warnings") or []) if not RIG_FAULTS_WARNING.search(w)]
        for key, tol in (("Rm_MPa", RM_TOL), ("Rp02_MPa", RP02_TOL)):
            got, want = r.result.get(key), ref.values.get(key)
            if not isinstance(got, (int, float)) or want is None or any(VALUE_MARK[key].search(w) for w in warnings):
                continue
            if abs(got / want - 1) > tol and not claim_holds(r.result, key, want):
                bad.append((f"{key.split('_')[0]} beyond the fault-free run's", f"{got:.1f} MPa for {want:.1f} ({100 * (got / want - 1):+.2f} %)"))
    return bad


def _curve_violations(r: CellRun, rec, tolerance_pct: float = CURVE_TOLERANCE_PCT) -> list[tuple[str, str]]:
    if r.identify_code not in (0, None) and not r.identify_exception:
        err_lines = [l for l in r.identify_err.splitlines() if l.startswith("flowcurve: error:")]
        if not err_lines:
            return [("identify failed without a one-line error", r.identify_err.strip()[-200:])]
        if (rec.meta.get("status") == "complete" and r.cell.fault is NO_FAULT and r.cell.rate_Hz >= 50
                and "sample faster" not in err_lines[0]):  # a record too sparse for a modulus may be refused, saying so
            return [("a clean record refused", err_lines[0][:200])]
        return []
    if r.result is None:
        return []
    found = curve_deviation_pct(r.result, r)
    if found is None:
        return [("no hardening law to compare", str((r.result.get("hardening") or {}).get("law")))]
    dev, (lo, hi) = found
    if dev <= tolerance_pct:
        return []
    hard = r.result.get("hardening") or {}
    excuses = [w for w in (r.result.get("warnings") or []) + (hard.get("warnings") or [])
               if not NOT_ABOUT_THE_CURVE.search(w) and not RIG_FAULTS_WARNING.search(w)]
    flagged = hard.get("quality") not in (None, "good") or bool(excuses)
    beyond = (hard.get("start_uncertainty") or {}).get("below_limit_from_eps_p")
    if flagged and all(START_ONLY.search(w) for w in excuses) and hard.get("quality") == "good" and beyond is not None:
        past = curve_deviation_pct(r.result, r, from_eps_p=beyond)  # the start's warning excuses the start only
        if past is not None and past[0] > tolerance_pct:
            return [("flow curve off past the start the strain zero excuses", f"{past[0]:.1f} % over εp {past[1][0]:.3f}…{past[1][1]:.3f}")]
    if flagged:
        return []
    return [("flow curve off without a warning", f"{dev:.1f} % over εp {lo:.3f}…{hi:.3f}, quality {hard.get('quality')}, "
             f"status {rec.meta.get('status')}")]


def _last_line(text: str) -> str:
    lines = [l for l in (text or "").strip().splitlines() if l.strip()]
    return lines[-1].strip() if lines else ""


def _first(text: str, word: str) -> str:
    return next((l for l in text.splitlines() if word in l), "")[:200]


def cell_hash(cell: Cell) -> str:
    return hashlib.sha1(cell.id.encode()).hexdigest()[:8]
