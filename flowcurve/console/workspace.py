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
        """The identify service (``flowcurve identify``'s) on one record into OUT/results/<stem>/; its summary."""
        from flowcurve.services.identify import IdentifyRequest, identify

        self.within(record)
        self.result_folder(record)  # results/<stem> written only inside --out
        try:
            identify(IdentifyRequest(record, self.within(self.results)))
        except Exception as exc:  # noqa: BLE001 — named without the record's text
            raise FlowcurveError(self.public_error(exc)) from None
        return self.result_summary(record)

    # series fit and card ----------------------------------------------------------------------
    def fit_and_card(self, names: list[str], options: dict) -> dict:
        """The series fit on the named records (their result folders when identified), then its
        card: the services ``flowcurve fit`` and ``flowcurve card`` call, with requests built from
        the form. Every input the two lack is named at once (a FormError by field) before anything
        is written, and a fit or card that fails leaves no folder behind."""
        import shutil

        from flowcurve.console.setup_form import FormError
        from flowcurve.identification.series.series import load_members
        from flowcurve.reports.card_formats import card_suffix
        from flowcurve.services.card import card, missing_for_fit_and_card
        from flowcurve.services.fit import fit, summary

        if not names:
            raise FlowcurveError("fit: select at least one record")
        inputs = []
        for name in names:
            record = self.record_path(name)
            folder = self.result_folder(record)
            inputs.append(str(self.checked_folder(folder) if (folder / "result.json").is_file() else record))
        out = self.within(self.fits) / f"fit-{_dt.datetime.now():%Y%m%d-%H%M%S-%f}"
        fit_request, card_request = _requests(inputs, out, options)
        fmt = card_request.format
        card_path = out / f"card-{bare_name(fmt, 'format')}.{card_suffix(fmt)}"
        card_request.output = str(card_path)
        try:
            members = load_members(fit_request.inputs)
        except Exception as exc:  # noqa: BLE001 — a record or result named without its text
            raise FlowcurveError(self.public_error(exc)) from None
        missing = {FORM_FIELD[k]: v for k, v in missing_for_fit_and_card(members, fit_request, card_request).items()}
        if missing:
            listed = ", ".join(FIT_LABELS[k] for k in missing)
            raise FormError({**missing, "fit": f"the fit and card need {len(missing)} input(s) not given: {listed}"})
        try:
            series, fit_json = fit(fit_request, members)
            card_request.fit = str(fit_json)
            card(card_request)
        except BaseException:
            shutil.rmtree(out, ignore_errors=True)  # a refused fit or card leaves no fits/fit-* folder
            raise
        plots = sorted((out / "plots").glob("*.png"))
        return {"summary": summary(series, fit_json), "fit": self.url(fit_json), "card": self.url(card_path), "card_name": card_path.name,
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


def fit_choices() -> dict[str, list]:
    """The fit form's choices from the registries, [[value, shown], …] each (a new law or unit
    system needs no edit of the page): laws (Johnson–Cook first: the default), fit methods, unit
    systems (the default first) and LS-DYNA materials ("": *MAT_015 with *MAT_024, the default)."""
    from flowcurve.identification.laws.base import registered_laws
    from flowcurve.reports.cards.data import LSDYNA_MATERIAL_NAMES
    from flowcurve.reports.units import DEFAULT_UNIT_SYSTEM, UNIT_SYSTEMS
    from flowcurve.services.fit import METHODS

    laws = sorted(registered_laws().items(), key=lambda item: (item[0] != "johnson_cook", item[1].display_name))
    return {"laws": [[name, law.display_name] for name, law in laws],
            "fit_methods": [[m, m] for m in METHODS],
            "unit_systems": [[u, u] for u in sorted(UNIT_SYSTEMS, key=lambda u: u != DEFAULT_UNIT_SYSTEM)],
            "lsdyna_materials": [["", "*MAT_015 and *MAT_024"]] + [[k, f"{k} ({v})"] for k, v in LSDYNA_MATERIAL_NAMES.items()]}


# the fit form's fields → (request, its field); how the form labels every input it may lack
FIT_FIELDS = {"melt_temp": ("fit", "melt_temp"), "fix_C": ("fit", "fix_C"), "fix_m": ("fit", "fix_m"), "ref_rate": ("fit", "ref_rate"),
              "ref_temp": ("fit", "ref_temp"), "poisson": ("card", "poisson"), "density": ("card", "density_kg_per_m3"),
              "cp": ("card", "specific_heat_J_per_kgK"), "E_MPa": ("card", "E_MPa")}
FORM_FIELD = {field: form for form, (_, field) in FIT_FIELDS.items()}  # a request's field → the form's
FIT_LABELS = {"melt_temp": "Melting temperature, °C", "fix_C": "fix C", "fix_m": "fix m", "poisson": "Poisson's ratio",
              "density": "Density, kg/m³", "cp": "Specific heat, J/(kg K)", "E_MPa": "E, MPa"}


def _requests(inputs: list[str], out: Path, options: dict):
    """The fit's and the card's requests from the fit form (FormError: a value that is no number,
    an unknown method, format or unit system, each by its field)."""
    from flowcurve.console.setup_form import FormError
    from flowcurve.services import FieldError
    from flowcurve.services.card import CardRequest
    from flowcurve.services.fit import FitRequest

    values: dict[str, dict] = {"fit": {}, "card": {}}
    errors: dict[str, str] = {}
    for form, (request, field) in FIT_FIELDS.items():
        text = str(options.get(form) or "").strip()
        try:
            values[request][field] = float(text) if text else None
        except ValueError:
            errors[form] = f"not a number: {text!r}"
    units = str(options.get("units") or "").strip()
    law = str(options.get("law") or "").strip() or "johnson_cook"
    material = str(options.get("lsdyna_material") or "").strip() or None  # none: *MAT_015 with *MAT_024
    fit_request = FitRequest(inputs, out, method=str(options.get("method") or "global"), law=law, **values["fit"])
    card_request = CardRequest("fit.json", str(options.get("format") or "lsdyna"), **values["card"], **({"units": units} if units else {}),
                               lsdyna_material=material)
    for request in (fit_request, card_request):
        try:
            request.check()
        except FieldError as exc:
            errors.update(exc.errors)
    if errors:
        raise FormError(errors)
    return fit_request, card_request


