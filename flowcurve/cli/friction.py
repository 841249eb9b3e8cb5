"""``flowcurve friction``: the adhesion friction law (2.25) from rotating-sphere adhesiometer tests.

Writes ``friction.json`` (docs/adhesion.md), ``tests.csv`` (each test, measured and model),
plots (τ against σ_nr per temperature with the fitted law; residuals) and, on request,
solver cards. ``flowcurve friction-demo`` runs the virtual adhesiometer first.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from flowcurve.cli.choices import ADHESION_COLUMNS, CONTACT_RATIO_MODELS, FRICTION_CARD_FORMATS, HOT_FROM_C
from flowcurve.reports.units import DEFAULT_UNIT_SYSTEM, UNIT_SYSTEMS

if TYPE_CHECKING:  # the fit and the tables import numpy: imported where a command runs, not for --help
    from flowcurve.identification.compression.adhesion import FrictionFit

CARD_FILES = {"abaqus": "friction_abaqus.inp", "lsdyna": "friction_lsdyna.k"}


def register(subparsers) -> None:
    """Add ``friction`` to the subcommands."""
    p = subparsers.add_parser(
        "friction",
        help="adhesion friction constants tau0, beta0, k_b, theta_k from adhesiometer tests",
        description=(
            "Identify the friction law tau = tau0 + (beta0 - k_b*max(0, T - theta_k))*sigma_nr + mu_d*sigma_n "
            "(seed (2.25)) from rotating-sphere adhesiometer tests (N_z, M_z, imprint radius r, temperature): "
            "the simple fit (3.35)-(3.37) or the refined fit (3.38)-(3.44) over the Hertz pressure distribution, "
            "which also gives the surface flow stress sigma_S. Writes friction.json, tests.csv, plots/ and cards."
        ),
    )
    p.add_argument("records", nargs="+", metavar="RECORD", help="adhesion tables (flowcurve-adhesion CSV, or any CSV with --column)")
    p.add_argument("--out", default="friction", metavar="DIR", help="output folder (default: ./friction)")
    _fit_options(p)
    p.add_argument("--column", action="append", default=[], metavar="QUANTITY=COLUMN[:UNIT]",
                   help="for a foreign CSV: which column holds which quantity, e.g. normal_force=Fz:kN moment=Mz:N*mm "
                        "imprint_radius=r:um temperature=T:K (quantities: " + ", ".join(ADHESION_COLUMNS) + "); "
                        "repeat per column; without a unit the file's units row is used")
    p.set_defaults(func=run)

    d = subparsers.add_parser(
        "friction-demo",
        help="virtual adhesiometer tests from known constants, then 'flowcurve friction' on them",
        description=("Run the virtual rotating-sphere adhesiometer (steel 45 against an 8 mm hard-alloy sphere) at "
                     "loads from first yield to a fully plastic imprint, at 20 C and (with --hot) 600/700/800 C, "
                     "write the table to DIR/adhesion_tests.csv and identify the friction law from it."),
    )
    d.add_argument("--out", default="friction-demo", metavar="DIR", help="output folder (default ./friction-demo)")
    d.add_argument("--hot", action="store_true", help="add tests at 600, 700 and 800 C")
    d.add_argument("--contact", choices=("full", "bowden_tabor"), default="full",
                   help="real contact of the virtual tests (default full: K_r = 1)")
    d.add_argument("--noise", type=float, default=0.005, metavar="REL", help="relative scatter of M_z (default 0.005)")
    d.add_argument("--radius-noise", type=float, default=0.5, metavar="UM", help="scatter of the measured imprint radius, um (default 0.5)")
    d.add_argument("--seed", type=int, default=1, help="random seed of the scatter")
    _fit_options(d, demo=True)
    d.set_defaults(func=run_demo)


def _fit_options(p, demo: bool = False) -> None:
    p.add_argument("--method", choices=("simple", "refined"), default="simple", help="simple (3.35)-(3.37) or refined (3.38)-(3.44) fit")
    p.add_argument("--mu-d", type=float, metavar="VALUE", help="deformation component mu_d of the friction (else from the microrelief)")
    p.add_argument("--contact-model", choices=sorted(CONTACT_RATIO_MODELS), metavar="MODEL",
                   help="real-to-nominal contact area K_r: none (K_r = 1) or bowden_tabor (min(1, sigma_n/(3 sigma_S))); "
                        "default none for the simple fit, bowden_tabor for the refined fit")
    p.add_argument("--flow-stress", type=float, metavar="MPa", help="surface flow stress sigma_S of the tests that do not state it")
    p.add_argument("--hot-from", type=float, default=HOT_FROM_C, metavar="C", help=f"tests at or above this temperature give k_b, theta_k (default {HOT_FROM_C:g})")
    p.add_argument("--weights", choices=("relative", "absolute"), default="relative",
                   help="least-squares residuals relative to the measured value (default) or absolute (the seed's plain sum)")
    p.add_argument("--moment-accuracy", type=float, metavar="REL",
                   help="relative scatter of the measured M_z (e.g. 0.005); with --radius-accuracy, residuals are weighted "
                        "by their effective variance and the uncertainties account for the imprint radius error")
    p.add_argument("--radius-accuracy", type=float, metavar="UM", help="scatter of the measured imprint radius, um")
    p.add_argument("--asperity-radius", type=float, metavar="UM", help="asperity radius of the sphere's microrelief, um (mu_d from R_p, t_m)")
    p.add_argument("--bearing-exponent", type=float, default=2.0, metavar="NU", help="exponent nu of the bearing curve (default 2)")
    p.add_argument("--card", action="append", default=[], choices=FRICTION_CARD_FORMATS, help="also write a solver card (repeatable)")
    p.add_argument("--units", default=DEFAULT_UNIT_SYSTEM, choices=sorted(UNIT_SYSTEMS), help=f"unit system of the cards (default {DEFAULT_UNIT_SYSTEM})")
    p.add_argument("--at-pressure", type=float, metavar="MPa", help="LS-DYNA FS/FD at this contact pressure (default: geometric middle of the range)")
    p.add_argument("--at-temperature", type=float, metavar="C", help="LS-DYNA FS/FD at this temperature (default: the lowest tested)")


def _fit(table, args) -> FrictionFit:
    from flowcurve.identification.compression.adhesion import fit_friction

    if args.flow_stress is not None and args.flow_stress <= 0:
        from flowcurve.errors import IdentificationError

        raise IdentificationError(f"--flow-stress must be > 0 MPa, got {args.flow_stress:g}")
    model = args.contact_model or ("none" if args.method == "simple" else "bowden_tabor")
    accuracy = None
    if args.moment_accuracy is not None or args.radius_accuracy is not None:
        accuracy = (args.moment_accuracy or 0.0, args.radius_accuracy or 0.0)
    return fit_friction(table, args.method, mu_d=args.mu_d, mu_d_source=getattr(args, "mu_d_source", None), contact_model=model, flow_stress_MPa=args.flow_stress,
                        hot_from_C=args.hot_from, weights=args.weights, asperity_radius_um=args.asperity_radius,
                        bearing_exponent=args.bearing_exponent, accuracy=accuracy)


def run(args) -> int:
    """``flowcurve friction``: adhesion friction constants from adhesiometer tables; the exit status."""
    from flowcurve.record.adhesion import parse_adhesion_column_option, read_adhesion_tables

    columns = dict(parse_adhesion_column_option(text) for text in args.column)
    table = read_adhesion_tables(args.records, columns=columns or None)
    fit = _fit(table, args)
    given = {k: v for k, v in vars(args).items() if k not in ("command", "func", "records", "out", "verbose", "log_level") and v is not None}
    path = write_friction(fit, table, args.out, cards=args.card, units=args.units,
                          at_pressure_MPa=args.at_pressure, at_temperature_C=args.at_temperature, options=given)
    print(summary(fit, path))
    return 0


def run_demo(args) -> int:
    """``flowcurve friction --demo``: virtual adhesiometer tables written and fitted; the exit status."""
    import numpy as np

    from flowcurve.record.adhesion import write_adhesion_table
    from flowcurve.rig.virtual.adhesiometer import VirtualAdhesiometer

    device = VirtualAdhesiometer(contact=args.contact, moment_noise_rel=args.noise, radius_noise_um=args.radius_noise, seed=args.seed)
    forces = list(np.geomspace(5.0, 1300.0, 24))
    temps = [20.0] * len(forces)
    if args.hot:
        for t in (600.0, 700.0, 800.0):
            forces += [200.0, 400.0, 800.0]
            temps += [t] * 3
    data, traces = device.run_series(forces, temps, trace_seconds=20.0)
    out = Path(args.out)
    table_path = write_adhesion_table(out / "adhesion_tests.csv", data, device.table_meta(), traces)
    t = device.truth
    print(f"virtual adhesiometer: {len(data)} tests written to {table_path}; truth tau0 = {t.tau0_MPa:g} MPa, beta0 = {t.beta0:g}, "
          f"k_b = {t.k_b_per_C:.4g} 1/C, theta_k = {t.theta_k_C:g} C, mu_d = {t.mu_d:g}, "
          f"sigma_S(20 C) = {device.surface_flow_stress_MPa(20.0):.1f} MPa")
    if args.mu_d is None:
        args.mu_d, args.mu_d_source = t.mu_d, "default: the virtual adhesiometer's own (not given, not measured; set it with --mu-d)"
    args.records, args.column = [str(table_path)], []
    return run(args)


def write_friction(fit: FrictionFit, table, outdir, *, cards=(), units: str = DEFAULT_UNIT_SYSTEM,
                   at_pressure_MPa=None, at_temperature_C=None, options: dict | None = None) -> Path:
    """friction.json, tests.csv, plots/*.png and the requested cards in ``outdir``; friction.json
    and the cards carry the provenance (each table's SHA-256, the options as given)."""
    import pandas as pd

    from flowcurve.identification.outcome import to_jsonable
    from flowcurve.identification.provenance import file_sha256, provenance
    from flowcurve.reports.friction_cards import friction_card

    outdir = Path(outdir)
    (outdir / "plots").mkdir(parents=True, exist_ok=True)
    data = fit.as_dict()
    data["material"] = table.material or None
    data["records"] = list(table.sources)
    data["provenance"] = provenance({source: file_sha256(source) for source in table.sources}, options or {})
    data["plots"] = _plots(fit, outdir / "plots")
    data["cards"] = {}
    for fmt in dict.fromkeys(cards):
        text = friction_card(data, fmt, units, at_pressure_MPa=at_pressure_MPa, at_temperature_C=at_temperature_C)
        (outdir / CARD_FILES[fmt]).write_text(text, encoding="utf-8")
        data["cards"][fmt] = CARD_FILES[fmt]
    pd.DataFrame(fit.tests).to_csv(outdir / "tests.csv", index=False, float_format="%.6g", lineterminator="\n")
    path = outdir / "friction.json"
    path.write_text(json.dumps(to_jsonable(data), indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return path


def _plots(fit: FrictionFit, folder: Path) -> list[str]:
    """Each test's adhesion stress against its mean pressure per temperature, with the model and law; residuals."""
    import matplotlib
    import numpy as np

    from flowcurve.identification.compression.adhesion import HERTZ_MEAN_FACTOR, adhesion_shear

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tests = fit.tests
    temps = sorted({t["temperature_C"] for t in tests})
    fig, ax = plt.subplots(figsize=(7, 5))
    for i, T in enumerate(temps):
        group = sorted((t for t in tests if t["temperature_C"] == T), key=lambda t: t["nominal_mean_pressure_MPa"])
        x = np.array([t["nominal_mean_pressure_MPa"] for t in group])
        # what each test shows: the mean stress (3.35) less the deformation part, measured and as the model gives it
        y = np.array([t["tau_n_MPa"] - t["mu_d"] * t["nominal_mean_pressure_MPa"] for t in group])
        model = y * np.array([1.0 + t["residual_pct"] / 100.0 for t in group]) if fit.method == "simple" else \
            np.array([HERTZ_MEAN_FACTOR * t["model_moment_N_m"] * 1e3 / t["imprint_radius_mm"] ** 3
                      - t["mu_d"] * t["nominal_mean_pressure_MPa"] for t in group])
        color = f"C{i % 10}"
        ax.plot(x, y, "o", ms=4, color=color, label=f"{T:g} C tests" + ("" if all(t["used"] for t in group) else " (not used)"))
        ax.plot(x, model, "-", color=color, lw=1, label=f"{T:g} C fitted model, as (3.35) reads it")
        grid = np.linspace(0.0, x.max() * 1.05, 50)
        v = fit.values
        law = adhesion_shear(grid, T, v["tau0_MPa"], v["beta0"], v["k_b_per_C"], v["theta_k_C"])
        ax.plot(grid, law, "--", color=color, lw=1, label=f"law (2.25) at {T:g} C, full contact")
    ax.set(xlabel="nominal mean pressure N/(pi r^2), MPa (= sigma_nr at full contact)", ylabel="adhesion shear stress, MPa",
           title=f"{fit.method} fit: tau0 = {fit.values['tau0_MPa']:.3g} MPa, beta0 = {fit.values['beta0']:.3g}")
    ax.text(0.02, 0.02, "points: 0.540 M/r^3 - mu_d p (3.35); (3.35) reads a uniform tau0 as 1.132 tau0",
            transform=ax.transAxes, fontsize=7)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(folder / "tau_vs_pressure.png", dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for i, T in enumerate(temps):
        group = [t for t in tests if t["temperature_C"] == T]
        ax.plot([t["nominal_mean_pressure_MPa"] for t in group], [t["residual_pct"] for t in group], "o", ms=4, color=f"C{i % 10}", label=f"{T:g} C")
    ax.axhline(0.0, color="0.3", lw=0.8)
    ax.set(xlabel="nominal mean pressure N/(pi r^2), MPa", ylabel="model - measured, %",
           title=f"residuals of the {fit.method} fit ({'tau_adh' if fit.method == 'simple' else 'M_z'})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(folder / "residuals.png", dpi=110)
    plt.close(fig)
    return ["plots/tau_vs_pressure.png", "plots/residuals.png"]


def summary(fit: FrictionFit, path: Path) -> str:
    """The terminal's summary of a friction fit: each constant ± its standard error."""
    v, se = fit.values, fit.stderr

    def pm(key, unit="", fmt="{:.4g}"):
        """One constant as "value ± error unit", or why it is not given."""
        if v[key] is None:
            return "not identified"
        flag = " (UNDETERMINED: smaller than its own uncertainty)" if key in fit.extra.get("undetermined", ()) else ""
        return fmt.format(v[key]) + (f" ± {se[key]:.2g}" if se.get(key) else "") + unit + flag

    p, T = fit.covered["nominal_mean_pressure_MPa"], fit.covered["temperature_C"]
    lines = [f"friction law (2.25), {fit.method} fit over {fit.extra['tests_used']} tests "
             f"(pressure {p[0]:.4g}..{p[1]:.4g} MPa, {T[0]:g}..{T[1]:g} C), rms residual {fit.extra['rms_residual_pct']:.2g} %",
             f"  tau0 = {pm('tau0_MPa', ' MPa')}, beta0 = {pm('beta0')}, mu_d = {pm('mu_d')} ({fit.sources['mu_d']})",
             f"  k_b = {pm('k_b_per_C', ' 1/C')}, theta_k = {pm('theta_k_C', ' C')} ({fit.sources['hot_constants']})"]
    if fit.method == "refined":
        lines.append(f"  sigma_S = {pm('sigma_S_MPa', ' MPa')}; contact model {fit.contact_model}")
    lines += [f"  warning: {w}" for w in fit.warnings]
    lines.append(f"written: {path}")
    return "\n".join(lines)
