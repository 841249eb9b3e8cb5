"""Fixtures for the records/CLI tests: small native records written to tmp_path."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from flowcurve.record.format import Record, write_record

# the 42CrMoS4 validation set is part of the repository (tests/data/42CrMoS4, CC BY 4.0)
INSTRON_FILE = Path(__file__).resolve().parents[1] / "data" / "42CrMoS4" / "original_data" / "46NT71.csv"


@pytest.fixture
def instron_file() -> Path:
    return INSTRON_FILE


@pytest.fixture
def write_native(tmp_path):
    """write_native(name, force_N, meta_overrides) → path of a tension record with that force."""

    def make(name: str, force_N: np.ndarray, **meta) -> Path:
        n = len(force_N)
        t = np.arange(n) * 0.1
        data = pd.DataFrame({"time_s": t, "force_N": force_N, "crosshead_mm": 0.01 * t})
        header = {"flowcurve-record": "1", "status": "complete", "test": "tension", "material": "synthetic",
                  "specimen.d0_mm": "6.0", "specimen.l0_mm": "30.0", "crosshead_speed_mm_per_s": "0.01"}
        header.update({k.replace("__", "."): v for k, v in meta.items()})
        header = {k: v for k, v in header.items() if v is not None}
        return write_record(tmp_path / f"{name}.csv", Record(meta=header, data=data, source=name))

    return make
