"""A bar that breaks at the onset of necking (the virtual 12Kh18N12M3TL: its fracture strain below its
Considère strain, du = dk): ε_f = ln(F0/Fk) from dk and the diagram's uniform plastic strain meet within
their readings, and a little below it is no misread dk — the fracture has no neck (a/R 0); well below the
uncertainty of dk's reading the record is refused with the one-line error that names post.dk_mm."""

import math

import pytest

from flowcurve.acquisition.session import run_virtual_test
from flowcurve.clock import ModelClock
from flowcurve.demo import demo_specs
from flowcurve.errors import IdentificationError
from flowcurve.identification.tension import identify as ti
from flowcurve.record.format import Record, read_record

MATERIAL = "12Kh18N12M3TL"


@pytest.fixture(scope="module")
def rig_record(tmp_path_factory):
    spec = next(s for s in demo_specs(MATERIAL) if s.test == "tension")
    path = tmp_path_factory.mktemp("neck_onset") / "t.csv"
    run_virtual_test(spec, path, material=MATERIAL, time_scale=15.0, clock=ModelClock(), link="inprocess")
    return read_record(path)


class _Readings:
    """What :func:`identify._fracture_strain_u` reads of the identification's inputs: the record and d0."""

    def __init__(self, record: Record, d0_mm: float):
        self.record, self.d0 = record, d0_mm


def _with_fracture_strain(rec: Record, eps_f: float) -> Record:
    """The record with dk set so that ln(F0/Fk) = 2·ln(d0/dk) is ``eps_f``."""
    d0 = float(rec.meta["specimen.d0_mm"])
    return Record(meta={**rec.meta, "post.dk_mm": f"{d0 * math.exp(-eps_f / 2.0):.6f}"}, data=rec.data, source=rec.source)


def test_the_fracture_strains_reading_uncertainty_is_the_closed_form(rig_record):
    """u(ε_f) = 2·√((u_d0/d0)² + (u_dk/dk)²), each u = √(r²/12 + MPE²/3) (the record's micrometer or the defaults)."""
    from flowcurve.identification.quality.assurance import instruments_from_meta

    inst = instruments_from_meta(rig_record.meta)
    u = math.sqrt(inst["diameter_resolution_mm"] ** 2 / 12.0 + inst["micrometer_mpe_mm"] ** 2 / 3.0)
    d0, dk = float(rig_record.meta["specimen.d0_mm"]), 5.0
    got = ti._fracture_strain_u(_Readings(rig_record, d0), dk)
    assert got == pytest.approx(2.0 * math.hypot(u / d0, u / dk), rel=1e-12)


def test_a_fracture_strain_within_its_reading_below_the_uniform_one_is_a_break_without_a_neck(rig_record):
    first = ti.identify_tension(rig_record).result
    eps_pu = first["uniform_true_plastic_strain"]
    d0 = float(rig_record.meta["specimen.d0_mm"])
    u = ti._fracture_strain_u(_Readings(rig_record, d0), d0 * math.exp(-eps_pu / 2.0))
    near = ti.identify_tension(_with_fracture_strain(rig_record, eps_pu - 1.5 * u)).result
    assert near["neck_corrections"]["a_over_R"] == 0.0
    assert near["fracture_true_strain"] == pytest.approx(eps_pu - 1.5 * u, rel=1e-4)
    with pytest.raises(IdentificationError, match="below the strain at maximum force.*check post.dk_mm"):
        ti.identify_tension(_with_fracture_strain(rig_record, eps_pu - 3.0 * u))
