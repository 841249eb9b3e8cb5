"""Fixtures for the adhesion tests: virtual adhesiometer series written as tables."""

from __future__ import annotations

import pytest

from .synthetic import virtual_table


@pytest.fixture
def make_table(tmp_path):
    def make(name="series.csv", **options):
        return virtual_table(tmp_path / name, **options)

    return make
