"""Look-alikes of issue 43's held-out CalculiX upsetting record (12Kh18N12M3TL, toe, μ 0.15, frame
136 N/µm, no material.E_MPa): the CalculiX run of the vendored ``tests/fe/data/other_settings_C1.csv``
(A 105, B 1392, n 0.642, E 194 GPa, μ 0.15 — the held-out record's specimen and law) taken off its
rig and put on a rig with a softer seating toe, without the handbook E and under a GOST grade name.

The specimen's shortening is read back from the vendored record, s = x − toe(F) − F/C (its own rig:
toe 0.02·(1 − e^(−F/100 N)) mm, C 136 N/µm, the force averaged over 5 samples against its 15 N
noise), and :func:`second_model.write_record` writes it again with ``toe_mm``·(1 − e^(−F/``toe_force_N``)).
The truth stays in the header (``fe2.*``). Made by::

    cd tests/uncertainty && python lookalikes.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "fe"))

import second_model as sm  # noqa: E402

from flowcurve.record.format import amend_record, read_record  # noqa: E402

SOURCE = HERE.parent / "fe" / "data" / "other_settings_C1.csv"
# name → (toe mm, toe force N): the mild toe leaves an apparent slope of about 50 GPa, the long one about 26 GPa
TOES = {"upsetting_12Kh18N12M3TL_toe20": (0.02, 1000.0), "upsetting_12Kh18N12M3TL_toe50": (0.05, 1000.0)}
GRADE = "12Kh18N12M3TL"


def run_from_record(path: Path, *, toe_mm: float = 0.02, toe_force_N: float = 100.0) -> sm.SecondRun:
    """The specimen's loading (shortening, force) and unloaded shape read back off a second-model record."""
    rec = read_record(path)
    m = rec.meta
    case = sm.Case(m["specimen.id"], *(float(m[f"fe2.{k}"]) for k in ("A_MPa", "B_MPa", "n")), float(m["material.E_MPa"]),
                   float(m["fe2.mu"]), float(m["specimen.d0_mm"]), float(m["specimen.h0_mm"]), float(m["post.hk_mm"]))
    force, cross = -rec.column("force_N"), -rec.column("crosshead_mm")
    end = int(np.argmax(cross))
    force, cross = force[: end + 1], cross[: end + 1]
    smooth = np.convolve(force, np.ones(5) / 5.0, mode="same")
    smooth[:2], smooth[-2:] = force[:2], force[-2:]
    stiffness = float(m["rig.frame_stiffness_N_per_um"]) * 1000.0
    s = np.maximum.accumulate(cross - toe_mm * -np.expm1(-np.clip(smooth, 0.0, None) / toe_force_N) - smooth / stiffness)  # x = s + toe(F) + F/C
    keep = np.r_[True, np.diff(s) > 0]
    s, smooth = s[keep], smooth[keep]
    return sm.SecondRun(case=case, stroke_mm=s[1:], force_N=smooth[1:], height_mm=case.h0_mm - float(s[-1]), hk_mm=float(m["post.hk_mm"]),
                        dmax_mm=float(m["post.dmax_mm"]), dface_mm=float(m["post.dface_mm"]), solver_s=0.0)


def write_lookalike(path: Path, toe_mm: float, toe_force_N: float) -> Path:
    """The held-out record's look-alike: C1 on a rig with this toe, no material.E_MPa, a GOST grade name."""
    sm.write_record(run_from_record(SOURCE), path, toe_mm=toe_mm, toe_force_N=toe_force_N)
    amend_record(path, {"material": GRADE, "material.E_MPa": None, "fe2.E_MPa": "194000.0",
                        "fe2.rig": f"toe {toe_mm:g}*(1 - exp(-F/{toe_force_N:g} N)) mm, frame 136 N/um, 15 N noise, 1 um counts, 10 Hz"})
    return path


if __name__ == "__main__":
    for name, (toe, force) in TOES.items():
        write_lookalike(HERE / "data" / f"{name}.csv", toe, force)
