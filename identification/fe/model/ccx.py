"""Run a CalculiX deck and read its ``.dat`` prints; results cached by the deck's hash.

Each run gets its own temporary folder and ``OMP_NUM_THREADS=1`` (two one-thread jobs side by
side beat one two-thread job, docs/calculix.md). A run counts as failed when ccx exits non-zero,
prints ``*ERROR`` (it can exit 0 after one), or when the last printed step time is below 1.0
(unconverged: too many cutbacks). One ``*ERROR`` does not fail a run that printed its converged
state at step time 1 (:func:`reached_the_end`): with cutbacks, ccx's summed time can end 10⁻⁶
short of 1, and the extra 10⁻⁶ increment it then tries is below the smallest increment
("increment size smaller than minimum") — 21 of 159 runs of one inverse fit were thrown away
for that. The cache folder is ``$FLOWCURVE_FE_CACHE`` or ``~/.cache/flowcurve/fe``; a cached
result is keyed by the SHA-256 of the deck text and the ccx version line, so a changed deck or
solver is a new run.
"""

from __future__ import annotations

import hashlib
import logging
import os
import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flowcurve.errors import FlowcurveError

log = logging.getLogger(__name__)

JOB = "job"
DEFAULT_TIMEOUT_S = 600.0
_TOTAL = re.compile(r"total force \(fx,fy,fz\) for set (\S+) and time\s+(\S+)")
_NODAL = re.compile(r"(displacements \(vx,vy,vz\)|forces \(fx,fy,fz\)) for set (\S+) and time\s+(\S+)")


class SolverError(FlowcurveError):
    """CalculiX is missing, failed, timed out or did not converge (one line, names the job)."""


def timeout_by(deadline: float | None) -> float | None:
    """The solver time-out of a run that must end by ``deadline`` (wall clock, ``time.time()``; None:
    no deadline): the time left, held to :data:`DEFAULT_TIMEOUT_S`; None when the deadline has come
    (start no run). A run stopped so is the time limit's, not a failed one (:mod:`.solver_fit`)."""
    if deadline is None:
        return DEFAULT_TIMEOUT_S
    left = deadline - time.time()
    return min(left, DEFAULT_TIMEOUT_S) if left > 0.0 else None


@dataclass
class CcxOutput:
    """What one run printed: step times, total reactions and nodal displacements per set."""

    time: np.ndarray  # step time of each printed increment (0..1]
    totals: dict[str, np.ndarray] = field(default_factory=dict)  # set → (n_inc, 3) total RF (2° sector for CAX)
    displacements: dict[str, np.ndarray] = field(default_factory=dict)  # set → (n_inc, n_nodes, 3)
    nodes: dict[str, np.ndarray] = field(default_factory=dict)  # set → node numbers, in print order
    completed: bool = False  # the step reached time 1.0
    message: str = ""  # why it did not complete
    wall_s: float = 0.0
    cached: bool = False


END_TIME_TOL = 1e-5  # below the smallest increment the decks allow (1e-3 of 1/increments, increments ≤ 100)
_PAST_THE_END = "increment size smaller than minimum"


def reached_the_end(last_time: float, returncode: int, error_lines: list[str]) -> bool:
    """A run is complete when its last printed (converged) increment is at step time 1 and ccx
    either ended cleanly or only failed the sub-minimum increment it tries after a step whose
    summed time fell 10⁻⁶ short of 1."""
    if not last_time >= 1.0 - END_TIME_TOL:
        return False
    if not error_lines:
        return returncode == 0
    return all(_PAST_THE_END in line for line in error_lines)


def ccx_executable() -> str:
    """The CalculiX executable's path (FLOWCURVE_CCX or ``ccx`` on PATH); SolverError when absent."""
    exe = os.environ.get("FLOWCURVE_CCX", "ccx")
    path = shutil.which(exe)
    if path is None:
        raise SolverError(f"CalculiX executable {exe!r} not found (install the Debian package calculix-ccx, or set FLOWCURVE_CCX)")
    return path


_VERSION: dict[str, str] = {}


def ccx_version() -> str:
    """The version line ccx prints (``Version 2.20``)."""
    exe = ccx_executable()
    if exe not in _VERSION:
        out = subprocess.run([exe, "-v"], capture_output=True, text=True, timeout=30).stdout
        m = re.search(r"Version\s+(\S+)", out)
        _VERSION[exe] = f"ccx {m.group(1)}" if m else "ccx (unknown version)"
    return _VERSION[exe]


def cache_dir() -> Path:
    """The FE result cache folder (FLOWCURVE_FE_CACHE or ~/.cache/flowcurve/fe)."""
    return Path(os.environ.get("FLOWCURVE_FE_CACHE") or Path.home() / ".cache" / "flowcurve" / "fe")


def deck_key(deck: str) -> str:
    """The cache key of ``deck``: a hash of the CalculiX version and the deck."""
    return hashlib.sha256((ccx_version() + "\n" + deck).encode()).hexdigest()[:32]


