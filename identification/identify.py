"""Identify one record, whatever its test: common sanity checks, then tension or compression.

:func:`identify` checks what every test needs (enough samples, a force that rises above the
noise, stresses of a plausible size for the declared units and geometry), then hands the
record to :func:`identification.tension.identify_tension` or
:func:`identification.compression.identify_compression`, and completes the result's
``record`` block and ``warnings`` so that series fits can use the result folder alone.
:func:`identify_inverse_fe` is the one place that chooses the compression or the tension inverse
FE (``--method inverse-fe``); it imports them when called, so the fast path loads no FE code.
"""

from __future__ import annotations

import math
import re

import numpy as np

from flowcurve.record.format import STATUS_ABORTED, WRITER_STAMPING_KEY, Record
from flowcurve.record.summary import MEASURED_SPEED_KEY, record_summary, speed_mismatch
from flowcurve.errors import FlowcurveError, IdentificationError, RecordError
from flowcurve.identification.compression.identify import identify_compression
from flowcurve.identification.iso6892 import mad_sigma
from flowcurve.identification.outcome import Identification
from flowcurve.identification.quality.assurance import attach as attach_assurance
from flowcurve.identification.tension.identify import identify_tension

MIN_SAMPLES = 20
# a force rise smaller than this many noise standard deviations is no test at all
MIN_RISE_IN_NOISE = 10.0
NOISE_SAMPLES = 50_000  # differences used for the noise estimate (long records are thinned)
# peak engineering stress outside this range means the force or diameter units are wrong
PLAUSIBLE_STRESS_MPa = (2.0, 5000.0)
# the recorded temperature while the specimen carries load may stray this far from the nominal
TEMPERATURE_SPREAD_C = 10.0
LOADED_FRACTION = 0.05  # "carries load": |force| above this fraction of its maximum

DISPATCH = {"tension": identify_tension, "compression": identify_compression}
# The options each test's identification takes, written out: an option in neither list is a
# mistake (a typo) and an error; one the other test takes is a warning (a batch of tension
# and compression records is identified with one set of options).
# tests/compression/test_identify_options.py keeps the lists equal to the functions' keywords.
OPTIONS = {
    "tension": frozenset({"use_extensometer", "frame_stiffness_N_per_um", "crosshead_length_mm", "toe", "scale",
                          "modulus_window", "modulus_window_MPa", "modulus_reference", "E_MPa", "poisson",
                          "true_stress", "neck", "law", "hardening", "fracture_weight", "fit_range", "fracture_point",
                          "modulus_method"}),
    "compression": frozenset({"friction_method", "friction_correction", "law", "E_MPa", "frame_stiffness_N_per_um",
                              "modulus_window", "modulus_window_MPa", "modulus_reference", "toe", "fit_range", "modulus_method"}),
}


