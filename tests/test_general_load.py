"""The stack under a general load (issue 39, item 2) and the lateral stiffness in report.json
(item 1): `mst simulate --shear-ratio`.

Every number here is fixed outside the code under test: mirror symmetry (a push toward -x is the
mirror image of one toward +x), the off-centre press at no shear (the issue-24 code, which the
general load must reproduce exactly), statics (a tangential force F_t at height h over a pivot
has the moment of the normal force pressed F_t h / F_z further out), L0's closed forms
(lateral.py) for springs in series, and L2's own small-load solve.
"""

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mst_cli.cli.app import main
from mst_cli.estimation.offset_reading import OffsetEstimator
from mst_cli.model.general_load import field_jacobian_T, field_T, fields_T, loaded_stack, pose_field_T
from mst_cli.model.mechanics.lateral import closed_block_lateral_N_per_mm, lateral_stiffness_N_per_mm
from mst_cli.model.offcentre import simulate_offcentre
from mst_cli.model.plate_sway import section_regimes, stack_section
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"


@pytest.fixture(scope="module")
def scene():
    doc, _ = load_design_document(FORWARD)
    printed = as_printed(doc)
    return printed.geometry(), printed.material


@pytest.fixture(scope="module")
def stack(scene):
    return loaded_stack(*scene, "spring")


def test_no_shear_is_the_off_centre_press_exactly(scene, stack):
    geometry, material = scene
    plain = simulate_offcentre(geometry, material, (4.0, -2.0))
    F = plain.force_N[[20, 120, 260]]
    want = pose_field_T(geometry, stack.tilt, F, (4.0, -2.0))
    got = np.array([field_T(stack, float(f), (0.0, 0.0), (4.0, -2.0))[0] for f in F])
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-14)  # one solve from the axis vs the curve's
    # along the whole curve (each solve warm-started from the last) the issue-24 field, bit for bit
    np.testing.assert_array_equal(plain.B_T, pose_field_T(geometry, stack.tilt, plain.force_N, (4.0, -2.0)))


def test_one_forward_model_a_load_is_a_batch_of_one(scene, stack):
    """The batched model's rows are the loads solved alone (the magnet's field, one call for the
    batch, rounds alike to 1e-15); the offset estimator's field is its normal-load case, the
    off-centre press's path at one force; the Jacobian is the differences of single loads."""
    loads = np.array([[5.0, 1.0, -0.5, 2.0, 1.0], [20.0, -3.0, 2.0, -4.0, 2.0], [8.0, 0.0, 2.0, -6.0, -3.0]])
    chips = [(0.0, 0.0), (10.0, 6.0)]
    alone = np.array([field_T(stack, t[0], t[1:3], t[3:], chips).ravel() for t in loads])
    np.testing.assert_allclose(fields_T(stack, loads, chips), alone, rtol=1e-14, atol=1e-20)
    est = OffsetEstimator(*scene, "spring", 1e-6, 50.0)
    press = pose_field_T(scene[0], stack.tilt, np.array([12.0]), (3.0, -2.0))[0]
    np.testing.assert_array_equal(est.field_T(np.array([12.0, 3.0, -2.0])), press)
    J = field_jacobian_T(stack, loads[:1], chips, (0, 3))
    h = (1e-3, 1e-3)  # the steps: 1e-4 of 5 N floored at 1 mN, and 1 um
    for c, (i, step) in enumerate(zip((0, 3), h)):
        up, down = loads[0].copy(), loads[0].copy()
        up[i] += step
        down[i] -= step
        diff = field_T(stack, up[0], up[1:3], up[3:], chips) - field_T(stack, down[0], down[1:3], down[3:], chips)
        np.testing.assert_allclose(J[0, :, c], diff.ravel() / (2 * step), rtol=1e-6, atol=1e-12)


