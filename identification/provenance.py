"""Where a result came from: the ``provenance`` block of result.json, fit.json and friction.json.

A block holds ``flowcurve_version``, ``code_sha256`` (a fingerprint of the identification and
record code and data installed, so a changed method is seen even where the version number was
not raised), ``record_sha256`` (the SHA-256 of the record file's bytes; a
fit or friction fit maps each record's name to its checksum), ``options`` (the options as given,
in JSON form), ``date_utc`` (ISO 8601, UTC) and ``ccx_version`` where CalculiX ran. An auditor
ties a result or card to its records with ``sha256sum``; ``flowcurve identify`` skips a record
whose result already carries the same version, checksum and options (:func:`same_run`).
"""

from __future__ import annotations

import functools
import hashlib
import json
from datetime import datetime, timezone
from pathlib import Path

from flowcurve import __version__

CHUNK = 1 << 20


def file_sha256(path: str | Path) -> str:
    """SHA-256 (hex) of a file's bytes, as ``sha256sum`` prints it."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(CHUNK), b""):
            digest.update(block)
    return digest.hexdigest()


@functools.lru_cache(maxsize=1)
def code_sha256() -> str:
    """SHA-256 over the files of the identification and record packages (sources and data, by
    relative path): what decides the numbers of a result."""
    import flowcurve.record

    digest = hashlib.sha256()
    for package in (Path(__file__).parent, Path(flowcurve.record.__file__).parent):
        for path in sorted(p for p in package.rglob("*") if p.is_file() and "__pycache__" not in p.parts and p.suffix != ".pyc"):
            digest.update(f"{package.name}/{path.relative_to(package).as_posix()}\n".encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def as_json(options: dict) -> dict:
    """Options in the form they take in a JSON file (tuples as lists, keys as text), so that a
    block read back compares equal to one made now."""
    return json.loads(json.dumps(options, default=str))


def utc_now() -> str:
    """The date and time now, UTC, ISO 8601 to the second (``2026-11-26T11:40:00Z``)."""
    return datetime.now(timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def provenance(record_sha256: str | dict[str, str | None] | None, options: dict, *, ccx_version: str | None = None) -> dict:
    """The provenance block: this flowcurve's version, the record checksum(s), the options, the
    date (UTC) and, when the solver ran, its version line (``ccx 2.20``)."""
    block = {"flowcurve_version": __version__, "code_sha256": code_sha256(), "record_sha256": record_sha256, "options": as_json(options),
             "date_utc": utc_now()}
    if ccx_version:
        block["ccx_version"] = ccx_version
    return block


def same_run(block: object, record_sha256: str, options: dict) -> bool:
    """Does an existing result's provenance block say it was made by this version (and code),
    from the same record bytes, with the same options? (Then the record need not be identified again.)"""
    return (isinstance(block, dict) and block.get("flowcurve_version") == __version__ and block.get("code_sha256") == code_sha256()
            and block.get("record_sha256") == record_sha256 and block.get("options") == as_json(options))


def result_record_sha256(folder: str | Path) -> str | None:
    """The record checksum a result folder of ``flowcurve identify`` carries (None for a result
    written before provenance, or unreadable)."""
    try:
        block = json.loads((Path(folder) / "result.json").read_text(encoding="utf-8")).get("provenance")
    except (OSError, ValueError, AttributeError):
        return None
    return block.get("record_sha256") if isinstance(block, dict) else None


def member_record_sha256(kind: str, source: str) -> str | None:
    """The record checksum of a series member: its file's (a record) or the one its result
    folder carries (a result of ``flowcurve identify``); None when neither says."""
    if kind == "record":
        try:
            return file_sha256(source)
        except OSError:
            return None
    return result_record_sha256(source) if kind == "result" else None


def comment_lines(block: object, what: str) -> list[str]:
    """The provenance of ``what`` (e.g. "fit file") as comment lines for a card; none when the
    file carries no block (written before provenance)."""
    if not isinstance(block, dict):
        return [f"provenance: {what} carries none (written before flowcurve recorded it)"]
    sha = block.get("record_sha256")
    records = ([f"{value or 'not recorded'} {name}" for name, value in sha.items()] if isinstance(sha, dict)
               else [str(sha or "not recorded")])  # the 64 hex digits first: a comment line holds them whole
    options = json.dumps(block.get("options") or {}, sort_keys=True, ensure_ascii=True)
    code = str(block.get("code_sha256") or "")[:12]
    lines = [f"provenance of the {what}: flowcurve {block.get('flowcurve_version', '?')}" + (f" (code {code})" if code else "")
             + f", {block.get('date_utc', 'date not recorded')}"
             + (f", solver {block['ccx_version']}" if block.get("ccx_version") else ""),
             f"options: {options}"]
    return lines + [f"sha256 {r}" for r in records]
