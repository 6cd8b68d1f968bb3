"""Rung L2 (scikit-fem continuum): equilibrium, linear limits, beam-theory limit."""

import numpy as np
import pytest

from mst_cli.geometry import HexCell
from mst_cli.material import Material
from mst_cli.mechanics import layer_law
from mst_cli.mechanics.continuum import (_kinematics, _lame_3d, linear_stiffness_N_per_mm,
                                         solve_continuum)
from mst_cli.mechanics.spring import spring_layer

MAT = Material()


def test_tangent_at_rest_is_plane_stress_elasticity():
    mu, lam = _lame_3d(12.0, 0.45)
    I = np.eye(2)[:, :, None]
    P, FiT, lnJ, beta = _kinematics(I + 0.0, mu, lam)
    assert np.allclose(P, 0.0)
    # plane-stress Lame constant 2 mu lam / (2 mu + lam) = E nu / (1 - nu^2)
    assert lam * beta[0] == pytest.approx(12.0 * 0.45 / (1 - 0.45 ** 2))


def test_uniaxial_small_stretch_has_youngs_modulus():
    mu, lam = _lame_3d(12.0, 0.45)
    # find F22 with P22 = 0 for F11 = 1 + eps by bisection; then P11 / eps -> E
    eps = 1e-6
    lo, hi = 1 - 1e-5, 1.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        F = np.array([[1 + eps, 0], [0, mid]])[:, :, None]
        P = _kinematics(F, mu, lam)[0]
        lo, hi = (mid, hi) if P[1, 1, 0] < 0 else (lo, mid)
    assert P[0, 0, 0] / eps == pytest.approx(12.0, rel=1e-4)


def test_slender_wall_tends_to_beam_theory():
    cell = HexCell(45, 0.4, 6.0)        # t/L ~ 0.1
    k_fe = linear_stiffness_N_per_mm(cell, MAT)
    k_beam = spring_layer(cell, MAT, corrected=False).k_N_per_mm
    assert k_fe == pytest.approx(k_beam, rel=0.04)


@pytest.fixture(scope="module")
def reference_run():
    return solve_continuum(HexCell(33, 1.0, 2.8), MAT)


def test_equilibrium_reaction_equals_applied(reference_run):
    assert reference_run.reaction_balance < 1e-8


def test_small_load_agrees_with_linear_solve():
    res = solve_continuum(HexCell(40, 0.8, 3.0), MAT, first_step_frac=1e-4, levels=0)
    assert res.force_N[1] / res.displacement_mm[1] == pytest.approx(res.k_linear_N_per_mm, rel=2e-3)


def test_stubby_cell_locks_at_the_pads(reference_run):
    cell = HexCell(33, 1.0, 2.8)
    assert reference_run.contact_at == "pad"
    assert reference_run.d_contact_mm == pytest.approx(cell.d_lock_mm, rel=1e-2)
    assert np.all(np.diff(reference_run.force_N) > 0)


def test_frame_and_continuum_agree_for_a_slender_layer():
    cell = HexCell(45, 0.5, 5.0)
    fr = layer_law(cell, MAT, "frame")
    co = layer_law(cell, MAT, "continuum")
    assert fr.k_N_per_mm == pytest.approx(co.k_N_per_mm, rel=0.05)
    assert fr.lock_force_N == pytest.approx(co.lock_force_N, rel=0.10)


def test_unmeshable_cell_is_a_clear_error():
    with pytest.raises(ValueError, match="continuum model needs"):
        solve_continuum(HexCell(30, 1.0, 2.0), MAT)
