"""Synthetic tension records drawn by hypothesis, with their truth in closed form.

The material: a hardening law (Johnson–Cook, Swift or Voce) from the yield stress σy on, linear
elastic below it, optionally an upper yield point and a Lüders plateau before hardening starts.
True stress → engineering at constant volume (e = exp(εp + σ/E) − 1, s = σ/(1 + e)); after the
force maximum the force falls (neck) to the fracture, or the record stops early. The strain
channel is an extensometer or the crosshead (frame compliance and a toe added); it is read in
quanta; the force carries Gaussian noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from hypothesis import strategies as st
from scipy.optimize import brentq

from flowcurve.identification.laws.hardening import johnson_cook_static, swift, voce
from flowcurve.record.format import Record

D0_MM, L0_MM, FRAME_N_PER_UM = 6.0, 30.0, 136.0


@dataclass
class Truth:
    E_MPa: float
    law: object  # callable εp (from the start of hardening) → true stress, MPa
    hardening_start: float  # εp where the law starts (after a plateau)
    Rp02_MPa: float | None  # engineering, closed form (None with a plateau: ReL applies)
    ReH_MPa: float | None
    ReL_MPa: float | None
    uniform_plastic_strain: float  # εp at the force maximum of the record
    Rm_MPa: float  # max recorded force / S0
    elastic_samples: int
    noise_MPa: float
    sample_step_MPa: float  # the stress change over one plastic sample at Rp0.2 (the curve is drawn at Δεp = 0.001)


class HypothesisPick:
    """The choices of :func:`tension_record` drawn by hypothesis (shrinkable, its database's examples)."""

    def __init__(self, draw):
        self.draw = draw

    def floats(self, lo: float, hi: float) -> float:
        return self.draw(st.floats(lo, hi))

    def integers(self, lo: int, hi: int) -> int:
        return self.draw(st.integers(lo, hi))

    def booleans(self) -> bool:
        return self.draw(st.booleans())

    def sampled_from(self, options: list):
        return self.draw(st.sampled_from(options))


class SeededPick:
    """The same choices from numpy's generator: a population that is one and the same on every
    machine and hypothesis version (the coverage campaign judges shares of it)."""

    def __init__(self, seed: int):
        self.rng = np.random.default_rng(seed)

    def floats(self, lo: float, hi: float) -> float:
        return float(self.rng.uniform(lo, hi))

    def integers(self, lo: int, hi: int) -> int:
        return int(self.rng.integers(lo, hi, endpoint=True))

    def booleans(self) -> bool:
        return bool(self.rng.integers(0, 2))

    def sampled_from(self, options: list):
        return options[int(self.rng.integers(0, len(options)))]


@st.composite
def tension_records(draw):
    """(Record, Truth, description) of one tension test drawn by hypothesis."""
    return tension_record(HypothesisPick(draw))


def seeded_tension_record(seed: int):
    """(Record, Truth, description) of one tension test drawn from numpy's generator with ``seed``."""
    return tension_record(SeededPick(seed))


def tension_record(pick):
    """(Record, Truth, description) of one tension test whose choices ``pick`` makes
    (floats, integers, booleans, sampled_from)."""
    E = pick.floats(150_000.0, 220_000.0)
    sy = pick.floats(200.0, 1200.0)
    law_name = pick.sampled_from(["johnson_cook", "swift", "voce"])
    if law_name == "johnson_cook":
        B, n = pick.floats(0.3, 2.0) * sy, pick.floats(0.1, 0.6)
        law = lambda ep: johnson_cook_static(ep, sy, B, n)  # noqa: E731
    elif law_name == "swift":
        n, e0 = pick.floats(0.1, 0.3), pick.floats(0.002, 0.02)
        law = lambda ep: swift(ep, sy / e0**n, e0, n)  # noqa: E731
    else:
        Q, b = pick.floats(0.2, 1.0) * sy, pick.floats(5.0, 40.0)
        law = lambda ep: voce(ep, sy, Q, b)  # noqa: E731
    n_el = pick.integers(3, 50)
    plateau = pick.booleans()
    drop = pick.floats(0.03, 0.08) if plateau else 0.0
    ae = pick.floats(0.005, 0.02) if plateau else 0.0
    channel = pick.sampled_from(["extensometer", "crosshead"])
    toe_mm = pick.sampled_from([0.0, 0.02, 0.08]) if channel == "crosshead" else 0.0
    quantum_mm = pick.sampled_from([0.0, 0.0005, 0.001] if channel == "extensometer" else [0.0, 0.001, 0.01])
    noise_frac = pick.sampled_from([0.0, 0.0005, 0.002, 0.005])
    early_stop = pick.sampled_from([None, 0.3, 0.6, 0.9])
    seed = pick.integers(0, 2**16)
    description = dict(law=law_name, sy=round(sy), E=round(E), n_el=n_el, plateau=plateau, channel=channel, toe=toe_mm,
                       quantum=quantum_mm, noise=noise_frac, early_stop=early_stop)

    # true curve: elastic samples, (upper yield point, plateau), hardening
    s_el = np.linspace(0.0, sy * (1 + drop) * 0.999, n_el + 1)
    ep_el = np.zeros_like(s_el)
    parts_s, parts_ep = [s_el], [ep_el]
    start = 0.0
    if plateau:
        ep_pl = np.linspace(1e-5, ae, max(20, int(ae / 2e-4)))
        parts_s.append(np.full_like(ep_pl, sy)), parts_ep.append(ep_pl)
        start = ae
    ep_h = np.linspace(start + 1e-5, start + 0.6, 600)
    parts_s.append(law(ep_h - start)), parts_ep.append(ep_h)
    sig = np.concatenate(parts_s)
    ep = np.concatenate(parts_ep)
    eps = ep + sig / E
    e = np.expm1(eps)
    s_eng = sig / (1 + e)
    i_m = int(np.argmax(s_eng[n_el + 1:])) + n_el + 1
    if plateau and i_m <= n_el + 1 + 20:  # no hardening beyond the plateau: keep the test well posed
        i_m = n_el + 1 + 20 + 5
    s_eng, e, ep, sig = s_eng[: i_m + 1], e[: i_m + 1], ep[: i_m + 1], sig[: i_m + 1]
    if early_stop is not None:
        keep = n_el + 1 + max(3, int(early_stop * (i_m - n_el)))
        s_eng, e, ep, sig = s_eng[:keep], e[:keep], ep[:keep], sig[:keep]
    else:  # neck: the force falls by 25 % over 30 samples, then fracture
        tail = s_eng[-1] * np.linspace(1.0, 0.75, 31)[1:]
        s_eng = np.concatenate([s_eng, tail])
        e = np.concatenate([e, e[-1] + np.linspace(0, 0.05, 31)[1:]])
    s0 = math.pi * D0_MM**2 / 4
    force = s_eng * s0
    rng = np.random.default_rng(seed)
    force_rec = force + rng.normal(0, noise_frac * float(np.max(force)), force.size) * (np.arange(force.size) > 0)
    disp = e * L0_MM
    data = {"time_s": np.arange(force.size) * 0.1, "force_N": force_rec}
    meta = {"test": "tension", "specimen.d0_mm": repr(D0_MM), "specimen.l0_mm": repr(L0_MM)}
    if channel == "extensometer":
        data["extensometer_mm"] = _quantize(disp, quantum_mm)
        data["crosshead_mm"] = disp
        meta["specimen.extensometer_gauge_mm"] = repr(L0_MM)
    else:
        P = np.clip(force, 0, None)
        seat = toe_mm * (1 - np.clip(1 - P / (0.1 * np.max(P)), 0, 1) ** 2)
        data["crosshead_mm"] = _quantize(disp + P / (FRAME_N_PER_UM * 1000) + seat, quantum_mm)
        meta["rig.frame_stiffness_N_per_um"] = repr(FRAME_N_PER_UM)
        meta["specimen.parallel_length_mm"] = repr(L0_MM)  # the crosshead stretches L0 (disp = e·L0): Lc = L0
    record = Record(meta=meta, data=pd.DataFrame(data), source="drawn.csv")
    truth = Truth(E_MPa=E, law=law, hardening_start=start,
                  Rp02_MPa=None if plateau else rp02_closed_form(law, E, sy),
                  ReH_MPa=float(s_eng[n_el]) if plateau else None, ReL_MPa=float(np.min(s_eng[n_el + 1: n_el + 1 + parts_ep[1].size])) if plateau else None,
                  uniform_plastic_strain=float(ep[min(i_m, ep.size - 1)]), Rm_MPa=float(np.max(force_rec)) / s0,
                  elastic_samples=n_el, noise_MPa=noise_frac * float(np.max(force)) / s0,
                  sample_step_MPa=float(law(0.003) - law(0.002)))
    return record, truth, description


def _quantize(x, quantum):
    return np.round(x / quantum) * quantum if quantum else x


def rp02_closed_form(law, E, sy) -> float:
    """Engineering stress where e − s/E = 0.002 on the drawn curve (root on εp, closed form)."""
    def g(ep):
        sig = float(law(ep))
        e = math.expm1(ep + sig / E)
        return e - sig / (1 + e) / E - 0.002
    ep = brentq(g, 0.0, 0.01)
    sig = float(law(ep))
    return sig / (1 + math.expm1(ep + sig / E))
