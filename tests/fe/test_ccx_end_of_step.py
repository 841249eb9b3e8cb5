"""A run that printed its converged state at step time 1 is complete even when ccx then fails
the sub-minimum increment it tries after a step whose summed time fell 10⁻⁶ short of 1 (seen
in CalculiX 2.20's .sta: increment 50 at 1.000000, then increment 51 at 0.999999 with
Δt 1e-6 → "*ERROR: increment size smaller than minimum"). Before, such runs were thrown away
and run again (21 of 159 runs of one inverse fit). A fake ``ccx`` (a script printing what
CalculiX prints) drives the real runner; any other error, or a last print short of 1, still
fails the run."""

from __future__ import annotations

import stat
import textwrap

import numpy as np
import pytest

from flowcurve.identification.fe.model import ccx
from flowcurve.identification.fe.model.ccx import SolverError, reached_the_end, run_deck

PAST_THE_END = " *ERROR: increment size smaller than minimum"


def _dat(times) -> str:
    blocks = []
    for t in times:
        blocks.append(f"\n total force (fx,fy,fz) for set PLN and time  {t:.7E}\n\n"
                      f"       -6.523999E+00 {-35.8 * t:.6E} -1.133684E-12\n")
    return "".join(blocks)


@pytest.fixture
def fake_ccx(tmp_path, monkeypatch):
    """A ``ccx`` that writes job.dat with the given print times, prints ``stdout`` and exits ``code``."""
    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path / "cache"))
    ccx._VERSION.clear()

    def make(times, stdout: str, code: int):
        script = tmp_path / "ccx"
        (tmp_path / "job.dat.in").write_text(_dat(times))
        (tmp_path / "stdout.txt").write_text(stdout + "\n")
        script.write_text(textwrap.dedent(f"""\
            #!/bin/sh
            if [ "$1" = "-v" ]; then echo "This is Version 2.20 (fake)"; exit 0; fi
            cp "{tmp_path / 'job.dat.in'}" job.dat
            cat "{tmp_path / 'stdout.txt'}"
            exit {code}
            """))
        script.chmod(script.stat().st_mode | stat.S_IEXEC)
        monkeypatch.setenv("FLOWCURVE_CCX", str(script))
        return script

    yield make
    ccx._VERSION.clear()


def test_the_rule():
    assert reached_the_end(1.0, 0, [])
    assert reached_the_end(1.0, 201, [PAST_THE_END.strip()])
    assert not reached_the_end(0.9995, 201, [PAST_THE_END.strip()])  # short of the end: a stopped run
    assert not reached_the_end(1.0, 0, ["*ERROR in e_c3d: nonpositive jacobian"])
    assert not reached_the_end(1.0, 1, [])  # killed after the last print, no word why


def test_a_run_failing_only_past_the_end_is_complete(fake_ccx):
    fake_ccx([0.5, 0.98, 1.0], f" increment 51 attempt 1\n{PAST_THE_END}", 201)
    out = run_deck("*HEADING\nfake one\n", name="past the end")
    assert out.completed and out.message == ""
    np.testing.assert_allclose(out.time, [0.5, 0.98, 1.0])
    np.testing.assert_allclose(out.totals["PLN"][-1, 1], -35.8)
    assert run_deck("*HEADING\nfake one\n", name="past the end").cached  # and so cached


@pytest.mark.parametrize("times, stdout", [([0.5, 0.9994531], PAST_THE_END),  # 0.05 % short: stopped
                                           ([0.5, 1.0], " *ERROR: too many cutbacks"),
                                           ([0.5, 1.0], f"{PAST_THE_END}\n *ERROR: too many cutbacks")])
def test_other_ends_still_fail(fake_ccx, times, stdout):
    fake_ccx(times, stdout, 201)
    with pytest.raises(SolverError, match="did not converge") as info:
        run_deck("*HEADING\nfake two\n", name="stopped")
    assert "\n" not in str(info.value)


def test_a_cache_entry_written_under_the_old_rule_loads_complete(fake_ccx, tmp_path):
    fake_ccx([0.5, 1.0], "", 0)
    deck = "*HEADING\nfake three\n"
    key = ccx.deck_key(deck)
    old = ccx.CcxOutput(time=np.array([0.5, 1.0]), totals={"PLN": np.zeros((2, 3))}, completed=False,
                        message="stopped at step time 1 < 1 (*ERROR: increment size smaller than minimum)")
    ccx._save(ccx.cache_dir() / f"{key}.npz", old)
    out = run_deck(deck, name="old entry")
    assert out.cached and out.completed
    stopped = ccx.CcxOutput(time=np.array([0.5, 0.9994531]), totals={"PLN": np.zeros((2, 3))}, completed=False,
                            message="stopped at step time 0.9995 < 1 (*ERROR: increment size smaller than minimum)")
    deck2 = "*HEADING\nfake four\n"
    ccx._save(ccx.cache_dir() / f"{ccx.deck_key(deck2)}.npz", stopped)
    with pytest.raises(SolverError, match="did not converge"):
        run_deck(deck2, name="old stopped entry")
