"""Friction and the friction-corrected flow curve of a compression test.

Friction on the platens barrels the specimen and raises the force above what the flow
stress alone needs. The friction coefficient μ comes from the barrel: the largest diameter
after the test (post.dmax_mm) and the final height (post.hk_mm) (docs/methods.md §4.2); the
flow stress is the mean platen pressure divided by a friction factor (§4.4, §4.5). Several
corrections are computed; this script asks for the slab method's, which is also the
friction law of the virtual rig that made the record (recorded before the rig's compression
came from CalculiX runs: its force is the slab factor's and its barrel the seed's (3.18), the
rig's ``compression_response="slab"`` today; the default corrections read a few per cent off on it).

The record was made on the virtual rig (examples/data/README.md), whose material and
friction are known: the script prints what it identified; tests/test_examples.py compares
it with the virtual material.

Run: python examples/compression_friction.py
"""

from pathlib import Path

from flowcurve.identification.identify import identify
from flowcurve.record.format import read_record

RECORD = Path(__file__).parent / "data" / "compression-steel45.csv"


def main() -> None:
    record = read_record(RECORD)
    result = identify(record, friction_correction="slab").result
    print(f"{RECORD.name}: d0 {record.meta['specimen.d0_mm']} mm, h0 {record.meta['specimen.h0_mm']} mm, "
          f"after the test hk {record.meta['post.hk_mm']} mm, dmax {record.meta['post.dmax_mm']} mm")
    for method, mu in result["friction"].items():
        print(f"friction μ ({method}): {mu:.4f}")
    law = result["hardening"]
    lo, hi = law["strain_range"]
    print(f"Johnson-Cook static ({law['correction']} correction): A {law['A_MPa']:.1f} MPa, B {law['B_MPa']:.1f} MPa, "
          f"n {law['n']:.4f}, identified over true plastic strain {lo:.3f} … {hi:.3f}")
    for e in (0.1, 0.3, 0.6):
        print(f"flow stress at true plastic strain {e:.1f}: {law['A_MPa'] + law['B_MPa'] * e ** law['n']:.1f} MPa")


if __name__ == "__main__":
    main()
