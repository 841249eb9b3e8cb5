"""Archive throughput of ``flowcurve identify``: records per minute at --jobs 1 and 2 and on a
Dask LocalCluster, and the same command again (every result current, so skipped) as a fraction
of the first run.

The 40 records: 36 real tension tests of the 42CrMoS4 set (tests/data, CC BY 4.0) and 4 copies
of the virtual-rig compression record of examples/data, each copy with its specimen id varied
(so its bytes, and its checksum, differ). Each run is the command line a lab would type, in a
fresh process, into an empty output folder; the times include the process start. The load
average before and after each run and the cores the run got (its CPU time over its wall time)
are printed: on a machine shared with other work the figures move with them — when the other
work already fills the cores, a second job gets no second core.

Run: python bench/archive_throughput.py [--records 40] [--no-plots]   (~3-6 min on 2 cores)
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TENSION = ROOT / "tests" / "data" / "42CrMoS4" / "original_data"
COMPRESSION = ROOT / "examples" / "data" / "compression-steel45.csv"


def make_records(folder: Path, n: int) -> list[str]:
    """n records: real tension tests, and compression copies with a varied specimen id (1 in 10)."""
    folder.mkdir(parents=True, exist_ok=True)
    n_compression = max(1, n // 10)
    paths = []
    for src in sorted(TENSION.glob("*.csv"))[: n - n_compression]:
        shutil.copyfile(src, folder / src.name)
        paths.append(str(folder / src.name))
    text = COMPRESSION.read_text(encoding="utf-8")
    for k in range(n_compression):
        path = folder / f"C{k + 1:02d}.csv"
        path.write_text(text.replace("# specimen.id: virtual-C1", f"# specimen.id: virtual-C{k + 1}", 1), encoding="utf-8")
        paths.append(str(path))
    if len(paths) != n:
        raise SystemExit(f"only {len(paths)} records could be made (the 42CrMoS4 set holds 67)")
    return paths


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed_identify(records: list[str], out: Path, extra: list[str]) -> tuple[float, float, str]:
    """Wall time, CPU time (the command and the worker processes it waited for; not a Dask
    cluster's workers) of one `flowcurve identify` run, and its last output line."""
    command = [sys.executable, "-m", "flowcurve", "identify", *records, "--out", str(out), *extra]
    cpu0, t0 = _children_cpu_s(), time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"})
    wall, cpu = time.perf_counter() - t0, _children_cpu_s() - cpu0
    if done.returncode != 0:
        raise SystemExit(f"identify failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return wall, cpu, done.stdout.strip().splitlines()[-1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--records", type=int, default=40)
    parser.add_argument("--no-plots", action="store_true", help="pass --no-plots to identify (the default draws the PNG plots)")
    args = parser.parse_args()
    plots = ["--no-plots"] if args.no_plots else []
    rows = []
    with tempfile.TemporaryDirectory(prefix="flowcurve-archive-") as tmp:
        tmp = Path(tmp)
        records = make_records(tmp / "records", args.records)
        print(f"{len(records)} records, {os.cpu_count()} cores, plots {'off' if plots else 'on'}", flush=True)

        def run(label: str, out: str, extra: list[str]) -> float:
            load = os.getloadavg()[0]
            wall, cpu, last = timed_identify(records, tmp / out, [*plots, *extra])
            rows.append((label, wall, cpu, load, os.getloadavg()[0], last))
            print(f"  {label}: {wall:.1f} s ({last})", flush=True)
            return wall

        first = run("--jobs 1", "jobs1", ["--jobs", "1"])
        run("--jobs 2", "jobs2", ["--jobs", "2"])
        from dask.distributed import LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
            run("Dask LocalCluster (2 workers x 1 thread)", "dask", ["--scheduler", cluster.scheduler_address])
        again = run("--jobs 1 again (all current)", "jobs1", ["--jobs", "1"])

    print()
    print("| run | wall, s | records per minute | vs --jobs 1 | CPU, s | cores used (CPU / wall) | load average before / after |")
    print("|---|---|---|---|---|---|---|")
    for label, wall, cpu, before, after, _ in rows:
        cpu_text = "(workers not counted) | " if label.startswith("Dask") else f"{cpu:.1f} | {cpu / wall:.2f}"
        print(f"| {label} | {wall:.1f} | {60.0 * len(records) / wall:.0f} | {first / wall:.2f}x | {cpu_text} | {before:.1f} / {after:.1f} |")
    print(f"\nthe same command again: {again:.1f} s, {100.0 * again / first:.0f} % of the first run (target < 20 %)")


if __name__ == "__main__":
    main()
