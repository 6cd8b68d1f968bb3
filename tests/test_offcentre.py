"""Off-centre loads (issue 24, first part): the rigid-plate tilt rung, the magnet's pose and the
field on three axes, and `mst simulate --load-offset-mm / --offset-map`.

Every number here is fixed by something outside the code under test: the centred model (zero
offset), beam-free statics of two springs and a uniform strip (small loads), a midpoint rule
over the depth, mirror symmetry, and magpylib's object interface.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mst_cli.cli.app import main
from mst_cli.model import magnet_field as fld
from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import layer_law
from mst_cli.model.mechanics.contact_patch import pressed_patch
from mst_cli.model.mechanics.depth import in_web
from mst_cli.model.mechanics.tilt import LayerTiltLaw, chevron_lever_mm, depth_moments, solve_layer_tilt
from mst_cli.model.offcentre import simulate_offcentre
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
CELL = HexCell(14.81, 0.401, 1.867)


@pytest.fixture(scope="module")
def scene():
    doc, _ = load_design_document(FORWARD)
    printed = as_printed(doc)
    return printed.geometry(), printed.material


@pytest.fixture(scope="module")
def layer():
    mat = Material()
    return LayerTiltLaw.from_layer(layer_law(CELL, mat), CELL, in_web(CELL, mat).youngs_modulus_MPa, mat.poisson_ratio)


def lever(cell=CELL):
    return chevron_lever_mm(math.radians(cell.theta_deg), cell.t_mm, cell.h_mm, cell.width_mm)


def test_zero_offset_is_the_centred_model(scene):
    geometry, material = scene
    r = simulate_offcentre(geometry, material, (0.0, 0.0))
    assert np.all(r.layer_tilt_rad == 0.0)
    np.testing.assert_allclose(r.B_T, r.axial.B_T, rtol=1e-9, atol=1e-15)
    # the reading recovers the force itself (interpolation on the centred curve's own samples)
    assert np.nanmax(np.abs(r.read_error_N)) <= 1e-9 * r.force_N.max()
    # each layer's sides lock together, where the centred model's regimes end (in the order the
    # layers lock: with the cap the top one closes before the one below it)
    np.testing.assert_allclose(r.side_lock_N[:, 0], r.side_lock_N[:, 1], rtol=1e-9)
    np.testing.assert_allclose(np.sort(r.side_lock_N[:, 0]), r.axial.lock_forces_N, rtol=1e-9)


@pytest.mark.parametrize(
    "cell", [CELL, HexCell(25, 0.6, 2.0), HexCell(37, 1.4, 3.5), HexCell(60, 0.6, 4.0), HexCell(8, 0.5, 1.5)]
)
def test_the_rungs_lever_is_where_L2_puts_the_chevrons_force(cell):
    # two small-strain L2 solves (the plates lifted, then turned) put the force of a turned
    # chevron at x_eff; the rung's fitted lever must sit there (cells with pads longer than 4 t,
    # where the fit's out-of-sample error is 0.07 % median, 2.1 % max)
    from mst_cli.model.mechanics.continuum_tilt import linear_tilt_lever_mm

    assert lever(cell) == pytest.approx(linear_tilt_lever_mm(cell, Material()), rel=1e-2)
    # ... and not at the wall roots, which is where a chevron hands its force to the pad
    assert lever(cell) > cell.p_mm


@pytest.mark.parametrize("x0", [-6.0, 2.0, 7.5])
def test_small_load_tilts_like_two_springs(layer, x0):
    # below the knee the layer is linear: two chevrons k/2 at +-x_c, so phi_y = F x0 / (k x_c^2)
    F = 0.02
    r = solve_layer_tilt(layer, F, (x0, 0.0))
    k = layer.walls.F_knots_N[1] / layer.walls.d_knots_mm[1]
    assert r.d_mm == pytest.approx(F / k, rel=1e-10)
    assert r.phi_y_rad == pytest.approx(F * x0 / (k * lever() ** 2), rel=1e-10)
    assert r.phi_x_rad == 0.0


@pytest.mark.parametrize("y0", [-4.0, 1.0, 8.0])
def test_small_load_tilts_like_a_uniform_strip(layer, y0):
    # a strip of uniform stiffness k over the depth D turns as a section of inertia D^3/12
    F = 0.01
    D = CELL.depth_mm
    r = solve_layer_tilt(layer, F, (0.0, y0))
    k = layer.walls.F_knots_N[1] / layer.walls.d_knots_mm[1]
    assert r.phi_x_rad == pytest.approx(F * y0 / (k * D**2 / 12), rel=1e-10)
    assert r.phi_y_rad == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("a, s", [(0.2, 0.0), (0.5, 0.03), (0.9, -0.05), (0.1, 0.08)])
def test_depth_integrals_match_a_midpoint_rule(layer, a, s):
    law = layer.walls
    half = 10.0
    (I0, I1), _ = depth_moments(law, a, s, half)
    y = np.linspace(-half, half, 400001)
    mid = 0.5 * (y[1:] + y[:-1])
    F = law.force_N(a + s * mid) * np.diff(y)
    assert I0 == pytest.approx(F.sum(), rel=1e-7)
    assert I1 == pytest.approx((mid * F).sum(), rel=1e-6, abs=1e-9)


@pytest.mark.parametrize(
    "c, alpha, beta", [(0.3, 0.0, 0.0), (-0.1, 0.02, 0.0), (0.05, -0.03, 0.01), (-0.2, 0.01, -0.04)]
)
def test_pressed_patch_matches_a_midpoint_rule(c, alpha, beta):
    a, b = 11.0, 10.0
    f, J = pressed_patch(a, b, c, alpha, beta)
    n = 1500
    x = (np.arange(n) + 0.5) / n * 2 * a - a
    y = (np.arange(n) + 0.5) / n * 2 * b - b
    X, Y = np.meshgrid(x, y)
    p = np.maximum(c + alpha * X + beta * Y, 0.0) * (2 * a / n) * (2 * b / n)
    np.testing.assert_allclose(f, [p.sum(), (X * p).sum(), (Y * p).sum()], rtol=2e-5, atol=1e-9)
    # the derivative in c is the pressed area (midpoint rule again)
    assert J[0, 0] == pytest.approx(((c + alpha * X + beta * Y) > 0).sum() * (2 * a / n) * (2 * b / n), rel=2e-3)


def test_equilibrium_holds_once_the_loaded_pads_touch(layer):
    # a load that closes the pads at their +x end: force and both moments balance, checked by
    # midpoint rules over the walls' lines and the pads' rectangle
    F, x0, y0 = 1.3, 6.0, 3.0
    D, a = CELL.depth_mm, layer.pad_half_width_mm
    r = solve_layer_tilt(layer, F, (x0, y0))
    assert r.pads_touch == (False, True)
    y = np.linspace(-D / 2, D / 2, 200001)
    mid = 0.5 * (y[1:] + y[:-1])
    total = np.zeros(3)
    for sign in (-1, 1):
        x = sign * layer.lever_mm
        q = layer.walls.force_N(r.d_mm + r.phi_y_rad * x + r.phi_x_rad * mid) * np.diff(y) / (2 * D)
        total += [q.sum(), x * q.sum(), (mid * q).sum()]
    n = 2000
    xs = (np.arange(n) + 0.5) / n * 2 * a - a
    ys = (np.arange(n) + 0.5) / n * D - D / 2
    X, Y = np.meshgrid(xs, ys)
    closure = r.d_mm + r.phi_y_rad * X + r.phi_x_rad * Y - layer.pad_gap_mm
    p = layer.pad_stiffness_N_per_mm / (2 * a * D) * np.maximum(closure, 0.0) * (2 * a / n) * (D / n)
    total += [p.sum(), (X * p).sum(), (Y * p).sum()]
    np.testing.assert_allclose(total, [F, F * x0, F * y0], rtol=1e-4)


def test_mirrored_offsets_mirror_the_field(scene):
    geometry, material = scene
    a = simulate_offcentre(geometry, material, (5.0, 2.0))
    b = simulate_offcentre(geometry, material, (-5.0, 2.0))
    np.testing.assert_allclose(a.B_T[:, 0], -b.B_T[:, 0], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(a.B_T[:, 1:], b.B_T[:, 1:], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(a.side_lock_N, b.side_lock_N[:, ::-1], rtol=1e-9)
    # the loaded side locks first, the other after the centred lock (or never)
    R = np.array(a.axial.lock_forces_N)
    assert np.all(a.side_lock_N[:, 1] < R)
    assert np.all(~(a.side_lock_N[:, 0] <= R))


def test_pose_field_matches_magpylibs_object_interface():
    magpy = pytest.importorskip("magpylib")
    from scipy.spatial.transform import Rotation

    rotvec = np.array([[0.0, 0.0, 0.0], [0.03, -0.02, 0.0], [-0.05, 0.04, 0.01]])
    r = np.array([[0.0, 0.0, -9.0], [0.4, -0.3, -8.0], [1.0, 2.0, -12.0]])
    B = fld.cylinder_pose_B_T(r, 6.0, 2.0, 1.3, rotvec)
    for i in range(3):
        # the chip at the origin and the magnet moved to -r, turned: the same relative scene
        mag = magpy.magnet.Cylinder(
            polarization=(0, 0, 1.3),
            dimension=(6e-3, 2e-3),
            position=-r[i] * 1e-3,
            orientation=Rotation.from_rotvec(rotvec[i]),
        )
        np.testing.assert_allclose(B[i], mag.getB((0.0, 0.0, 0.0)), rtol=1e-12, atol=1e-15)


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_cli_writes_offcentre_files_and_report(tmp_path):
    out = tmp_path / "out"
    res = run(["simulate", FORWARD, "--out", out, "--load-offset-mm", "5,0", "--offset-map", "--no-plot"])
    assert res.exit_code == 0, res.output
    assert {p.name for p in out.iterdir()} == {"report.json", "response.csv", "offcentre.csv", "offset_map.csv"}
    rep = json.loads((out / "report.json").read_text())
    oc = rep["off_centre"]
    assert oc["load_offset_mm"] == [5.0, 0.0] and len(oc["layers"]) == 3
    assert all(lay["lock_force_plus_x_side_N"] < lay["lock_force_axial_N"] for lay in oc["layers"])
    rows = (out / "offset_map.csv").read_text().splitlines()
    assert len(rows) == 1 + 9 * 7 * 9  # header + (9 x 7 grid) x (3 forces x 3 regimes)
    assert "its +x side" in res.output
    # 5 mm is outside the middle third of the pads (a = 11.4 mm): the far side never closes
    assert all(lay["lock_force_minus_x_side_N"] is None for lay in oc["layers"])
    # a plain run afterwards removes the off-centre files it did not write
    assert run(["simulate", FORWARD, "--out", out, "--no-plot"]).exit_code == 0
    assert {p.name for p in out.iterdir()} == {"report.json", "response.csv"}


@pytest.mark.parametrize(
    "value, says", [("abc", "two numbers"), ("1,2,3", "two numbers"), ("nan,0", "finite"), ("40,0", "top face")]
)
def test_cli_refuses_a_bad_offset_in_one_line(tmp_path, value, says):
    out = tmp_path / "out"
    res = run(["simulate", FORWARD, "--out", out, "--load-offset-mm", value, "--no-plot"])
    assert res.exit_code == 2
    assert len(res.output.strip().splitlines()) == 1 and "--load-offset-mm" in res.output and says in res.output
    assert not out.exists() or not any(out.iterdir())


def test_tilted_L2_at_zero_tilt_is_the_centred_L2():
    from mst_cli.model.mechanics.continuum import solve_continuum
    from mst_cli.model.mechanics.continuum_tilt import solve_tilted_chevron

    mat = Material()
    base = solve_continuum(CELL, mat)
    tilted = solve_tilted_chevron(CELL, mat, 0.0)
    np.testing.assert_array_equal(tilted.displacement_mm, base.displacement_mm)
    # the centred law's force carries its mesh scale; dividing it out again rounds once each
    # way (x * s / s is within 2 ulp of x, not always x: numpy 2.4's own division shows it)
    np.testing.assert_allclose(tilted.force_N, base.force_N / base.mesh_scale, rtol=4.5e-16, atol=0)


def test_tilted_L2_follows_the_rung_on_a_thin_shallow_cell():
    # the loaded chevron (tilt +0.03 rad per mm of closure): before the pads touch it is the
    # untilted layer at the closure of its lever line, and its pads touch at their end x = a
    # (studies/check_tilt_rung.py measures this over the box)
    from mst_cli.model.mechanics.continuum import solve_continuum
    from mst_cli.model.mechanics.continuum_tilt import solve_tilted_chevron

    mat, tau = Material(), 0.03
    base = solve_continuum(CELL, mat)
    d0, F0 = base.displacement_mm, base.force_N / base.mesh_scale
    res = solve_tilted_chevron(CELL, mat, tau)
    a = CELL.p_mm - CELL.t_mm * math.tan(0.5 * math.radians(CELL.theta_deg))
    d_on = base.d_contact_mm / (1 + tau * a)
    assert res.d_contact_mm == pytest.approx(d_on, rel=5e-3)
    d_half = 0.5 * d_on
    F_half = np.interp(d_half, res.displacement_mm, res.force_N)
    assert F_half == pytest.approx(np.interp(d_half * (1 + tau * lever()), d0, F0), rel=0.02)


def test_read_estimates_the_offset_and_corrects_the_force(tmp_path):
    # noise-free readings of the design's own tilt rung, pressed at (6, 3) mm: the estimate,
    # polished by the exact solve from a coarse table's root, must give back the press and the
    # force; the centred reading is far off
    import shutil

    from mst_cli.estimation.inverse_map import inverse_map
    from mst_cli.estimation.inverse_table import TABLE_FILE
    from mst_cli.estimation.table_store import build_beside
    from mst_cli.model.general_load import pose_field_T
    from mst_cli.model.stack_pose import tilt_laws

    doc, _ = load_design_document(FORWARD)
    model = tmp_path / "model.yaml"
    shutil.copy(FORWARD, model)
    top = float(inverse_map(doc, "spring")[0].force_N[-1])
    build_beside(model, doc, "spring", 1.0, top, (17, 3.0)).save(tmp_path / TABLE_FILE)
    geo, mat = doc.geometry(), doc.material
    F = np.array([4.0, 8.0, 15.0, 25.0, 40.0])
    B = pose_field_T(geo, tilt_laws(geo, mat, "spring"), F, (6.0, 3.0))
    csv = tmp_path / "readings.csv"
    csv.write_text(
        "Bx_uT,By_uT,Bz_uT,force_N\n"
        + "".join(f"{b[0] * 1e6:.6f},{b[1] * 1e6:.6f},{b[2] * 1e6:.6f},{f}\n" for b, f in zip(B, F))
    )
    out = tmp_path / "out"
    res = run(["read", model, csv, "--out", out, "--estimate-offset", "--polish"])
    assert res.exit_code == 0, res.output
    assert "offset: estimated on" in res.output
    import csv as csvmod

    rows = list(csvmod.DictReader((out / "forces.csv").open()))
    ok = [r for r in rows if r["offset_flag"] == "ok"]
    assert len(ok) >= 4
    for r in ok:
        f_true = float(r["force_N_reference"])
        assert float(r["force_N"]) == pytest.approx(f_true, rel=2e-3)
        assert float(r["x_mm"]) == pytest.approx(6.0, abs=0.02) and float(r["y_mm"]) == pytest.approx(3.0, abs=0.02)
    centred = [abs(float(r["force_centred_N"]) / float(r["force_N_reference"]) - 1) for r in rows]
    assert max(centred) > 0.1  # what the correction is for


@pytest.mark.parametrize(
    "args, says",
    [(["--serial", "/dev/null", "--polish"], "--polish"), (["--max-offset-sigma-mm", "-1"], "max-offset-sigma")],
)
def test_read_refuses_bad_offset_options(tmp_path, args, says):
    csv = tmp_path / "r.csv"
    csv.write_text("Bx_uT,By_uT,Bz_uT\n0,0,3400\n")
    cmd = (
        ["read", FORWARD]
        + ([] if "--serial" in args else [csv])
        + ["--out", tmp_path / "o", "--estimate-offset"]
        + args
    )
    res = run(cmd)
    assert res.exit_code == 2 and says in res.output
    assert len(res.output.strip().splitlines()) == 1


def test_design_reports_the_off_centre_error_over_its_region(tmp_path):
    import yaml

    spec = yaml.safe_load((ROOT / "configs" / "mohammadi2021.yaml").read_text())
    spec.setdefault("design", {})["offcentre_region_mm"] = [5, 3]
    (tmp_path / "spec.yaml").write_text(yaml.safe_dump(spec))
    res = run(["design", tmp_path / "spec.yaml", "--out", tmp_path / "out", "--no-plot"])
    assert res.exit_code == 0, res.output
    oc = json.loads((tmp_path / "out" / "report.json").read_text())["design"]["off_centre"]
    assert oc["region_mm"] == [5.0, 3.0] and len(oc["regimes"]) == 3
    # the map is mirror-symmetric (chip on the axis): a worst corner has a mirrored twin
    for r in oc["regimes"]:
        assert abs(r["at_mm"][0]) == 5.0 and abs(r["at_mm"][1]) in (0.0, 3.0)
    assert "off centre: a touch within +-5 x +-3 mm" in res.output
    # a region of one point, the axis, is the centred reading: no error but the read-back's
    # linear interpolation on the centred curve's samples (400 a regime: under 1e-5)
    spec["design"]["offcentre_region_mm"] = [0, 0]
    (tmp_path / "spec0.yaml").write_text(yaml.safe_dump(spec))
    res = run(["design", tmp_path / "spec0.yaml", "--out", tmp_path / "out0", "--no-plot"])
    assert res.exit_code == 0, res.output
    oc0 = json.loads((tmp_path / "out0" / "report.json").read_text())["design"]["off_centre"]
    assert oc0["worst_read_error_rel"] <= 1e-5


def test_a_negative_region_is_refused_in_one_line(tmp_path):
    import yaml

    spec = yaml.safe_load((ROOT / "configs" / "mohammadi2021.yaml").read_text())
    spec.setdefault("design", {})["offcentre_region_mm"] = [-1, 3]
    (tmp_path / "spec.yaml").write_text(yaml.safe_dump(spec))
    res = run(["design", tmp_path / "spec.yaml", "--out", tmp_path / "out", "--no-plot"])
    assert res.exit_code == 2 and "design.offcentre_region_mm" in res.output
    assert len(res.output.strip().splitlines()) == 1
