"""Rung L1 (corotational frame): verified against beam theory and its own linearisation."""

import math

import numpy as np
import pytest

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import layer_law
from mst_cli.model.mechanics.frame import _element_forces, monotone_envelope, solve_frame
from mst_cli.model.mechanics.spring import spring_layer

MAT = Material()


@pytest.mark.parametrize("theta, t, h", [(25, 0.6, 2.0), (45, 0.5, 5.0), (60, 1.2, 4.0), (15, 0.4, 1.4)])
def test_linear_stiffness_is_clamped_guided_timoshenko(theta, t, h):
    # Timoshenko elements are exact for end-loaded beams: the FE chain must reproduce the
    # closed form of rung L0 (Roark Table 8.1 case 1e + shear + axial), uncorrected
    cell = HexCell(theta, t, h)
    res = solve_frame(cell, MAT)
    assert res.k_linear_N_per_mm == pytest.approx(spring_layer(cell, MAT, corrected=False).k_N_per_mm, rel=1e-9)


def test_small_load_secant_matches_linear_solve():
    cell = HexCell(35, 0.8, 3.0)
    res = solve_frame(cell, MAT, first_step_frac=1e-4)
    secant = res.force_N[1] / res.displacement_mm[1]
    assert secant == pytest.approx(res.k_linear_N_per_mm, rel=1e-3)


def test_rigid_rotation_gives_no_internal_force():
    X = np.array([[0.0, 0.0], [1.0, 0.3]])
    l0 = np.array([math.hypot(1.0, 0.3)])
    beta0 = np.array([math.atan2(0.3, 1.0)])
    a = 1.1  # a large rigid rotation about node 1
    R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    U = np.zeros((2, 3))
    U[1, :2] = R @ X[1] - X[1]
    U[:, 2] = a
    f, _ = _element_forces(X, U, l0, beta0, 12.0, 1.0, np.array([0.1]))
    assert np.abs(f).max() < 1e-12


def test_tangent_is_derivative_of_internal_force():
    X = np.array([[0.0, 0.0], [0.5, 0.2], [1.0, 0.5]])
    l0 = np.hypot(*np.diff(X, axis=0).T)
    beta0 = np.arctan2(*np.diff(X, axis=0).T[::-1])
    U = np.array([[0.0, 0.0, 0.0], [0.05, -0.1, 0.3], [0.1, -0.2, -0.2]])
    f, K = _element_forces(X, U, l0, beta0, 7.0, 0.3, np.array([0.2, 0.2]))
    eps = 1e-7
    for e in range(2):
        for j in range(6):
            Up = U.copy().ravel()
            Up[3 * e + j] += eps
            fp, _ = _element_forces(X, Up.reshape(-1, 3), l0, beta0, 7.0, 0.3, np.array([0.2, 0.2]))
            assert np.allclose((fp[e] - f[e]) / eps, K[e][:, j], atol=1e-4 * np.abs(K[e]).max())


def test_lock_stroke_is_l0s_fit_of_the_continuum_lock():
    # a beam has no faces to pinch: L1 follows its path to the lock stroke L0 fitted to L2's
    # stiffness knee (or the rigid pads' stroke, if that came first)
    from mst_cli.model.mechanics.spring import spring_layer

    for cell in (HexCell(33, 1.0, 2.8), HexCell(45, 0.5, 5.0), HexCell(14, 0.4, 1.87)):
        res = solve_frame(cell, MAT)
        expected = min(spring_layer(cell, MAT).d_lock_mm, cell.h_mm - 2 * cell.t_mm - cell.contact_allowance_mm)
        assert res.d_contact_mm == pytest.approx(expected, rel=1e-6)
        assert np.all(np.diff(res.force_N) > 0)


def test_layer_law_is_monotone_and_continuous_through_the_lock():
    law = layer_law(HexCell(25, 0.6, 2.0), MAT, "frame")
    F = np.linspace(0, 3 * law.lock_force_N, 500)
    d = law.displacement_mm(F)
    assert np.all(np.diff(d) > 0) and np.all(np.isfinite(d))
    assert law.displacement_mm(law.lock_force_N) == pytest.approx(law.d_lock_mm)


def test_monotone_envelope_snaps_through_at_the_peak():
    d, F = monotone_envelope([0, 1, 2, 3, 4], [0, 2, 1.5, 1.8, 1.9])
    assert list(d) == [0, 1, 4] and F[-1] > 2 and F[-1] == pytest.approx(2)


def test_invalid_cell_is_a_clear_error():
    with pytest.raises(ValueError, match="frame model needs"):
        solve_frame(HexCell(30, 1.0, 2.0), MAT)


def test_shallow_thin_wall_follows_to_its_lock():
    # at theta 5 deg the walls flatten onto the plate: the path reaches the lock stroke with
    # a finite, positive force
    from mst_cli.model.mechanics.frame import solve_frame

    cell = HexCell(5, 0.4, 1.25)
    res = solve_frame(cell, MAT)
    assert 0.2 * cell.d_lock_mm < res.d_contact_mm <= cell.d_lock_mm * (1 + 1e-9)
    assert np.isfinite(res.force_N).all() and res.force_N[-1] > 0
