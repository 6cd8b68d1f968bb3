"""Rung L0 against textbook limits and an independent matrix frame analysis.

The walls are webs D = 20 mm wide and 0.4-3 mm thick: plane strain, so every bending and
axial reference below uses E' = E / (1 - nu^2) (shear G = E / 2 (1 + nu) unchanged).
"""

import math
import warnings

import numpy as np
import pytest

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import correction, layer_law
from mst_cli.model.mechanics.spring import (
    KNEE_FRACTION,
    SHEAR_COEFFICIENT_RECT,
    layer_stiffness_N_per_mm,
    pad_compression_modulus_MPa,
    spring_arrays,
    spring_layer,
    spring_layers,
    wall_compliance_mm_per_N,
)

E, NU = 12.0, 0.45
E_PS = E / (1 - NU**2)  # plane-strain modulus of a wide web


def timoshenko_frame_compliance(theta_rad, L, b, t, E, nu):
    """Vertical tip compliance of one inclined member by the direct stiffness method.

    Independent of the closed form: a 2-node Timoshenko frame element (axial + bending with
    the shear parameter phi = 12 E I / (kappa G A L^2)), rotated to the global frame;
    node 1 clamped, node 2 with rotation fixed and free in x and y; unit vertical load.
    Plane strain (a web b wide): axial and bending stiffness with E / (1 - nu^2).
    """
    A, I = b * t, b * t**3 / 12.0
    Ep = E / (1 - nu**2)
    G = E / (2 * (1 + nu))
    phi = 12 * Ep * I / (SHEAR_COEFFICIENT_RECT * G * A * L**2)
    a = Ep * A / L
    c = Ep * I / (L**3 * (1 + phi))
    k_local = np.array(
        [
            [a, 0, 0, -a, 0, 0],
            [0, 12 * c, 6 * c * L, 0, -12 * c, 6 * c * L],
            [0, 6 * c * L, (4 + phi) * c * L**2, 0, -6 * c * L, (2 - phi) * c * L**2],
            [-a, 0, 0, a, 0, 0],
            [0, -12 * c, -6 * c * L, 0, 12 * c, -6 * c * L],
            [0, 6 * c * L, (2 - phi) * c * L**2, 0, -6 * c * L, (4 + phi) * c * L**2],
        ]
    )
    cs, sn = math.cos(theta_rad), math.sin(theta_rad)
    rot = np.array([[cs, sn, 0], [-sn, cs, 0], [0, 0, 1]])
    T = np.zeros((6, 6))
    T[:3, :3] = T[3:, 3:] = rot
    K = T.T @ k_local @ T
    free = [3, 4]  # node 2: x and y free, rotation fixed
    u = np.linalg.solve(K[np.ix_(free, free)], np.array([0.0, 1.0]))
    return u[1]


@pytest.mark.parametrize("theta_deg", [15, 25, 37, 45, 60, 75])
@pytest.mark.parametrize("t_mm,h_mm", [(0.4, 2.0), (1.0, 3.0), (1.4, 6.0)])
def test_wall_compliance_equals_matrix_frame_analysis(theta_deg, t_mm, h_mm):
    th = math.radians(theta_deg)
    cell = HexCell(theta_deg, t_mm, h_mm)
    ref = timoshenko_frame_compliance(th, cell.wall_length_mm, cell.b_mm, t_mm, E, NU)
    got = wall_compliance_mm_per_N(th, t_mm, h_mm, cell.b_mm, E, NU)
    assert got == pytest.approx(ref, rel=1e-10)


def test_slender_wall_tends_to_pure_bending():
    """t/L -> 0: shear and axial terms vanish as (t/L)^2 against bending."""
    th, b = math.radians(30), 1.0
    ratios = []
    for t in (0.2, 0.02, 0.002):
        h = 2 * t + 200 * t  # keeps t/L small and shrinking in proportion
        full = wall_compliance_mm_per_N(th, t, h, b, E, NU)
        L = 0.5 * (h - t) / math.sin(th)
        bending = math.cos(th) ** 2 * L**3 / (12 * E_PS * b * t**3 / 12)
        ratios.append(full / bending - 1)
    assert ratios[0] < 1e-3
    assert ratios[1] == pytest.approx(ratios[0], rel=0.05)  # same t/L -> same ratio
    # and at a fixed height, thinner walls approach pure bending quadratically
    h = 5.0
    r = [
        wall_compliance_mm_per_N(th, t, h, b, E, NU)
        / (math.cos(th) ** 2 * (0.5 * (h - t) / math.sin(th)) ** 3 / (E_PS * b * t**3))
        - 1
        for t in (0.1, 0.05)
    ]
    assert r[0] / r[1] == pytest.approx(4.0, rel=0.05)


