"""The whole part's L0 prediction (issue 44, docs/design.md 4.6): the cap's, plates' and cover's
compliance (mst_cli.model.load_path) in series with the layers, in mst simulate and the design
loop. Asserted against the analytic limits: rigid members give the layers' model to the bit,
the part's compliance is the closed form's sum, and the field change per newton of a centred
press is the field's gradient times that compliance."""

from pathlib import Path

import numpy as np
import pytest

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.response import field_magnitude_T, regime_kernel, simulate
from mst_cli.model.stack import Stack

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"


@pytest.fixture(scope="module")
def forward():
    doc = mst.load(FORWARD)
    return doc, doc.geometry()


@pytest.mark.parametrize("mechanics", ["spring", "frame"])
def test_rigid_members_reproduce_the_layer_model_exactly(forward, mechanics):
    """whole_part=False and members of zero compliance give the layers' curve to the bit, and the
    whole part's response carries that same curve beside its own."""
    doc, g = forward
    layers = simulate(g, doc.material, mechanics, whole_part=False)
    part = simulate(g, doc.material, mechanics)
    assert layers.members.total_mm_per_N == 0.0
    np.testing.assert_array_equal(layers.displacement_mm, layers.displacement_layers_mm)
    np.testing.assert_array_equal(layers.displacement_mm, part.displacement_layers_mm)
    np.testing.assert_array_equal(layers.dB_rel, part.dB_rel_layers)
    laws = layer_laws(g.layers, doc.material, mechanics)
    F = part.force_N
    np.testing.assert_array_equal(Stack(laws, 0.0).displacement_mm(F), Stack(laws).displacement_mm(F))
    for a, b in zip(layers.regimes, part.regimes):
        assert a.sensitivity_secant_per_N == a.sensitivity_layers_secant_per_N == b.sensitivity_layers_secant_per_N
        assert a.force_to_N == b.force_to_N  # the same force passes every member: the locks stay


def test_the_parts_compliance_is_the_closed_forms_sum(forward):
    """In every regime 1/k_effective = the layers' compliance + cap + plates + cover, and the
    drop is the layers' compression plus the members' compliance times the force."""
    doc, g = forward
    part = simulate(g, doc.material)
    parts = lp.members(g, doc.material)
    assert part.members == parts
    assert parts.total_mm_per_N == pytest.approx(parts.cap_mm_per_N + sum(parts.plates_mm_per_N) + parts.cover_mm_per_N)
    stack = Stack(layer_laws(g.layers, doc.material, "spring"))
    layer_c = lp.layer_compliances_mm_per_N(stack).sum(axis=1)
    for r, c in zip(part.regimes, layer_c):
        assert 1.0 / r.k_effective_N_per_mm == pytest.approx(c + parts.total_mm_per_N, rel=1e-9)
    np.testing.assert_allclose(
        part.displacement_mm, part.displacement_layers_mm + parts.total_mm_per_N * part.force_N, rtol=1e-12, atol=1e-15
    )


def test_the_field_change_per_newton_is_the_gradient_times_the_compliance(forward):
    """A centred press at small force: d(dB/B0)/dF = (d|B|/dgap)/B0 x the compliance, for the part
    and for the layers alone; their ratio is the compliances' ratio."""
    doc, g = forward
    part = simulate(g, doc.material)
    model = part.field_model
    h = 1e-4
    grad = (field_magnitude_T(g.gap0_mm - h, g, model) - field_magnitude_T(g.gap0_mm + h, g, model)) / (2 * h)
    c_part = part.displacement_mm[1] / part.force_N[1]
    c_layers = part.displacement_layers_mm[1] / part.force_N[1]
    slope_part = part.dB_rel[1] / part.force_N[1]
    slope_layers = part.dB_rel_layers[1] / part.force_N[1]
    # the first step closes the gap by ~0.01 mm of 13.9: the secant is the tangent to 0.3 %
    assert slope_part == pytest.approx(float(grad) / part.B0_T * c_part, rel=5e-3)
    assert slope_layers == pytest.approx(float(grad) / part.B0_T * c_layers, rel=5e-3)
    assert slope_part / slope_layers == pytest.approx(c_part / c_layers, rel=5e-3)
    assert c_part / c_layers > 2.0  # the forward design's cap: 60 % of regime 1's motion


def test_the_design_loop_predicts_what_simulate_does(forward):
    """The vectorised kernel (regime_kernel with the members' compliance from member_compliances)
    gives simulate's whole-part S and R for the L0 laws."""
    doc, g = forward
    part = simulate(g, doc.material)
    scene = lp.member_scene(g, doc.material)
    cells = g.layers
    theta, t, h = (np.array([getattr(c, k) for c in cells]) for k in ("theta_rad", "t_mm", "h_mm"))
    members = lp.members_total_mm_per_N(scene, theta, t, h)
    assert members == pytest.approx(part.members.total_mm_per_N, rel=1e-12)
    laws = layer_laws(cells, doc.material, "spring")
    k, dl, kl, R = (np.array([getattr(law, a) for law in laws]) for a in ("k_N_per_mm", "d_lock_mm", "k_locked_N_per_mm", "lock_force_N"))
    field = lambda gap: field_magnitude_T(gap, g, part.field_model)  # noqa: E731
    R_sorted, S, _, _ = regime_kernel(k, dl, kl, g.gap0_mm, field, R, members)
    np.testing.assert_allclose(R_sorted, part.lock_forces_N, rtol=1e-12)
    np.testing.assert_allclose(S, [r.sensitivity_secant_per_N for r in part.regimes], rtol=1e-9)
