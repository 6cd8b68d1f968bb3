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

from mst_cli.calibrate.fit import as_printed
from mst_cli.cli.app import main
from mst_cli.io.schema import load_design_document
from mst_cli.model import field as fld
from mst_cli.model.geometry import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import layer_law
from mst_cli.model.mechanics.tilt import PiecewiseForce, chevron_lever_mm, depth_moments, solve_layer_tilt
from mst_cli.model.offcentre import simulate_offcentre

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
CELL = HexCell(14.81, 0.401, 1.867)


@pytest.fixture(scope="module")
def scene():
    doc, _ = load_design_document(FORWARD)
    printed = as_printed(doc)
    return printed.geometry(), printed.material


@pytest.fixture(scope="module")
def law():
    return PiecewiseForce.from_law(layer_law(CELL, Material()))


def lever(cell=CELL):
    return chevron_lever_mm(math.radians(cell.theta_deg), cell.t_mm, cell.p_mm)


def test_zero_offset_is_the_centred_model(scene):
    geometry, material = scene
    r = simulate_offcentre(geometry, material, (0.0, 0.0))
    assert np.all(r.layer_tilt_rad == 0.0)
    np.testing.assert_allclose(r.B_T, r.axial.B_T, rtol=1e-9, atol=1e-15)
    # the reading recovers the force itself (interpolation on the centred curve's own samples)
    assert np.nanmax(np.abs(r.read_error_N)) <= 1e-9 * r.force_N.max()
    np.testing.assert_allclose(r.side_lock_N, np.repeat(np.array(r.axial.lock_forces_N)[:, None], 2, axis=1), rtol=1e-9)


@pytest.mark.parametrize("x0", [-6.0, 2.0, 7.5])
def test_small_load_tilts_like_two_springs(law, x0):
    # below the knee the layer is linear: two chevrons k/2 at +-x_c, so phi_y = F x0 / (k x_c^2)
    F = 0.02
    r = solve_layer_tilt(law, F, (x0, 0.0), lever(), CELL.depth_mm)
    k = law.F_knots_N[1] / law.d_knots_mm[1]
    assert r.d_mm == pytest.approx(F / k, rel=1e-10)
    assert r.phi_y_rad == pytest.approx(F * x0 / (k * lever() ** 2), rel=1e-10)
    assert r.phi_x_rad == 0.0


@pytest.mark.parametrize("y0", [-4.0, 1.0, 8.0])
def test_small_load_tilts_like_a_uniform_strip(law, y0):
    # a strip of uniform stiffness k over the depth D turns as a section of inertia D^3/12
    F = 0.01
    D = CELL.depth_mm
    r = solve_layer_tilt(law, F, (0.0, y0), lever(), D)
    k = law.F_knots_N[1] / law.d_knots_mm[1]
    assert r.phi_x_rad == pytest.approx(F * y0 / (k * D**2 / 12), rel=1e-10)
    assert r.phi_y_rad == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("a, s", [(0.2, 0.0), (0.5, 0.03), (0.9, -0.05), (0.1, 0.08)])
def test_depth_integrals_match_a_midpoint_rule(law, a, s):
    half = 10.0
    (I0, I1), _ = depth_moments(law, a, s, half)
    y = np.linspace(-half, half, 400001)
    mid = 0.5 * (y[1:] + y[:-1])
    F = law.force_N(a + s * mid) * np.diff(y)
    assert I0 == pytest.approx(F.sum(), rel=1e-7)
    assert I1 == pytest.approx((mid * F).sum(), rel=1e-6, abs=1e-9)


def test_equilibrium_holds_past_the_lock_of_one_side(law):
    # a load that locks the +x side: force and both moments balance (checked by a midpoint rule)
    F, x0, y0 = 1.3, 6.0, 3.0
    D = CELL.depth_mm
    r = solve_layer_tilt(law, F, (x0, y0), lever(), D)
    assert r.side_max_mm[1] > law.d_knots_mm[-1]  # locked somewhere on the +x side
    y = np.linspace(-D / 2, D / 2, 200001)
    mid = 0.5 * (y[1:] + y[:-1])
    total = np.zeros(3)
    for sign in (-1, 1):
        q = law.force_N(r.d_mm + r.phi_y_rad * sign * lever() + r.phi_x_rad * mid) * np.diff(y) / (2 * D)
        total += [q.sum(), sign * lever() * q.sum(), (mid * q).sum()]
    np.testing.assert_allclose(total, [F, F * x0, F * y0], rtol=1e-5)


def test_mirrored_offsets_mirror_the_field(scene):
    geometry, material = scene
    a = simulate_offcentre(geometry, material, (5.0, 2.0))
    b = simulate_offcentre(geometry, material, (-5.0, 2.0))
    np.testing.assert_allclose(a.B_T[:, 0], -b.B_T[:, 0], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(a.B_T[:, 1:], b.B_T[:, 1:], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(a.side_lock_N, b.side_lock_N[:, ::-1], rtol=1e-9)
    # the loaded side locks first, the other after the centred lock
    R = np.array(a.axial.lock_forces_N)
    assert np.all(a.side_lock_N[:, 1] < R) and np.all(a.side_lock_N[:, 0] > R)


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
    assert "its +x side at" in res.output
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
