"""Properties over the whole design bounds (valid cells or not): finite, monotone, silent."""

import warnings

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics.spring import spring_arrays
from mst_cli.model.response import simulate
from mst_cli.model.stack import series_displacement_mm
from mst_cli.sensor.sections import DEFAULT_DESIGN

TH = DEFAULT_DESIGN["theta_deg_bounds"]
T = DEFAULT_DESIGN["t_mm_bounds"]
H = DEFAULT_DESIGN["h_mm_bounds"]

theta = st.floats(*TH)
t_mm = st.floats(*T)
h_mm = st.floats(*H)
layer = st.tuples(theta, t_mm, h_mm)


def test_vectorised_spring_is_finite_and_positive_on_a_dense_grid_of_the_bounds():
    th, t, h = np.meshgrid(np.radians(np.linspace(*TH, 40)), np.linspace(*T, 40), np.linspace(*H, 40))
    with np.errstate(all="raise"):
        k, dl, R, kl = spring_arrays(th, t, h, 20.0, 30.0, 0.1, 12.0, 0.45)
    for a in (k, dl, R, kl):
        assert np.all(np.isfinite(a)) and np.all(a > 0)
    assert np.all(kl > k)
    assert np.all(R <= k * dl * (1 + 1e-12))  # walls soften before the lock, never stiffen


@settings(max_examples=200, deadline=None)
@given(st.lists(layer, min_size=1, max_size=6), st.floats(4.0, 60.0))
def test_stack_curve_is_finite_and_strictly_monotone(layers, depth_mm):
    th, t, h = (np.array(v, dtype=float) for v in zip(*layers))
    with np.errstate(all="raise"):
        k, dl, R, kl = spring_arrays(np.radians(th), t, h, depth_mm, 30.0, 0.1, 12.0, 0.45)
        F = np.linspace(0.0, 10 * R.max(), 301)
        d = series_displacement_mm(F, k, dl, kl, R)
    assert np.all(np.isfinite(d)) and np.all(np.diff(d) > 0)


@settings(max_examples=40, deadline=None)
@given(st.lists(layer, min_size=1, max_size=4))
def test_simulate_valid_designs_is_finite_monotone_and_silent(layers):
    cells = tuple(HexCell(*v) for v in layers)
    cells = tuple(c for c in cells if not c.violations())
    if not cells:
        return
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            r = simulate(SensorGeometry(cells), Material(), points_per_regime=40)
    assert np.all(np.isfinite(r.dB_rel)) and np.all(np.diff(r.dB_rel) >= 0)
    assert np.all(np.diff(r.force_N) >= 0) and np.all(np.diff(r.displacement_mm) >= 0)
    # members soft enough to close the whole gap inside the range: said, and past it the field holds
    reaches = r.gap_min_mm <= 0.0
    assert reaches == any("the magnet reaches the chip" in w for w in r.warnings)
    contact_N = r.force_N[np.argmax(r.gap_mm <= 0.0)] if reaches else np.inf
    for reg in r.regimes:
        assert np.isfinite(reg.sensitivity_secant_per_N)
        assert reg.sensitivity_secant_per_N > 0 or reg.force_from_N >= contact_N