def force_noise_N(force_N: np.ndarray) -> float:
    """Noise standard deviation of a force signal, robust to the test's own trend.

    From the median absolute successive difference: for white noise σ, diff has σ√2 and
    MAD·1.4826 estimates a standard deviation.
    """
    force_N = np.asarray(force_N, dtype=float)
    step = max(1, len(force_N) // NOISE_SAMPLES)
    later = force_N[1::step]  # successive differences, evenly thinned (np.diff(F)[::step], only those taken): same statistics
    d = later - force_N[::step][: later.size]
    d = d[np.isfinite(d)]
    if d.size == 0:
        return 0.0
    return mad_sigma(d) / math.sqrt(2.0)


def temperature_stray_C(record: Record) -> tuple[float, float, float] | None:
    """(lowest, highest, nominal) °C recorded while the specimen carries load, where it strays beyond
    TEMPERATURE_SPREAD_C from the nominal temperature (a stuck relay, a lost furnace heat it on);
    None within it, or without a temperature column or a numeric nominal temperature."""
    if not record.has("temperature_C") or not record.has("force_N"):
        return None
    force, temp = np.abs(record.column("force_N")), record.column("temperature_C")
    loaded = np.isfinite(force) & np.isfinite(temp)
    if not loaded.any():
        return None
    loaded &= force >= LOADED_FRACTION * np.max(force[loaded])
    try:
        nominal = record.number("nominal_temperature_C")
    except RecordError:  # not a number: nothing to hold the recording against
        return None
    if not loaded.any() or nominal is None or not math.isfinite(nominal):
        return None
    lo, hi = float(np.min(temp[loaded])), float(np.max(temp[loaded]))
    return None if max(nominal - lo, hi - nominal) <= TEMPERATURE_SPREAD_C else (lo, hi, float(nominal))


def temperature_warnings(record: Record) -> list[str]:
    """The recorded temperature while the specimen carries load against the nominal one
    (:func:`temperature_stray_C`) and a temperature recorded under load but not all through it."""
    unread = (unread_temperature_warnings(record, np.abs(record.column("force_N")), record.column("temperature_C"))
              if record.has("temperature_C") and record.has("force_N") else [])
    stray = temperature_stray_C(record)
    if stray is None:
        return unread
    lo, hi, nominal = stray
    return unread + [f"the recorded temperature under load ranges {lo:.0f}–{hi:.0f} C against the nominal {nominal:g} C: the flow "
            f"curve mixes temperatures (did the furnace hold its set-point?) and is not the nominal temperature's"]


def unread_temperature_warnings(record: Record, force_N: np.ndarray, temperature_C: np.ndarray) -> list[str]:
    """A heated test whose temperature was recorded under load but not all through it (the furnace
    stopped answering: the rows after its last reading carry none): that part of the curve is of an
    unknown temperature. Empty when every loaded row has one, or none has (no furnace recorded)."""
    finite = np.isfinite(force_N)
    if not finite.any():
        return []
    loaded = finite & (force_N >= LOADED_FRACTION * np.max(force_N[finite]))
    unread = loaded & ~np.isfinite(temperature_C)
    if not unread.any() or not (loaded & np.isfinite(temperature_C)).any():
        return []
    since = f" from {record.column('time_s')[unread][0]:.1f} s" if record.has("time_s") else ""
    return [f"the temperature was not recorded over {100 * unread.sum() / loaded.sum():.0f} % of the loading{since} (the furnace did "
            "not answer): the flow curve there is of an unknown temperature, not the nominal one's"]


# record events in which the acquisition declares a rig fault (docs/record-format.md)
FAULT_EVENTS = ("data_loss", "frames_missing", "corrupt", "stream_restart", "late_reply", "retry", "dropped", "stream_latency", "carried", "wrong_address", "stream_gap_undecided", "stream_gap_in_doubt")  # a retry delays a reading: the crosshead may lag
POOR_LOSS_FRACTION = 0.05  # samples lost beyond this share of the test mark the hardening poor


def _is_number(text) -> bool:
    try:
        return math.isfinite(float(text))
    except (TypeError, ValueError):
        return False


def _last_count(text: str) -> int | None:
    """The running count a ``frames_missing`` event ends with: "(N so far" or "N … in all"."""
    found = re.search(r"\((\d+) so far", text) or re.search(r"(\d+) frames? missing from its stream in all", text)
    return int(found.group(1)) if found else None


def fault_warnings(record: Record) -> tuple[list[str], bool]:
    """The rig faults a record declares (its fault events), as one warning per kind, and whether
    they make the curve doubtful: more than :data:`POOR_LOSS_FRACTION` of the samples lost, a
    reading rejected as corrupt (the gap it leaves is bridged), or a load-cell stream gap left
    undecided (``stream_gap_undecided``: the later forces may be a period off the crosshead)."""
    seen: dict[str, list[str]] = {}
    for event in record.events:
        if event.name in FAULT_EVENTS:
            seen.setdefault(event.name, []).append(" ".join(str(event.text).split()))
    missing = record.meta.get("samples_missing")
    try:
        lost = float(missing) / (len(record.data) + float(missing)) if missing not in (None, "") else 0.0
    except (TypeError, ValueError, ZeroDivisionError):
        lost = 0.0
    counted = {name: f"{len(texts)}×" for name, texts in seen.items()}
    if "frames_missing" in seen:  # frames, not events: the header's count, which the events' last one says too
        frames = int(float(missing)) if _is_number(missing) else _last_count(seen["frames_missing"][-1])
        counted["frames_missing"] = f"{frames} frame{'s' if frames != 1 else ''}" if frames is not None else counted["frames_missing"]
    warnings = [f"the record declares rig faults ({name}, {counted[name]}): {texts[-1][:200]} — the curve may carry them"
                for name, texts in seen.items()]
    # a stream gap the acquisition could not tell latency or loss of: the forces after it may lag the crosshead by a period
    return warnings, lost > POOR_LOSS_FRACTION or "corrupt" in seen or "stream_gap_undecided" in seen


MISALIGNED_TOL = 0.01  # a possible misalignment of the force against the crosshead beyond this share of the force marks the curve
LOADED_SHARE = 0.2  # ... judged over the rows loaded to this share of the maximum force (a fracture's fall left out)


def misalignment_share(time_s, force_N, after_s: float, doubt_s: float) -> float:
    """The largest share of the force a stamp error of ``doubt_s`` after ``after_s`` can cost: the
    force's change over the doubt, max |F(t) − F(t − δ)| / |F(t)| over the rows after the gap loaded to
    LOADED_SHARE of the maximum (F(t − δ) interpolated in the record's own rows). 0 without such rows."""
    t, f = np.asarray(time_s, dtype=float), np.asarray(force_N, dtype=float)
    ok = np.isfinite(t) & np.isfinite(f)
    t, f = t[ok], f[ok]
    later = (t > after_s + doubt_s) & (np.abs(f) >= LOADED_SHARE * np.max(np.abs(f), initial=0.0))
    if not np.any(later):
        return 0.0
    shifted = np.interp(t[later] - doubt_s, t, f)  # F(t − δ)
    return float(np.max(np.abs(f[later] - shifted) / np.abs(f[later])))


def gap_in_doubt_warnings(record: Record) -> tuple[list[str], bool]:
    """A load-cell stream gap the acquisition took as lost frames without evidence (``stream_gap_in_doubt``:
    the force stayed within its noise across it): had it been the line's latency, every later force lags
    the crosshead by the doubt. Where that can cost more than MISALIGNED_TOL of the force later (a steeper
    stretch: the fall after Fm), a warning and the curve doubtful; within it, nothing."""
    if record.data.empty or not (record.has("time_s") and record.has("force_N")):
        return [], False
    from flowcurve.identification.quality.stream_gap import gaps

    warnings = []
    for after_s, doubt_s in gaps(record, ("stream_gap_in_doubt",)):
        share = misalignment_share(record.column("time_s"), record.column("force_N"), after_s, doubt_s)
        if share > MISALIGNED_TOL:
            warnings.append(f"the load cell's stream gap after {after_s:.1f} s could not be told lost frames or latency: the "
                            f"forces after it may lag the crosshead by {doubt_s:.2f} s, up to {100 * share:.1f} % of the force")
    return warnings, bool(warnings)


LOSS_EVENTS = ("frames_missing", "stream_restart", "data_loss")  # a load-cell frame went missing


# a fault after the loading that heats the specimen where it stands, under the stop's load (the furnace's watch)
HEATED_AFTER_LOADING = re.compile(r"heater does not switch off|over-temperature")


def after_loading_warnings(record: Record) -> list[str]:
    """A fault the record declares after its last row that heated the specimen in the machine (a
    stuck relay found by the furnace's watch after the stop, an over-temperature): the specimen
    stood under the stop's load while it heated and may have flowed on, so its post-test
    measurements (``post.*``) may describe a specimen the rows do not. Empty without ``post.*``
    keys or such an event."""
    post = sorted(k for k in record.meta if k.startswith("post."))
    if not post or record.data.empty or not record.has("time_s"):
        return []
    times = record.column("time_s")
    last = float(np.nanmax(times)) if np.isfinite(times).any() else math.nan
    late = next((e for e in record.events if e.name == "fault" and e.time_s > last and HEATED_AFTER_LOADING.search(e.text)), None)
    if late is None:
        return []
    return [f"after the loading's last row ({last:.1f} s) the record declares at {late.time_s:.1f} s: "
            f"{' '.join(late.text.split())[:160]} — the specimen stood in the machine under the stop's load while it heated, "
            f"so the post-test measurements ({', '.join(post)}) may include flow after the record, and whatever rests on them "
            "(the strain's scaling K_l and μ in compression, A, Z and the neck in tension) with them"]


def old_writer_warning(record: Record) -> str | None:
    """A record written before the force samples were stamped on the stream's rhythm (no
    ``writer.stamping`` in its header) that declares lost load-cell frames: that writer stamped
    the frames after a loss as if none had been lost, so from the first loss on each force may
    sit against an earlier crosshead position (docs/record-format.md, "Time stamps and losses")."""
    stamping = record.meta.get(WRITER_STAMPING_KEY)
    if stamping == "2":
        return _straight_gap_warning(record)
    if stamping not in (None, ""):
        return None
    try:
        missing = float(record.meta.get("samples_missing") or 0)
    except ValueError:
        missing = 0.0
    first = next((e for e in record.events if e.name in LOSS_EVENTS), None)
    if not missing and first is None:
        return None
    at = f" from {first.time_s:.1f} s ({first.name})" if first is not None else ""
    lost = f"{missing:.0f} lost load-cell frames" if missing else "lost load-cell frames"
    return (f"the record was written before flowcurve stamped force samples on the load cell's rhythm (no "
            f"{WRITER_STAMPING_KEY} in its header) and declares {lost}: the force may be shifted against the "
            f"crosshead after the first loss{at} — each later force paired with an earlier crosshead position, "
            f"Fm and the curve too high while the force rises; use the curve up to the first loss, or test again")


def _straight_gap_warning(record: Record) -> str | None:
    """A record of writer.stamping 2 whose crosshead reads were retried: that writer drew the rows'
    crosshead straight across the gap a retried read leaves, so a stop inside the gap (the fracture,
    the target) reads as a climb (docs/record-format.md, "Rows across a gap")."""
    retried = next((e for e in record.events if e.name == "retry" and "encoder" in e.text.split(":")[0]), None)
    if retried is None:
        return None
    return (f"the record was written with {WRITER_STAMPING_KEY} 2 and its crosshead encoder's reads were retried (from "
            f"{retried.time_s:.1f} s): that writer drew the crosshead straight across the gap a retried read leaves, so "
            "where the crosshead stopped inside a gap (the fracture, the target) the rows read it still climbing — the "
            "points after such a stop are not to be trusted; the force before it is")


def check_record(record: Record) -> list[str]:
    """The checks every identification needs; returns warnings, raises on unusable records."""
    record.test  # an unknown test is the first error named
    source = record.source
    n = len(record.data)
    if n < MIN_SAMPLES:
        raise RecordError(source, f"only {n} samples; an identification needs at least {MIN_SAMPLES}")
    force = record.column("force_N")
    finite = np.isfinite(force)
    if finite.sum() < MIN_SAMPLES:
        raise RecordError(source, f"only {int(finite.sum())} samples with a force value", column="force_N")
    force = force[finite] if not finite.all() else force
    head = force[: max(5, len(force) // 50)]
    baseline = float(np.median(head))
    top, bottom = float(np.max(force)), float(np.min(force))
    rise = max(top - baseline, baseline - bottom)  # max |F − baseline| (subtraction is monotone: the extremes' differences)
    noise = force_noise_N(force)
    if rise <= MIN_RISE_IN_NOISE * noise or rise == 0.0:
        raise RecordError(source, f"force never rises above noise (largest change {rise:.3g} N, noise {noise:.3g} N); is this the right column?", column="force_N")
    moving = [c for c in ("crosshead_mm", "extensometer_mm") if record.has(c)]
    def spread(column: str) -> float:
        """The spread (max − min) of a column's finite values."""
        values = record.column(column)
        finite = np.isfinite(values)
        values = values if finite.all() else values[finite]
        return float(np.ptp(values)) if values.size else 0.0

    if moving and not any(spread(c) > 0 for c in moving):
        raise RecordError(source, f"the displacement never changes ({', '.join(moving)} constant): a dead channel, "
                                  "or a column scaled to zero?", column=moving[0])
    specimen = record.specimen  # d0 and l0 (or h0) required
    d0, area_mm2 = specimen.d0_mm, specimen.area0_mm2
    peak_N = max(top, -bottom)  # max |F|
    peak_MPa = peak_N / area_mm2
    lo, hi = PLAUSIBLE_STRESS_MPa
    if not lo <= peak_MPa <= hi:
        raise RecordError(source, f"peak engineering stress {peak_MPa:.3g} MPa (force {peak_N:.4g} N on d0 = {d0:g} mm) is outside {lo:g}–{hi:g} MPa; check units of force and diameter")
    warnings = list(record.warnings) + temperature_warnings(record)
    if record.meta.get("status") == STATUS_ABORTED:  # a fault ended the test: the curve ends there, and may not be one test's
        why = " ".join(str(record.meta.get("abort_reason") or "no reason recorded").split())
        warnings.append(f"the test was aborted ({why}): the results cover the record up to the fault, a short and maybe disturbed part of the test")
    if record.truncated and not any("cut short" in w for w in warnings):
        warnings.append("the record was cut short; results cover only the samples recorded")
    return warnings


def route_options(test: str, options: dict) -> tuple[dict, list[str]]:
    """Split options into those the test's identification takes and those only the other
    test takes; an option neither takes is an :class:`IdentificationError` naming it."""
    unknown = sorted(set(options).difference(*OPTIONS.values()))
    if unknown:
        known = ", ".join(sorted(set().union(*OPTIONS.values())))
        raise IdentificationError(f"unknown identification option(s): {', '.join(unknown)} (known: {known})")
    taken = {k: v for k, v in options.items() if k in OPTIONS[test]}
    return taken, sorted(set(options) - set(taken))


def identify(record: Record, **options) -> Identification:
    """Identify a tension or compression record (dispatch on ``record.test``).

    Parameters
    ----------
    record : Record
        The record (``flowcurve.record.format.read_record`` or ``record.importers.load_record``).
    **options
        Routed by :data:`OPTIONS`; ``law`` is any law one record identifies
        (:func:`.laws.hardening.static_law_names`) or ``best`` (the lowest AIC); ``None`` values are dropped, so callers can pass every
        command-line option. An option only the other test takes is reported in the result's
        warnings; an option no test takes raises IdentificationError.

    Returns
    -------
    Identification
        ``result`` (the JSON-able result, units in its keys, ``uncertainty`` budgets at k = 2)
        and ``curves`` (the diagrams and true curves as DataFrames).
    """
    warnings = check_record(record)
    func = DISPATCH[record.test]
    given = {k: v for k, v in options.items() if v is not None}
    if given.get("law", "best") != "best":  # an unknown or a rate law: one line before any work
        from flowcurve.identification.laws.hardening import static_form

        static_form(given["law"])
    accepted, ignored = route_options(record.test, given)
    ident = func(record, **accepted)
    result = ident.result
    result.setdefault("test", record.test)
    summary = record_summary(record)
    block = result.setdefault("record", {})
    for key, value in summary.items():
        if block.get(key) is None:
            block[key] = value
    if ignored:
        warnings.append(f"option(s) not used by {record.test} identification: {', '.join(ignored)}")
    after, stray = after_loading_warnings(record), temperature_stray_C(record)  # each read once: a long record's passes
    warnings += _what_the_record_says(result, record, after, stray)
    attach_assurance(result, ident.curves, record)
    if after and record.test == "compression":
        warnings += _post_test_spread(result, record, func, accepted)
    warnings += _filter_lag_spread(result, record, func, accepted)
    warnings += _stream_gap_spread(result, record, func, accepted, ident)
    warnings += off_temperature_warnings(result, record, stray)
    old = list(result.get("warnings") or [])
    result["warnings"] = old + [w for w in warnings if w not in old]
    return ident


def _what_the_record_says(result, record: Record, after: list[str], stray: tuple | None) -> list[str]:
    """The record's declared faults, an old writer's shift, a heating after its last row (``after``:
    :func:`after_loading_warnings`), a speed mismatch and a temperature that strayed under load
    (``stray``: :func:`temperature_stray_C`), as warnings; a good hardening fit on such a record
    marked poor (its ``doubt``)."""
    warnings, doubtful = fault_warnings(record)
    misaligned, may_lag = gap_in_doubt_warnings(record)
    warnings += misaligned
    doubtful = doubtful or may_lag
    shifted = old_writer_warning(record)
    if shifted:
        warnings.append(shifted)
        doubtful = True
    warnings += after
    mismatch = speed_mismatch(record.number("crosshead_speed_mm_per_s"), record.number(MEASURED_SPEED_KEY))
    warnings += [mismatch] if mismatch else []
    fit = getattr(getattr(result, "hardening", None), "fit", None)  # the main fit (result["hardening"] is its copy)
    if (doubtful or after or stray) and fit is not None and fit.quality == "good":
        why = ("the record declares lost, corrupt or possibly misaligned samples" if doubtful else "the post-test measurements may be of a specimen changed after the record"
               if after else "the curve mixes temperatures away from the nominal one")
        fit.doubt = why
        fit.warnings.append(f"marked poor: {why} (see the warnings)")
    return warnings


def _post_test_spread(result, record: Record, func, options: dict) -> list[str]:
    """A compression result whose post-test measurements are doubtful (:func:`after_loading_warnings`):
    identified again on the specimen as the record left it, the difference entered into each budget
    (:mod:`.quality.post_test_doubt`); where that cannot be done, the budgets it would widen are
    stated not certifiable. Returns the warnings."""
    from flowcurve.identification.quality import post_test_doubt as doubt

    unc = result.get("uncertainty") or {}
    hk = doubt.record_final_height_mm(result)
    why = None
    if hk is None:
        why = "the record's own shortening gives no final height to compare the measured hk with"
    else:
        try:
            alt = func(doubt.as_left_by_record(record, hk), **options)
            attach_assurance(alt.result, alt.curves, record)
        except FlowcurveError as exc:
            why = f"the specimen as the record left it (hk {hk:.4g} mm) does not identify: {str(exc).splitlines()[0]}"
        else:
            missing = doubt.widen(unc, alt.result.get("uncertainty") or {})
            measured = result["record"]["post"]["hk_mm"]
            note = (f"the budgets include the spread between the measured hk {measured:.4g} mm and the record's own "
                    f"{hk:.4g} mm ({doubt.COMPONENT})")
            if not missing:
                return [note]
            why = f"the specimen as the record left it (hk {hk:.4g} mm) states no {', '.join(missing)}"
    state_not_certifiable(unc, ("friction_mu", "Rp02_MPa", "flow_stress_MPa", "hardening"),
                          f"post-test measurements after a heating fault: {why}")
    return [f"not certifiable: {why}; the post-test measurements may include flow after the record"]


def _filter_lag_spread(result, record: Record, func, options: dict) -> list[str]:
    """A tension record that states its load cell's filter (:mod:`.quality.filter_lag`) and has hardening budgets:
    identified again with the force the filter delayed restored, the difference of each hardening constant, Rp0.2
    and flow-curve point entered into its budget. Returns the warnings (one when the second identification fails:
    the budgets are then left as they were). Compression's range runs to the operator's target, where the yield
    knee has little weight (docs/methods.md §2.13)."""
    from flowcurve.identification.quality import filter_lag

    tau = filter_lag.lag_s(record)
    hard = (result.get("uncertainty") or {}).get("hardening")
    if tau is None or record.test != "tension" or not hard:
        return []
    try:
        alt = func(filter_lag.unlagged(record, tau), **filter_lag.pinned_options(result, record.test, options))
        attach_assurance(alt.result, alt.curves, record)
    except FlowcurveError as exc:
        return [f"the load cell's filter lag ({1e3 * tau:.0f} ms) is not in the budgets of Rp0.2 and the flow curve: the record with "
                f"the force restored does not identify ({str(exc).splitlines()[0]})"]
    filter_lag.widen(result["uncertainty"], alt.result.get("uncertainty") or {})
    return []


def _stream_gap_spread(result, record: Record, func, options: dict, ident: Identification | None = None) -> list[str]:
    """A record naming a load-cell stream gap it could not tell latency or loss of (:mod:`.quality.stream_gap`):
    identified again with the later forces a period earlier, the difference of Rp0.2, Ag, each flow-curve point
    and hardening constant entered into its budget; a budget the second identification lacks, or all of them when
    it fails, stated not certifiable. Each row of ``ident``'s true curve gets its own difference as a column
    (:func:`_stream_gap_rows`). Returns the warnings."""
    from flowcurve.identification.quality import filter_lag, stream_gap

    found = stream_gap.gaps(record)
    unc = result.get("uncertainty")
    if not found or not isinstance(unc, dict):
        return []
    try:
        alt = func(stream_gap.realigned(record, found), **filter_lag.pinned_options(result, record.test, options))
        attach_assurance(alt.result, alt.curves, record)
    except FlowcurveError as exc:
        why = f"a load-cell stream gap (latency or loss undecided): the record read as latency does not identify ({str(exc).splitlines()[0]})"
        state_not_certifiable(unc, (*stream_gap.WIDENED_VALUES, *stream_gap.WIDENED_BLOCKS), why)
        _stream_gap_rows(result, ident, None, why)
        return [f"not certifiable: {why}"]
    missing = stream_gap.widen(unc, alt.result.get("uncertainty") or {})
    stream_gap.refuse(unc, missing, "a load-cell stream gap (latency or loss undecided): the record read as latency states no such value")
    _stream_gap_rows(result, ident, alt.true_curve, None)
    return []


def _stream_gap_rows(result, ident: Identification | None, alt_curve, why: str | None) -> None:
    """The true curve's rows (true_curve.csv) each with its share of the stream gap's doubt
    (:func:`.quality.stream_gap.row_doubt` against ``alt_curve``, the record read as latency; all NaN without
    one, ``why``), and result.json ``methods.stream_gap_rows`` saying what the column holds."""
    from flowcurve.identification.outcome import TRUE_CURVE_COLUMNS
    from flowcurve.identification.quality import stream_gap

    curve = getattr(ident, "true_curve", None)
    if curve is None or any(c not in curve.columns for c in TRUE_CURVE_COLUMNS):
        return
    x, s = (curve[c].to_numpy(dtype=float) for c in TRUE_CURVE_COLUMNS)
    if alt_curve is None or any(c not in alt_curve.columns for c in TRUE_CURVE_COLUMNS):
        u = np.full(x.shape, np.nan)
        why = why or "the record read as latency states no true curve"
    else:
        u = stream_gap.row_doubt(x, s, *(alt_curve[c].to_numpy(dtype=float) for c in TRUE_CURVE_COLUMNS))
    curve[stream_gap.ROW_COLUMN] = u
    methods = result.get("methods")
    if isinstance(methods, dict):
        methods["stream_gap_rows"] = stream_gap.rows_note(x, u, why)


def state_not_certifiable(uncertainty: dict, keys, why: str) -> None:
    """Each budget of ``uncertainty`` under ``keys`` (a budget, or a block of them: flow_stress_MPa,
    hardening) replaced by the statement that it is not certifiable, and why (no U)."""
    from flowcurve.identification.quality.assurance import not_certifiable

    for key in keys:
        block = uncertainty.get(key)
        if isinstance(block, dict) and "components" in block:
            uncertainty[key] = not_certifiable(block, why)
        elif isinstance(block, dict):
            for name, b in block.items():
                if isinstance(b, dict):
                    block[name] = not_certifiable(b, why)


def off_temperature_warnings(result, record: Record, stray: tuple | None) -> list[str]:
    """A record whose temperature under load strays from the nominal (``stray``: :func:`temperature_stray_C`):
    its strengths, flow stresses and constants are not the nominal temperature's, and no U can say
    by how much without the material's temperature sensitivity: stated not certifiable."""
    if stray is None or not isinstance(result.get("uncertainty"), dict):
        return []
    lo, hi, nominal = stray
    why = f"recorded under load at {lo:.0f}–{hi:.0f} C, not at the nominal {nominal:g} C (±{TEMPERATURE_SPREAD_C:g} C)"
    state_not_certifiable(result["uncertainty"], ("Rp02_MPa", "Rm_MPa", "flow_stress_MPa", "hardening"), why)
    return [f"the strengths, flow stresses and hardening constants are not certifiable: {why}"]


def inverse_time_limit_s(test: str) -> float:
    """The inverse FE's default wall-time budget for a ``test``'s record, s (tension's is longer: its runs are)."""
    from flowcurve.identification.fe import inverse, inverse_tension

    return inverse_tension.TIME_LIMIT_S if test == "tension" else inverse.TIME_LIMIT_S


def identify_inverse_fe(record: Record, *, law: str = "auto", workers: int | None = None, scheduler=None, progress=None,
                        E_MPa: float | None = None, time_limit_s: float | None | str = "default", **options) -> Identification:
    """Identify with CalculiX in the loop (``--method inverse-fe``), dispatched on ``record.test``.

    Compression: the law and μ fitted to the force–stroke and dmax
    (:func:`.fe.inverse.identify_inverse_fe_compression`); tension: the hardening beyond Fm fitted
    to the force–elongation and dk (:func:`.fe.inverse_tension.identify_inverse_fe_tension`).

    Parameters
    ----------
    record : Record
        A tension or compression record.
    law : str
        A law name, or "auto": the law that best follows the fast (or FE-consistent) curve.
    workers, scheduler : optional
        CalculiX runs in parallel: local processes, or a Dask scheduler's address.
    progress : callable, optional
        ``progress(runs, elapsed_s, left_s, limit_s)`` while the solver runs.
    E_MPa : float, optional
        Young's modulus of the model, MPa (compression).
    time_limit_s : float, None or "default"
        The wall-time budget, s (None: none; "default": :func:`inverse_time_limit_s`).
    **options
        The other keywords of the test's inverse.

    Returns
    -------
    Identification
        Whose result carries the ``inverse_fe`` block.

    Raises
    ------
    IdentificationError
        For an unknown law or a record of another test.
    """
    from flowcurve.identification.fe.law_choice import check_law

    check_law(law)
    limit = {"time_limit_s": time_limit_s} if time_limit_s != "default" else {}
    if record.test == "tension":
        from flowcurve.identification.fe.inverse_tension import identify_inverse_fe_tension

        return identify_inverse_fe_tension(record, workers=workers, scheduler=scheduler, progress=progress,
                                           law="johnson_cook" if law == "auto" else law, refit_law=None if law == "auto" else law,
                                           **({"E_MPa": E_MPa} if E_MPa is not None else {}), **limit, **options)
    if record.test == "compression":
        from flowcurve.identification.fe.inverse import identify_inverse_fe_compression

        return identify_inverse_fe_compression(record, law=law, workers=workers, scheduler=scheduler, progress=progress,
                                               E_MPa=E_MPa, **limit, **options)
    raise IdentificationError(f"{record.source}: --method inverse-fe needs a compression or tension record (this is {record.test!r})")
