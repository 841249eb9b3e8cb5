"""Run many cells of the scenario matrix and print the table of issue 31's closing note.

    python tests/scenarios/report.py cells.jsonl [subset|default|all]   # run (resumable), then the table
    python tests/scenarios/report.py cells.jsonl --table                # the table of cells already run
    FLOWCURVE_MATRIX_CELLS=id,id python tests/scenarios/report.py cells.jsonl named   # those cells

``subset`` (the default): every fault-free cell (the whole product of the other five axes, 288)
and each fault on test × temperature × speed (24 each), its rate and material drawn with seed 31.
One JSON line per cell; a cell already in the file is not run again. A fault cell is judged against
the same cell without its fault (run once, cached): its violations include the numbers beyond the
fault-free truth's tolerance (matrix.survived).
"""

from __future__ import annotations

import collections
import itertools
import json
import random
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from scenarios import matrix as M  # noqa: E402
from scenarios.known_defects import KNOWN  # noqa: E402

SUBSET_SEED = 31


def subset_cells() -> list:
    rng = random.Random(SUBSET_SEED)
    chosen = [c for c in M.all_cells() if c.fault is M.NO_FAULT]
    for fault in M.FAULTS[1:]:
        for test, temperature, speed in itertools.product(M.TESTS, M.TEMPERATURES_C, M.SPEEDS_MM_PER_S):
            chosen.append(M.Cell(test, temperature, speed, rng.choice(M.RATES_HZ), rng.choice(M.materials()), fault))
    return sorted(chosen, key=lambda c: (c.fault is M.NO_FAULT, rng.random()))


def run(out: Path, cells: list) -> None:
    done = {json.loads(line)["id"] for line in out.read_text().splitlines() if line.strip()} if out.exists() else set()
    with out.open("a") as fh, tempfile.TemporaryDirectory() as tmp:
        for cell in (c for c in cells if c.id not in done):
            t0 = time.monotonic()
            r = M.run_cell(cell, Path(tmp) / M.cell_hash(cell))
            M.remember(r)
            ref = None if cell.fault is M.NO_FAULT else M.reference(cell, Path(tmp) / M.cell_hash(cell))
            dev = M.curve_deviation_pct(r.result, r) if r.result else None
            fh.write(json.dumps({"id": cell.id, "wall_s": time.monotonic() - t0, "run_code": r.run_code, "identify_code": r.identify_code,
                                 "injected_at_s": r.injected_at_s, "curve_deviation_pct": dev[0] if dev else None,
                                 "violations": M.violations(r, ref), "run": (r.run_out.strip().splitlines() or [""])[0][-200:],
                                 "identify_error": r.identify_err.strip()[-300:], "warnings": (r.result or {}).get("warnings")}, default=str) + "\n")
            fh.flush()
            shutil.rmtree(Path(tmp) / M.cell_hash(cell), ignore_errors=True)


def table(out: Path) -> None:
    cells = {c.id: c for c in M.all_cells()}
    rows = [json.loads(line) for line in out.read_text().splitlines() if line.strip()]

    def status(r):
        if not r["violations"]:
            return "passed", []
        known = [reason.split(":")[0] for reason, applies in KNOWN if applies(cells[r["id"]])]
        return ("failed, known defect" if known else "FAILED, new"), known or [k for k, _ in r["violations"]]

    kinds = ("passed", "failed, known defect", "FAILED, new")
    print(f"cells run {len(rows)}: " + ", ".join(f"{k} {sum(status(r)[0] == k for r in rows)}" for k in kinds))
    axes = [("test", lambda c: c.test), ("temperature C", lambda c: f"{c.temperature_C:g}"), ("speed mm/s", lambda c: f"{c.speed_mm_per_s:g}"),
            ("rate Hz", lambda c: f"{c.rate_Hz:g}"), ("material", lambda c: c.material), ("fault", lambda c: c.fault.label)]
    for name, value in axes:
        counts = collections.defaultdict(collections.Counter)
        for r in rows:
            counts[value(cells[r["id"]])][status(r)[0]] += 1
        print(f"\n| {name} | run | " + " | ".join(kinds) + " |\n|---|---|---|---|---|")
        order = [value(c) for c in M.all_cells()]
        for key, n in sorted(counts.items(), key=lambda item: order.index(item[0])):
            print(f"| {key} | {sum(n.values())} | " + " | ".join(str(n[k]) for k in kinds) + " |")
    causes = collections.Counter((status(r)[0], " + ".join(status(r)[1])) for r in rows if r["violations"])
    print("\n| cause | cells |\n|---|---|")
    for (kind, why), n in causes.most_common():
        print(f"| {kind}: {why} | {n} |")
    broken = collections.Counter(k for r in rows for k, _ in r["violations"])
    print("\n| invariant broken | cells |\n|---|---|")
    for k, n in broken.most_common():
        print(f"| {k} | {n} |")
    for r in rows:
        if status(r)[0] == "FAILED, new":
            print(f"new: {r['id']}: " + "; ".join(f"{k}: {d}" for k, d in r["violations"]))


def main(argv: list[str]) -> int:
    out = Path(argv[0])
    if "--table" not in argv:
        which = argv[1] if len(argv) > 1 else "subset"
        cells = {"subset": subset_cells, "all": M.all_cells, "default": lambda: M.default_selection(M.all_cells(), M.matrix_seed()),
                 "named": lambda: [c for c in M.all_cells() if c.id in (M.cells_from_env() or ())]}[which]()
        run(out, cells)
    table(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
