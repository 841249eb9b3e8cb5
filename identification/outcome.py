"""What an identification hands to the command line and the reports.

Tension and compression identifications both return an :class:`Identification`; the
``identify`` command writes it as ``result.json``, ``true_curve.csv`` and PNG plots, so the
two test types share one output path.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import numpy as np

if TYPE_CHECKING:  # annotations only; pandas stays out of `flowcurve --help`
    import pandas as pd

TRUE_CURVE_COLUMNS = ("true_plastic_strain", "true_stress_MPa")


@dataclass
class Identification:
    """Results of identifying one record.

    Attributes
    ----------
    result : Mapping
        What result.json holds (units in its keys: ``Rm_MPa``): a TensionResult or CompressionResult
        (typed, readable as a mapping; the inverse FE's with its typed ``inverse_fe`` block), or a plain dict.
    true_curve : DataFrame
        At least the columns of :data:`TRUE_CURVE_COLUMNS`.
    curves : dict of DataFrame
        Named curves for plots and comparison ("raw_diagram", "engineering", "true", "fit" …).
    plots : dict of callable
        name → function(path) drawing one PNG (filled by the caller; :meth:`write` calls them).
    """

    result: Mapping  # TensionResult | CompressionResult (| dict)
    true_curve: pd.DataFrame
    curves: dict[str, pd.DataFrame] = field(default_factory=dict)
    plots: dict[str, Callable[[Path], None]] = field(default_factory=dict)

    def write(self, outdir: str | Path) -> Path:
        """Write result.json and the curves (CSV) into ``outdir``; the result.json path."""
        outdir = Path(outdir)
        outdir.mkdir(parents=True, exist_ok=True)
        (outdir / "result.json").write_text(json.dumps(to_jsonable(self.result), indent=2, allow_nan=False) + "\n", encoding="utf-8")
        self.true_curve.to_csv(outdir / "true_curve.csv", index=False, float_format="%.6g", lineterminator="\n")
        for name, draw in self.plots.items():
            draw(outdir / f"{name}.png")
        return outdir


def to_jsonable(value):
    """numpy scalars/arrays → Python; NaN/inf → None (JSON has no NaN); a mapping (a typed
    result) → dict."""
    if isinstance(value, Mapping):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [to_jsonable(v) for v in value.tolist()]
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def read_json_object(path: str | Path, error: type[Exception], what: str = "JSON file") -> dict:
    """Read a JSON object (result.json, fit.json); any problem is one ``error`` naming the file
    (and the line and column of a syntax error)."""
    path = Path(path)
    try:
        value = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{path}: cannot read: {exc}") from None
    except json.JSONDecodeError as exc:
        raise error(f"{path}, line {exc.lineno}, column {exc.colno}: not valid JSON: {exc.msg}") from None
    if not isinstance(value, dict):
        raise error(f"{path}: a {what} holds a JSON object, not {type(value).__name__}")
    return value
