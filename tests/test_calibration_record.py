"""The calibration's parts without the command line: the fit's iteration count and force-error
statistics, the C header against the inverse map it tabulates (issue 23)."""

from __future__ import annotations

import numpy as np
import pytest
from test_calibrate import DESIGN, PrintedSensor

from mst_cli.calibrate import fit as cal
from mst_cli.io.schema import load_document


@pytest.fixture(scope="module")
def load_test():
    """40 noisy readings of the printed sensor of test_calibrate (known print errors)."""
    s = PrintedSensor()
    rng = np.random.default_rng(5)
    F = np.sort(rng.uniform(0.0, s.range_N, 40))
    codes = s.codes(F, rng)
    lsb = np.array([s.setting.xy_uT_per_lsb, s.setting.xy_uT_per_lsb, s.setting.z_uT_per_lsb]) * 1e-6
    return load_document(DESIGN), F, np.linalg.norm(codes * lsb, axis=1)


@pytest.mark.parametrize("mechanics", ["spring", "frame"])
def test_the_fit_counts_its_space_mapping_iterations(load_test, mechanics):
    doc, F, B = load_test
    fit = cal.fit_parameters(doc, F, B, 2e-6, tuple(cal.PARAMETERS), mechanics)
    if mechanics == "spring":          # the fitted rung itself: one solve, no mapping
        assert fit.iterations == 1
        return
    # the dear rung is corrected at the start's wall offset; the fit moves it, so at least one
    # more solve follows, and the loop stops once the correction sits at the fitted offset
    assert 2 <= fit.iterations <= cal.MAX_SPACE_MAPPING_ITERATIONS
    if fit.iterations < cal.MAX_SPACE_MAPPING_ITERATIONS:
        assert abs(fit.model.correction.wall_offset_mm - fit.values["wall_offset_mm"]) < 1e-4