def test_vertical_wall_is_axial_only():
    """theta -> 90 deg: the wall is a column, compliance L / (E' A) (plane strain)."""
    th = math.radians(90 - 1e-7)
    t, h, b = 1.0, 4.0, 1.0
    L = 0.5 * (h - t)
    assert wall_compliance_mm_per_N(th, t, h, b, E, NU) == pytest.approx(L / (E_PS * b * t), rel=1e-9)


def test_layer_stiffness_scales_with_web_width_and_modulus():
    th, t, h, b = math.radians(30), 0.8, 3.0, 20.0
    k = layer_stiffness_N_per_mm(th, t, h, b, E, NU)
    assert layer_stiffness_N_per_mm(th, t, h, 2 * b, E, NU) == pytest.approx(2 * k)
    assert layer_stiffness_N_per_mm(th, t, h, b, 3 * E, NU) == pytest.approx(3 * k)


def test_plane_strain_stiffens_a_slender_wall_by_one_over_one_minus_nu_squared():
    # slender: bending dominates, and bending goes with E'; nu = 0 is plane stress
    th, t, h, b = math.radians(40), 0.1, 20.0, 20.0
    ratio = layer_stiffness_N_per_mm(th, t, h, b, E, NU) / layer_stiffness_N_per_mm(th, t, h, b, E, 0.0)
    assert ratio == pytest.approx(1 / (1 - NU**2), rel=1e-3)


def test_layer_is_two_walls_in_series_times_two_chevrons():
    cell = HexCell(30, 0.8, 3.0, depth_mm=17.0)
    law = spring_layer(cell, Material(youngs_modulus_MPa=E, poisson_ratio=NU), corrected=False)
    c_wall = timoshenko_frame_compliance(cell.theta_rad, cell.wall_length_mm, 17.0, 0.8, E, NU)
    chevron = 1.0 / (2 * c_wall)
    assert law.k_N_per_mm == pytest.approx(2 * chevron, rel=1e-10)
    assert law.lock_force_N == pytest.approx(law.k_N_per_mm * (3.0 - 1.6 - 0.1))


def bonded_layer_modulus_fe(E, nu, a, H):
    """Compression modulus (mean stress / strain) of a layer 2a wide and H thick bonded to two
    rigid plates, plane strain, from scikit-fem's own linear elasticity (P2 triangles, the
    right half with u_x = 0 on the mirror plane x = 0, elements graded towards the free edge).
    Independent of the closed form it checks."""
    from skfem import Basis, ElementTriP2, ElementVector, MeshTri, asm, condense, solve
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    nx = max(8, int(math.ceil(16 * a / H)))
    xs = a * np.sin(0.5 * np.pi * np.linspace(0, 1, nx + 1))
    mesh = MeshTri.init_tensor(xs, np.linspace(0, H, 9)).refined(2 if a / H < 2 else 1)
    basis = Basis(mesh, ElementVector(ElementTriP2()))
    K = asm(linear_elasticity(*lame_parameters(E, nu)), basis)
    bottom = basis.get_dofs(lambda x: np.isclose(x[1], 0.0))
    top = basis.get_dofs(lambda x: np.isclose(x[1], H))
    mirror = basis.get_dofs(lambda x: np.isclose(x[0], 0.0))
    top_z = np.concatenate([top.nodal["u^2"], top.facet["u^2"]])
    fixed = np.concatenate([bottom.all(), top.all(), mirror.nodal["u^1"], mirror.facet["u^1"]])
    u = np.zeros(basis.N)
    u[top_z] = -1.0
    u = solve(*condense(K, np.zeros(basis.N), x=u, D=fixed))
    return -(K @ u)[top_z].sum() / a * H


