"""Names and defaults that the parser shows and other packages publish, written here so that
``flowcurve --help`` imports none of those packages (they import numpy at module level).

``SOURCES`` names where each one comes from; tests/test_cli_startup.py keeps every value here
equal to its source (``tuple(source)`` for a collection), so a method, format or column added
there and not here fails that test.
"""

from __future__ import annotations

# name here → (module, attribute) it copies
SOURCES = {
    "TEST_TYPES": ("flowcurve.acquisition.procedure", "TEST_GEOMETRY"),
    "NECK_METHODS": ("flowcurve.identification.tension.necking", "METHODS"),
    "FRICTION_METHODS": ("flowcurve.identification.compression.friction", "FRICTION_METHODS"),
    "FRICTION_CORRECTIONS": ("flowcurve.identification.compression.friction", "CORRECTIONS"),
    "FRICTION_CARD_FORMATS": ("flowcurve.reports.friction_cards", "FRICTION_CARD_FORMATS"),
    "CONTACT_RATIO_MODELS": ("flowcurve.identification.compression.adhesion", "CONTACT_RATIO_MODELS"),
    "HOT_FROM_C": ("flowcurve.identification.compression.adhesion", "HOT_FROM_C"),
    "ADHESION_COLUMNS": ("flowcurve.record.adhesion", "ADHESION_COLUMNS"),
}

TEST_TYPES = ("tension", "compression")
NECK_METHODS = ("davidenkov", "bridgman", "mirone")
FRICTION_METHODS = ("fe_table", "bulge_regression", "ebrahimi_najafizadeh")
FRICTION_CORRECTIONS = ("fe_table", "k_sigma", "siebel", "slab")
FRICTION_CARD_FORMATS = ("abaqus", "lsdyna")
CONTACT_RATIO_MODELS = ("none", "bowden_tabor")
HOT_FROM_C = 600.0
ADHESION_COLUMNS = ("normal_force", "moment", "imprint_radius", "temperature", "sphere_diameter", "sphere_rp", "sphere_tm",
                    "flow_stress", "test_id", "trace_file")
