"""The material class a record's ``material`` names (identification.elastic_modulus.material_class):
the grade systems of docs/materials.md told, a non-metal or an unknown name not (issue 43)."""

from __future__ import annotations

import pytest

from flowcurve.identification.elastic_modulus import CLASS_MODULI, choose_modulus, class_modulus, material_class

GRADES = {
    "steel": ["42CrMoS4", "1.4404", "X5CrNi18-10", "X2CrNiMo17-12-2", "C45E", "S355J2", "16MnCr5", "100Cr6",  # EN/DIN
              "1045", "4140", "SAE 4340", "304", "AISI 316L", "17-4PH",  # AISI/SAE
              "S31603", "G10450",  # UNS
              "12Kh18N12M3TL", "12Х18Н10Т", "40Kh", "40Х", "45", "Ст3", "Ст3сп", "09G2S", "30KhGSA", "ШХ15", "У8",  # GOST
              "steel 45", "stainless", "сталь 20"],
    "aluminium": ["AlMg3", "EN AW-6061", "AA 7075", "6061-T6", "2024", "3.3547", "A96061", "Д16Т", "АМг6", "aluminium"],
    "titanium": ["Ti-6Al-4V", "TiAl6V4", "3.7165", "R56400", "ВТ6", "VT1-0", "Ti Grade 2", "titanium"],
    "copper": ["CuZn37", "CuSn8", "Cu-ETP", "2.0321", "C11000", "brass"],
    "nickel": ["Inconel 718", "Alloy 625", "2.4668", "N07718", "ХН77ТЮР", "NiCr20TiAl"],
}


@pytest.mark.parametrize("cls, grade", [(c, g) for c, gs in GRADES.items() for g in gs])
def test_each_listed_grade_is_recognised(cls, grade):
    assert material_class(grade) is not None and material_class(grade)[0] == cls, material_class(grade)
    assert class_modulus(grade)[1:] == CLASS_MODULI[cls][:2]


@pytest.mark.parametrize("name", ["PMMA", "polycarbonate", "oak wood", "concrete C30/37", "rubber", "unobtainium", "synthetic",
                                  "second FE model C2", "other-settings FE model C1", "3D-printed PLA", "specimen A", "",
                                  "steel-aluminium clad"])
def test_a_non_metal_an_unknown_name_or_two_classes_are_not(name):
    assert material_class(name) is None


def test_the_rule_takes_given_then_handbook_then_measured_then_the_class():
    assert choose_modulus(given=190e3, handbook=195e3, measured=205e3, material="45").source == "given"
    assert choose_modulus(handbook=195e3, measured=205e3, material="45").source == "handbook"
    measured = choose_modulus(measured=205e3, measured_u_MPa=900.0, material="45")
    assert (measured.E_MPa, measured.u_MPa, measured.source) == (205e3, 900.0, "measured")
    by_class = choose_modulus(material="12Kh18N12M3TL")
    assert (by_class.E_MPa, by_class.u_MPa, by_class.source) == (200e3, 10e3, "class") and "GOST" in by_class.basis
    assert choose_modulus(material="PMMA").E_MPa is None
