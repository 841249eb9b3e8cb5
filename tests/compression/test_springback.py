"""The spring-back K_l adds to h0 − hk (3.1): from the handbook E, else as the unloading branch
shows it — without it K_l scaled the loaded shortening to the unloaded one."""

import numpy as np
import pytest

from flowcurve.identification.compression.identify import identify_compression
from flowcurve.identification.compression.values import springback_from_unloading

from .toe_records import make_toe_compression


def test_the_unloading_slope_gives_the_springback():
    rng = np.random.default_rng(5)
    f_max, c = 40_000.0, 6e-7  # N, mm/N: 24 µm back from 40 kN
    load = np.linspace(0.0, f_max, 300)
    unload = np.linspace(f_max, 0.0, 200)[1:]
    force = np.concatenate([load, unload, np.linspace(0.0, 5000.0, 20)])  # and a reloading after it
    disp = np.concatenate([3.0 * load / f_max, 3.0 - c * (f_max - unload), np.full(20, 3.0 - c * f_max)])
    force = force + rng.normal(0.0, 30.0, force.size)
    disp = disp + rng.normal(0.0, 0.3e-3, disp.size)  # a re-read 10 µm count: 0.3 µm
    got, samples = springback_from_unloading(force, disp, end=299)
    assert got == pytest.approx(c * f_max, rel=0.02) and 150 <= samples <= 160  # the 10–90 % band of the unloading only
    assert springback_from_unloading(force[:305], disp[:305], end=299) is None  # 5 samples: too few


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_without_handbook_E_the_unloading_branch_gives_the_springback(seed):
    record, truth = make_toe_compression(rate_hz=10.0, toe_mm=0.05, seed=seed)
    indicator = identify_compression(record).result["indicator"]
    assert indicator["springback_source"].startswith("unloading branch")
    assert indicator["springback_mm"] == pytest.approx(truth["springback_mm"], rel=0.05)
    # the record's crosshead less F/C is the specimen's shortening: scaled to h0 − hk + spring-back it is
    # left as it was (K_l was 0.993 without the spring-back: 0.7 % of the shortening)
    assert indicator["K_l"] == pytest.approx(1.0, abs=1e-3)
    record.meta["material.E_MPa"] = "194000"
    assert identify_compression(record).result["indicator"]["springback_source"] == "handbook E"
