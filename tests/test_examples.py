"""Every script in examples/ runs (as a user would run it) and prints what it claims; each
figure is checked against a value obtained another way: the file read with the csv module,
the lab's published results, closed forms on the raw columns, the virtual rig's material."""

from __future__ import annotations

import csv
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from flowcurve.rig.virtual.materials import get_material

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
DATA = EXAMPLES / "data"
NUMBER = r"([-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?)"


def run_example(name: str) -> str:
    done = subprocess.run([sys.executable, str(EXAMPLES / name)], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def number_after(text: str, label: str) -> float:
    match = re.search(re.escape(label) + r"\s*" + NUMBER, text)
    assert match, f"no '{label} <number>' in:\n{text}"
    return float(match.group(1))


def instron_header(path: Path) -> dict[str, float]:
    """The INSTRON export's ``name:<TAB>value<TAB>unit`` header, read with the csv module."""
    out = {}
    with open(path, encoding="latin-1", newline="") as fh:
        for row in csv.reader(fh, delimiter="\t"):
            if not row or not row[0].endswith(":"):
                break
            try:
                out[row[0][:-1]] = float(row[1])
            except ValueError:
                pass  # text fields (material, machine, date)
    return out


def instron_columns(path: Path) -> dict[str, np.ndarray]:
    with open(path, encoding="latin-1", newline="") as fh:
        rows = list(csv.reader(fh, delimiter="\t"))
    start = next(i for i, r in enumerate(rows) if r and r[0] == "Time")
    names, data = rows[start], np.array([[float(v) for v in r[:len(rows[start])]] for r in rows[start + 2:] if r], dtype=float)
    return {n: data[:, i] for i, n in enumerate(names)}


def test_every_example_is_checked():
    scripts = sorted(p.name for p in EXAMPLES.glob("*.py"))
    assert scripts == sorted(CHECKS), "an example without a check (or a check without an example)"


def check_read_a_record(out: str) -> None:
    path = DATA / "compression-steel45.csv"
    header, events, rows = {}, [], []
    with open(path, newline="", encoding="utf-8") as fh:
        for row in csv.reader(fh):
            if row and row[0].startswith("# event:"):
                events.append(row[0].split()[3])
            elif row and row[0].startswith("#"):
                key, _, value = ",".join(row)[2:].partition(": ")
                header[key] = value
            elif row:
                rows.append(row)
    names, samples = rows[0], rows[1:]
    force = np.array([float(r[names.index("force_N")]) for r in samples])
    assert number_after(out, "samples:") == len(samples)
    assert re.findall(r"^event: \S+ s (\S+)", out, re.M) == events
    assert number_after(out, "peak force:") == pytest.approx(np.abs(force).max(), abs=0.05)
    area = math.pi * float(header["specimen.d0_mm"]) ** 2 / 4
    assert number_after(out, "peak engineering stress:") == pytest.approx(np.abs(force).max() / area, abs=0.005)


def check_tension_iso_6892(out: str) -> None:
    lab = instron_header(DATA / "46NT71.csv")
    published = {"E": "Slope of linear-elastic region", "Rp0.2": "Yield stress at 0.2% plastic strain",
                 "Rm": "Ultimate tensile strength", "Ag": "Uniform elongation", "A": "Elongation after fracture",
                 "Z": "Reduction of area"}
    ours = {label: number_after(out, f"{label}:") for label in published}
    # the acceptance limits of the 42CrMoS4 validation (tests/tension/test_validation_42CrMoS4.py)
    assert ours["E"] == pytest.approx(lab[published["E"]], rel=0.02)
    for label in ("Rp0.2", "Rm"):
        assert ours[label] == pytest.approx(lab[published[label]], rel=0.005)
    for label in ("Ag", "A", "Z"):
        assert ours[label] == pytest.approx(lab[published[label]], abs=0.5)


def check_tension_true_curve(out: str) -> None:
    lab = instron_header(DATA / "46NT71.csv")
    Rm, Ag, E = lab["Ultimate tensile strength"], lab["Uniform elongation"] / 100, lab["Slope of linear-elastic region"]
    # constant volume at the force maximum: σ_true = Rm·(1 + e), e = Ag (plastic) + Rm/E (elastic)
    assert number_after(out, "true stress at the force maximum:") == pytest.approx(Rm * (1 + Ag + Rm / E), rel=0.005)
    # fracture true strain ln(S0/Su) from the lab's cross-sections
    S0, Su = lab["Original cross-section"], lab["Cross-section after fracture"]
    assert number_after(out, "fracture: true strain") == pytest.approx(math.log(S0 / Su), abs=2e-3)
    # the fitted law against the true curve computed here from the raw extensometer and force columns
    A, B, n = (number_after(out, label) for label in ("Johnson-Cook static: A", "MPa, B", "MPa, n"))
    raw = instron_columns(DATA / "46NT71.csv")
    e = raw["Displacement"] / lab["Gauge length"]
    sigma_true = raw["Force"] * 1000 / S0 * (1 + e)
    eps_p = np.log1p(e) - sigma_true / E
    up_to_max = slice(0, int(np.argmax(raw["Force"])) + 1)
    for strain in (0.01, 0.03, 0.05):
        measured = np.interp(strain, np.maximum.accumulate(eps_p[up_to_max]), sigma_true[up_to_max])
        assert A + B * strain**n == pytest.approx(measured, rel=0.02), strain


def check_compression_friction(out: str) -> None:
    header = {}
    for line in (DATA / "compression-steel45.csv").read_text(encoding="utf-8").splitlines():
        if line.startswith("# ") and ": " in line and not line.startswith("# event:"):
            key, _, value = line[2:].partition(": ")
            header[key] = value
    assert number_after(out, "friction μ (bulge_regression):") == pytest.approx(float(header["virtual.friction_mu"]), abs=0.01)
    material = get_material(header["material"])
    rate = float(header["crosshead_speed_mm_per_s"]) / float(header["specimen.h0_mm"])  # the virtual rig's nominal rate
    for strain in (0.1, 0.3, 0.6):
        truth = float(material.flow_stress(strain, rate, float(header["nominal_temperature_C"])))
        # 3 %: the limit of the virtual compression check in tests/acquisition/test_end_to_end.py
        assert number_after(out, f"flow stress at true plastic strain {strain:.1f}:") == pytest.approx(truth, rel=0.03)


CHECKS = {
    "read_a_record.py": check_read_a_record,
    "tension_iso_6892.py": check_tension_iso_6892,
    "tension_true_curve.py": check_tension_true_curve,
    "compression_friction.py": check_compression_friction,
}


@pytest.mark.parametrize("script", sorted(CHECKS))
def test_example(script):
    CHECKS[script](run_example(script))