def parse_dat(text: str) -> CcxOutput:
    """Total forces and nodal displacements of every ``*NODE PRINT`` block, per increment."""
    times: list[float] = []
    totals: dict[str, list] = {}
    disp: dict[str, list] = {}
    nodes: dict[str, np.ndarray] = {}
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        m = _TOTAL.search(line)
        if m:
            name, t = m.group(1), float(m.group(2))
            j = i + 1
            while j < len(lines) and not lines[j].strip():
                j += 1
            totals.setdefault(name, []).append((t, [float(v) for v in lines[j].split()[:3]]))
            i = j + 1
            continue
        m = _NODAL.search(line)
        if m and m.group(1).startswith("displacements"):
            name, t = m.group(2), float(m.group(3))
            j = i + 1
            while j < len(lines) and not lines[j].strip():
                j += 1
            rows = []
            while j < len(lines) and lines[j].strip():
                parts = lines[j].split()
                rows.append([float(v) for v in parts[:4]])
                j += 1
            arr = np.array(rows)
            nodes.setdefault(name, arr[:, 0].astype(int))
            disp.setdefault(name, []).append((t, arr[:, 1:4]))
            i = j
            continue
        i += 1
    for series in list(totals.values()) + list(disp.values()):
        times = [t for t, _ in series]
        break
    out = CcxOutput(time=np.array(times, dtype=float))
    out.totals = {k: np.array([v for _, v in s]) for k, s in totals.items()}
    out.displacements = {k: np.array([v for _, v in s]) for k, s in disp.items()}
    out.nodes = nodes
    return out


def _save(path: Path, out: CcxOutput) -> None:
    arrays = {"time": out.time, "completed": np.array(out.completed), "message": np.array(out.message), "wall_s": np.array(out.wall_s)}
    for k, v in out.totals.items():
        arrays[f"total__{k}"] = v
    for k, v in out.displacements.items():
        arrays[f"disp__{k}"] = v
        arrays[f"nodes__{k}"] = out.nodes[k]
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + f".{os.getpid()}.tmp.npz")
    np.savez_compressed(tmp, **arrays)
    tmp.replace(path)


def _load(path: Path) -> CcxOutput:
    with np.load(path) as z:
        message = str(z["message"])
        # an entry written before the end-of-step rule: its one error line is in the message
        completed = bool(z["completed"]) or (z["time"].size > 0 and reached_the_end(float(z["time"][-1]), 1, [message]))
        out = CcxOutput(time=z["time"], completed=completed, message="" if completed else message, wall_s=float(z["wall_s"]), cached=True)
        for k in z.files:
            if k.startswith("total__"):
                out.totals[k[7:]] = z[k]
            elif k.startswith("disp__"):
                out.displacements[k[6:]] = z[k]
            elif k.startswith("nodes__"):
                out.nodes[k[7:]] = z[k]
    return out


def _last_sta_time(sta: Path) -> float | None:
    """Total time of the last converged increment in the ``.sta`` file."""
    if not sta.exists():
        return None
    last = None
    for line in sta.read_text(errors="replace").splitlines():
        parts = line.split()
        if len(parts) >= 7 and parts[0].isdigit():
            try:
                last = float(parts[4])
            except ValueError:
                continue
    return last


def run_deck(deck: str, *, name: str = "run", timeout_s: float = DEFAULT_TIMEOUT_S, use_cache: bool = True,
             require_complete: bool = True, keep_dir: str | Path | None = None) -> CcxOutput:
    """Run ``deck`` with ccx and return its prints.

    ``require_complete`` raises :class:`SolverError` for a failed or unconverged run; without
    it an unconverged run returns the increments it reached (``completed`` False). A run
    that printed ``*ERROR`` or nothing at all always raises. ``keep_dir`` keeps the job's
    files there (for inspection).
    """
    exe = ccx_executable()
    key = deck_key(deck)
    cached = cache_dir() / f"{key}.npz"
    if use_cache and cached.exists():
        try:
            out = _load(cached)
        except (OSError, ValueError, KeyError) as exc:
            log.warning("unreadable cache entry %s (%s); running again", cached, exc)
        else:
            if require_complete and not out.completed:
                raise SolverError(f"CalculiX run {name!r} did not converge ({out.message}; cached {cached.name})")
            return out
    with tempfile.TemporaryDirectory(prefix="flowcurve-ccx-") as tmp:
        folder = Path(keep_dir) if keep_dir else Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / f"{JOB}.inp").write_text(deck)
        env = {**os.environ, "OMP_NUM_THREADS": "1", "CCX_NPROC_EQUATION_SOLVER": "1"}
        t0 = time.perf_counter()
        try:
            proc = subprocess.run([exe, "-i", JOB], cwd=folder, env=env, capture_output=True, text=True, timeout=timeout_s)
        except subprocess.TimeoutExpired:
            raise SolverError(f"CalculiX run {name!r} timed out after {timeout_s:g} s") from None
        wall = time.perf_counter() - t0
        logtext = proc.stdout + proc.stderr
        dat = folder / f"{JOB}.dat"
        out = parse_dat(dat.read_text(errors="replace")) if dat.exists() else CcxOutput(time=np.array([]))
        out.wall_s = wall
        error_lines = [ln.strip() for ln in logtext.splitlines() if "*ERROR" in ln]
        if error_lines and out.time.size == 0:
            raise SolverError(f"CalculiX run {name!r} failed: {error_lines[0][:200]}")
        if out.time.size == 0:
            raise SolverError(f"CalculiX run {name!r} printed no results (exit code {proc.returncode})")
        last = float(out.time[-1])
        out.completed = reached_the_end(last, proc.returncode, error_lines)
        if not out.completed:
            why = error_lines[0][:160] if error_lines else f"exit code {proc.returncode}"
            out.message = f"stopped at step time {last:.4g} < 1 ({why})"
            log.info("ccx %s: %s", name, out.message)
    if use_cache:
        _save(cached, out)
    if require_complete and not out.completed:
        raise SolverError(f"CalculiX run {name!r} did not converge ({out.message})")
    return out
