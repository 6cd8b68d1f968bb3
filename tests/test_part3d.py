"""The 3D linear check of the part as exported (docs/design.md section 4.8): its solver against
closed forms, its rigid fit and field change against geometry and the axial field, its
tetrahedra against the export's own volumes, and one coarse whole-part run."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from mst_cli.model.magnet_field import axial_dBz_dz_T_per_mm
from mst_cli.model.mechanics import part3d

pytest.importorskip("skfem")


def _box(lx: float, ly: float, lz: float, n: tuple[int, int, int]):
    from skfem import MeshTet

    m = MeshTet.init_tensor(np.linspace(0, lx, n[0] + 1), np.linspace(0, ly, n[1] + 1), np.linspace(0, lz, n[2] + 1))
    return m.p.T.copy(), m.t.T.copy()


@pytest.mark.parametrize("order", [1, 2])
def test_confined_block_is_the_oedometer_closed_form(order):
    """A TPU block held at its bottom, its sides on rollers (no lateral motion), a uniform
    pressure over its whole top face: u_z = -p H / M with M = E (1 - nu) / ((1 + nu)(1 - 2 nu)),
    exact for any tetrahedra (the field is linear)."""
    L, W, H, E, nu = 4.0, 3.0, 5.0, 12.0, 0.45
    p, t = _box(L, W, H, (3, 2, 4))
    basis = part3d.vector_basis(p, t, order)
    K = part3d.stiffness(basis, np.full(len(t), E), np.full(len(t), nu))
    f = part3d.strip_load(basis, H, 0.5 * L, 2 * L)  # the strip covers the face: 1 N over L W
    held = [basis.get_dofs(part3d.plane_facets(basis, 2, 0.0)).all()]
    for axis, name in ((0, "u^1"), (1, "u^2")):
        for value in (0.0, (L, W)[axis]):
            held.append(basis.get_dofs(part3d.plane_facets(basis, axis, value)).all(name))
    u = part3d.solve_held(basis, K, f, np.unique(np.concatenate(held)))
    top = np.flatnonzero(np.abs(basis.mesh.p[2] - H) < 1e-9)
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    uz = u[basis.nodal_dofs[2, top]]
    np.testing.assert_allclose(uz, -(1.0 / (L * W)) * H / M, rtol=1e-9)


def _cantilever_tip_mm(L, b, h, a, E, nu) -> float:
    """Timoshenko cantilever (clamped at x = 0) under 1 N spread uniformly over [L - a, L]: the
    deflection at x = L from bending (integral of M (L - x) / EI) plus shear (V / (k G A))."""
    I, A, G, k = b * h**3 / 12, b * h, E / (2 * (1 + nu)), 10 * (1 + nu) / (12 + 11 * nu)
    x = np.linspace(0.0, L, 200001)
    M = np.where(x <= L - a, L - 0.5 * a - x, (L - x) ** 2 / (2 * a))
    V = np.where(x <= L - a, 1.0, (L - x) / a)
    return float(np.trapezoid(M * (L - x), x) / (E * I) + np.trapezoid(V, x) / (k * G * A))


def test_p2_cantilever_is_the_timoshenko_beam():
    """A 20 x 2 x 2 mm TPU beam clamped at one end, pressed over its last 2 mm: P2 tetrahedra
    give the Timoshenko deflection (bending + shear) within 2 % (the clamp's restrained Poisson
    contraction is what a beam does not see), and P1 on the same mesh is stiffer (it locks)."""
    L, b, h, a, E, nu = 20.0, 2.0, 2.0, 2.0, 12.0, 0.3
    p, t = _box(L, b, h, (40, 4, 4))
    closed = _cantilever_tip_mm(L, b, h, a, E, nu)
    tips = {}
    for order in (1, 2):
        basis = part3d.vector_basis(p, t, order)
        K = part3d.stiffness(basis, np.full(len(t), E), np.full(len(t), nu))
        f = part3d.strip_load(basis, h, L - 0.5 * a, a)
        u = part3d.solve_held(basis, K, f, basis.get_dofs(part3d.plane_facets(basis, 0, 0.0)).all())
        end = np.flatnonzero(np.abs(basis.mesh.p[0] - L) < 1e-9)
        tips[order] = -float(u[basis.nodal_dofs[2, end]].mean())
    assert tips[2] == pytest.approx(closed, rel=0.02)
    assert tips[1] < 0.9 * tips[2]


def test_rigid_fit_recovers_a_rigid_motion():
    rng = np.random.default_rng(0)
    pts = rng.normal(size=(30, 3))
    U, omega = np.array([0.1, -0.2, 0.3]), np.array([0.01, -0.02, 0.005])
    c = pts.mean(axis=0)
    fit = part3d.rigid_fit(pts, U + np.cross(omega, pts - c))
    np.testing.assert_allclose(fit.translation_mm_per_N, U, atol=1e-12)
    np.testing.assert_allclose(fit.rotation_rad_per_N, omega, atol=1e-12)


def test_a_pure_drop_changes_the_field_by_the_axial_gradient():
    """The exact cylinder at a moved pose against the axial closed form's dB_z/dz."""
    r, th, Br, gap, drop = 3.0, 2.0, 1.3, 6.0, 0.05
    centre = np.array([0.0, 0.0, gap + 0.5 * th])
    motion = part3d.RigidMotion(np.array([0.0, 0.0, -drop]), np.zeros(3), centre)
    dB = part3d.field_change_uT_per_N(motion, centre, np.zeros(3), 2 * r, th, Br)
    expected = 1e6 * drop * abs(float(axial_dBz_dz_T_per_mm(gap, r, th, Br)))
    assert dB[2] == pytest.approx(expected, rel=1e-5)
    assert abs(dB[0]) < 1e-9 * expected and abs(dB[1]) < 1e-9 * expected


