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

``--current-only`` times only the command again over results that are all current, at --jobs 1
and --jobs 2 (the records are identified once first): the work left is deciding that each is
current, so --jobs 2 should cost what --jobs 1 does (no pool started). ``--against DIR`` times
another checkout (e.g. the code before a change, ``git archive <commit> | tar -x -C DIR``) in
the same run, in its own output folder (a result is current only for the code that made it).

Run: python bench/archive_throughput.py [--records 40] [--no-plots]   (~3-6 min on 2 cores)
     python bench/archive_throughput.py --current-only [--repeat 5] [--against DIR]   (~1 min)
     python bench/archive_throughput.py --against DIR --repeat 2 --no-plots   (the first run of two checkouts, ~6 min)
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
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


def timed_identify(records: list[str], out: Path, extra: list[str], root: Path = ROOT) -> tuple[float, float, str]:
    """Wall time, CPU time (the command and the worker processes it waited for; not a Dask
    cluster's workers) of one `flowcurve identify` run of checkout ``root``, and its last output line."""
    command = [sys.executable, "-m", "flowcurve", "identify", *records, "--out", str(out), *extra]
    cpu0, t0 = _children_cpu_s(), time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, cwd=root,
                          env={**os.environ, "MPLBACKEND": "Agg", "FLOWCURVE_DEV_ROOT": str(root)})
    wall, cpu = time.perf_counter() - t0, _children_cpu_s() - cpu0
    if done.returncode != 0:
        raise SystemExit(f"identify failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return wall, cpu, done.stdout.strip().splitlines()[-1]


def current_only(records: list[str], tmp: Path, plots: list[str], roots: dict[str, Path], repeat: int) -> None:
    """The command again over results that are all current, --jobs 1 and 2, each checkout in
    ``roots`` in its own output folder; the runs take turns so that load changes fall on all."""
    for name, root in roots.items():
        timed_identify(records, tmp / name, [*plots, "--jobs", "2"], root)  # every result current from here on
    runs = {(name, jobs): [] for name in roots for jobs in ("1", "2")}
    last = {}
    for _ in range(repeat):
        for (name, jobs), times in runs.items():
            wall, _cpu, last[name] = timed_identify(records, tmp / name, [*plots, "--jobs", jobs], roots[name])
            times.append(wall)
    print(f"the same command again, every result current (median of {repeat}; {last[next(iter(roots))]})")
    print("| checkout | --jobs 1, s | --jobs 2, s | --jobs 2 / --jobs 1 |")
    print("|---|---|---|---|")
    for name, root in roots.items():
        one, two = statistics.median(runs[(name, "1")]), statistics.median(runs[(name, "2")])
        print(f"| {name} ({root}) | {one:.2f} | {two:.2f} | {two / one:.2f} |")


def first_runs(records: list[str], tmp: Path, plots: list[str], roots: dict[str, Path], repeat: int) -> None:
    """The first run (no result current) at --jobs 1 of each checkout in ``roots``, taking turns,
    each run into an empty output folder; the median wall time and its ratio to the first checkout's."""
    times = {name: [] for name in roots}
    for k in range(repeat):
        for name, root in roots.items():
            wall, _cpu, last = timed_identify(records, tmp / f"{name}{k}", [*plots, "--jobs", "1"], root)
            times[name].append(wall)
            print(f"  {name}: {wall:.1f} s ({last})", flush=True)
    reference = statistics.median(times[next(iter(roots))])
    print(f"the first run at --jobs 1 (median of {repeat})")
    print("| checkout | wall, s | records per minute | vs this |")
    print("|---|---|---|---|")
    for name, root in roots.items():
        wall = statistics.median(times[name])
        print(f"| {name} ({root}) | {wall:.1f} | {60.0 * len(records) / wall:.0f} | {wall / reference:.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--records", type=int, default=40)
    parser.add_argument("--no-plots", action="store_true", help="pass --no-plots to identify (the default draws the PNG plots)")
    parser.add_argument("--current-only", action="store_true", help="time only the command again over current results, --jobs 1 and 2")
    parser.add_argument("--repeat", type=int, default=5, help="--current-only: runs per figure (median)")
    parser.add_argument("--against", type=Path, metavar="DIR", help="another checkout to time beside this one (with --current-only: the "
                        "command again; else the first run at --jobs 1, the checkouts taking turns)")
    args = parser.parse_args()
    plots = ["--no-plots"] if args.no_plots else []
    if args.current_only:
        with tempfile.TemporaryDirectory(prefix="flowcurve-archive-") as tmp:
            records = make_records(Path(tmp) / "records", args.records)
            print(f"{len(records)} records, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}", flush=True)
            roots = {"this": ROOT, **({"against": args.against.resolve()} if args.against else {})}
            current_only(records, Path(tmp), plots, roots, args.repeat)
        return
    if args.against:
        with tempfile.TemporaryDirectory(prefix="flowcurve-archive-") as tmp:
            records = make_records(Path(tmp) / "records", args.records)
            print(f"{len(records)} records, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}", flush=True)
            first_runs(records, Path(tmp), plots, {"this": ROOT, "against": args.against.resolve()}, args.repeat)
        return
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
        run("--jobs 2 again (all current)", "jobs2", ["--jobs", "2"])

    print()
    print("| run | wall, s | records per minute | vs --jobs 1 | CPU, s | cores used (CPU / wall) | load average before / after |")
    print("|---|---|---|---|---|---|---|")
    for label, wall, cpu, before, after, _ in rows:
        cpu_text = "(workers not counted) | " if label.startswith("Dask") else f"{cpu:.1f} | {cpu / wall:.2f}"
        print(f"| {label} | {wall:.1f} | {60.0 * len(records) / wall:.0f} | {first / wall:.2f}x | {cpu_text} | {before:.1f} / {after:.1f} |")
    print(f"\nthe same command again: {again:.1f} s, {100.0 * again / first:.0f} % of the first run (target < 20 %)")


if __name__ == "__main__":
    main()
