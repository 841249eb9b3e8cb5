"""The scenario matrix of the whole chain, ``flowcurve run`` → ``flowcurve identify`` on model
time (tests/scenarios/matrix.py says what a cell is and what it must hold). A fault cell is also
judged against the same cell without its fault (run once per module, cached): its numbers must survive.

The default selection runs :data:`matrix.DEFAULT_CELLS` cells drawn with a seed fixed per
commit (printed at the end of the run; ``FLOWCURVE_MATRIX_SEED`` draws another set,
``FLOWCURVE_MATRIX_CELLS`` names cells to run); ``-m matrix`` runs the whole matrix (its cells are also ``slow``). A failing
cell re-runs by its node id: ``pytest 'tests/scenarios/test_matrix.py::test_cell[<cell id>]' -m ''``.
"""

import pytest

from . import matrix
from .known_defects import is_strict, known_defect

SEED = matrix.matrix_seed()
CELLS = matrix.all_cells()
NAMED = matrix.cells_from_env()
DEFAULT = {c.id for c in CELLS if c.id in NAMED} if NAMED else {c.id for c in matrix.default_selection(CELLS, SEED)}


def _param(cell):
    marks = [] if cell.id in DEFAULT else [pytest.mark.slow, pytest.mark.matrix]
    reason = known_defect(cell)
    if reason:
        marks.append(pytest.mark.xfail(reason=reason, strict=is_strict(cell)))
    return pytest.param(cell, id=cell.id, marks=marks)


@pytest.mark.parametrize("cell", [_param(c) for c in CELLS])
def test_cell(cell, tmp_path):
    run = matrix.run_cell(cell, tmp_path)
    matrix.remember(run)
    ref = None if cell.fault is matrix.NO_FAULT else matrix.reference(cell, tmp_path)
    assert ref is not None or cell.fault is matrix.NO_FAULT, f"cell {cell.id}: its fault-free run left no record to judge it by"
    bad = matrix.violations(run, ref)
    assert not bad, (f"cell {cell.id} (seed {SEED}): " + "; ".join(f"{kind}: {detail}" for kind, detail in bad)
                     + f"\nrun: {run.run_out.strip()[-400:]} {run.run_err.strip()[-400:]}\nidentify: {run.identify_err.strip()[-400:]}"
                     + (f"\n{run.run_exception or ''}{run.identify_exception or ''}"))


def test_default_selection_covers_every_value_of_every_axis():
    chosen = matrix.default_selection(CELLS, SEED)
    assert len(chosen) >= 40 and len(set(chosen)) == len(chosen)
    for axis, values in (("test", matrix.TESTS), ("temperature_C", matrix.TEMPERATURES_C), ("speed_mm_per_s", matrix.SPEEDS_MM_PER_S),
                         ("rate_Hz", matrix.RATES_HZ), ("material", matrix.materials()), ("fault", matrix.FAULTS)):
        assert {getattr(c, axis) for c in chosen} == set(values), axis
    assert matrix.default_selection(CELLS, SEED) == chosen  # the same seed draws the same cells
    assert all(t < matrix.MAX_TEMPERATURE_C for t in matrix.TEMPERATURES_C)


def test_fault_axis_holds_every_kind_of_the_virtual_rig_on_every_device():
    from flowcurve.rig.virtual.faults import MODEL_FAULTS, WIRE_FAULTS

    table = {(f.device, f.kind) for f in matrix.FAULTS}
    for device in matrix.DEVICE_NAMES:
        for kind in WIRE_FAULTS + MODEL_FAULTS.get(device, ()):
            assert (device, kind) in table, f"{device}:{kind} is not in the fault table"
