"""The load-cell amplifier (HBM AED command set): identity, settings, tare, force readings.

A thin device class over :class:`~rig.transport.SerialTransport` and the pure codec
:mod:`rig.codecs.aed`. Counts become newtons by the stored calibration: nominal load reads
5 120 000 counts in 4-byte binary, 1 000 000 in ASCII and 20 000 in 2-byte binary.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Iterator

import numpy as np

from flowcurve.errors import DeviceError
from flowcurve.rig.codecs import ProtocolError
from flowcurve.rig.codecs import aed
from flowcurve.rig.transport import SerialTransport

logger = logging.getLogger(__name__)

SETTING_RETRIES = 2  # ICR/ASF/COF/TAR are idempotent: safe to repeat
READ_RETRIES = 2
PERIOD_MARGIN = 1.01  # the stamps' chain steps 1 % longer than the nominal period (an AED crystal is within 0.01 %)
REALIGN_FRAMES = 8  # a garbled frame: the next frame boundary is looked for this many frames' bytes on
REALIGN_CHECK = {"ascii": 1, "binary4": 2, "binary2": 2}  # ... where this many good frames in a row line up
# (an ASCII frame parses or not; a binary one has only its CR LF, which a value's bytes can hold by chance)
LATENCY_HISTORY = 8  # good frames before a gap whose per-frame force change predicts the frame after it
LATENCY_NOISE_SIGMAS = 6.0  # the two predictions must differ by this many σ of a frame's change to be told apart
LATENCY_MIN_S = 0.2  # host s: a gap's extra time under this is taken as lost frames (a run of them at 100 Hz, or host jitter the chain heals; a latency that small costs little force)
LATENCY_FIT = 0.25  # ... and the step must lie within this share of their difference from one frame's change
LATENCY_SE_MARGIN = 2.0  # ... a latency even with the line off by this many of its extrapolation errors (step_rule_verdict)
LATENCY_BEND_CHI2 = 16.0  # ... and, for a gap longer than the frames' span, their line's χ²/dof against the force's noise under this
DEFER_FRAMES = 3  # a gap with too few good frames before it for the step rule: decided with this many frames after it
DEFER_CLEAR = 0.1  # ... the hypothesis that fits must leave under this share of the other's squared residual
DEFER_FIT = 0.25  # ... and its residual must be within this share of one frame's change times the gap's extra periods
DEFER_NOISE_FRAMES = 6  # ... the force's noise from the third differences of the loaded frames before the gap, where this many
DEFER_LOADED = 0.5  # a frame before the gap under this share of the first frame after it is before the elastic rise (off the curve)
STREAM_WRITER = "stream-rhythm-1"  # how this driver stamps the stream (the record header's writer.stamping)


def stream_stamps(arrival, period: float, last: float | None = None, margin: float = PERIOD_MARGIN):
    """Send times of a fixed-rate stream's frames from their arrival times, and the output
    periods each frame's gap spans — the *rhythm rule*::

        j_k = max(1, round((a_k − s_(k−1)) / T))        periods since the previous frame
        s_k = min(a_k, s_(k−1) + j_k · m · T)          its send time (no frame arrives before it is sent)

    ``arrival`` a_k (host seconds, strictly increasing: the driver back-dates a frame read from a
    burst by the frames buffered behind it), ``period`` T the configured output period, ``margin``
    m ≥ 1 + the device crystal's tolerance, ``last`` the previous frame's stamp (None: the stream
    starts, s_0 = a_0). AED frames carry no counter or stamp, so the gap in arrival is the only
    count of frames lost: m lost frames leave a gap of m + 1 periods in the stamps and never move a
    later one. A single late frame is stamped at most at its arrival and the next on-time frame
    heals the chain; a device crystal slower than nominal by less than m − 1 makes the chain run
    late, and the arrivals clip it (the stamp is never later than the arrival). Returns
    (stamps, periods) as arrays. Before the fix (``lower_envelope_stamps``) j_k was always 1: after
    a loss every later stamp stayed the lost periods too early.
    """
    a = np.asarray(arrival, dtype=float)
    stamps, spans = np.empty(a.size), np.ones(a.size, dtype=int)
    prev = last
    for k, ak in enumerate(a):
        if prev is None:
            stamps[k] = ak
        else:
            spans[k] = max(1, int(round((ak - prev) / period)))
            stamps[k] = min(ak, prev + spans[k] * margin * period)
        prev = stamps[k]
    return stamps, spans


def gap_is_latency(recent_periods, recent_N, next_N: float, periods: int, min_periods: int = 2) -> bool:
    """Whether a gap of ``periods`` output periods in arrival before the frame ``next_N`` is the
    line's latency growing (no frame lost: the next frame was sent one period after the last)
    rather than ``periods`` − 1 lost frames — the *step rule* (:func:`step_rule_verdict`) says
    "latency". Where the force changes too little to tell (under k·σ over the gap) the gap is taken
    as a loss: its stamps then err by the gap, but the force that error costs is within the noise. A
    step far from both (a fracture, a yield drop inside the gap) is a loss too, and so is a gap under
    ``min_periods`` (the driver: 1 + LATENCY_MIN_S of periods — a few frames lost in a row at a high
    rate, whose steps differ too little from one frame's change to tell; a latency that small costs
    as little). ``recent_periods``, ``recent_N``: stamps (in periods) and forces of the good frames
    before the gap (at least 4), oldest first."""
    return step_rule_verdict(recent_periods, recent_N, next_N, periods, min_periods) == "latency"


def step_rule_verdict(recent_periods, recent_N, next_N: float, periods: int, min_periods: int = 2) -> str | None:
    """The step rule: a line through the good frames before a gap of j = ``periods`` output periods::

        f ≈ a + b·x, σ the residual    fitted to the n good frames before the gap, x their stamps in
                                        periods from the last one (gaps among them are allowed)
        loss predicts next ≈ a + b·j, a latency jump next ≈ a + b;  apart = |(j − 1)·b|
        se = max over x ∈ {1, j} of σ·√(1/n + (x − x̄)²/Σ(x_i − x̄)²)   the line's extrapolation error
        latency ⇔ j ≥ min_periods, apart > k·σ  and  |next − a − b| + 2·se < LATENCY_FIT·apart
                  and, where j − 1 > x_n − x_1 (n ≥ 6), σ²/σ_n² < 16,  σ_n = med|Δ³f|/(0.6745·√20)
        loss    ⇔ j ≥ min_periods, apart > k·σ  and  |next − a − b·j| < LATENCY_FIT·apart

    k = LATENCY_NOISE_SIGMAS, 2 = LATENCY_SE_MARGIN, 16 = LATENCY_BEND_CHI2. "latency" moves every later
    stamp, so the frame must lie in its window even with the line off by twice its own extrapolation
    error over the gap: a force bending within the frames (the hardening slowing towards Fm) gives the
    line their mean slope, not the one at the gap, where a lost frame's step can fall near a + b
    (bench/stream_gap_rule.py measures both kinds of wrong verdict). Extrapolated beyond the frames' own
    span (a 0.5 s gap at 50 Hz), a line whose frames bend off it by more than the force's noise (the
    elastic rise's knee, the frames starting at standstill) is no measurement: no "latency". Else
    None — too few frames, σ swollen by a bending force (the elastic rise's knee, the hardening within
    the frames at 2 Hz), a frame far from both (the line's curvature or a fracture), or a latency the
    line cannot vouch for. The driver then decides on the frames after the gap
    (:func:`gap_after_verdict`); a gap under ``min_periods`` is a loss either way."""
    x, f = np.asarray(recent_periods, dtype=float), np.asarray(recent_N, dtype=float)
    if periods < max(2, min_periods) or f.size < 4:
        return None
    x = x - x[-1]
    b, a = np.polyfit(x, f, 1)  # f = a + b·x, least squares
    sigma = float(np.sqrt(np.sum((f - a - b * x) ** 2) / (f.size - 2)))
    apart = abs((periods - 1) * b)
    if apart <= LATENCY_NOISE_SIGMAS * sigma:
        return None
    sxx = float(np.sum((x - x.mean()) ** 2))
    se = sigma * math.sqrt(1.0 / f.size + max((1.0 - x.mean()) ** 2, (periods - x.mean()) ** 2) / sxx)
    if abs(next_N - a - b) + LATENCY_SE_MARGIN * se < LATENCY_FIT * apart:
        if periods - 1 > -x[0] and f.size >= 6:  # extrapolated beyond the frames' span: they must lie on their line
            noise = _noise_from_third_differences(f)
            if sigma * sigma >= LATENCY_BEND_CHI2 * max(noise * noise, 1e-12):
                return None
        return "latency"
    if abs(next_N - a - b * periods) < LATENCY_FIT * apart:
        return "loss"
    return None


def _noise_from_third_differences(f) -> float:
    """σ of a smooth force's noise from its third differences (median, robust to one knee among them):
    σ ≈ median |Δ³f| / (0.6745·√20) (Δ³ of white noise has variance 20·σ²)."""
    return float(np.median(np.abs(np.diff(np.asarray(f, dtype=float), 3))) / (0.6745 * math.sqrt(20.0)))


def _quadratic_residual(x, f) -> float:
    """Σ (f − q(x))² of the least-squares quadratic q through (x, f)."""
    return float(np.sum((f - np.polyval(np.polyfit(x, f, 2), x)) ** 2))


def gap_after_verdict(before_N, after_N, after_offsets, periods: int, noise_N: float = 0.0) -> str | None:
    """Whether a gap of ``periods`` output periods in arrival is the line's latency growing or
    ``periods`` − 1 lost frames, judged on the frames *after* it — the *deferred rule* for a gap
    with too few frames before it for :func:`gap_is_latency`::

        before: the last ≤ 2 loaded frames (|f| ≥ DEFER_LOADED·|f_a1|) at x_b = −(n_b − 1) … 0
        after:  x_a = s + after_offsets;  R(s) = Σ (f − q_s(x))², q_s the least-squares quadratic
        latency (s = 1) ⇔ R(1) < DEFER_CLEAR·R(j) and √R(1) < DEFER_FIT·d;   loss (s = j) symmetric
        d = (j − 1)·|b_a|, b_a the after-frames' least-squares change per period; |b_a| ≤ 6·σ_b: "noise"

    A smooth force lies on one quadratic across the gap only where the after-frames are placed at
    their true send times; placed one period off they leave a step of d. The elastic rise's knee is
    no part of a smooth curve: with no loaded frame before the gap, or only one (it may lie on the
    knee, whose step into the after-frames looks like a lost frame's), the gap is not called a loss;
    nor is one with a maximum among the frames (the force's change turns sign: Fm, a yield drop).
    Returns "latency", "loss", "noise" where the force changes within its noise across the gap (no
    evidence here; the later stamps' doubt costs force only where the force later changes faster:
    identify judges that on the record), or None where it cannot be told (the stamps after the gap
    are in doubt by the gap's extra periods). ``before_N``: forces of the good frames before the gap (≥ 1),
    ``after_N``: forces of the frames after it (≥ 2), ``after_offsets``: their periods after the
    first of them (0, 1, 2 … without further gaps), ``noise_N``: the force's noise σ (its resolution at least)."""
    b = np.asarray(before_N, dtype=float)
    g = np.asarray(after_N, dtype=float)
    k = np.asarray(after_offsets, dtype=float)
    if periods < 2 or b.size < 1 or g.size < 2:
        return "loss"
    spread = math.sqrt(float(np.sum((k - k.mean()) ** 2)))
    slope = float(np.polyfit(k, g, 1)[0]) if spread > 0 else 0.0  # the after-frames' change per period
    step = abs((periods - 1) * slope)  # d
    if abs(slope) * spread <= LATENCY_NOISE_SIGMAS * noise_N:  # |b| ≤ k·σ_b, σ_b = σ/√Σ(k − k̄)²
        return "noise"  # the force changes within its noise: no evidence either way here
    unloaded = np.flatnonzero(np.abs(b) < DEFER_LOADED * abs(g[0]))
    loaded = b.size - (unloaded[-1] + 1 if unloaded.size else 0)  # the loaded frames just before the gap
    if loaded == 0 or loaded + g.size < 4:
        return None
    if loaded >= DEFER_NOISE_FRAMES:  # the force's noise from its third differences: a plateau's gap is a loss within its noise
        noise_N = max(noise_N, _noise_from_third_differences(b[-loaded:][-LATENCY_HISTORY:]))
        if abs(slope) * spread <= LATENCY_NOISE_SIGMAS * noise_N:
            return "noise"
    b = b[-min(loaded, 2):]
    if np.ptp(np.sign(np.diff(np.concatenate([b, g])))) > 0:  # a maximum (Fm, a yield drop) within the frames: its
        return None  # curvature turns where the gap is, and neither placement is the smoother one
    xb, f = np.arange(1.0 - b.size, 1.0), np.concatenate([b, g])
    latency = _quadratic_residual(np.concatenate([xb, 1.0 + k]), f)
    loss = _quadratic_residual(np.concatenate([xb, periods + k]), f)
    if latency < DEFER_CLEAR * loss and math.sqrt(latency) < DEFER_FIT * step:
        return "latency"
    if loss < DEFER_CLEAR * latency and math.sqrt(loss) < DEFER_FIT * step and loaded >= 2:
        return "loss"
    return None


@dataclass(frozen=True)
class ForceSample:
    """One force reading: host monotonic time (the port's clock) — a streamed frame's send time on
    the stream's rhythm (:func:`stream_stamps`), a polled value's exchange midpoint — force, raw
    status byte and overload flag."""

    t_monotonic_s: float
    force_N: float
    status: int | None
    overload: bool
    counts: int


class LoadCell:
    """HBM AED-class load-cell amplifier.

    Give the calibration either as ``nominal_load_N`` (the force that reads nominal counts)
    or as ``calibration_N_per_count`` (newtons per count on the 4-byte binary scale, where
    nominal reads 5 120 000). ``raise_on_overload`` makes an overloaded reading raise
    :class:`DeviceError` instead of only flagging the sample.
    """

    probe_parities = ("E", "N", "O")  # rig check --probe: the AED's line settings

    def __init__(self, port_url, *, name: str = "load cell", address: int | None = 31,
                 calibration_N_per_count: float | None = None, nominal_load_N: float | None = None,
                 baudrate: int = 9600, parity: str = "E", timeout_s: float = 0.2,
                 output_format: int = 3, select_address: bool = False,
                 raise_on_overload: bool = False, output_rate_per_s: float | None = None,
                 opener=None):
        if (calibration_N_per_count is None) == (nominal_load_N is None):
            raise ValueError("give exactly one of calibration_N_per_count and nominal_load_N")
        if calibration_N_per_count is not None:
            nominal_load_N = calibration_N_per_count * aed.NOMINAL_COUNTS_4BYTE
        if not nominal_load_N > 0:
            raise ValueError(f"nominal load must be positive, got {nominal_load_N}")
        self.name = name
        self.address = address
        self.nominal_load_N = float(nominal_load_N)
        self.raise_on_overload = raise_on_overload
        self.select_address = select_address
        self.fmt = aed.output_format(output_format)
        if isinstance(port_url, SerialTransport):
            self.transport = port_url
        else:
            self.transport = SerialTransport(port_url, name=name, baudrate=baudrate, parity=parity,
                                             timeout_s=timeout_s, opener=opener)
        self.output_rate_per_s = output_rate_per_s  # set by configure(rate_code=...)
        self.nov = 0  # NOV scale, read by configure() / read_scale()
        self.streaming = False
        self.stream_silence_s = 1.0
        self.max_resyncs = 3  # stream restarts in a row before a garbled stream is an error
        self.stream_resyncs = 0  # restarts so far (for the record's warnings)
        self.frames_received = 0  # good stream frames since the first start_stream
        self.frames_garbled = 0  # frames skipped by realigning on the next frame (no restart)
        self._first_stamp: float | None = None
        self._last_stamp: float | None = None
        self._frames_skipped = 0  # frames_lost: the largest count of frames the stamps' span shows missing
        self._phase_known = False  # after a (re)start the stream's phase is new: the chain starts again
        self.latency_s = 0.0  # the line's latency grown since the stream started (gap_is_latency): arrivals less it
        self.latency_jumps = 0  # gaps taken as a latency jump, not lost frames
        self._recent_N: list[tuple[float, float]] = []  # the latest good frames' (stamp, force) (LATENCY_HISTORY)
        self._held: list[tuple[float, object, float]] = []  # (arrival, value, force) after a gap awaiting its verdict
        self._released: list[ForceSample] = []  # held frames stamped, for the next read_stream
        self.gaps_undecided: list[tuple[float, float]] = []  # (stamp before the gap, s in doubt): neither rule could tell
        self.gaps_in_doubt: list[tuple[float, float]] = []  # ... the force within its noise across it: taken as lost, unproven
        self._carry = b""  # bytes read past a realignment, framed next
        self._resyncs_in_a_row = 0
        self._last_frame_t = 0.0
        self._last_sample_t = -math.inf
        self._selected = False

    @classmethod
    def from_config(cls, section, **kw) -> "LoadCell":
        """The amplifier of a rig file's ``[loadcell]`` section (:class:`rig.config.LoadCellConfig`)."""
        return cls(section.port, address=section.address, nominal_load_N=section.nominal_load_N,
                   calibration_N_per_count=section.calibration_N_per_count,
                   output_format=section.output_format, select_address=section.select_address,
                   **section.transport_kwargs("load cell"), **kw)

    @staticmethod
    def supported_rates_Hz() -> tuple[float, ...]:
        """Output rates (values/s) by ``ICR`` rate code 0..7 (FMD0)."""
        return tuple(aed.ICR_RATES_PER_S)

    def resolution_N(self) -> float:
        """One count of the output format (the force's quantum, the noise σ's floor); 0 when unknown.
        Equation: nominal load / counts at the nominal load (ASCII: ``NOV`` when set)."""
        try:
            counts = self.nov if self.fmt.kind == "ascii" and self.nov > 0 else self.fmt.nominal_counts
            return float(self.nominal_load_N) / counts
        except (AttributeError, TypeError, ZeroDivisionError):
            return 0.0

    # -- life cycle -------------------------------------------------------------------
    def open(self) -> "LoadCell":
        """Open the port and select the amplifier's address; the load cell."""
        self.transport.open()
        if self.select_address and not self._selected and self.address is not None:
            self.transport.send(aed.command(f"S{self.address:02d}"))  # never answers
            self._selected = True
        return self

    def close(self) -> None:
        """Stop a running stream and close the port."""
        if self.transport.is_open and self.streaming:
            try:
                self.stop_stream()
            except DeviceError as exc:  # the port is closed next anyway
                logger.warning("%s: stopping the stream on close failed: %s", self.name, exc)
        self.transport.close()

    def __enter__(self) -> "LoadCell":
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    # -- exchanges --------------------------------------------------------------------
    def _query(self, text: str, *, retries: int = READ_RETRIES, parse=None, length=None):
        self._not_streaming(text)
        self.open()
        term = None if length else b"\r\n"
        return self.transport.exchange(aed.command(text), length=length, terminator=term,
                                       retries=retries, what=f"'{text}'", parse=parse)

    def _set(self, text: str, *, retries: int = SETTING_RETRIES) -> None:
        accepted = self._query(text, retries=retries, parse=aed.parse_ack)
        if not accepted:
            raise DeviceError(self.name, f"refused '{text}' (answered '?'; see ESR?)")

    def _not_streaming(self, text: str) -> None:
        if self.streaming:
            raise DeviceError(self.name, f"cannot send '{text}' while streaming (stop_stream first)")

    # -- commands ---------------------------------------------------------------------
    def answers(self) -> None:
        """One exchange that names the amplifier (``IDN?``); raises :class:`DeviceError` when silent."""
        self.identify()

    def check_lines(self, section) -> Iterator[str]:
        """What ``flowcurve rig check`` prints of the open amplifier: identity, settings (a note
        where they differ from the rig file's ``section``) and one reading in newtons."""
        idn = self.identify()
        yield f"  identity: {idn['manufacturer']} {idn['model']}, serial {idn['serial']}, firmware {idn['firmware']}"
        s = self.settings()
        rate = aed.ICR_RATES_PER_S[s["rate_code"]] if 0 <= s["rate_code"] < 8 else float("nan")
        cutoff = aed.ASF_CUTOFF_HZ.get(s["filter"])
        yield (f"  settings: {s['baud']} baud, parity {s['parity']}, COF{s['output_format']}, "
               f"ICR{s['rate_code']} ({rate:g} values/s), ASF{s['filter']} "
               f"({'off' if cutoff is None else f'{cutoff:g} Hz'})"
               + (f", NOV{s['nov']} (ASCII nominal = {s['nov']} counts)" if s["nov"] else ""))
        for key, want in (("output_format", section.output_format), ("rate_code", section.rate_code),
                          ("filter", section.filter)):
            if s[key] != want:
                yield f"  note: device has {key} {s[key]}, the configuration says {want} (set when a test starts)"
        self.fmt = aed.output_format(s["output_format"])  # read in the device's present format
        sample = self.read()
        flag = "  OVERLOAD" if sample.overload else ""
        yield (f"  reading: {sample.force_N:.1f} N ({sample.counts} counts"
               f"{'' if sample.status is None else f', status {sample.status:#04x}'}){flag}")

    def identify(self) -> dict[str, str]:
        """``IDN?`` → manufacturer, model, serial, firmware."""
        return self._query("IDN?", parse=aed.parse_idn)

    def settings(self) -> dict[str, object]:
        """Read back baud/parity, output format, rate and filter codes."""
        baud, parity = self._query("BDR?", parse=aed.parse_baud)
        return {"baud": baud, "parity": parity,
                "output_format": self._query("COF?", parse=aed.parse_int_reply),
                "rate_code": self._query("ICR?", parse=aed.parse_int_reply),
                "filter": self._query("ASF?", parse=aed.parse_int_reply),
                "nov": self.read_scale()}

    def read_scale(self) -> int:
        """``NOV?``: the ASCII count of nominal load (0 = factory 1 000 000), kept for scaling.

        An amplifier that refuses the query is taken to be at the factory scale.
        """
        reply = self._query("NOV?")
        self.nov = 0 if reply.strip() == b"?" else aed.parse_int_reply(reply)
        if self.nov < 0:
            raise DeviceError(self.name, f"NOV? answered {self.nov}, not a count")
        return self.nov

    def configure(self, *, rate_code: int | None = None, filter: int | None = None,
                  fmt: int | None = None) -> None:
        """Set the output rate (``ICR0..7``), the filter (``ASF0..8``) and the format (``COF``);
        then read the ``NOV`` scale the force conversion needs."""
        if rate_code is not None:
            if rate_code not in range(len(aed.ICR_RATES_PER_S)):
                raise ValueError(f"rate code must be 0..7, got {rate_code}")
            self._set(f"ICR{rate_code}")
            self.output_rate_per_s = aed.ICR_RATES_PER_S[rate_code]
        if filter is not None:
            if filter not in aed.ASF_CUTOFF_HZ:
                raise ValueError(f"filter must be 0..8, got {filter}")
            self._set(f"ASF{filter}")
        if fmt is not None:
            new = aed.output_format(fmt)
            self._set(f"COF{fmt}")
            self.fmt = new
        self.read_scale()  # a NOV left set by someone would scale ASCII forces wrongly

    def tare(self) -> None:
        """``TAR``: take the present load as zero (switches to net)."""
        self._set("TAR")

    def read(self) -> ForceSample:
        """One ``MSV?`` measured value as a :class:`ForceSample`, stamped at the middle of the
        exchange (its request and reply bracket the measurement)."""
        asked = self.transport.clock.now()
        frame = self._query("MSV?", length=self.fmt.frame_length, parse=self._check_frame)
        return self._sample(frame, 0.5 * (asked + self.transport.clock.now()))

    def _check_frame(self, frame: bytes) -> bytes:
        aed.decode_msv(frame, self.fmt)  # raises ProtocolError (a ValueError) → retried
        return frame

    def _sample(self, frame: bytes, t: float) -> ForceSample:
        try:
            value = aed.decode_msv(frame, self.fmt)
        except ProtocolError as exc:
            raise DeviceError(self.name, f"garbled measured value: {exc}") from None
        return self._to_sample(value, t)

    def _force_N(self, value: aed.MeasuredValue) -> float:
        return float(aed.counts_to_newtons(value.counts, self.fmt, self.nominal_load_N, self.nov))

    def _to_sample(self, value: aed.MeasuredValue, t: float) -> ForceSample:
        force = self._force_N(value)
        sample = ForceSample(t, force, value.status, value.overflow, value.counts)
        if sample.overload and self.raise_on_overload:
            raise DeviceError(self.name, f"overload: status {value.status:#04x}, {force:.0f} N")
        return sample

    def recover_line(self, bauds=aed.BAUD_RATES, parities=("E", "N")) -> dict[str, str]:
        """Bring an amplifier left at an unknown baud rate back to this driver's line settings.

        docs/protocols.md: send ``;S98;BDR<rate>,<parity>;`` at each rate in turn (``S98``
        addresses every unit, so a wrong address does not matter either), then select this
        unit (``S<address>``) at the wanted rate and ask ``IDN?``. Returns the identity.
        """
        if self.streaming:
            raise DeviceError(self.name, "cannot recover the line while streaming")
        baud, parity = self.transport.settings["baudrate"], self.transport.settings["parity"]
        if parity not in aed.PARITY_CODES:
            raise ValueError(f"the AED line has parity E or N, not {parity!r}")
        command = f";S98;BDR{baud},{aed.PARITY_CODES[parity]};".encode("ascii")
        self.transport.close()
        for trial_baud in bauds:
            for trial_parity in parities:
                with self.transport.with_line(baudrate=trial_baud, parity=trial_parity) as trial:
                    trial.send(command)
                    trial.clock.sleep(len(command) * 11 / trial_baud)  # let it leave the UART
        self.transport.open()
        if self.address is not None:
            self.transport.send(aed.command(f"S{self.address:02d}"))  # leave broadcast mode
        return self.identify()

    # -- continuous measurement -------------------------------------------------------
    def start_stream(self) -> None:
        """``MSV?0``: the amplifier sends values continuously until ``STP``."""
        self._not_streaming("MSV?0")
        self.open()
        self.transport.discard_input()
        self._carry = b""
        self.transport.send(aed.command("MSV?0"))
        self.streaming = True
        self._phase_known = False  # a new stream: its frames keep a new phase
        self._last_frame_t = self.transport.clock.now()

    def read_stream(self, max_samples: int, timeout: float) -> list[ForceSample]:
        """Up to ``max_samples`` frames (by length) arriving within ``timeout`` seconds.

        Returns early when ``max_samples`` are in; a frame cut by the deadline stays
        buffered for the next call, so framing never slips. Each sample is stamped with its
        send time on the stream's rhythm (:func:`stream_stamps` over its arrival, back-dated by
        one output period per complete frame still buffered behind it): a lost, garbled or
        skipped frame leaves a gap in the stamps and never moves a later one. A frame that
        fails its check (a lost or extra byte: no CR LF where one is due) costs that frame:
        the stream is realigned on the next frame boundary where good frames line up (:meth:`_realign`); only when none does within :data:`REALIGN_FRAMES`
        frames is the stream restarted (``STP``, ``MSV?0``) — formats without CR LF (+32)
        cannot be checked. More than ``max_resyncs`` restarts in a row, or a stream silent
        for more than ``stream_silence_s``, raise DeviceError.
        """
        if not self.streaming:
            raise DeviceError(self.name, "read_stream without start_stream")
        deadline = self.transport.clock.now() + timeout
        samples: list[ForceSample] = []
        while len(samples) < max_samples:
            remaining = deadline - self.transport.clock.now()
            if remaining <= 0:
                break
            try:
                frame = self._next_frame(remaining)
            except DeviceError:
                if not self.transport.is_open:  # the port disappeared
                    raise
                break
            now = self.transport.clock.now()
            try:
                value = aed.decode_msv(frame, self.fmt)
            except ProtocolError as exc:
                self._realign(frame, exc)
                continue
            self._resyncs_in_a_row = 0
            self.frames_received += 1
            force_N = self._force_N(value)
            self._last_frame_t = now
            self._hold_or_stamp(self._stream_time(now), value, force_N)  # its send time on the stream's rhythm
            samples += self._released
            self._released = []
        samples += self._released  # held frames a restart released
        self._released = []
        silent = self.transport.clock.now() - self._last_frame_t
        if not samples and silent > self.stream_silence_s:
            raise DeviceError(self.name, f"stream ('MSV?0') silent for {silent:.1f} s")
        return samples

    @property
    def frames_lost(self) -> int:
        """Frames the amplifier sent that did not arrive good (lost on the line, garbled, skipped
        by the amplifier or a restart): the output periods between the first and the latest good
        frame's stamp (:func:`stream_stamps`), plus one, less the frames received. A late frame
        does not count (the next one heals the span). The count never goes down, so the events,
        the header and the operator's alert that read it at different times tell one number."""
        return self._frames_skipped

    def _next_frame(self, timeout: float) -> bytes:
        """The next frame's bytes by length (first what a realignment read past)."""
        n = self.fmt.frame_length
        if len(self._carry) >= n:
            frame, self._carry = self._carry[:n], self._carry[n:]
            return frame
        frame = self._carry + self.transport.read_exactly(n - len(self._carry), timeout, what="'MSV?0' stream")
        self._carry = b""
        return frame

    def _realign(self, bad: bytes, exc: ProtocolError) -> None:
        """A garbled frame costs that frame: go on from the first place after its start where
        :data:`REALIGN_CHECK` frames in a row decode, within :data:`REALIGN_FRAMES` frames' bytes.
        An ASCII frame parses or not, so any byte may start one; a binary frame is only its bytes
        and a CR LF, so it may start only right after a CR LF (the garbled frame's own, or the next
        frame's when that one was hit): the remnant of a frame with a byte too many also ends in
        CR LF and would pass for a frame. None lines up (the bytes stay unreadable, or the stream
        stalls meanwhile): restart the stream."""
        n, check = self.fmt.frame_length, REALIGN_CHECK[self.fmt.kind]
        ascii_frames = self.fmt.kind == "ascii"
        buf = bad + self._carry
        self._carry = b""
        period = 1.0 / self.output_rate_per_s if self.output_rate_per_s else 0.0
        wait_s = self.transport.timeout_s + (REALIGN_FRAMES + check) * period
        for offset in range(1, REALIGN_FRAMES * n + 1):
            need = offset + check * n
            if len(buf) < need:
                try:
                    buf += self.transport.read_exactly(need - len(buf), wait_s, what="'MSV?0' stream")
                except DeviceError:
                    if not self.transport.is_open:
                        raise
                    break
            if not ascii_frames and buf[offset - 2:offset] != aed.CRLF:
                continue
            if all(self._decodes(buf[offset + i * n: offset + (i + 1) * n]) for i in range(check)):
                self._carry = buf[offset:]
                self.frames_garbled += 1
                logger.info("%s: garbled frame (%s): realigned %d bytes on", self.name, exc, offset)
                return
        self._resync(exc)

    def _decodes(self, frame: bytes) -> bool:
        try:
            aed.decode_msv(frame, self.fmt)
        except ProtocolError:
            return False
        return True

    def _period_s(self) -> float:
        return 1.0 / self.output_rate_per_s

    def _resync(self, exc: ProtocolError) -> None:
        self.stream_resyncs += 1
        self._resyncs_in_a_row += 1
        logger.info("%s: garbled stream (%s), restarting it (%d in a row)", self.name, exc, self._resyncs_in_a_row)
        if self._resyncs_in_a_row > self.max_resyncs:
            raise DeviceError(self.name, f"garbled stream: {self._resyncs_in_a_row} restarts in a row "
                                         f"did not regain the framing ({exc})")
        self.release_held()  # frames held before the restart keep the old phase
        self.stop_stream()
        self.start_stream()

    def _stream_time(self, now: float) -> float:
        # a frame read while later ones already wait in the buffer arrived earlier: back-date
        # it by one output period per complete frame behind it (a burst read at once keeps
        # its spacing); never before the previous sample
        t = now
        if self.output_rate_per_s:
            behind = (self.transport.buffered() + len(self._carry)) // self.fmt.frame_length
            t -= behind / self.output_rate_per_s
        t = max(t, self._last_sample_t + 1e-6)
        self._last_sample_t = t
        return t

    def _stamp(self, arrival: float, force_N: float | None = None) -> float:
        """The frame's send time on the stream's rhythm (:func:`stream_stamps`, one step), less the
        line's latency; a gap the force shows to be latency (:func:`gap_is_latency`) grows
        :attr:`latency_s` instead of counting lost frames. The frames missing from the stamps' span
        so far update :attr:`frames_lost`."""
        arrival -= self.latency_s
        if not self.output_rate_per_s or self._last_stamp is None or not self._phase_known:
            t = arrival  # the stream (re)started: a new phase, the chain starts at this arrival
            self._recent_N.clear()
        else:
            period = self._period_s()
            if self.latency_s > 0 and arrival < self._last_stamp + 0.5 * period:  # the latency shrank again
                shrunk = min(self.latency_s, self._last_stamp + period - arrival)
                self.latency_s -= shrunk
                arrival += shrunk
            periods = max(1, int(round((arrival - self._last_stamp) / period)))
            if force_N is not None and gap_is_latency([t / period for t, _ in self._recent_N], [f for _, f in self._recent_N],
                                                      force_N, periods, 1 + math.ceil(LATENCY_MIN_S / period)):
                grown = arrival - (self._last_stamp + period)
                self.latency_s += grown
                self.latency_jumps += 1
                arrival -= grown
                logger.info("%s: the stream's arrivals jumped %.3f s with one frame's force change: "
                            "latency, not lost frames (now %.3f s)", self.name, grown, self.latency_s)
            t = float(stream_stamps([arrival], self._period_s(), last=self._last_stamp)[0][0])
        self._phase_known = True
        if force_N is not None:
            self._recent_N = (self._recent_N + [(t, force_N)])[-LATENCY_HISTORY:]
        self._first_stamp = t if self._first_stamp is None else self._first_stamp
        self._last_stamp = t
        if self.output_rate_per_s:
            sent = round((t - self._first_stamp) * self.output_rate_per_s) + 1
            self._frames_skipped = max(self._frames_skipped, sent - self.frames_received)
        return t

    def _hold_or_stamp(self, arrival: float, value, force_N: float) -> None:
        """Stamp the frame into :attr:`_released`, or hold it: a gap the step rule cannot judge (fewer
        than 4 good frames before it, or a bending force) waits for :data:`DEFER_FRAMES` frames after it
        (:meth:`release_held` decides it with :func:`gap_after_verdict`)."""
        if self._held:
            self._held.append((arrival, value, force_N))
            if len(self._held) >= DEFER_FRAMES:
                self.release_held()
            return
        if self._gap_awaits_frames_after(arrival, force_N):
            self._held = [(arrival, value, force_N)]
            return
        self._released.append(self._to_sample(value, self._stamp(arrival, force_N)))

    def _gap_awaits_frames_after(self, arrival: float, force_N: float) -> bool:
        """Whether a frame arriving at ``arrival`` ends a gap the step rule would judge but cannot
        (:func:`step_rule_verdict`: fewer than 4 frames before it, a force that bends within them, or
        a frame after it near neither prediction)."""
        if not self.output_rate_per_s or self._last_stamp is None or not self._phase_known or not self._recent_N:
            return False
        period = self._period_s()
        periods = int(round((arrival - self.latency_s - self._last_stamp) / period))
        min_periods = 1 + math.ceil(LATENCY_MIN_S / period)
        if periods < max(2, min_periods):
            return False
        return step_rule_verdict([t / period for t, _ in self._recent_N], [f for _, f in self._recent_N], force_N, periods,
                                 min_periods) is None

    def release_held(self) -> list[ForceSample]:
        """Decide the held gap with the frames after it (:func:`gap_after_verdict`) and stamp them: a
        latency grows :attr:`latency_s` by the gap's extra time, a loss leaves the gap in the stamps;
        a gap neither fits is stamped as a loss and noted in :attr:`gaps_undecided`, one across which
        the force stays within its noise in :attr:`gaps_in_doubt`. Returns (and
        keeps for the next :meth:`read_stream`) the stamped samples."""
        held, self._held = self._held, []
        if held:
            period = self._period_s()
            first = held[0][0] - self.latency_s
            periods = max(1, int(round((first - self._last_stamp) / period)))
            offsets = [round((a - held[0][0]) / period) for a, _, _ in held]
            verdict = gap_after_verdict([f for _, f in self._recent_N], [f for *_, f in held], offsets, periods,
                                        self.resolution_N())
            if verdict == "latency":
                grown = first - (self._last_stamp + period)
                self.latency_s += grown
                self.latency_jumps += 1
                logger.info("%s: the frames after a %d-period gap lie on the force's curve at one period each: latency, "
                            "not lost frames (now %.3f s)", self.name, periods, self.latency_s)
            elif verdict == "noise":
                self.gaps_in_doubt.append((self._last_stamp, (periods - 1) * period))
            elif verdict is None:
                self.gaps_undecided.append((self._last_stamp, (periods - 1) * period))
                logger.warning("%s: a %d-period gap in the stream could be %d lost frames or the line's latency "
                               "growing: stamped as lost", self.name, periods, periods - 1)
            for arrival, value, force_N in held:
                self._released.append(self._to_sample(value, self._stamp(arrival, force_N)))
        return self._released

    def flush_held(self) -> list[ForceSample]:
        """At the stream's end: the held frames decided with what came (:meth:`release_held`), and every
        stamped frame not yet returned."""
        self.release_held()
        out, self._released = self._released, []
        return out

    def stop_stream(self) -> None:
        """``STP`` (never answers), then discard the frames still in flight."""
        self.transport.send(aed.command("STP"))
        self.streaming = False
        self.transport.clock.sleep(min(0.05, self.transport.timeout_s))
        self.transport.discard_input()
        self._carry = b""
