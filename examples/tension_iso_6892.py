"""ISO 6892-1 results of a real tension test, beside the ones the lab published.

The record is an INSTRON export of a 42CrMoS4 specimen (examples/data/README.md): its
header carries the lab's own results, its columns the raw time, force, extensometer and
crosshead signals. ``load_record`` recognises the format; ``identify`` computes E, Rp0.2,
Rm, Ag, A and Z from the raw columns alone (docs/methods.md §2, §3.1–§3.3).

Run: python examples/tension_iso_6892.py
"""

from pathlib import Path

from flowcurve.identification.identify import identify
from flowcurve.record.importers import load_record

RECORD = Path(__file__).parent / "data" / "46NT71.csv"

# result key → (label, unit, the INSTRON header line holding the published value)
RESULTS = {
    "E_MPa": ("E", "MPa", "Slope of linear-elastic region"),
    "Rp02_MPa": ("Rp0.2", "MPa", "Yield stress at 0.2% plastic strain"),
    "Rm_MPa": ("Rm", "MPa", "Ultimate tensile strength"),
    "Ag_pct": ("Ag", "%", "Uniform elongation"),
    "A_pct": ("A", "%", "Elongation after fracture"),
    "Z_pct": ("Z", "%", "Reduction of area"),
}


def published(path: Path) -> dict[str, float]:
    """The lab's values from the export's header (``name:<TAB>value<TAB>unit`` lines)."""
    values = {}
    for line in path.read_text(encoding="latin-1").splitlines()[:40]:
        name, _, rest = line.partition(":\t")
        values[name] = rest.split("\t")[0]
    return {key: float(values[header]) for key, (_, _, header) in RESULTS.items()}


def main() -> None:
    result = identify(load_record(RECORD)).result
    lab = published(RECORD)
    print(f"{RECORD.name}: identified from the raw columns | published by the lab")
    for key, (label, unit, _) in RESULTS.items():
        print(f"{label}: {result[key]:.2f} {unit} | {lab[key]:.2f} {unit}")


if __name__ == "__main__":
    main()