@pytest.mark.parametrize("a_over_H", [1.0, 2.0, 4.0, 8.0, 16.0])
def test_pad_compression_modulus_equals_fe_of_a_bonded_layer(a_over_H):
    # the design range: contact half-width c = 7-14 mm over 2t = 0.8-4 mm, a/H >= 1.7
    fe = bonded_layer_modulus_fe(E, NU, a_over_H, 1.0)
    assert float(pad_compression_modulus_MPa(E, NU, a_over_H, 1.0)) == pytest.approx(fe, rel=0.01)


def test_pad_compression_modulus_limits():
    M = E * (1 - NU) / ((1 + NU) * (1 - 2 * NU))  # constrained (oedometric) modulus
    assert float(pad_compression_modulus_MPa(E, NU, 1e6, 1.0)) == pytest.approx(M, rel=1e-5)
    assert float(pad_compression_modulus_MPa(E, NU, 1e-6, 1.0)) == pytest.approx(E_PS, rel=1e-9)
    assert float(pad_compression_modulus_MPa(E, 0.0, 3.0, 1.0)) == pytest.approx(E, rel=1e-12)
    # nearly incompressible: the squeeze-film layer, 4 mu (1 + (a/H)^2)
    nu = 0.5 - 1e-9
    mu = E / (2 * (1 + nu))
    assert float(pad_compression_modulus_MPa(E, nu, 3.0, 1.0)) == pytest.approx(4 * mu * (1 + 9.0), rel=1e-5)


def test_locked_stiffness_is_walls_plus_contact_column():
    """Past the lock the walls keep bending while the closed pads (2t, bonded to the plates)
    carry load over the contact width 2c and the whole web width D."""
    cell = HexCell(25, 0.6, 2.0)
    law = layer_law(cell, Material(youngs_modulus_MPa=E, poisson_ratio=NU))
    c = 15.0 - 0.6 / math.sin(math.radians(25))  # inner tip half-width
    column = bonded_layer_modulus_fe(E, NU, c, 1.2) * 20.0 * 2 * c / 1.2
    assert law.k_locked_N_per_mm - law.k_N_per_mm == pytest.approx(column, rel=0.01)
    # for the soft reference layer the locked stiffness is hundreds of times the open one
    assert law.k_locked_N_per_mm / law.k_N_per_mm > 300


def test_softened_law_is_continuous_and_passes_its_knee_and_lock_point():
    cell = HexCell(45, 0.8, 4.0)
    law = spring_layer(cell, Material(youngs_modulus_MPa=E, poisson_ratio=NU))
    k, dl, R = law.k_N_per_mm, law.d_lock_mm, law.lock_force_N
    assert 0 < R < k * dl  # steep walls soften before the lock
    knee, lock = law.knots_N
    assert (knee, lock) == pytest.approx((KNEE_FRACTION * R, R), rel=1e-15)
    assert law.displacement_mm(knee) == pytest.approx(knee / k, rel=1e-14)
    assert law.displacement_mm(R) == pytest.approx(dl, rel=1e-14)
    eps = 1e-9 * R
    for F in (knee, R):  # no jump at either knot
        assert law.displacement_mm(F + eps) - law.displacement_mm(F - eps) < 1e-6 * dl
    # slopes: k first, the secant through the lock point next, k_locked after
    d = law.displacement_mm
    assert (d(0.5 * knee) - 0) / (0.5 * knee) == pytest.approx(1 / k, rel=1e-12)
    assert (dl - knee / k) / (R - knee) == pytest.approx((d(0.9 * R) - d(0.6 * R)) / (0.3 * R), rel=1e-12)
    assert (d(2 * R) - dl) / R == pytest.approx(1 / law.k_locked_N_per_mm, rel=1e-12)


def test_textbook_law_is_bilinear_with_the_pads_stroke():
    cell = HexCell(45, 0.8, 4.0)
    law = spring_layer(cell, Material(youngs_modulus_MPa=E, poisson_ratio=NU), corrected=False)
    assert law.knots_N == (law.lock_force_N,)
    assert law.d_lock_mm == pytest.approx(cell.h_mm - 2 * cell.t_mm - cell.contact_allowance_mm)
    assert law.lock_force_N == pytest.approx(law.k_N_per_mm * law.d_lock_mm, rel=1e-15)


