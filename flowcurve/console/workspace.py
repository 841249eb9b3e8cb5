"""The console's folder (``--out``): records, their results, series fits and cards.

::

    OUT/records/<record>.csv        written by the procedure, amended with post-test values
    OUT/results/<record stem>/      flowcurve identify's folder (result.json, plots, true curve)
    OUT/fits/<fit name>/            flowcurve fit's folder (fit.json, curves/, plots/) and cards

Nothing the console reads or writes goes anywhere else: every path a request names is a bare
name checked against these folders (:func:`inside`), never a path joined as given, and every
path is resolved before use — a link that leaves ``--out`` is refused (:meth:`Workspace.within`).
An error from reading a file reaches an HTTP answer as :meth:`Workspace.public_error`: file,
line and column, never the file's text.
"""

from __future__ import annotations

import datetime as _dt
import logging
import re
from pathlib import Path

from flowcurve.errors import FlowcurveError, MissingValueError, RecordError

log = logging.getLogger(__name__)

NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,120}$")


class PathError(FlowcurveError):
    """A request named a file outside the console's folder, or a name that is not one."""


def inside(root: Path, relative: str) -> Path:
    """``root/relative`` resolved, refused unless it stays inside ``root`` (no .., no links out)."""
    root = Path(root).resolve()
    if not relative or "\x00" in relative or relative.startswith(("/", "\\")) or "\\" in relative:
        raise PathError(f"not a file of the console's folder: {relative!r}")
    path = (root / relative).resolve()
    if path != root and root not in path.parents:
        raise PathError(f"not a file of the console's folder: {relative!r}")
    return path


def bare_name(name: str, what: str = "name") -> str:
    """A single file-name component (letters, digits, . _ -), or PathError."""
    if not isinstance(name, str) or not NAME_RE.match(name) or ".." in name:
        raise PathError(f"{what}: not a plain name: {name!r}")
    return name


