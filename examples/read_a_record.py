"""Read a native flowcurve record: its header, its events and its samples.

A record is a CSV file with a ``# key: value`` header, ``# event:`` lines and unit-named
columns (docs/record-format.md). ``read_record`` gives the metadata as a dict, the events as
a list and the samples as a pandas DataFrame.

Run: python examples/read_a_record.py [RECORD]
"""

import math
import sys
from pathlib import Path

from flowcurve.record.format import read_record

RECORD = Path(__file__).parent / "data" / "compression-steel45.csv"


def main(path: Path) -> None:
    record = read_record(path)
    print(f"record: {path.name} ({record.test} test, material {record.meta['material']}, status {record.meta['status']})")
    print(f"columns: {', '.join(record.data.columns)}")
    print(f"samples: {len(record.data)}")
    for event in record.events:
        print(f"event: {event.time_s:.3f} s {event.name} {event.text}".rstrip())
    force_N = record.column("force_N")
    d0_mm = record.number("specimen.d0_mm", required=True)
    peak = abs(force_N).max()
    print(f"peak force: {peak:.1f} N")
    print(f"peak engineering stress: {peak / (math.pi * d0_mm**2 / 4):.2f} MPa (d0 = {d0_mm} mm)")
    print(f"crosshead travel: {abs(record.column('crosshead_mm')).max():.4f} mm")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else RECORD)
