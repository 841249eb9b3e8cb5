"""Start-up time of the ``flowcurve`` command: ``--help`` of the command and of every
sub-command, against a bare ``python -c pass`` measured in the same run.

Each figure is the median wall time of ``--repeat`` fresh processes (the Python interpreter
of this run, ``-m flowcurve``), so the difference to the bare interpreter is what flowcurve's
own imports and parser cost; the ratio is the figure over the bare interpreter's. Also lists
the heavy libraries each ``--help`` pulled in (should be none: numpy, pandas, scipy, lmfit,
matplotlib and pyserial are imported where they are used).

``--against DIR`` times another checkout of flowcurve in the same run, e.g. the code before a
change (``git archive <commit> | tar -x -C DIR``), beside this one: the before/after columns.

Usage: python bench/cli_startup.py [--repeat 7] [--against DIR]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HEAVY = ("numpy", "pandas", "scipy", "lmfit", "matplotlib", "serial")
ROOT = Path(__file__).resolve().parents[1]

# the heavy libraries in sys.modules after `flowcurve <words> --help`, printed on standard error
HEAVY_AFTER_HELP = ("import contextlib, io, sys; from flowcurve.cli import main\n"
                    "with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
                    "    main(sys.argv[1:] + ['--help'])\n"
                    f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)")


def in_checkout(root: Path) -> dict:
    """subprocess.run's arguments that make a fresh process import flowcurve from checkout
    ``root`` (its folder first on sys.path, and the editable install's variable)."""
    return {"cwd": root, "env": {**os.environ, "FLOWCURVE_DEV_ROOT": str(root)}}


def wall_times_s(commands: dict[str, tuple[list[str], dict]], repeat: int) -> dict[str, float]:
    """Median wall time of ``repeat`` fresh processes of each command (name → (argv, where)),
    the commands taking turns so that a change of the machine's load falls on all alike."""
    times: dict[str, list[float]] = {name: [] for name in commands}
    for _ in range(repeat):
        for name, (argv, where) in commands.items():
            start = time.perf_counter()
            subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True, **where)
            times[name].append(time.perf_counter() - start)
    return {name: statistics.median(t) for name, t in times.items()}


def sub_commands() -> list[str]:
    from flowcurve.cli import build_parser

    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")
    return list(action.choices)


def heavy_after_help(words: list[str], where: dict) -> list[str]:
    """The heavy libraries ``flowcurve <words> --help`` imports."""
    out = subprocess.run([sys.executable, "-c", HEAVY_AFTER_HELP, *words], capture_output=True, text=True, check=True, **where)
    return out.stderr.split()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7, help="processes per figure (median)")
    ap.add_argument("--against", type=Path, metavar="DIR", help="another flowcurve checkout to time beside this one (e.g. before a change)")
    args = ap.parse_args()
    roots = {"this": ROOT, **({"against": args.against.resolve()} if args.against else {})}
    print(f"median of {args.repeat} processes each, taking turns with a bare `python -c pass`; ms, and the ratio to the bare one")
    print(f"{'':<30}{'python -c pass':>16}" + "".join(f"{f'{name} ({root})':>44}" for name, root in roots.items()))
    rows = [("flowcurve --help", [])] + [(f"flowcurve {c} --help", [c]) for c in sub_commands()]
    heavy_seen: dict[str, set[str]] = {name: set() for name in roots}
    for label, words in rows:
        commands = {"bare": ([sys.executable, "-c", "pass"], in_checkout(ROOT))}
        commands.update({name: ([sys.executable, "-m", "flowcurve", *words, "--help"], in_checkout(root)) for name, root in roots.items()})
        t = wall_times_s(commands, args.repeat)
        cells = []
        for name, root in roots.items():
            heavy = heavy_after_help(words, in_checkout(root))
            heavy_seen[name].update(heavy)
            cells.append(f"{t[name] * 1000:7.0f} ms {t[name] / t['bare']:5.2f}x  heavy: {','.join(heavy) or 'none':<14}")
        print(f"{label:<30}{t['bare'] * 1000:13.0f} ms" + "".join(f"{cell:>44}" for cell in cells), flush=True)
    for name, heavy in heavy_seen.items():
        print(f"heavy libraries imported by --help ({name}): {', '.join(sorted(heavy)) or 'none'}")


if __name__ == "__main__":
    main()