class Workspace:
    """The folders under ``--out`` and what the console does with them."""

    def __init__(self, root: Path):
        self.root = Path(root).resolve()
        self.records = self.root / "records"
        self.results = self.root / "results"
        self.fits = self.root / "fits"

    def relative(self, path) -> str:
        """``path`` as named under --out (``records/x.csv``), not resolved: the name a link has."""
        try:
            return Path(path).relative_to(self.root).as_posix()
        except ValueError:
            return Path(path).name

    def within(self, path: Path) -> Path:
        """``path`` resolved (links followed), or PathError when it leaves --out."""
        resolved = Path(path).resolve()
        if resolved != self.root and self.root not in resolved.parents:
            raise PathError(f"{self.relative(path)}: refused: a link out of the console's folder")
        return resolved

    def record_path(self, name: str) -> Path:
        """OUT/records/``name`` resolved inside --out, or PathError."""
        name = bare_name(name, "record")
        if not name.endswith(".csv"):
            raise PathError(f"record: not a record file name (.csv): {name!r}")
        path = self.within(self.records / name)
        if not path.is_file():
            raise PathError(f"record: no such record in {self.records}: {name}")
        return path

    def result_folder(self, record: Path) -> Path:
        """OUT/results/<record stem> resolved inside --out (it may not exist yet), or PathError."""
        return self.within(self.results / Path(record).stem)

    def checked_folder(self, folder: Path) -> Path:
        """``folder`` and everything in it resolved inside --out, or PathError naming the first link out."""
        folder = self.within(folder)
        for path in folder.rglob("*"):
            self.within(path)
        return folder

    def public_error(self, exc: BaseException) -> str:
        """What an HTTP answer may say of an error from reading a file of --out: the file (as named
        under --out), line and column and what kind of problem — never the file's text. The whole
        message goes to the console's log (the operator's terminal)."""
        log.warning("reading the console's folder: %s", exc, exc_info=not isinstance(exc, FlowcurveError))
        if isinstance(exc, PathError):
            return str(exc)
        if isinstance(exc, RecordError):
            where = self.relative(exc.path)
            where += f", line {exc.line}" if exc.line is not None else ""
            where += f", column '{exc.column}'" if exc.column and NAME_RE.match(str(exc.column)) else ""
            if isinstance(exc, MissingValueError):
                return f"{where}: {exc.explain()}"  # from the keys asked for, not from the file
            return f"{where}: not readable as a record (flowcurve identify {self.relative(exc.path)} on the console's computer says why)"
        if isinstance(exc, FlowcurveError):  # the identification's or the fit's own words and figures
            return str(exc).replace(f"{self.root}/", "")
        return f"a file of the console's folder cannot be read ({type(exc).__name__})"

    def url(self, path: Path) -> str:
        """The /files/ address of a file inside the folder."""
        return "/files/" + Path(path).resolve().relative_to(self.root).as_posix()

    # records ---------------------------------------------------------------------------------
    def list_records(self) -> list[dict]:
        """Every record in OUT/records with its header's essentials and its result, newest first."""
        from flowcurve.record.format import read_record

        rows = []
        try:
            records = self.within(self.records)
        except PathError as exc:
            return [{"name": "records", "url": None, "error": str(exc), "refused": True, "result": None}]
        if not records.is_dir():
            return rows
        for path in sorted(self.records.glob("*.csv"), key=_mtime, reverse=True):
            entry: dict = {"name": path.name, "url": None}
            try:
                resolved = self.within(path)
                entry["url"] = self.url(resolved)
                rec = read_record(resolved)
                meta = rec.meta
                entry.update({
                    "test": meta.get("test"), "material": meta.get("material"), "specimen_id": meta.get("specimen.id"),
                    "date": meta.get("date"), "status": meta.get("status"), "stop_reason": meta.get("stop_reason") or meta.get("abort_reason"),
                    "samples": len(rec.data), "nominal_temperature_C": meta.get("nominal_temperature_C"),
                })
            except PathError as exc:
                entry.update(error=str(exc), refused=True)
            except Exception as exc:  # noqa: BLE001 — one unreadable file never breaks the list
                entry["error"] = self.public_error(exc)
            entry["result"] = None if entry.get("refused") else self.result_summary(path)
            rows.append(entry)
        return rows

    def result_summary(self, record: Path) -> dict | None:
        """The key figures of a record's result.json, with links to its files; None if not identified."""
        from flowcurve.identification.outcome import read_json_object

        try:
            folder = self.result_folder(record)
            path = self.within(folder / "result.json")
            if not path.is_file():
                return None
            res = read_json_object(path, FlowcurveError, "result.json")
        except Exception as exc:  # noqa: BLE001 — a link out refused, an unreadable result named
            return {"error": self.public_error(exc)}
        hard = res.get("hardening") or {}
        figures = {k: res.get(k) for k in ("E_MPa", "Rp02_MPa", "Rm_MPa", "A_pct", "Z_pct", "fracture_true_strain", "friction_mu", "final_true_strain", "max_force_N") if res.get(k) is not None}
        for k in ("A_MPa", "B_MPa", "n", "fit_error_pct"):
            if hard.get(k) is not None:
                figures[f"JC {k}"] = hard[k]
        files = sorted(p for p in folder.iterdir() if _inside_file(self, p))  # links out of --out are left out
        return {
            "folder": self.url(folder),
            "figures": figures,
            "hardening_law": hard.get("law"),
            "warnings": list(res.get("warnings") or []),
            "plots": [self.url(p) for p in files if p.suffix == ".png"],
            "files": [{"name": p.name, "url": self.url(p)} for p in files],
        }

    # identification --------------------------------------------------------------------------
    def identify(self, record: Path) -> dict:
        """``flowcurve identify`` on one record into OUT/results/<stem>/; its summary."""
        from flowcurve.demo import identify_and_write

        self.within(record)
        self.result_folder(record)  # results/<stem> written only inside --out
        try:
            identify_and_write(record, self.within(self.results))
        except Exception as exc:  # noqa: BLE001 — named without the record's text
            raise FlowcurveError(self.public_error(exc)) from None
        return self.result_summary(record)

    # series fit and card ----------------------------------------------------------------------
    def fit_and_card(self, names: list[str], options: dict) -> dict:
        """``flowcurve fit`` on the named records (their result folders when identified), then
        ``flowcurve card``: both with the command line's own parsers and functions. Every input
        the two lack is named at once (a FormError by field) before anything is written, and a
        fit or card that fails leaves no folder behind."""
        import shutil

        from flowcurve.cli import build_parser
        from flowcurve.cli.reports import run_card
        from flowcurve.cli.series import summary, write_fit
        from flowcurve.identification.series import fit_series, load_members
        from flowcurve.reports.cards import card_suffix

        if not names:
            raise FlowcurveError("fit: select at least one record")
        inputs = []
        for name in names:
            record = self.record_path(name)
            folder = self.result_folder(record)
            inputs.append(str(self.checked_folder(folder) if (folder / "result.json").is_file() else record))
        out = self.within(self.fits) / f"fit-{_dt.datetime.now():%Y%m%d-%H%M%S-%f}"
        argv = ["fit", *inputs, "--out", str(out)]
        for key, option in (("melt_temp", "--melt-temp"), ("fix_C", "--fix-C"), ("fix_m", "--fix-m"), ("ref_rate", "--ref-rate"), ("ref_temp", "--ref-temp")):
            value = str(options.get(key) or "").strip()
            if value:
                argv += [option, value]
        if options.get("method"):
            argv += ["--method", str(options["method"])]
        args = _parse(build_parser(), argv)
        fmt = str(options.get("format") or "lsdyna")
        units = str(options.get("units") or "").strip()
        card = out / f"card-{bare_name(fmt, 'format')}.{card_suffix(fmt)}"
        card_argv = ["card", "fit.json", "--format", fmt, "-o", str(card)] + (["--units", units] if units else [])
        for key, option in CARD_FIELDS.items():
            value = str(options.get(key) or "").strip()
            if value:
                card_argv += [option, value]
        card_args = _parse(build_parser(), card_argv)
        try:
            members = load_members(args.inputs)
        except Exception as exc:  # noqa: BLE001 — a record or result named without its text
            raise FlowcurveError(self.public_error(exc)) from None
        fixed = {k: v for k, v in (("C", args.fix_C), ("m", args.fix_m)) if v is not None}
        _check_complete(members, args, card_args, fixed)
        try:
            series = fit_series(members, method=args.method, ref_strain_rate_per_s=args.ref_rate, ref_temperature_C=args.ref_temp,
                                melt_temperature_C=args.melt_temp, fixed=fixed, max_points=args.max_points,
                                shape_error_pct=args.shape_error)
            fit_json = write_fit(series, out)
            card_args.fit = str(fit_json)
            run_card(card_args)
        except BaseException:
            shutil.rmtree(out, ignore_errors=True)  # a refused fit or card leaves no fits/fit-* folder
            raise
        text = summary(series, fit_json)
        plots = sorted((out / "plots").glob("*.png"))
        return {"summary": text, "fit": self.url(fit_json), "card": self.url(card), "card_name": card.name,
                "plots": [self.url(p) for p in plots], "folder": self.url(out)}