@pytest.fixture(scope="module")
def forward_export(tmp_path_factory):
    import mst_cli as mst

    out = tmp_path_factory.mktemp("fe3d") / "forward"
    mst.export(Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml", out)
    return out


@pytest.mark.slow
def test_the_exported_part_meshes_to_its_declared_volumes(forward_export):
    """The tetrahedra fill the body to export.json's volume (within its own tolerance) and the
    plate to its declared volume within 3 % (a tetrahedron is the plate's when its centroid lies
    in the plate's box; the slot's 0.2 mm clearance is left empty)."""
    pytest.importorskip("tetgenpy")
    from mst_cli.cad.part3d_check import Check3DOptions, mesh_scene, read_scene

    scene = read_scene(forward_export)
    mesh, E, _ = mesh_scene(scene, Check3DOptions(max_volume_mm3=100.0, radius_edge_ratio=3.0))
    body = json.loads((forward_export / "export.json").read_text())["body"]
    vol = mesh.volumes_mm3()
    assert (vol > 0).all()
    tpu = E == scene.tpu.youngs_modulus_MPa
    assert vol[tpu].sum() == pytest.approx(body["volume_mm3"], abs=body["volume_tolerance_mm3"])
    assert vol[~tpu].sum() == pytest.approx(scene.insert_volume_mm3, rel=0.03)


@pytest.mark.slow
def test_a_coarse_whole_part_press(forward_export):
    """P1 on coarse tetrahedra: the magnet drops under a centred press, its side motion and turn
    stay small beside the drop (the part is symmetric in x; in y the board slot breaks it), and
    the field at the chip grows by the drop times the axial gradient to within the turn's share."""
    pytest.importorskip("tetgenpy")
    from mst_cli.cad.part3d_check import Check3DOptions, press_exported, read_scene

    r = press_exported(forward_export, Check3DOptions(max_volume_mm3=100.0, radius_edge_ratio=3.0, order=1))
    scene = read_scene(forward_export)
    assert r.drop_mm_per_N > 0
    assert abs(r.translation_mm_per_N[0]) < 0.05 * r.drop_mm_per_N  # mirror symmetry in x
    gap = scene.magnet_box_mm[0][2] - scene.chip_mm[2]
    axial = (
        1e6
        * r.drop_mm_per_N
        * abs(float(axial_dBz_dz_T_per_mm(gap, 0.5 * scene.diameter_mm, scene.thickness_mm, scene.remanence_T)))
    )
    assert r.field_uT_per_N[2] == pytest.approx(axial, rel=0.1)
    assert math.isfinite(r.dofs) and r.dofs > 1000
