"""Solver runs side by side: a local process pool (``workers``) or a Dask distributed cluster.

:func:`run_many` maps a picklable function over items and returns the results in the items'
order, reporting progress (``done/total``) through a callback or the log. With ``scheduler``
(an address such as ``tcp://host:8786``, or a ``dask.distributed.Client``/``LocalCluster``)
the runs go to that cluster — install the ``fe`` extra (``dask[distributed]``).
"""

from __future__ import annotations

import logging
import os
import time
from typing import Any, Callable, Iterable

from flowcurve.errors import FlowcurveError

log = logging.getLogger(__name__)


def default_workers() -> int:
    """The CPUs this process may use (at least 1)."""
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


def _report(progress: Callable[[int, int, float], None] | None, done: int, total: int, t0: float) -> None:
    if progress is not None:
        progress(done, total, time.perf_counter() - t0)
    else:
        log.info("solver runs: %d/%d (%.0f s)", done, total, time.perf_counter() - t0)


def run_many(fn: Callable[[Any], Any], items: Iterable[Any], *, workers: int | None = None, scheduler: Any = None,
             progress: Callable[[int, int, float], None] | None = None) -> list:
    """[fn(item) for item in items], run in parallel; exceptions propagate (the first one)."""
    items = list(items)
    total, t0 = len(items), time.perf_counter()
    if scheduler is not None:
        return _run_dask(fn, items, scheduler, progress, t0)
    workers = default_workers() if workers is None else int(workers)
    if workers < 1:
        raise FlowcurveError(f"--workers must be ≥ 1, got {workers}")
    if workers == 1 or total <= 1:
        out = []
        for k, item in enumerate(items, start=1):
            out.append(fn(item))
            _report(progress, k, total, t0)
        return out
    from concurrent.futures import ProcessPoolExecutor, as_completed

    results: list = [None] * total
    with ProcessPoolExecutor(max_workers=min(workers, total)) as pool:
        futures = {pool.submit(fn, item): k for k, item in enumerate(items)}
        for done, fut in enumerate(as_completed(futures), start=1):
            results[futures[fut]] = fut.result()
            _report(progress, done, total, t0)
    return results


def _run_dask(fn, items, scheduler, progress, t0) -> list:
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise FlowcurveError("--scheduler needs dask.distributed: pip install 'flowcurve[fe]'") from None
    own = not isinstance(scheduler, Client)
    try:
        client = Client(scheduler) if own else scheduler
    except (OSError, TimeoutError, ValueError) as exc:
        raise FlowcurveError(f"--scheduler {scheduler}: cannot connect to the Dask scheduler ({exc})") from None
    try:
        futures = client.map(fn, items, pure=False)
        index = {f.key: k for k, f in enumerate(futures)}
        results: list = [None] * len(items)
        for done, fut in enumerate(as_completed(futures), start=1):
            results[index[fut.key]] = fut.result()
            _report(progress, done, len(items), t0)
        return results
    finally:
        if own:
            client.close()