def test_lock_corrections_vanish_with_the_stroke():
    # the softening is large rotation, first order in the stroke: none without a stroke
    x, theta = np.array([0.1, 0.3, 0.5]), np.radians([25.0, 40.0, 60.0])
    for sigma, close in ((0.0, 0.0), (1e-6, 1e-5)):
        assert np.allclose(correction.lock_force_factor(x, theta, sigma), 1.0, atol=close + 1e-15)
        assert np.allclose(correction.lock_stroke_factor(x, theta, sigma), 1.0, atol=close + 1e-15)
    assert np.all(correction.lock_force_factor(x, theta, 1.0) < 1.0)


def test_wall_pinch_hinge_is_off_at_full_stroke_and_on_where_walls_close_early():
    # p = 0 where the stroke fit says the pads meet at the rigid stroke (ln q = 0), and grows like
    # -ln q - offset once the walls close early (q well under 1 - offset)
    ln_q = np.array([0.0, -0.2, -0.4])
    p = correction.hinge_design_matrix(0.2, 1.0, 0.5, ln_q)[:, 0]
    assert p[0] == 0.0
    off, w = correction.HINGE_OFFSET, correction.HINGE_WIDTH
    expected = -ln_q[1:] - off - w * math.log1p(math.exp(-off / w))
    assert p[1:] == pytest.approx(expected, abs=1e-9)


def test_hinge_sum_is_the_hinge_matrix_times_its_coefficients():
    # the design loop's lean sum and the fit's design matrix are one model
    rng = np.random.default_rng(5)
    x, th, sig = rng.uniform(0.05, 1.5, 200), rng.uniform(0.1, 1.3, 200), rng.uniform(0.2, 1.8, 200)
    ln_q = rng.uniform(-0.3, 0.05, 200)
    coef = rng.normal(size=len(correction.HINGE_TERMS))
    w, off = correction.HINGE_WIDTH, correction.HINGE_OFFSET
    lean = correction.hinge_sum(x, th, sig, ln_q, coef, w, off)
    assert lean == pytest.approx(correction.hinge_design_matrix(x, th, sig, ln_q, w, off) @ coef, rel=1e-12, abs=1e-14)
    # a NaN probe stays NaN, silently (the optimiser's non-finite guard handles it)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isnan(correction.hinge_sum(x[:1], th[:1], sig[:1], np.array([np.nan]), coef, w, off)).all()


def test_spring_lock_force_is_smooth_where_the_hinge_switches_on():
    # t 0.6, h 4: L0 predicts the walls close early (q < 0.97) below theta ~ 44 deg; across the
    # switch R(theta) must stay smooth as the issue 20 criterion asks of L2: no point off its
    # neighbours' mean by more than 0.5 %
    theta = np.arange(38.0, 50.01, 0.25)
    laws = [spring_layer(HexCell(th, 0.6, 4.0), Material()) for th in theta]
    q = np.array([law.d_lock_mm for law in laws]) / (4.0 - 2 * 0.6 - HexCell(40, 0.6, 4.0).contact_allowance_mm)
    assert q.min() < 0.965 and q.max() > 0.975  # the sweep crosses the switch (q = 0.97)
    R = np.array([law.lock_force_N for law in laws])
    assert np.max(np.abs(R[1:-1] / (0.5 * (R[:-2] + R[2:])) - 1)) < 0.005


def test_stiffness_correction_vanishes_for_slender_walls():
    # every term of the joint fit vanishes with x = t/L: beam theory is exact for slender walls
    theta = np.radians(np.linspace(5, 75, 15))
    for x, tol in ((0.0, 0.0), (1e-4, 2e-3)):
        assert np.allclose(correction.stiffness_factor(x, theta), 1.0, atol=tol)
    assert np.allclose(correction.design_matrix(0.0, theta), 0.0)


