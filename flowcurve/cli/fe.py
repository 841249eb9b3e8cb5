"""``flowcurve verify``: run an identified curve in CalculiX on a record's specimen.

The identified flow curve (``result.json`` or its folder, or a CalculiX card with a
``*PLASTIC`` table) and the friction μ drive the upsetting model on the record's geometry;
the frame-corrected force–stroke of the record is compared with the FE force.
``DIR/verify.json`` holds ``max_force_deviation_pct``; ``DIR/verify.png`` the two curves and
the deviation.
"""

from __future__ import annotations

import json
from pathlib import Path


def register(subparsers) -> None:
    """Add ``verify`` to the subcommands."""
    p = subparsers.add_parser(
        "verify", help="run the identified curve in CalculiX on the record's specimen and report the force-stroke deviation",
        description=__doc__.split("\n\n")[1].replace("\n", " "))
    p.add_argument("curve", metavar="RESULT_OR_CARD", help="result.json (or its folder) of an identification, or a CalculiX card (*ELASTIC, *PLASTIC)")
    p.add_argument("record", metavar="RECORD", help="the compression record to verify against")
    p.add_argument("--out", metavar="DIR", default="flowcurve-verify", help="folder for verify.json and verify.png (default ./flowcurve-verify)")
    p.add_argument("--mu", type=float, help="friction coefficient (default: the result's friction_mu; for a card, the record's fe_table μ)")
    p.add_argument("--increments", type=int, help="solver increments of the check (default 200; the inverse FE fits with 50)")
    p.add_argument("--layers", type=int, help="boundary-layer elements at the free surface (default 4; the inverse FE's 2)")
    p.add_argument("--no-plots", action="store_true", help="skip verify.png")
    p.set_defaults(func=run_verify)


def _plot(report: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c = report["curves"]
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7, 7), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    ax.plot(c["stroke_mm"], c["record_force_N"] / 1000.0, label="record (frame-corrected)")
    ax.plot(c["stroke_mm"], c["fe_force_N"] / 1000.0, "--", label=f"CalculiX, μ = {report['mu']:.3f}")
    ax.set_ylabel("force, kN")
    ax.legend()
    ax2.plot(c["stroke_mm"], c["deviation_pct"])
    ax2.axhline(0.0, color="0.5", lw=0.5)
    ax2.set_xlabel("specimen shortening, mm")
    ax2.set_ylabel("record − FE, %")
    ax.set_title(f"max deviation {report['max_force_deviation_pct']:.2f} %")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run_verify(args) -> int:
    """``flowcurve verify``: the identified curve run in CalculiX against the record; the exit status."""
    from flowcurve.identification.fe.verify import VERIFY_INCREMENTS, VERIFY_LAYERS, load_curve, verify_compression
    from flowcurve.identification.outcome import to_jsonable
    from flowcurve.record.importers import load_record

    curve = load_curve(args.curve)
    record = load_record(args.record)
    report = verify_compression(curve, record, mu=args.mu, increments=args.increments or VERIFY_INCREMENTS, layers=args.layers or VERIFY_LAYERS)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "verify.json").write_text(json.dumps(to_jsonable(report), indent=2) + "\n", encoding="utf-8")
    if not args.no_plots:
        _plot(report, out / "verify.png")
    dd = report["dmax_deviation_mm"]
    print(f"{args.record}: CalculiX, μ {report['mu']:.3f}, E {report['E_MPa']:.0f} MPa ({report['E_source']}), to {report['stroke_end_mm']:.3f} mm "
          f"({report['solver_wall_s']:.0f} s{', cached' if report['solver_cached'] else ''})")
    print(f"  force deviation: max {report['max_force_deviation_pct']:.2f} %, rms {report['rms_force_deviation_pct']:.2f} %, "
          f"at the end {report['final_force_deviation_pct']:+.2f} %" + ("" if dd is None else f"; dmax record − FE {dd:+.3f} mm"))
    if report.get("fold_over_strain") is not None and report.get("max_force_deviation_before_fold_over_pct") is not None:
        print(f"  up to strain {report['before_fold_over_to_strain']:.3f}, before the band where the model's own force error grows "
              f"(its side folds onto the platen from {report['fold_over_strain']:.3f}): max "
              f"{report['max_force_deviation_before_fold_over_pct']:.2f} %")
    disc = report.get("discretisation")
    if disc:
        print(f"  the check's model ({report['model']['layers']} rim layers, {report['model']['increments']} increments) against the fit's "
              f"({disc['layers']}, {disc['increments']}): force up to {disc['max_force_gap_pct']:.2f} % apart — the check's own "
              f"discretisation error; the fit's model reads {disc['max_force_deviation_pct']:.2f} % from the record")
    print(f"  → {out / 'verify.json'}")
    return 0
