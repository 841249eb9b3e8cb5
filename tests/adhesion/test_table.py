"""The adhesion test table: native format, foreign CSVs through --column, units, bad rows, traces."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from flowcurve.errors import RecordError
from flowcurve.record.adhesion import (
    moment_conversion,
    parse_adhesion_column_option,
    read_adhesion_table,
    read_adhesion_tables,
    write_adhesion_table,
)

NATIVE = """# flowcurve-adhesion: 1
# material: steel 45
# sphere.diameter_mm: 8.0
# sphere.Rp_um: 0.2
# sphere.tm: 0.5
test_id,normal_force_N,moment_N_m,imprint_radius_mm,temperature_C
A1,500,0.05,0.40,20
A2,1000,0.11,0.52,20
"""

FOREIGN = """Probe;Fz;Mz;r;T;Ra
;kN;N*mm;um;K;um
P1;0,5;50,0;400;293,15;0,2
P2;1,0;110,0;520;293,15;0,2
"""


def _write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_native_table_reads_header_defaults_into_rows(tmp_path):
    table = read_adhesion_table(_write(tmp_path, "a.csv", NATIVE))
    assert list(table.data["test_id"]) == ["A1", "A2"]
    assert table.column("sphere_diameter_mm").tolist() == [8.0, 8.0]
    assert table.column("sphere_Rp_um").tolist() == [0.2, 0.2]
    assert table.material == "steel 45"
    assert table.data["line"].tolist() == [7, 8]


def test_foreign_csv_units_are_converted(tmp_path):
    """kN → N, N·mm → N·m, µm → mm, K → °C, decimal commas in a ';' file, and a units row."""
    path = _write(tmp_path, "f.csv", FOREIGN)
    columns = dict(parse_adhesion_column_option(o) for o in
                   ("normal_force=Fz:kN", "moment=Mz:N*mm", "imprint_radius=r:um", "temperature=T:K", "test_id=Probe"))
    table = read_adhesion_table(path, columns=columns)
    assert table.column("normal_force_N") == pytest.approx([500.0, 1000.0])
    assert table.column("moment_N_m") == pytest.approx([0.050, 0.110])
    assert table.column("imprint_radius_mm") == pytest.approx([0.400, 0.520])
    assert table.column("temperature_C") == pytest.approx([20.0, 20.0])
    assert list(table.data["test_id"]) == ["P1", "P2"]


def test_units_from_the_units_row_when_the_option_gives_none(tmp_path):
    path = _write(tmp_path, "f.csv", FOREIGN)
    columns = dict(parse_adhesion_column_option(o) for o in ("normal_force=Fz", "moment=Mz", "imprint_radius=r", "temperature=T"))
    table = read_adhesion_table(path, columns=columns)
    assert table.column("moment_N_m") == pytest.approx([0.050, 0.110])


@pytest.mark.parametrize("unit, factor", [("N*m", 1.0), ("N·mm", 1e-3), ("kN*m", 1e3), ("Nmm", 1e-3),
                                          ("lbf*in", 4.4482216152605 * 0.0254)])
def test_moment_units_are_force_times_length(unit, factor):
    assert moment_conversion(unit) == pytest.approx(factor, rel=1e-12)


def test_unknown_moment_unit_is_an_error():
    with pytest.raises(RecordError, match="moment unit"):
        moment_conversion("Nm2x")


@pytest.mark.parametrize("row, column, words", [
    ("A3,800,0.07,0.0,20", "imprint_radius_mm", "imprint radius r must be > 0"),
    ("A3,800,0.07,-0.2,20", "imprint_radius_mm", "imprint radius r must be > 0"),
    ("A3,800,-0.07,0.45,20", "moment_N_m", "moment M_z must be >= 0"),
    ("A3,800,0.07,0.45,", "temperature_C", "missing temperature"),
    ("A3,800,0.07,abc,20", "imprint_radius_mm", "not a number"),
])
def test_bad_rows_name_file_line_and_column(tmp_path, row, column, words):
    path = _write(tmp_path, "bad.csv", NATIVE + row + "\n")
    with pytest.raises(RecordError) as info:
        read_adhesion_table(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}, line 9, column '{column}'")
    assert words in message


def test_bad_row_in_a_foreign_csv_names_the_file_column(tmp_path):
    path = _write(tmp_path, "f.csv", FOREIGN + "P3;1,0;-5,0;500;293,15;0,2\n")
    columns = dict(parse_adhesion_column_option(o) for o in ("normal_force=Fz:kN", "moment=Mz:N*mm", "imprint_radius=r:um", "temperature=T:K"))
    with pytest.raises(RecordError, match=r"line 5, column 'Mz': moment M_z must be >= 0"):
        read_adhesion_table(path, columns=columns)


def test_foreign_csv_without_mapping_names_the_columns_found(tmp_path):
    path = _write(tmp_path, "f.csv", FOREIGN)
    with pytest.raises(RecordError, match="no column mapping given.*Fz"):
        read_adhesion_table(path)


def test_mapping_lacking_the_temperature_is_an_error(tmp_path):
    path = _write(tmp_path, "f.csv", FOREIGN)
    columns = dict(parse_adhesion_column_option(o) for o in ("normal_force=Fz:kN", "moment=Mz:N*mm", "imprint_radius=r:um"))
    with pytest.raises(RecordError, match="lacks temperature"):
        read_adhesion_table(path, columns=columns)


def test_a_wrong_quantity_unit_is_an_error(tmp_path):
    path = _write(tmp_path, "f.csv", FOREIGN)
    columns = dict(parse_adhesion_column_option(o) for o in ("normal_force=Fz:mm", "moment=Mz:N*mm", "imprint_radius=r:um", "temperature=T:K"))
    with pytest.raises(RecordError, match="measures length, not force"):
        read_adhesion_table(path, columns=columns)


def test_column_option_rejects_unknown_quantity():
    with pytest.raises(RecordError, match=r"'torque=Mz:N\*m' is not QUANTITY=COLUMN"):
        parse_adhesion_column_option("torque=Mz:N*m")
    assert parse_adhesion_column_option("moment=M:z:N*mm") == ("moment", ("M:z", "N*mm"))


def test_roundtrip_with_traces_and_moment_from_trace(tmp_path):
    t = np.linspace(0.0, 10.0, 501)
    trace = pd.DataFrame({"time_s": t, "moment_N_m": np.where(t < 2.0, 0.02 * t, 0.04)})
    data = pd.DataFrame({"test_id": ["B1", "B2"], "normal_force_N": [400.0, 600.0], "moment_N_m": [0.03, math.nan],
                         "imprint_radius_mm": [0.35, 0.41], "temperature_C": [20.0, 20.0]})
    path = write_adhesion_table(tmp_path / "t" / "table.csv", data, {"material": "x", "sphere.diameter_mm": 8.0},
                                traces={"B2": trace})
    table = read_adhesion_table(path)
    assert set(table.traces) == {"B2"}
    # the second half of the trace is the plateau 0.04 N·m
    assert table.column("moment_N_m")[1] == pytest.approx(0.04)
    assert any("B2: M_z" in w for w in table.warnings)


def test_several_tables_join(tmp_path):
    a = _write(tmp_path, "a.csv", NATIVE)
    b = _write(tmp_path, "b.csv", NATIVE.replace("A1", "C1").replace("A2", "C2"))
    table = read_adhesion_tables([a, b])
    assert len(table) == 4
    assert set(table.data["source"]) == {str(a), str(b)}