def test_stiffness_correction_over_the_printable_box():
    # shallow walls end in a solid tip wedge t / tan(theta) long: far stiffer than the beam
    # clamped at the centre line (x5 and more at theta 5-10 deg); stubby steep walls are softer
    # than beam theory with its rigid clamps (the joints give: 0.75 at theta 75, t/L 1.6)
    assert correction.stiffness_factor(0.15, np.radians(7.0)) > 3.0
    assert 0.6 < correction.stiffness_factor(1.6, np.radians(75.0)) < 0.9
    # finite and bounded wherever an optimiser may probe, valid cell or not: the inputs are
    # held in the fitted box, where the largest factor is at its shallowest, stubbiest corner
    # (theta 5 deg, y = t/(h - t) = 0.88: the beam's free length L (1 - y) is an eighth of L)
    x, th = np.meshgrid(np.linspace(-1, 5, 40), np.radians(np.linspace(0.5, 89.5, 40)))
    for sigma in (0.0, 0.5, 1.0, 2.5):
        for f in (
            correction.stiffness_factor(x, th),
            correction.lock_force_factor(x, th, sigma),
            correction.lock_stroke_factor(x, th, sigma),
        ):
            assert np.isfinite(f).all() and (f > 0).all() and f.max() < 50


def test_fitted_box_is_the_printable_box():
    fit = correction._fit()["fitted_on"]
    assert fit["t_over_L_range"][1] > 1.6  # walls shorter than they are thick
    lo, hi = np.degrees(correction.fitted_theta_rad_range())
    assert lo < 5.5 and hi > 74.5
    assert correction.fitted_t_over_L_max() == fit["t_over_L_range"][1]


def test_corrected_spring_meets_l2_across_the_box_out_of_sample():
    # the stored verification (tools/fit_l0_correction.py): L0 corrected against L2 on
    # cells it was not fitted on, every band of t/L and theta
    oos = correction._fit()["out_of_sample"]
    assert oos["seed"] != correction._fit()["fitted_on"]["seed"]
    for band, s in oos["bands"]["spring"].items():
        assert s["n"] > 0 and s["failures"] == 0, band
        assert s["median_abs_err_k"] < 0.03 and s["median_abs_err_lock_force"] < 0.05, band


def test_expected_error_reads_the_measured_band_table():
    table = correction._fit()["out_of_sample"]["expected_error"]
    err = np.array(table["median_abs_err_lock_force"])
    # vectorised, one value per (t/L, theta); each band's own measured median
    x = np.array([0.3, 0.3, 0.3, 0.8, 0.8, 1.3, 1.3])
    th = np.radians([10.0, 40.0, 70.0, 40.0, 70.0, 40.0, 70.0])
    got = correction.expected_error_rel(x, th)
    assert got.shape == (7,)
    assert np.allclose(got, [err[0, 0], err[0, 1], err[0, 2], err[1, 1], err[1, 2], err[2, 1], err[2, 2]])
    assert float(correction.expected_error_rel(0.3, np.radians(40.0))) == err[0, 1]
    # past the outer edges: the nearest band; every value a positive fraction
    assert correction.expected_error_rel(5.0, np.radians(89.0)) == err[-1, -1]
    assert correction.expected_error_rel(-1.0, np.radians(1.0)) == err[0, 0]
    assert (err > 0).all() and (err < 1).all()


def test_thin_band_is_fitted_and_measured_apart():
    # compact designs live at the printable minimum wall (t 0.4-0.6 mm, small shallow cavities,
    # a/t up to 0.25): sampled apart in the fit and verified on its own held-out cells
    oos = correction._fit()["out_of_sample"]
    thin = oos["bands"]["spring"]["thin t 0.4-0.6 mm"]
    assert thin["n"] >= 50 and thin["failures"] == 0
    assert thin["median_abs_err_k"] < 0.02
    assert thin["median_abs_err_d_lock"] < 0.02
    # the lock force: within the 3 % median of issue 20, over the box and in the thin band
    # (2.3 % and 2.0 % against the contact-defined L2 lock of 0.6; single cells reach 6 %:
    # the stored example cells, which the design optimiser once visited, are -5.0 / +3.7 /
    # +6.1 % in R and within 2.1 % in d_lock)
    assert thin["median_abs_err_lock_force"] < 0.03
    assert oos["bands"]["spring"]["all"]["median_abs_err_lock_force"] < 0.03
    for e in oos["example_cells"]:
        assert abs(e["err_d_lock"]) < 0.03, e
    # the stored table gives the thin band its own median when t is known
    table = oos["expected_error"]
    th = np.radians([20.0, 20.0, 50.0])
    got = correction.expected_error_rel(0.3, th, t_mm=np.array([0.45, 1.0, 0.45]))
    assert got[0] == table["thin"]["median_abs_err_lock_force"]
    assert got[1] == got[2] == correction.expected_error_rel(0.3, np.radians(20.0))


