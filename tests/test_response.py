"""The sensor's forward model against hand-computed and theorem-fixed numbers."""

import numpy as np
import pytest

from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.cell import HexCell
from mst_cli.model.magnet_field import axial_Bz_T, axial_dBz_dz_T_per_mm
from mst_cli.model.material import Material
from mst_cli.model.mechanics import layer_law
from mst_cli.model.response import field_magnitude_T, regime_kernel, simulate

MAT = Material()
REF = SensorGeometry((HexCell(25, 0.6, 2.0), HexCell(33, 1.0, 2.8), HexCell(37, 1.4, 3.5)))


def test_single_layer_by_hand():
    cell = HexCell(30, 0.8, 3.0)
    g = SensorGeometry((cell,))
    law = layer_law(cell, MAT)
    r = simulate(g, MAT, whole_part=False)
    B0 = axial_Bz_T(g.gap0_mm, 3.0, 2.0, 1.3)
    B1 = axial_Bz_T(g.gap0_mm - law.d_lock_mm, 3.0, 2.0, 1.3)
    assert r.B0_T == pytest.approx(B0, rel=1e-12)
    assert r.lock_forces_N == pytest.approx([law.lock_force_N])
    assert r.regimes[0].sensitivity_secant_per_N == pytest.approx((B1 / B0 - 1) / law.lock_force_N, rel=1e-12)
    assert r.gap_min_mm == pytest.approx(g.gap0_mm - law.d_lock_mm)


def test_sensitivity_is_gradient_times_secant_compliance_for_a_small_stroke():
    # S = g c with g = -(1/B0) dB/dgap (docs/design.md section 2) and c = d_lock / R the layer's
    # secant compliance, exact as the stroke -> 0; the secant's error is first order in the
    # stroke (half the field's curvature term)
    errors = []
    for stroke in (0.02, 0.01, 0.005):
        cell = HexCell(30, 0.8, 1.72, contact_allowance_mm=0.12 - stroke)
        g = SensorGeometry((cell,))
        r = simulate(g, MAT, whole_part=False)
        grad = -axial_dBz_dz_T_per_mm(g.gap0_mm, 3.0, 2.0, 1.3) / axial_Bz_T(g.gap0_mm, 3.0, 2.0, 1.3)
        law = layer_law(cell, MAT)
        errors.append(r.regimes[0].sensitivity_secant_per_N / (grad * law.d_lock_mm / law.lock_force_N) - 1)
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.02)
    assert errors[1] / errors[2] == pytest.approx(2.0, rel=0.02)
    assert abs(errors[2]) < 2e-3


def test_secant_lies_between_local_slopes_and_curves_are_monotone():
    r = simulate(REF, MAT, whole_part=False)
    assert r.dB_rel[0] == 0.0
    assert np.all(np.diff(r.dB_rel) > 0) and np.all(np.diff(r.displacement_mm) > 0)
    for reg in r.regimes:  # mean value theorem
        assert reg.sensitivity_min_per_N <= reg.sensitivity_secant_per_N <= reg.sensitivity_max_per_N
    # each regime is softer to the field than the one before (a stiffer stack moves less)
    S = [reg.sensitivity_secant_per_N for reg in r.regimes]
    assert S[0] > S[1] > S[2]


def test_vectorised_kernel_agrees_with_simulate():
    r = simulate(REF, MAT, whole_part=False)
    laws = [layer_law(c, MAT) for c in REF.layers]
    k, dl, kl, R_law = (
        np.array([getattr(l, a) for l in laws])
        for a in ("k_N_per_mm", "d_lock_mm", "k_locked_N_per_mm", "lock_force_N")
    )
    assert np.all(R_law < k * dl)  # the softened laws: two knots before each lock
    R, S, gap, B = regime_kernel(k, dl, kl, REF.gap0_mm, lambda gp: field_magnitude_T(gp, REF, "axial"), R_law)
    assert np.allclose(R, r.lock_forces_N, rtol=1e-13)
    assert np.allclose(S, [x.sensitivity_secant_per_N for x in r.regimes], rtol=1e-12)
    assert B[-1] == pytest.approx(r.B_full_T, rel=1e-13)


def test_force_resolution_is_field_resolution_over_B0_S():
    r = simulate(REF, MAT, noise_uT_rms=3.0, whole_part=False)
    for reg in r.regimes:
        assert reg.force_resolution_N == pytest.approx(3e-6 / (r.B0_T * reg.sensitivity_secant_per_N))
        assert reg.force_resolution_worst_N >= reg.force_resolution_N


def test_points_past_the_last_lock_are_flagged_out_of_range():
    r = simulate(REF, MAT, whole_part=False)
    last = r.lock_forces_N[-1]
    assert np.all(r.in_range == (r.force_N <= last * (1 + 1e-12)))
    assert r.force_N.max() > last


def test_field_model_choice_is_reported_and_dipole_reads_high():
    from dataclasses import replace

    assert simulate(REF, MAT, whole_part=False).field_model == "axial"
    assert simulate(replace(REF, chip_offset_mm=(0.5, 0.0)), MAT, whole_part=False).field_model == "cylinder"
    assert simulate(REF, MAT, field_model="dipole", whole_part=False).B0_T > simulate(REF, MAT, whole_part=False).B0_T


def test_a_magnet_too_close_saturates_the_chip_and_says_so():
    from dataclasses import replace

    from mst_cli.model.assembly import Housing

    close = replace(REF, layers=(HexCell(30, 0.4, 1.2),), housing=Housing(cover_mm=0.2, pocket_floor_mm=0.2))
    r = simulate(close, MAT, whole_part=False)
    assert r.B_full_T > 0.05 and r.saturated and r.chip_setting is None
    assert any("saturation" in w for w in r.warnings)


def test_a_layer_squeezed_past_the_crease_onset_is_named_in_the_warnings():
    """Only a tabulated (L2) law whose stretch at the lock is below the onset gets a line, naming
    its layer and its R; L0's laws carry no marker and get none."""
    from mst_cli.model.material import CREASE_ONSET_STRETCH
    from mst_cli.model.mechanics.frame import TabulatedLockingLayer
    from mst_cli.model.response import _crease_warnings
    from mst_cli.model.stack import Stack

    def law(R, stretch):
        return TabulatedLockingLayer.from_curve([0.0, 1.0], [0.0, R], R, 50 * R, False, stretch)

    l0 = layer_law(HexCell(20.0, 0.6, 2.5), Material(), "spring")
    stack = Stack((l0, law(4.0, CREASE_ONSET_STRETCH + 0.01), law(16.0, 0.59), law(30.0, None)))
    (line,) = _crease_warnings(stack)
    assert line.startswith("layer 3: ") and "stretch of 0.59" in line and "R_3 = 16 N" in line
