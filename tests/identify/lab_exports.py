"""Tension records written the way other labs' software writes them, from a known curve.

The curve: engineering stress s and strain e of a Ramberg–Osgood material,
e = s/E + 0.002·(s/Rp)^N, rising to Rm, then a falling neck branch and a fracture drop.
By construction Rp0.2 = Rp (the plastic part is 0.2 % exactly at s = Rp), E is E, and
Rm = max force / S0, so results can be checked against values obtained without flowcurve.

Writers (layouts as the vendors' exports are laid out, not as flowcurve writes records):

* :func:`write_bluehill` — Instron Bluehill raw-data CSV: a results preamble, names, a units
  row ``(s),(mm),(N),(%)``, quoted samples with thousands separators; the strain channel
  "Tensile strain (Strain 1)" in %, and the derived "Tensile stress" (to be left aside).
* :func:`write_testxpert` — Zwick testXpert text export: German names (Prüfzeit,
  Standardkraft, Traversenweg absolut, Standardweg, Breitenänderung, Dehnung), a units row,
  tab-separated with decimal commas, UTF-16 with a BOM (Excel's "Unicode text") or
  Windows-1252, or ``;``-separated.
* :func:`write_mts` — MTS TestSuite export: a key/value preamble, then "Running Time",
  "Axial Force", "Axial Displacement", "Axial Strain" with a units row (sec, lbf, in, in/in).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

LBF_N = 0.45359237 * 9.80665  # the international pound-force, N
INCH_MM = 25.4


@dataclass
class Truth:
    """A synthetic tension test in native units, and the values it was built with."""

    time_s: np.ndarray
    force_N: np.ndarray
    crosshead_mm: np.ndarray
    extensometer_mm: np.ndarray
    strain: np.ndarray  # engineering strain on the extensometer (ratio)
    d0_mm: float
    l0_mm: float
    le_mm: float
    E_MPa: float
    Rp02_MPa: float
    Rm_MPa: float  # max force / S0 of the samples as generated

    @property
    def s0_mm2(self) -> float:
        return np.pi * self.d0_mm**2 / 4.0


def tension_truth(*, E_MPa: float = 200e3, Rp_MPa: float = 400.0, N: float = 20.0, s_top_MPa: float = 460.0,
                  d0_mm: float = 6.0, l0_mm: float = 30.0, le_mm: float = 25.0, samples: int = 1200, fracture: bool = True) -> Truth:
    """The Ramberg–Osgood test above, sampled evenly in time at two strain rates."""
    s_up = np.linspace(0.0, s_top_MPa, 4000)
    e_up = s_up / E_MPa + 0.002 * (s_up / Rp_MPa) ** N  # Ramberg–Osgood, rising branch
    e_m = float(e_up[-1])
    e_end = 3.0 * e_m if fracture else 1.2 * e_m
    # ISO 6892-1 method B: slow on the elastic line, faster beyond (a sixth of the samples)
    e_slow = 2.0 * Rp_MPa / E_MPa
    e = np.concatenate([np.linspace(0.0, e_slow, samples // 6, endpoint=False), np.linspace(e_slow, e_end, samples - samples // 6)])
    s = np.where(e <= e_m, np.interp(e, e_up, s_up), s_top_MPa * (1.0 - 0.25 * ((e - e_m) / (3.0 * e_m - e_m)) ** 2))
    s0 = np.pi * d0_mm**2 / 4.0
    force = s * s0
    if fracture:
        force = np.concatenate([force, [0.02 * force[-1], 0.01 * force[-1]]])
        e = np.concatenate([e, [e[-1], e[-1]]])
    t = np.arange(force.size) * 0.5
    ext = e * le_mm
    cross = e * 36.0 + force / 60e3  # parallel length 36 mm and a 60 N/µm frame
    return Truth(time_s=t, force_N=force, crosshead_mm=cross, extensometer_mm=ext, strain=e, d0_mm=d0_mm, l0_mm=l0_mm,
                 le_mm=le_mm, E_MPa=E_MPa, Rp02_MPa=Rp_MPa, Rm_MPa=float(force.max() / s0))


def write_bluehill(path: Path, truth: Truth, *, strain: bool = True, crosshead: bool = True, force_unit: str = "N") -> Path:
    """Instron Bluehill raw-data CSV: a results preamble, a names row, a units row ``(s),(mm),(N),(%)``
    and quoted samples with thousands separators (``"1,004.80328"``), as Bluehill writes them."""
    scale = {"N": 1.0, "kN": 1e-3}[force_unit]
    names, units, cols = ["Time"], ["(s)"], [truth.time_s]
    if crosshead:
        names.append("Extension"), units.append("(mm)"), cols.append(truth.crosshead_mm)
    names.append("Load"), units.append(f"({force_unit})"), cols.append(truth.force_N * scale)
    if strain:
        names.append("Tensile strain (Strain 1)"), units.append("(%)"), cols.append(100.0 * truth.strain)
    else:
        names.append("Tensile extension (Strain 1)"), units.append("(mm)"), cols.append(truth.extensometer_mm)
    names.append("Tensile stress"), units.append("(MPa)"), cols.append(truth.force_N / truth.s0_mm2)
    lines = ["Specimen number (included),1", f'Modulus (Automatic Young\'s),"{truth.E_MPa:,.5f}",MPa',
             f'Diameter,"{truth.d0_mm:.5f}",mm', 'Specimen ID,"0038"', ""]
    lines += [",".join(names), ",".join(units)]
    lines += [",".join(f'"{v:,.6f}"' for v in row) for row in zip(*cols)]
    path.write_text("\r\n".join(lines) + "\r\n", encoding="utf-8")
    return path


def write_testxpert(path: Path, truth: Truth, *, encoding: str = "utf-16", sep: str = "\t") -> Path:
    """Zwick testXpert export: a key/value preamble, German channel names as testXpert names them
    (Prüfzeit, Standardkraft, Traversenweg absolut, Standardweg, Breitenänderung, Dehnung), a
    units row, decimal commas; UTF-16 with a BOM (Excel's "Unicode text") by default."""
    lines = ["Prüfprotokoll Zugversuch ISO 6892-1", f"Prüfer{sep}Müller", f"Messlänge Standardweg{sep}{truth.le_mm:g}{sep}mm", "",
             sep.join(["Prüfzeit", "Standardkraft", "Traversenweg absolut", "Standardweg", "Breitenänderung", "Dehnung"]),
             sep.join(["s", "N", "mm", "mm", "mm", "%"])]
    width_change = -0.3 * truth.strain * truth.d0_mm
    for row in zip(truth.time_s, truth.force_N, truth.crosshead_mm, truth.extensometer_mm, width_change, 100.0 * truth.strain):
        lines.append(sep.join(f"{v:.6f}".replace(".", ",") for v in row))
    path.write_text("\r\n".join(lines) + "\r\n", encoding=encoding)  # Python's utf-16 writes the BOM
    return path


def write_mts(path: Path, truth: Truth, *, bom: bool = True) -> Path:
    """MTS TestSuite export: preamble, names, units row in US units (sec, lbf, in, in/in)."""
    lines = ['"Test Run Name:","Run 1"', '"Specimen:","S-1"', '"Method:","ASTM E8 Tension"', "",
             '"Running Time","Axial Force","Axial Displacement","Axial Strain"', '"sec","lbf","in","in/in"']
    for row in zip(truth.time_s, truth.force_N / LBF_N, truth.crosshead_mm / INCH_MM, truth.strain):
        lines.append(",".join(f'"{v:.9g}"' for v in row))
    path.write_text(("\ufeff" if bom else "") + "\n".join(lines) + "\n", encoding="utf-8")
    return path