def _mtime(path: Path) -> float:
    """A file's modification time; 0 for a link to nothing (listed, not a traceback)."""
    try:
        return path.stat().st_mtime
    except OSError:
        return 0.0


def _inside_file(workspace: Workspace, path: Path) -> bool:
    """A file that resolves inside --out."""
    try:
        return workspace.within(path).is_file()
    except PathError:
        return False


# the fit form's card fields → card option; and how the form labels every input it may lack
CARD_FIELDS = {"poisson": "--poisson", "density": "--density", "cp": "--cp", "E_MPa": "--E"}
FIT_LABELS = {"melt_temp": "Melting temperature, °C", "fix_C": "fix C", "fix_m": "fix m", "poisson": "Poisson's ratio",
              "density": "Density, kg/m³", "cp": "Specific heat, J/(kg K)", "E_MPa": "E, MPa"}
FIELD_OF_CONSTANT = {"melt_temperature_C": "melt_temp", "poisson": "poisson", "density_kg_per_m3": "density",
                     "specific_heat_J_per_kgK": "cp", "E_MPa": "E_MPa"}


def _check_complete(members, args, card_args, fixed) -> None:
    """Every input the fit and the card lack, by form field, in one FormError (nothing written)."""
    from flowcurve.cli.reports import CARD_OPTIONS, missing_constants, overrides
    from flowcurve.cli.series import FIT_INPUTS, missing_inputs
    from flowcurve.console.setup_form import FormError
    from flowcurve.reports.cards.data import CONSTANTS, card_data_from_fit

    missing = {k: f"needed: {FIT_INPUTS[k][2]}" for k in missing_inputs(
        members, ref_strain_rate_per_s=args.ref_rate, ref_temperature_C=args.ref_temp, melt_temperature_C=args.melt_temp, fixed=fixed)}
    # the card's constants as fit.json will carry them (the records' mean E and Poisson's ratio), the law a stand-in
    Es = [m.E_MPa for m in members if m.E_MPa is not None]
    nus = [m.poisson_ratio for m in members if m.poisson_ratio is not None]
    provisional = {"A_MPa": 1.0, "B_MPa": 1.0, "n": 0.5, "melt_temperature_C": args.melt_temp,
                   "E_MPa": sum(Es) / len(Es) if Es else None, "poisson_ratio": sum(nus) / len(nus) if nus else None}
    data = card_data_from_fit(provisional, "fit.json", **overrides(card_args))
    card_options = {k: getattr(card_args, k) for k in CARD_OPTIONS}
    for name in missing_constants(data, card_args.format, card_args.units, card_options):
        missing.setdefault(FIELD_OF_CONSTANT[name], f"needed: the {card_args.format} card needs the {CONSTANTS[name][2]}")
    if missing:
        listed = ", ".join(FIT_LABELS[k] for k in missing)
        raise FormError({**missing, "fit": f"the fit and card need {len(missing)} input(s) not given: {listed}"})


def _parse(parser, argv: list[str]):
    """argparse on ``argv``; its complaint (it would exit) becomes one FlowcurveError line."""
    import contextlib
    import io

    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            return parser.parse_args(argv)
    except SystemExit:
        lines = [ln for ln in err.getvalue().splitlines() if ln.strip()]
        raise FlowcurveError(lines[-1] if lines else f"bad options: {' '.join(argv)}") from None
