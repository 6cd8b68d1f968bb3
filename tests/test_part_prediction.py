"""The whole part's L0 prediction (issue 44, docs/design.md 4.6): the cap's, plates' and cover's
compliance (mst_cli.model.load_path) in series with the layers, in mst simulate and the design
loop. Asserted against the analytic limits: rigid members give the layers' model to the bit,
the part's compliance is the closed form's sum, and the field change per newton of a centred
press is the field's gradient times that compliance."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.past_lock import by_regime
from mst_cli.model.response import capped_lock_forces_N, field_magnitude_T, regime_kernel, simulate
from mst_cli.model.stack import Stack

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"


@pytest.fixture(scope="module")
def forward():
    doc = mst.load(FORWARD)
    return doc, doc.geometry()


@pytest.mark.parametrize("mechanics", ["spring", "frame"])
def test_rigid_members_reproduce_the_layer_model_exactly(forward, mechanics):
    """whole_part=False gives the layers' curve to the bit, a cap of zero compliance is the layer
    itself, and the whole part's response carries the layers' curve beside its own."""
    doc, g = forward
    layers = simulate(g, doc.material, mechanics, whole_part=False)
    part = simulate(g, doc.material, mechanics)
    assert layers.members.total_mm_per_N == 0.0
    np.testing.assert_array_equal(layers.displacement_mm, layers.displacement_layers_mm)
    np.testing.assert_array_equal(layers.dB_rel, layers.dB_rel_layers)
    laws = layer_laws(g.layers, doc.material, mechanics)
    np.testing.assert_array_equal(Stack(laws).displacement_mm(part.force_N), part.displacement_layers_mm)
    F = part.force_N
    np.testing.assert_array_equal(Stack(laws, 0.0).displacement_mm(F), Stack(laws).displacement_mm(F))
    rigid_cap = lp.CappedLayer(laws[-1], 0.0)
    assert rigid_cap.lock_force_N == laws[-1].lock_force_N
    np.testing.assert_array_equal(rigid_cap.displacement_mm(F), laws[-1].displacement_mm(F))
    for a, b in zip(layers.regimes, part.regimes):
        assert a.sensitivity_secant_per_N == a.sensitivity_layers_secant_per_N == b.sensitivity_layers_secant_per_N


def test_the_parts_compliance_is_the_closed_forms_sum(forward):
    """Before the first lock the drop is the layers' compression plus (cap + plates + cover) x F,
    and 1/k_effective the layers' compliance plus the members'; the cap closes the top layer's
    cavity where the layer's compression plus the cap's bending reach d_lock. The part without
    its insert (a bare TPU cap), so that the cap closes the top layer below the layers' first knee."""
    doc, g = forward
    g = replace(g, insert_plate=None)
    part = simulate(g, doc.material)
    parts = lp.members(g, doc.material)
    assert part.members == parts
    outside = parts.cap_mm_per_N + sum(parts.plates_mm_per_N) + sum(parts.joints_mm_per_N) + parts.cover_mm_per_N
    assert parts.total_mm_per_N == pytest.approx(outside)
    assert len(parts.joints_mm_per_N) == len(g.layers) and min(parts.joints_mm_per_N) > 0.0  # every layer on a plate
    laws = layer_laws(g.layers, doc.material, "spring")
    first = part.force_N <= part.lock_forces_N[0]
    np.testing.assert_allclose(
        part.displacement_mm[first],
        Stack(laws).displacement_mm(part.force_N[first]) + parts.total_mm_per_N * part.force_N[first],
        rtol=1e-12,
        atol=1e-15,
    )
    layer_c = sum(1.0 / law.k_N_per_mm for law in laws)  # the forward design's laws are bilinear
    assert 1.0 / part.regimes[0].k_effective_N_per_mm == pytest.approx(layer_c + parts.total_mm_per_N, rel=1e-9)
    top, C = laws[-1], parts.cap_mm_per_N + parts.joints_mm_per_N[-1]  # the cap and the top layer's joints
    closes = lp.CappedLayer(top, C).lock_force_N
    assert float(top.displacement_mm(closes)) + C * closes == pytest.approx(top.d_lock_mm, rel=1e-12)
    assert closes == pytest.approx(top.d_lock_mm / (1.0 / top.k_N_per_mm + C), rel=1e-12)
    assert closes == pytest.approx(min(part.lock_forces_N), rel=1e-12)  # the soft cap closes it first: 3.8 N
    assert closes < laws[0].lock_force_N


