"""identify does each piece of work once (issue 43: a one-hour record within twice its read): the
elastic line's iteration stops when a step's window is the last one's (SDAR's window does not
depend on the reference), with the numbers the full iteration gives."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _bench_record(rows: int):
    spec = importlib.util.spec_from_file_location("identify_long_record", ROOT / "bench" / "identify_long_record.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.synthetic_tension(rows)


def test_the_elastic_line_is_not_recomputed_for_a_window_it_already_had(monkeypatch):
    from flowcurve.identification.identify import identify
    from flowcurve.identification.tension import elastic

    record = _bench_record(20_000)  # SDAR finds its line (at 5400 rows it does not: the window method, whose window moves)
    windows = []
    real = elastic.compensate_toe
    monkeypatch.setattr(elastic, "compensate_toe", lambda *a, **k: windows.append(k["window_N"]) or real(*a, **k))
    fast = identify(record).result
    assert len(windows) == 1  # SDAR's window: the second step would have had the same

    monkeypatch.setattr(elastic, "_modulus_window", _window_never_the_same(elastic._modulus_window))
    windows.clear()
    full = identify(record).result
    assert len(windows) == 2  # the full iteration: a second step, to the same fixed point
    for key in ("E_MPa", "Rp02_MPa", "Ag_pct", "modulus_window_MPa"):
        assert fast[key] == full[key]
    assert fast["hardening"] == full["hardening"]


def _window_never_the_same(real):
    """_modulus_window whose automatic fit is a new unequal object every step (the shortcut never taken)."""
    class Unequal:
        def __init__(self, fit):
            self.__dict__.update(fit.__dict__)

        def __eq__(self, other):
            return False

    def window(*args, **kwargs):
        window_MPa, points, how, auto, ref = real(*args, **kwargs)
        return window_MPa, points, how, (Unequal(auto) if auto is not None else None), ref

    return window
