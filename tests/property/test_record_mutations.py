"""`flowcurve identify` on real records mutated the ways files go wrong (issue 29's input campaign):
whatever the mutation, the command ends with a result or one clean line naming the file — never an
internal error, a traceback or a hang.

The command runs in-process (``flowcurve.cli.main``) with FLOWCURVE_DEBUG set, so an internal
error raises here instead of being printed; a clean error is a :class:`FlowcurveError` printed as
``flowcurve: error: <file>…``. Each case has 60 s (an alarm) before it counts as a hang. The
default selection draws 150 cases (about 20 s); ``-m slow`` runs a campaign of 2 500, the size
of issue 29's (FLOWCURVE_MUTATION_TABLE=1 with ``-s`` prints the outcomes per mutation).
"""

from __future__ import annotations

import functools
import io
import os
import signal
import tempfile
from collections import Counter
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from pathlib import Path

import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from flowcurve.cli import main

from . import mutated_records as mr

CASE_TIMEOUT_S = 60
OUTCOMES: Counter = Counter()


@functools.lru_cache(maxsize=1)
def corpus() -> list:
    """The bases, made once (a module-level cache: hypothesis does not print it with a failing case)."""
    return mr.bases(Path(tempfile.mkdtemp(prefix="flowcurve-bases-")))


fractions = st.floats(0.0, 1.0)
mutations = st.one_of(
    st.tuples(st.just("truncate"), st.builds(lambda f: {"fraction": f}, fractions)),
    st.tuples(st.just("flip_bytes"), st.builds(lambda p, v: {"positions": p, "values": v},
                                                st.lists(fractions, min_size=1, max_size=8), st.lists(st.integers(1, 255), min_size=8, max_size=8))),
    st.tuples(st.just("bad_header_value"), st.builds(lambda w, j: {"which": w, "junk": j}, fractions, st.sampled_from(mr.JUNK_VALUES))),
    st.tuples(st.just("bad_cell"), st.builds(lambda r, c, j: {"row": r, "column": c, "junk": j}, fractions, st.integers(0, 7), st.sampled_from(mr.JUNK_CELLS))),
    st.tuples(st.just("scale_column"), st.builds(lambda c, f: {"column": c, "factor": f}, st.integers(0, 7),
                                                  st.sampled_from([0.0, -1.0, 1e-9, 1e-3, 1e3, 1e9, 1e300]))),
    st.tuples(st.just("shuffle_columns"), st.builds(lambda s, n: {"seed": s, "names_only": n}, st.integers(0, 1000), st.booleans())),
    st.tuples(st.just("reencode"), st.builds(lambda e: {"encoding": e}, st.sampled_from(mr.ENCODINGS))),
    st.tuples(st.just("line_endings"), st.builds(lambda s, seed: {"style": s, "seed": seed}, st.sampled_from(["cr", "crlf", "mixed"]), st.integers(0, 1000))),
    st.tuples(st.just("junk"), st.builds(lambda w, k, s: {"where": w, "kind": k, "seed": s}, fractions, st.sampled_from(mr.JUNK_KINDS), st.integers(0, 1000))),
)


@contextmanager
def deadline(seconds: int):
    def hung(signum, frame):
        raise TimeoutError(f"identify ran over {seconds} s: a hang")
    old = signal.signal(signal.SIGALRM, hung)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@contextmanager
def debug():
    """FLOWCURVE_DEBUG set: the command raises an internal error instead of printing it."""
    old = os.environ.get("FLOWCURVE_DEBUG")
    os.environ["FLOWCURVE_DEBUG"] = "1"
    try:
        yield
    finally:
        if old is None:
            del os.environ["FLOWCURVE_DEBUG"]
        else:
            os.environ["FLOWCURVE_DEBUG"] = old


def identify_outcome(path, args, out) -> str:
    """Run `flowcurve identify` on ``path``: 'result' or 'clean error'; anything else fails the test."""
    out_buf, err_buf = io.StringIO(), io.StringIO()
    with debug(), deadline(CASE_TIMEOUT_S), redirect_stdout(out_buf), redirect_stderr(err_buf):
        code = main(["identify", str(path), *args, "--no-plots", "--out", str(out)])
    stdout, stderr = out_buf.getvalue(), err_buf.getvalue()
    assert "Traceback" not in stdout + stderr and "internal error" not in stderr, stderr
    if code == 0:
        return "result"
    errors = [line for line in stderr.splitlines() if line.startswith("flowcurve: error:")]
    assert code == 2 and len(errors) == 1, (code, stderr)
    assert str(path) in errors[0], errors[0]  # the message names the file
    assert len(errors[0]) < len(str(path)) + 600, errors[0]  # a line to read, not a junk cell echoed whole
    return "clean error"


def check_mutation(which, mutation, tmp_path) -> None:
    base = corpus()[which % len(corpus())]
    name, kwargs = mutation
    data = getattr(mr, name)(base.data, **kwargs)
    path = tmp_path / f"mutated-{base.name}"
    path.write_bytes(data)
    outcome = identify_outcome(path, base.args, tmp_path / "out")
    OUTCOMES[(name, outcome)] += 1
    event(f"{name}: {outcome}")


def test_the_bases_identify(tmp_path):
    """Unmutated, every base gives a result (so a clean error below is the mutation's doing)."""
    for base in corpus():
        path = tmp_path / base.name
        path.write_bytes(base.data)
        assert identify_outcome(path, base.args, tmp_path / "out") == "result", base.name


@settings(max_examples=150)
@given(which=st.integers(0, 5), mutation=mutations)
def test_mutated_records_end_cleanly(which, mutation, tmp_path_factory):
    check_mutation(which, mutation, tmp_path_factory.mktemp("case"))


@pytest.mark.slow
@settings(max_examples=2500)
@given(which=st.integers(0, 5), mutation=mutations)
def test_mutation_campaign(which, mutation, tmp_path_factory):
    check_mutation(which, mutation, tmp_path_factory.mktemp("case"))


def teardown_module():
    if OUTCOMES and os.environ.get("FLOWCURVE_MUTATION_TABLE"):
        for (name, outcome), n in sorted(OUTCOMES.items()):
            print(f"{name:18s} {outcome:12s} {n}")
