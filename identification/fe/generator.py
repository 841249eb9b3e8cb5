"""What the FE data generators (:mod:`.make_table`, :mod:`.make_tension_response`) share: the
command line, the timed solver runs with progress on stderr, and the provenance every file
they write carries (ccx version, date, the command, run counts and times)."""

from __future__ import annotations

import argparse
import datetime as _dt
import sys
import time
from pathlib import Path
from typing import Any, Callable, Sequence

from flowcurve.identification.fe.model.ccx import ccx_version
from flowcurve.identification.fe.pool import run_many


def parser(module: str, doc: str, default_out: Path) -> argparse.ArgumentParser:
    """``python -m <module>`` with --out, --workers and --scheduler."""
    p = argparse.ArgumentParser(prog=f"python -m {module}", description=doc.split("\n\n")[0])
    p.add_argument("--out", type=Path, default=default_out)
    p.add_argument("--workers", type=int, default=2, help="ccx runs at once (default 2)")
    p.add_argument("--scheduler", default=None, help="Dask scheduler address")
    return p


def command_line(module: str, argv: Sequence[str] | None) -> str:
    """The command line that regenerates a data file: ``python -m module argv``."""
    return f"python -m {module} " + " ".join(argv if argv is not None else sys.argv[1:])


def now_utc() -> str:
    """The UTC time now, ISO 8601 to the second."""
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def run_timed(fn: Callable[[Any], dict], items: Sequence[Any], *, workers: int, scheduler=None) -> tuple[list[dict], float]:
    """``fn`` over ``items`` on the pool (or Dask), progress on stderr → (results, wall s)."""

    def progress(done, total, elapsed):
        """Print runs done of ``total`` and elapsed s to stderr."""
        print(f"  {done}/{total} runs, {elapsed:.0f} s", file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    runs = run_many(fn, items, workers=workers, scheduler=scheduler, progress=progress)
    return runs, time.perf_counter() - t0


def provenance(command: str, runs: Sequence[dict], wall_s: float) -> dict:
    """The solver, the date, the command and the cost of the runs (each with a ``wall_s``)."""
    return {"ccx_version": ccx_version(), "date": now_utc(), "command": command, "runs": len(runs),
            "wall_s": round(wall_s, 1), "solver_s": round(sum(r["wall_s"] for r in runs), 1)}


def summary(meta: dict) -> str:
    """One line for the screen after a generation."""
    import json

    return json.dumps({k: meta[k] for k in ("runs", "wall_s", "solver_s", "ccx_version")}) + f" incomplete: {len(meta['incomplete_runs'])}"
