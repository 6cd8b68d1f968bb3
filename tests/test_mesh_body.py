"""The STL/3MF body meshed without the CAD kernel (cad.mesh_body) against the B-rep body
(cad.assembly) both build from the same shapes (cad.shapes), and against hand geometry.

The B-rep volume is exact; the mesh differs from it only where the pocket's half disc is a
polygon of n segments with its vertices on the circle, which adds depth x (half-disc area -
half-polygon area) of material: that is added back analytically, then the two agree to 1e-6.
"""

import io
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sampling
import trimesh

from mst_cli.cad import checks, mesh_body, mesh_io, shapes
from mst_cli.cad.assembly import build_body, print_mesh
from mst_cli.cad.expected_body import body_bbox_mm, body_volume_mm3
from mst_cli.cad.manifest import export_manifest
from mst_cli.model.printer import Printer
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
TOL_MM = 0.01


def reference():
    return load_design_document(FORWARD)[1]


GEOMETRIES = [reference()] + sampling.random_valid_geometries(6, seed=11, max_offset_mm=2.0)
IDS = ["reference"] + [f"random{k}-{len(g.layers)}layers" for k, g in enumerate(GEOMETRIES[1:])]


def shoelace(points):
    x, y = np.array(points).T
    return 0.5 * abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def polygon_surplus_mm3(g, tolerance_mm):
    """Material the mesh has that the B-rep has not: the pocket's half disc as a half polygon."""
    n, r = mesh_body.circle_segments(g.pocket_radius_mm, tolerance_mm), g.pocket_radius_mm
    return g.pocket_depth_mm * (0.5 * math.pi * r * r - 0.25 * n * r * r * math.sin(2 * math.pi / n))


def signed_volume(vertices, triangles):
    tri = np.asarray(vertices)[np.asarray(triangles)]
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)


@pytest.mark.parametrize("g", GEOMETRIES, ids=IDS)
def test_mesh_and_brep_bodies_agree(g):
    vertices, triangles = mesh_body.body_mesh(g, TOL_MM)
    assert mesh_io.is_closed_oriented(vertices, triangles)
    body = build_body(g)
    volume = signed_volume(vertices, triangles)
    assert volume - polygon_surplus_mm3(g, TOL_MM) == pytest.approx(body.volume, rel=1e-6)
    assert volume - polygon_surplus_mm3(g, TOL_MM) == pytest.approx(body_volume_mm3(g), rel=1e-6)
    bb = body.bounding_box()
    assert vertices.min(axis=0) == pytest.approx([bb.min.X, bb.min.Y, bb.min.Z], abs=1e-9)
    assert vertices.max(axis=0) == pytest.approx([bb.max.X, bb.max.Y, bb.max.Z], abs=1e-9)
    assert vertices.min(axis=0) == pytest.approx(body_bbox_mm(g)[0], abs=1e-9)
    assert vertices.max(axis=0) == pytest.approx(body_bbox_mm(g)[1], abs=1e-9)


def check_results(vertices, triangles, manifest):
    mesh = trimesh.load(io.BytesIO(mesh_io.stl_bytes(vertices, triangles)), file_type="stl")
    return {c.name: c for c in checks.run_checks(mesh, manifest)}


@pytest.mark.parametrize("g", GEOMETRIES[:4], ids=IDS[:4])
def test_mst_check_gives_both_paths_the_same_results(g):
    manifest = export_manifest("cmp", g, Printer(), TOL_MM, ["sensor.stl"])
    new = check_results(*mesh_body.print_mesh(g, TOL_MM), manifest)
    old = check_results(*print_mesh(g, build_body(g), TOL_MM), manifest)
    assert {k: c.passed for k, c in new.items()} == {k: c.passed for k, c in old.items()}
    assert all(c.passed for c in new.values() if not c.info), {k: c.note for k, c in new.items() if not c.passed}
    for name in ("bbox", "wall_thickness", "web_depth", "cavity_gap", "board_slot", "magnet_chip_gap"):
        for key, value in old[name].values.items():
            if key != "error_mm":
                assert new[name].values[key] == pytest.approx(value, abs=1e-4), (name, key)
    # the pocket: same floor and depth; the section and void as designed within the tolerance
    for key in ("floor_z_mm", "depth_mm"):
        assert new["magnet_pocket"].values[key] == pytest.approx(old["magnet_pocket"].values[key], abs=1e-4)
    assert new["overhang"].values["min_inclination_deg"] == pytest.approx(
        old["overhang"].values["min_inclination_deg"], abs=1e-3
    )


def test_layer_prism_is_profile_area_times_depth():
    g = reference()
    for cell, zb in zip(g.layers, g.layer_bottoms_mm):
        area = shoelace(cell.outer_profile_xz()) - shoelace(cell.inner_profile_xz())
        m = mesh_body._manifold(shapes.layer_web(cell, zb), TOL_MM)
        assert m.volume() == pytest.approx(area * cell.depth_mm, rel=1e-12)


@pytest.mark.parametrize("radius, tol", [(3.1, 0.01), (3.1, 0.0001), (10.0, 0.001), (3.1, 1.0)])
def test_pocket_polygon_keeps_the_chord_and_angle_limits(radius, tol):
    n = mesh_body.circle_segments(radius, tol)
    step = 2 * math.pi / n
    assert n % 4 == 0
    assert step <= mesh_io.ANGULAR_TOLERANCE_RAD + 1e-12
    assert radius * (1 - math.cos(step / 2)) <= tol + 1e-12
    # the next coarser multiple of four breaks one of the two limits
    coarser = 2 * math.pi / (n - 4)
    assert coarser > mesh_io.ANGULAR_TOLERANCE_RAD or radius * (1 - math.cos(coarser / 2)) > tol


def test_export_meshes_are_byte_identical_across_runs(tmp_path):
    mst = Path(sys.executable).with_name("mst")
    outs = []
    for k in range(2):
        out = tmp_path / f"o{k}"
        subprocess.run(
            [str(mst) if mst.exists() else "mst", "export", str(FORWARD), "--stl", "--3mf", "--out", str(out)],
            check=True,
            capture_output=True,
        )
        outs.append(out)
    for name in ("sensor.stl", "sensor.3mf"):
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name
    # and the files are the mesh this module builds
    vertices, triangles = mesh_body.print_mesh(reference(), TOL_MM)
    assert (outs[0] / "sensor.stl").read_bytes() == mesh_io.stl_bytes(vertices, triangles)


def test_export_imports_no_cad_kernel_without_step(tmp_path):
    code = (
        "import sys\nfrom mst_cli.cli.app import main\n"
        f"sys.argv = ['mst', 'export', {str(FORWARD)!r}, '--stl', '--3mf', '--out', {str(tmp_path / 'o')!r}]\n"
        "try:\n    main()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
        "print('loaded:' + ','.join(m for m in ('build123d', 'OCP', 'trimesh', 'scipy') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    assert out.stdout.strip().splitlines()[-1] == "loaded:"
