"""One virtual test on ptys in real time against the same test in-process on model time.

Runs the demo's tension (or compression) test on the virtual rig twice through the real
drivers and the procedure: once on pseudo-terminals on the wall clock (what ``flowcurve
run`` does), once on ``virtual://`` ports on a :class:`flowcurve.clock.ModelClock` (what the
fast tests do), and prints for each the wall time, the CPU time of this process, the
samples recorded and the force maximum — the two records describe the same test, the
model-time one costs only its computing.

Usage: python bench/virtual_test_model_time.py [--test tension|compression] [--time-scale 15]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from flowcurve.acquisition.session import run_virtual_test
from flowcurve.clock import WALL, ModelClock
from flowcurve.demo import demo_specs
from flowcurve.record.format import read_record

MATERIAL = "steel45"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--test", choices=("tension", "compression"), default="tension")
    parser.add_argument("--time-scale", type=float, default=15.0)
    args = parser.parse_args()
    spec_index = 0 if args.test == "tension" else 1
    folder = Path(tempfile.mkdtemp(prefix="flowcurve-bench-"))
    print(f"{args.test} of {MATERIAL} at time scale {args.time_scale:g}")
    print(f"{'ports and clock':32s} {'wall_s':>8s} {'cpu_s':>8s} {'samples':>8s} {'max_force_N':>12s}")
    for label, link in (("ptys, wall clock", {"clock": WALL, "link": "pty"}),
                        ("virtual://, model clock", {"clock": ModelClock(), "link": "inprocess"})):
        spec = demo_specs(MATERIAL)[spec_index]
        path = folder / f"{link['link']}.csv"
        wall0, cpu0 = time.monotonic(), time.process_time()
        run = run_virtual_test(spec, path, material=MATERIAL, time_scale=args.time_scale, **link)
        wall, cpu = time.monotonic() - wall0, time.process_time() - cpu0
        rec = read_record(path)
        print(f"{label:32s} {wall:8.2f} {cpu:8.2f} {len(rec.data):8d} {rec.column('force_N').max():12.0f}"
              f"   ({run.outcome.reason})")


if __name__ == "__main__":
    main()
