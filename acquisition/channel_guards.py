"""The plausibility guard each channel of a test gets (:class:`~flowcurve.acquisition.plausibility.RateGuard`),
its limits from the rig: force rises at most at frame stiffness × speed, the crosshead moves at most at its
speed (both × :data:`SPEED_MARGIN`), a furnace's thermocouple at most :data:`FURNACE_MAX_RATE_C_PER_S`."""

from __future__ import annotations

from flowcurve.acquisition.plausibility import RateGuard

SPEED_MARGIN = 2.0  # readings may change at up to this multiple of the declared speed's rate
FORCE_TOLERANCE_OF_CAPACITY = 0.01  # plus this fraction of the frame's capacity (noise, a jerk)
FORCE_SPIKE_SIGMAS = 8.0  # ... and a one-sample spike at any size: this many of the signal's own noise σ (plausibility)
CROSSHEAD_TOLERANCE_MM = 0.05
FURNACE_MAX_RATE_C_PER_S = 10.0  # a furnace's thermocouple changes no faster than this ...
FURNACE_TOLERANCE_C = 20.0  # ... plus this (noise, a draught)
STAMP_SLACK_S = 0.05  # host seconds two time stamps may be off by (thread scheduling)
DEFAULT_CAPACITY_N = 100e3  # a frame that states none


def force_guard(device: str, *, speed_mm_per_s: float, frame_stiffness_N_per_um: float, capacity_N: float | None,
                time_scale: float, period_s: float, resolution_N: float) -> RateGuard:
    """The load cell's guard: rate ``frame stiffness × speed × SPEED_MARGIN`` (N per test second), tolerance 1 % of
    the capacity, falls freely (a fracture), one-sample spikes against the signal's noise (floor: one count,
    ``resolution_N``); time stamps uncertain by the host's slack or two frame periods (``period_s``, host s), in
    test seconds (× ``time_scale``)."""
    return RateGuard(device, max_rate=frame_stiffness_N_per_um * 1000.0 * speed_mm_per_s * SPEED_MARGIN,
                     tolerance=FORCE_TOLERANCE_OF_CAPACITY * (capacity_N or DEFAULT_CAPACITY_N), unit="N",
                     falls_freely=True, advice="check the amplifier, its cable and the load cell",
                     time_slack=max(STAMP_SLACK_S, 2.0 * period_s) * time_scale,
                     spike_sigmas=FORCE_SPIKE_SIGMAS, noise_floor=resolution_N)


def install_guards(sampler, rig, speed_mm_per_s: float) -> None:
    """Give ``sampler``'s force, temperature and crosshead channels their guards (the module docstring); the force
    only where the rig states its frame's stiffness."""
    slack = STAMP_SLACK_S * rig.time_scale  # stamps are host times: jitter scales with the rig's time
    force = sampler.channels.get("force_N")
    if force is not None and (rig.frame_stiffness_N_per_um or 0.0) > 0:
        force.guard = force_guard(force.device, speed_mm_per_s=speed_mm_per_s, frame_stiffness_N_per_um=rig.frame_stiffness_N_per_um,
                                  capacity_N=getattr(rig, "max_force_N", None), time_scale=rig.time_scale,
                                  period_s=rig.loadcell_period_s, resolution_N=_force_resolution_N(rig))
    temp = sampler.channels.get("temperature_C")
    if temp is not None:
        temp.guard = RateGuard(temp.device, max_rate=FURNACE_MAX_RATE_C_PER_S, tolerance=FURNACE_TOLERANCE_C, unit="C",
                               advice="check the thermocouple and its cable", time_slack=slack)
    cross = sampler.channels.get("crosshead_mm")
    if cross is not None:
        cross.guard = RateGuard(cross.device, max_rate=speed_mm_per_s * SPEED_MARGIN, tolerance=CROSSHEAD_TOLERANCE_MM, unit="mm",
                                advice="the counter lost or gained counts: check the encoder and its cable", time_slack=slack)


def _force_resolution_N(rig) -> float:
    """One count of the load cell's output format (the noise σ's floor), 0 when unknown."""
    cell = getattr(rig, "loadcell", None)  # a ForceDevice (rig/roles.py)
    return float(cell.resolution_N()) if cell is not None and hasattr(cell, "resolution_N") else 0.0
