"""The 67 real 42CrMoS4 specimens: our ISO 6892-1 results against the lab's published values."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[2] / "bench" / "validation_42CrMoS4.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("validation_42CrMoS4", BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert len(module.specimen_files()) == 67, f"the 42CrMoS4 set in the repository is incomplete: {module.DATA}"
    return module


def test_extensometer_path_reproduces_the_lab(bench):
    files = bench.specimen_files()
    assert len(files) == 67
    dev, failures = bench.deviations(files)
    assert not failures
    table = bench.summary(dev)
    # the brief: Rp0.2 and Rm within 0.5 %, E within 2 %, Ag within 0.5 pp on ≥ 95 % of specimens
    for q in ("E", "Rp0.2", "Rm", "Ag"):
        assert table[q]["pass_rate"] >= 0.95, (q, table[q])
    # A from the extensometer at fracture and Z from the area after fracture: same limits
    assert table["A"]["pass_rate"] >= 0.95 and table["Z"]["pass_rate"] >= 0.95


def test_crosshead_only_path_looser_bounds(bench):
    files = bench.specimen_files()
    loo, each = bench.leave_one_out_stiffness(files)
    assert 25 < np.median(each) < 60  # N/µm: a plausible frame for a 100 kN servo-hydraulic machine
    dev, failures = bench.deviations(files, [{"frame_stiffness_N_per_um": c} for c in loo], use_extensometer=False)
    assert len(failures) <= 3
    ok = {q: v[np.isfinite(v)] for q, v in dev.items()}
    # stresses barely depend on the strain channel; the offset method with the apparent E is robust
    assert np.mean(np.abs(ok["Rp0.2"]) <= 0.01) >= 0.95
    assert np.all(np.abs(ok["Rm"]) <= 1e-9)
    assert np.mean(np.abs(ok["Ag"]) <= 1.0) >= 0.95
    # E from the crosshead hinges on the frame stiffness: only the median is close
    assert np.median(np.abs(ok["E"])) <= 0.15
