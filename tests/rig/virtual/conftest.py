"""Fixtures shared by the virtual rig's FE-response tests."""

import numpy as np
import pytest


@pytest.fixture(scope="module")
def raw(request):
    """The rig data file named by the test module's ``DATA``, as stored (NaN where a CalculiX run
    stopped), read here with numpy rather than through the rig's reader."""
    with np.load(request.module.DATA) as z:
        return {k: np.asarray(z[k], float) for k in z.files}
