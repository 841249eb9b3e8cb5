"""Start-up time of the ``flowcurve`` command: ``--help`` of the command and of every
sub-command, against a bare ``python -c pass`` measured in the same run.

Each figure is the median wall time of ``--repeat`` fresh processes (the Python interpreter
of this run, ``-m flowcurve``), so the difference to the bare interpreter is what flowcurve's
own imports and parser cost. Also lists the heavy libraries the parser pulled in (should be
none: pandas, scipy, lmfit, matplotlib and pyserial are imported where they are used).

Usage: python bench/cli_startup.py [--repeat 7]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

HEAVY = ("pandas", "scipy", "lmfit", "matplotlib", "serial")


def wall_time_s(argv: list[str], repeat: int) -> float:
    """Median wall time of ``repeat`` runs of a fresh process."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def sub_commands() -> list[str]:
    from flowcurve.cli import build_parser

    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return list(action.choices)


def heavy_imports_of_the_parser() -> list[str]:
    code = ("import sys; from flowcurve.cli import build_parser; build_parser(); "
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.split()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7, help="processes per figure (median)")
    args = ap.parse_args()
    bare = wall_time_s([sys.executable, "-c", "pass"], args.repeat)
    print(f"python -c pass                       {bare * 1000:7.0f} ms")
    rows = [("flowcurve --help", [])] + [(f"flowcurve {c} --help", [c]) for c in sub_commands()]
    for label, words in rows:
        t = wall_time_s([sys.executable, "-m", "flowcurve", *words, "--help"], args.repeat)
        print(f"{label:<36} {t * 1000:7.0f} ms   ({(t - bare) * 1000:+.0f} ms over bare python)")
    heavy = heavy_imports_of_the_parser()
    print(f"heavy libraries imported by the parser: {', '.join(heavy) if heavy else 'none'}")


if __name__ == "__main__":
    main()
