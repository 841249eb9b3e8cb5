"""Reading the virtual rig's copies of CalculiX runs (``data/*.npz`` with a ``.json`` of provenance).

One reader for every FE response of the rig (:mod:`.fe_response`, :mod:`.neck_response`):
a missing or unreadable file, or one without the arrays asked for, is a one-line
:class:`~flowcurve.errors.ConfigError` that says how to write it again.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from flowcurve.errors import ConfigError


def read_arrays(path: Path, keys, what: str, command: str) -> dict[str, np.ndarray]:
    """The float arrays ``keys`` of the .npz at ``path`` (``what`` names it, ``command`` writes it)."""
    try:
        z = np.load(path)
    except FileNotFoundError:
        raise ConfigError(f"{path}: {what} is missing (write it: {command})") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{path}: {what} is unreadable ({exc})") from None
    with z:
        try:
            return {k: np.asarray(z[k], float) for k in keys}
        except KeyError as exc:
            raise ConfigError(f"{path}: {what} lacks {exc}") from None


def read_provenance(path: Path) -> dict:
    """The .json beside the .npz (empty when there is none)."""
    meta_path = Path(path).with_suffix(".json")
    return json.loads(meta_path.read_text(encoding="utf-8")) if meta_path.exists() else {}