@pytest.mark.parametrize("axis", [0, 1])
def test_opposite_pushes_mirror_the_field(scene, axis):
    geometry, material = scene
    r = np.zeros(2)
    r[axis] = 0.3
    a = simulate_offcentre(geometry, material, (0.0, 0.0), shear_ratio=tuple(r))
    b = simulate_offcentre(geometry, material, (0.0, 0.0), shear_ratio=tuple(-r))
    other = 1 - axis
    np.testing.assert_allclose(a.B_T[:, axis], -b.B_T[:, axis], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(a.B_T[:, [other, 2]], b.B_T[:, [other, 2]], rtol=1e-9, atol=1e-15)
    assert np.all(np.abs(a.B_T[1:, other]) < 1e-12)  # a push along x leaves By at 0 on the axis
    assert np.all(a.B_T[1:, axis] > 0)  # the magnet moves toward the push: the field leans with it


def test_a_tangential_force_has_the_moment_of_a_displaced_press(stack):
    """Statics: F_t at the top face, h over a layer's mid-plane, turns that layer as F_z
    pressed F_t h / F_z off the axis; layers only (the slides set to zero)."""
    g = stack.geometry
    layer, Fz, Fx = 0, 6.0, 0.9
    c = g.layers[layer]
    h = g.total_height_mm - (g.layer_bottoms_mm[layer] + 0.5 * c.h_mm)
    offsets = stack.layer_offsets_mm((0.0, 0.0), (Fx / Fz, 0.0))
    np.testing.assert_allclose(offsets[layer], [Fx * h / Fz, 0.0], rtol=1e-12)


def test_small_loads_slide_as_l0_springs_in_series(scene, stack):
    geometry, material = scene
    k = np.array([lateral_stiffness_N_per_mm(c, material) for c in geometry.layers])  # (n, 2)
    locks = np.array([t.lock_force_N for t in stack.tilt])
    F = np.array([0.3 * locks[0], 0.8 * locks[0]])
    slide = stack.slides_mm(F, (0.2, -0.1))
    n = len(geometry.layers)  # the layers', then the base's and the plates' sway (along x, per regime)
    np.testing.assert_allclose(slide[:, :n, 0], 0.2 * F[:, None] / k[None, :, 0], rtol=2e-3)
    np.testing.assert_allclose(slide[:, :n, 1], -0.1 * F[:, None] / k[None, :, 1], rtol=2e-3)
    regimes = section_regimes(stack_section(geometry, material), np.argsort(locks, kind="stable"))
    sways = (regimes.base_sway_mm_per_N, regimes.plate_sway_mm_per_N)
    for j, c in zip((n, n + 1), sways):  # before the first lock: regime 1's compliance
        np.testing.assert_allclose(slide[:, j], np.outer(0.2 * F * c[0], [1.0, 0.0]), rtol=1e-6)
    # past its lock a layer's pads stick and it shears as its filled block (90 times stiffer here)
    block = closed_block_lateral_N_per_mm(geometry.layers[0], material)
    assert 50.0 * k[0, 0] < block
    past = stack.slides_mm(np.array([1.5 * locks[0]]), (0.2, 0.0))[0, 0, 0]
    assert past == pytest.approx(0.2 * (locks[0] / k[0, 0] + 0.5 * locks[0] / block), rel=2e-3)


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def rows(path):
    return list(csv.DictReader(path.read_text().splitlines()))


def test_cli_shear_ratio_mirrors_and_zero_is_todays_curve(tmp_path):
    outs = {}
    for name, args in (("plain", []), ("zero", ["--shear-ratio", "0,0"]), ("p", ["--shear-ratio", "0.3,0"])):
        outs[name] = tmp_path / name
        assert (
            run(["simulate", FORWARD, "--out", outs[name], "--no-plot", "--load-offset-mm", "0,0", *args]).exit_code
            == 0
        )
    res = run(["simulate", FORWARD, "--out", tmp_path / "m", "--no-plot", "--shear-ratio", "-0.3,0"])
    assert res.exit_code == 0 and "tangential Fx = -0.3 F" in res.output and "axial is off by up to" in res.output
    plain, zero = rows(outs["plain"] / "offcentre.csv"), rows(outs["zero"] / "offcentre.csv")
    assert plain == zero and {r["Fx_N"] for r in zero} == {"0"}
    p, m = rows(outs["p"] / "offcentre.csv"), rows(tmp_path / "m" / "offcentre.csv")
    for a, b in zip(p, m):
        assert float(a["Bx_mT"]) == pytest.approx(-float(b["Bx_mT"]), rel=1e-9, abs=1e-15)
        # the mirror's Bz agrees to 1e-13 (the pose's solves), so a printed last digit may round apart
        assert float(a["Bz_mT"]) == pytest.approx(float(b["Bz_mT"]), rel=1e-8)
        assert float(a["Fx_N"]) == pytest.approx(0.3 * float(a["force_N"]))
    rep = json.loads((outs["p"] / "report.json").read_text())
    assert rep["off_centre"]["shear_ratio"] == [0.3, 0.0]


@pytest.mark.parametrize("value, says", [("1.5,0", "|r| <= 1"), ("0,-2", "|r| <= 1"), ("a,b", "two numbers")])
def test_cli_refuses_a_shear_ratio_out_of_the_cone_in_one_line(tmp_path, value, says):
    res = run(["simulate", FORWARD, "--out", tmp_path / "o", "--no-plot", "--shear-ratio", value])
    assert res.exit_code == 2
    assert len(res.output.strip().splitlines()) == 1 and "--shear-ratio" in res.output and says in res.output


def test_report_carries_every_layers_lateral_stiffness(tmp_path, scene):
    geometry, material = scene
    assert run(["simulate", FORWARD, "--out", tmp_path / "o", "--no-plot"]).exit_code == 0
    layers = json.loads((tmp_path / "o" / "report.json").read_text())["layers"]
    for row, cell in zip(layers, geometry.layers):  # the spring rung: L0's closed forms, as printed
        k_x, k_y = lateral_stiffness_N_per_mm(cell, material)
        assert row["lateral_stiffness_x_N_per_mm"] == pytest.approx(k_x, rel=1e-12)
        assert row["lateral_stiffness_y_N_per_mm"] == pytest.approx(k_y, rel=1e-12)


@pytest.mark.slow
def test_l2_compliance_at_no_load_is_l2s_small_load_stiffness(scene):
    from mst_cli.model.mechanics.continuum_lateral import lateral_stiffness_x_N_per_mm

    geometry, material = scene
    s = loaded_stack(geometry, material, "continuum")
    c_x, _ = s.lateral[0].compliance_mm_per_N(np.array([0.0]))
    # the integral's first sample is taken at its midpoint compression, 1/8000 of the lock's way in
    assert 1.0 / c_x[0] == pytest.approx(lateral_stiffness_x_N_per_mm(geometry.layers[0], material), rel=2e-4)