def test_the_field_change_per_newton_is_the_gradient_times_the_compliance(forward):
    """A centred press at small force: d(dB/B0)/dF = (d|B|/dgap)/B0 x the compliance, for the part
    and for the layers alone; their ratio is the compliances' ratio. The bare cap (no insert)."""
    doc, g = forward
    g = replace(g, insert_plate=None)
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
    assert c_part / c_layers > 2.0  # the forward design's bare cap: 60 % of regime 1's motion


def test_the_design_loop_predicts_what_simulate_does(forward):
    """The vectorised kernel (regime_kernel with the members' compliance from layer_caps_mm_per_N)
    gives simulate's whole-part S and R for the L0 laws."""
    doc, g = forward
    part = simulate(g, doc.material)
    scene = lp.member_scene(g, doc.material)
    cells = g.layers
    theta, t, h = (np.array([getattr(c, k) for c in cells]) for k in ("theta_rad", "t_mm", "h_mm"))
    members = lp.members_total_mm_per_N(scene, theta, t, h)
    assert members == pytest.approx(part.members.total_mm_per_N, rel=1e-12)
    laws = layer_laws(cells, doc.material, "spring")
    k, dl, kl, R = (
        np.array([getattr(law, a) for law in laws])
        for a in ("k_N_per_mm", "d_lock_mm", "k_locked_N_per_mm", "lock_force_N")
    )
    field = lambda gap: field_magnitude_T(gap, g, part.field_model)  # noqa: E731
    # each plate bends into the cavity under it as the cap into the top one's, each layer's joints
    # with the plates close its own: caps per layer; the cover's drop over the slot stops on the
    # board after the air under it (at 22 N here); each plate over a locked layer adds its share in
    # the regimes it acts in (model.past_lock)
    caps, over_slot, slot_walls, locked, (over_locked, walls_locked) = lp.layer_caps_mm_per_N(scene, theta, t, h)
    delta = over_locked + walls_locked - over_slot - slot_walls  # the cover under a locked layer 1
    contact = (over_slot, g.housing.chip_clearance_mm, over_locked, delta)
    extra = by_regime(locked[0], capped_lock_forces_N(k, dl, R, caps), locked[1])
    R_sorted, S, _, _ = regime_kernel(k, dl, kl, g.gap0_mm, field, R, over_slot + slot_walls, caps, contact, extra)
    np.testing.assert_allclose(R_sorted, part.lock_forces_N, rtol=1e-12)
    np.testing.assert_allclose(S, [r.sensitivity_secant_per_N for r in part.regimes], rtol=1e-9)


@pytest.mark.slow
def test_design_names_the_member_that_keeps_the_targets_out_of_reach(tmp_path):
    """The paper's forces at a tenth of its sensitivities (0.03 / 0.01 / 0.004 1/N) on the part as
    exported: in regime 1 every member outside the layers still moves (the cap, both plates, the
    cover until it lands on the board), and alone they give the field more change per newton than
    the target; the nearest design misses and the one line names that member, the one the forward
    model of the written design gives the largest compliance. The floor it states is the members'
    alone, so it lies between the target and what the whole part (members and layers in series)
    reaches. (This test's case was the paper's own targets with the default 0.8 mm cover: since
    the cover lands on the board after its 0.3 mm of air, mst design meets them, exit 0.)"""
    import re

    import yaml
    from click.testing import CliRunner

    from mst_cli.cli.app import main

    spec = yaml.safe_load((ROOT / "configs" / "mohammadi2021.yaml").read_text())
    # the default 0.8 mm cover and plates, as exported
    assert spec.pop("housing") == {"cover_mm": 3.0, "chip_clearance_mm": 1.5, "plate_mm": 1.6}
    S_target = (0.03, 0.01, 0.004)
    for layer, S in zip(spec["layers"], S_target):
        layer["target_sensitivity_per_N"] = S
    (tmp_path / "tenth.yaml").write_text(yaml.safe_dump(spec))
    res = CliRunner().invoke(main, ["design", str(tmp_path / "tenth.yaml"), "--out", str(tmp_path / "o"), "--no-plot"])
    assert res.exit_code == 1
    line = res.output.strip().splitlines()[-1]
    parts = mst.simulate(tmp_path / "o" / "design.yaml")
    m = parts.members
    by_member = {"cap": m.cap_mm_per_N, "plates": sum(m.plates_mm_per_N), "housing's cover": m.cover_mm_per_N}
    name = max(by_member, key=lambda k: by_member[k])
    assert line.startswith(f"mst design: targets not met: the {name} dominate"), line
    floor = float(re.search(r"S >= ([0-9.]+) 1/N in regime 1 ", line).group(1))
    S1 = parts.regimes[0].sensitivity_secant_per_N
    assert S_target[0] * 1.02 < floor <= S1
