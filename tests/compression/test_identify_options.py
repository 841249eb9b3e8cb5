"""Identification options are routed by an explicit table (identification/identify.py
OPTIONS): a mistyped option is an error naming it, not a warning or a silent default."""

import inspect

import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.identify import DISPATCH, OPTIONS, identify, route_options

from .conftest import make_compression


@pytest.mark.parametrize("test", sorted(DISPATCH))
def test_the_table_lists_exactly_the_keywords_of_each_identification(test):
    params = inspect.signature(DISPATCH[test]).parameters
    keywords = {name for name, p in params.items() if p.kind is inspect.Parameter.KEYWORD_ONLY}
    assert OPTIONS[test] == keywords


def test_an_option_only_the_other_test_takes_is_set_aside():
    taken, other = route_options("compression", {"law": "swift", "neck": "bridgman"})
    assert taken == {"law": "swift"} and other == ["neck"]


def test_a_mistyped_option_is_an_error_naming_it():
    record, _ = make_compression()
    with pytest.raises(IdentificationError, match="neck_corection"):
        identify(record, neck_corection="bridgman")


def test_a_tension_option_on_a_compression_record_is_a_warning():
    record, _ = make_compression()
    result = identify(record, neck="bridgman").result
    assert any("not used by compression identification: neck" in w for w in result["warnings"])
