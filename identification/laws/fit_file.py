"""The law of a fit.json (docs/fit-json.md): one reader for ``flowcurve-fit/1`` (Johnson–Cook from the
top-level keys) and ``flowcurve-fit/2`` (any registered law from its ``"law"`` block)."""

from __future__ import annotations

from typing import Mapping

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.base import Law, get_law

SCHEMAS = ("flowcurve-fit/1", "flowcurve-fit/2")


def law_of_fit(fit: Mapping) -> tuple[Law, dict[str, float]]:
    """The registered law of a fit.json and its values by name (parameters and conditions).

    v2: ``get_law(fit["law"]["name"])`` with ``law.from_keys({**parameters, **conditions})``;
    v1 (no "law" block): Johnson–Cook from the top-level ``A_MPa`` … ``melt_temperature_C``.
    A missing value is a one-line error naming the file's schema and the key.
    """
    schema = fit.get("schema", "flowcurve-fit/1")
    if schema not in SCHEMAS:
        raise IdentificationError(f"fit.json schema {schema!r} is not one this version reads ({', '.join(SCHEMAS)})")
    block = fit.get("law")
    if block is None:
        law, keys = get_law("johnson_cook"), fit
    else:
        law = get_law(str(block.get("name", "")))
        keys = {**(block.get("parameters") or {}), **(block.get("conditions") or {})}
    missing = [p.key for p in law.parameters + law.conditions if not isinstance(keys.get(p.key), (int, float))]
    if missing:
        raise IdentificationError(f"fit.json ({schema}, {law.name}): no value for {', '.join(missing)}")
    return law, law.from_keys(keys)