def test_allowance_over_t_term_is_recovered_and_bounded():
    # sigma = 2 (1 - y (1 + a/t)): a cell's a/t comes back from (t/L, theta, sigma)
    cell = HexCell(20.0, 0.4, 2.0)
    x, th = cell.t_mm / cell.wall_length_mm, cell.theta_rad
    sigma = correction.stroke_ratio(cell.h_mm - 2 * cell.t_mm - cell.contact_allowance_mm, cell.wall_length_mm, th)
    assert float(correction.allowance_over_t(x, th, sigma)) == pytest.approx(cell.contact_allowance_mm / 0.4)
    r = correction.allowance_over_t(
        np.array([0.0, 1e-9, 5.0]), np.radians([0.5, 45.0, 89.0]), np.array([-1.0, 3.0, 0.0])
    )
    assert np.isfinite(r).all() and (r >= 0).all() and (r <= correction.R_MAX).all()


def test_lock_factors_from_one_design_matrix_equal_the_two_fits_bit_for_bit():
    from mst_cli.model.mechanics import correction

    rng = np.random.default_rng(3)
    x, theta, sigma = rng.uniform(0, 2, 2000), np.radians(rng.uniform(0, 90, 2000)), rng.uniform(-0.5, 3, 2000)
    force, stroke = correction.lock_factors(x, theta, sigma)
    assert np.array_equal(force, correction.lock_force_factor(x, theta, sigma))
    assert np.array_equal(stroke, correction.lock_stroke_factor(x, theta, sigma))


def test_a_cells_law_does_not_depend_on_its_batch():
    """The same cells in any shape and order give the same bits: the lock and stiffness fits
    are summed in one order (no BLAS), so the solver's batches agree with single calls."""
    rng = np.random.default_rng(0)
    th, t, h = np.radians(rng.uniform(10, 70, (19, 3))), rng.uniform(0.4, 2.5, (19, 3)), rng.uniform(1.5, 7, (19, 3))
    args = (20.0, 25.0, 0.1, 30.0, 0.45)
    grid = spring_arrays(th, t, h, *args)
    flat = spring_arrays(th.ravel(), t.ravel(), h.ravel(), *args)
    rev = spring_arrays(th.ravel()[::-1].copy(), t.ravel()[::-1].copy(), h.ravel()[::-1].copy(), *args)
    for a, b, c in zip(grid, flat, rev):
        np.testing.assert_array_equal(a.ravel(), b)
        np.testing.assert_array_equal(b, c[::-1])


def test_a_stacks_laws_from_one_call_are_each_cells_own_law():
    """One kernel call for a stack gives every cell the bits it gets alone."""
    cells = [HexCell(20 + 5 * j, 0.5 + 0.2 * j, 2.0 + 0.6 * j) for j in range(6)]
    mat = Material(youngs_modulus_MPa=12.0, poisson_ratio=0.45)
    assert spring_layers(cells, mat) == tuple(spring_layer(c, mat) for c in cells)


def test_stacked_terms_is_numpys_stack_of_the_broadcast_terms():
    """The fits' design matrices are filled in place (model.arrays.stacked_terms): the same
    array as np.stack of the broadcast terms, in the same (C) order, so a matmul or an einsum
    over it gives the same bits."""
    from mst_cli.model.arrays import stacked_terms

    x = np.linspace(0.1, 0.9, 4)
    y = np.arange(3.0)[:, None]
    terms = (x, y, 2.5, x * y, np.ones_like(x))
    ours, numpys = stacked_terms(*terms), np.stack(np.broadcast_arrays(*terms), axis=-1)
    assert ours.shape == numpys.shape == (3, 4, 5) and ours.flags.c_contiguous and ours.dtype == numpys.dtype
    np.testing.assert_array_equal(ours, numpys)
    coef = np.array([0.3, -1.7, 2.2, 0.9, -0.4])
    np.testing.assert_array_equal(np.einsum("...j,j->...", ours, coef), np.einsum("...j,j->...", numpys, coef))
