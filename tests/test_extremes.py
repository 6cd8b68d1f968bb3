"""Stability at the corners of the design bounds: finite, monotone, or a clear error."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mst_cli import field as fld
from mst_cli.geometry import HexCell, Magnet, SensorGeometry
from mst_cli.material import Material
from mst_cli.mechanics import layer_law
from mst_cli.mechanics.continuum import solve_continuum
from mst_cli.mechanics.frame import solve_frame
from mst_cli.mechanics.spring import LinearLockingLayer, spring_arrays
from mst_cli.response import simulate
from mst_cli.stack import Stack

MAT = Material()


@settings(max_examples=300, deadline=None)
@given(theta=st.floats(15, 60), t=st.floats(0.4, 2.0), h=st.floats(1.2, 6.0),
       corrected=st.booleans())
def test_spring_is_finite_and_positive_everywhere_in_the_bounds(theta, t, h, corrected):
    # valid or not: the optimiser evaluates infeasible points too
    k, dl, R, kl = spring_arrays(np.radians(theta), t, h, 20.0, 30.0, 0.1, 12.0, 0.45, corrected)
    assert np.isfinite([k, dl, R, kl]).all() and k > 0 and dl > 0 and 0 < R <= k * dl and kl >= k


def test_spring_vectorised_over_the_corners():
    th, t, h = np.meshgrid(np.radians([15, 60]), [0.4, 2.0], [1.2, 6.0], indexing="ij")
    for corrected in (False, True):
        k, dl, R, kl = spring_arrays(th, t, h, 20.0, 30.0, 0.1, 12.0, 0.45, corrected)
        assert np.isfinite(k).all() and (k > 0).all() and (kl > k).all() and (R > 0).all()


def test_stack_with_stiffness_ratio_1e4_is_monotone_from_1mN_to_10x_range():
    laws = (LinearLockingLayer(0.01, 0.5, 50.0), LinearLockingLayer(100.0, 0.5, 5e5))
    stack = Stack(laws)
    F = np.geomspace(1e-3, 10 * stack.last_lock_force_N, 2000)
    d = stack.displacement_mm(F)
    assert np.isfinite(d).all() and np.all(np.diff(d) > 0)
    assert np.allclose(stack.force_N(d), F, rtol=1e-9)


def test_field_near_saturation_is_finite_and_monotone():
    gaps = np.linspace(0.05, 5.0, 400)
    for model in ("dipole", "axial", "cylinder"):
        B = np.linalg.norm(fld.field_at_chip_T(gaps, Magnet(), model), axis=-1)
        assert np.isfinite(B).all() and np.all(np.diff(B) < 0)
    # the exact models agree even at the pole face
    Ba = fld.field_at_chip_T(gaps, Magnet(), "axial")[:, 2]
    Bc = fld.field_at_chip_T(gaps, Magnet(), "cylinder")[:, 2]
    assert np.allclose(Ba, Bc, rtol=1e-9)


@pytest.mark.parametrize("layers", [
    [(15, 0.4, 1.2), (60, 2.0, 6.0)],         # softest to stiffest corner
    [(60, 0.4, 6.0), (20, 1.6, 4.0)],
])
def test_simulate_at_the_corners_is_finite_or_warns(layers):
    cells = tuple(HexCell(*c) for c in layers)
    for mech in ("spring", "frame"):
        try:
            resp = simulate(SensorGeometry(cells), MAT, mechanics=mech)
        except ValueError as exc:          # frame on an unmeshable corner: a clear message
            assert "frame model needs" in str(exc)
            continue
        assert np.isfinite(resp.displacement_mm).all() and np.isfinite(resp.B_abs_T).all()
        assert np.all(np.diff(resp.displacement_mm) >= 0)
        assert all(np.isfinite(r.sensitivity_secant_per_N) for r in resp.regimes)


@pytest.mark.parametrize("theta", [15.0, 60.0])
@pytest.mark.parametrize("t_over_L", [0.05, 0.3, 0.6])
def test_frame_at_theta_and_slenderness_corners(theta, t_over_L):
    # choose h so that t / L hits the target: L = (h - t) / (2 sin theta)
    t = 0.4
    h = t + 2 * np.sin(np.radians(theta)) * t / t_over_L
    cell = HexCell(theta, t, float(h))
    try:
        res = solve_frame(cell, MAT)
    except ValueError as exc:
        assert "frame model needs" in str(exc)
        return
    assert np.isfinite(res.force_N).all() and res.force_N[-1] > 0
    law = layer_law(cell, MAT, "frame")
    F = np.geomspace(1e-3, 10 * law.lock_force_N, 300)
    d = law.displacement_mm(F)
    assert np.isfinite(d).all() and np.all(np.diff(d) > 0)


def test_smallest_cavity():
    cell = HexCell(40, 0.4, 0.4 * 2 + 0.4)        # h - 2t = the printable minimum gap
    for mech in ("spring", "frame"):
        law = layer_law(cell, MAT, mech)
        assert np.isfinite([law.k_N_per_mm, law.d_lock_mm, law.lock_force_N]).all()
        assert law.d_lock_mm == pytest.approx(0.3, rel=1e-6)


@pytest.mark.parametrize("cell", [HexCell(15, 0.4, 1.3), HexCell(60, 1.5, 6.0)])
def test_continuum_at_two_corners(cell):
    res = solve_continuum(cell, MAT)
    assert np.isfinite(res.force_N).all() and np.all(np.diff(res.force_N) > 0)
    # the pads are elastic (bonded only on their outer face): contact may come a little after
    # the rigid-pad nominal h - 2t - allowance, never long after it
    assert 0 < res.d_contact_mm <= cell.d_lock_mm * 1.01
    assert res.reaction_balance < 1e-6
