"""The web's finite depth (mst_cli.model.mechanics.depth): the plane-strain rungs corrected for the
free faces at y = +-D/2, checked against the 3D model of tools/continuum_3d.py on cells the
fit never saw, and against its physical limits."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from mst_cli.design.problem import DesignProblem
from mst_cli.model import mechanics
from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics.depth import finite_depth_factor, in_web
from mst_cli.sensor.document import load_document

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
import continuum_3d as C3

MAT = Material()
NU = MAT.poisson_ratio


@pytest.mark.parametrize(
    "cell",
    [HexCell(27, 0.7, 2.5, depth_mm=16.0), HexCell(50, 1.6, 5.0, depth_mm=24.0), HexCell(12, 0.5, 2.2, depth_mm=12.4)],
)
def test_factor_matches_the_3d_model_on_cells_outside_the_fit(cell):
    """k of the 3D web with a free face over k with that face held (exactly plane strain; the
    tetrahedra's discretisation cancels): the fit's held-out error was 0.27 % at most."""
    grading = C3.depth_grading(cell, fine=False)
    k_held = mechanics.continuum.linear_k(C3.Problem3D(cell, MAT, grading, 2, 8, y_held_far=True))
    k_free = mechanics.continuum.linear_k(C3.Problem3D(cell, MAT, grading, 2, 8))
    phi = float(finite_depth_factor(cell.theta_rad, cell.t_mm, cell.h_mm, cell.b_mm, NU))
    assert 1 - k_free / k_held > 0.005  # the effect is there to be checked
    assert phi == pytest.approx(k_free / k_held, rel=4e-3)


def test_limits_plane_strain_deep_and_plane_stress_bound():
    theta, t, h = math.radians(40), 1.0, 3.5
    D = np.array([5.0, 10.0, 20.0, 80.0, 1e6])
    phi = finite_depth_factor(theta, t, h, D, NU)
    assert np.all(np.diff(phi) > 0)  # deeper webs are closer to plane strain
    assert phi[-1] == pytest.approx(1.0, abs=1e-5)  # an infinitely deep web is plane strain
    # never softer than plane stress through the whole depth (E against E / (1 - nu^2))
    assert np.all(finite_depth_factor(theta, 3.0, 8.0, np.array([0.5, 1.0, 2.0]), NU) >= 1 - NU**2 - 1e-12)
    # the boundary layer scales with the cross-section: same shape, twice the size, twice the deficit
    d1 = 1 - finite_depth_factor(theta, t, h, 20.0, NU)
    d2 = 1 - finite_depth_factor(theta, 2 * t, 2 * h, 20.0, NU)
    assert d2 == pytest.approx(2 * d1, rel=1e-12)


@pytest.mark.parametrize("model", ["spring", "frame"])
def test_every_rung_scales_its_force_by_the_factor(model):
    """Each rung is linear in E, so the web's law is the plane-strain law with every force times
    the factor: the same compression at the scaled force."""
    cell = HexCell(20, 0.6, 2.4)
    phi = float(finite_depth_factor(cell.theta_rad, cell.t_mm, cell.h_mm, cell.b_mm, NU))
    web = mechanics.layer_law(cell, MAT, model)
    plane = mechanics.uncached_layer_law(cell, MAT, model)
    assert web.k_N_per_mm == pytest.approx(phi * plane.k_N_per_mm, rel=1e-9)
    assert web.lock_force_N == pytest.approx(phi * plane.lock_force_N, rel=1e-9)
    F = np.linspace(0.0, 0.9 * plane.lock_force_N, 7)
    assert np.allclose(web.displacement_mm(phi * F), plane.displacement_mm(F), rtol=1e-9, atol=1e-12)
    assert in_web(cell, MAT).poisson_ratio == NU


def test_the_design_loop_uses_the_same_web_as_the_forward_model():
    """The optimiser's batched kernel (DesignProblem.layer_laws) and the forward model's law of
    the same cell (mechanics.layer_law) carry the same finite-depth factor: same k, R, d_lock."""
    doc = load_document(Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021.yaml")
    problem = DesignProblem(doc)
    theta, t, h = np.array([15.0, 30.0, 55.0]), np.array([0.45, 0.8, 1.6]), np.array([1.9, 2.6, 5.0])
    k, d_lock, R, _ = problem.layer_laws(theta, t, h)
    for i in range(3):
        law = mechanics.layer_law(doc.family.cell(theta[i], t[i], h[i]), doc.material)
        assert k[i] == pytest.approx(law.k_N_per_mm, rel=1e-12)
        assert R[i] == pytest.approx(law.lock_force_N, rel=1e-12)
        assert d_lock[i] == pytest.approx(law.d_lock_mm, rel=1e-12)
    # and that factor is really applied (the plane-strain law is stiffer)
    plane = mechanics.uncached_layer_law(doc.family.cell(theta[0], t[0], h[0]), doc.material, "spring")
    assert k[0] < plane.k_N_per_mm * (1 - 1e-3)
