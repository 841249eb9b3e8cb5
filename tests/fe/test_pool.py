"""Solver runs side by side: the local process pool and a Dask LocalCluster give the same
results, in the items' order, as running them one by one."""

from __future__ import annotations

import math
import shutil

import pytest

from flowcurve.errors import FlowcurveError
from flowcurve.identification.fe.pool import run_many


def slow_square(x):
    return math.fsum([x] * int(x)) if x > 0 else 0.0  # x² by repeated addition


def test_process_pool_keeps_the_order_and_reports_progress():
    seen = []
    out = run_many(slow_square, [5, 1, 9, 3], workers=2, progress=lambda d, t, s: seen.append((d, t)))
    assert out == [25.0, 1.0, 81.0, 9.0]
    assert seen[-1] == (4, 4) and [d for d, _ in seen] == [1, 2, 3, 4]


def test_bad_worker_count_is_one_line():
    with pytest.raises(FlowcurveError, match="--workers"):
        run_many(slow_square, [1, 2], workers=0)


def test_dask_local_cluster_gives_the_same_results():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        out = run_many(slow_square, [4, 2, 7], scheduler=client)
    assert out == [16.0, 4.0, 49.0]


@pytest.mark.solver
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
def test_a_calculix_run_through_dask_equals_the_direct_run(tmp_path, monkeypatch):
    distributed = pytest.importorskip("dask.distributed")
    from flowcurve.identification.fe.make_table import sample_run

    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path / "cache"))
    point = (0.1, 1.0, 0.2)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        (via_dask,) = run_many(sample_run, [point], scheduler=client)
    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path / "cache2"))  # a fresh run, not the cache
    direct = sample_run(point)
    assert not direct["cached"] and via_dask["factor_raw"].tolist() == direct["factor_raw"].tolist()
