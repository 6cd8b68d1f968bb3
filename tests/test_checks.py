"""mst_cli.cad.checks: every check passes on the exported reference body and fails when the mesh
or the expectation is broken in the way that check is about; the measurements (cad.measure) on
a known solid; the typed manifest (cad.manifest) refuses what it cannot check."""

import copy
import io
import math
import re
from pathlib import Path

import numpy as np
import pytest
import trimesh

from mst_cli.cad import checks, measure, mesh_io
from mst_cli.cad.assembly import build_sensor, print_mesh
from mst_cli.cad.expected_body import pocket_curved_area_mm2, pocket_volume_mm3
from mst_cli.cad.manifest import Manifest, export_manifest, load_manifest
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"


@pytest.fixture(scope="module")
def exported():
    doc, g = load_design_document(FORWARD)
    vertices, triangles = print_mesh(g, build_sensor(g).body, 0.01)
    stl = mesh_io.stl_bytes(vertices, triangles)
    manifest = export_manifest(doc.name, g, doc.printer, 0.01, ["sensor.stl"])
    return stl, manifest, g


def mesh_of(stl):
    return trimesh.load(io.BytesIO(stl), file_type="stl")


def by_name(results):
    return {c.name: c for c in results}


def failed(results):
    return {c.name for c in results if not c.passed and not c.info}


def test_reference_body_passes_every_check(exported):
    stl, manifest, g = exported
    res = by_name(checks.run_checks(mesh_of(stl), manifest))
    assert not failed(res.values())
    assert set(res) == {
        "watertight",
        "is_volume",
        "manifold3d",
        "one_body",
        "volume",
        "bbox",
        "wall_thickness",
        "web_depth",
        "cavity_gap",
        "magnet_pocket",
        "board_slot",
        "footprint",
        "magnet_chip_gap",
        "overhang",
        "layer_grid",
        "magnet_pause",
        "insert_slot",
        "load_path",
    }
    # measured on the mesh, equal to the design's own numbers
    assert res["wall_thickness"].values["per_layer_mm"] == pytest.approx([0.6, 1.0, 1.4], abs=1e-4)
    assert res["cavity_gap"].values["per_layer_mm"] == pytest.approx([0.8, 0.8, 0.7], abs=1e-4)
    assert res["web_depth"].values["per_layer_mm"] == pytest.approx([20.0] * 3, abs=1e-4)
    assert res["magnet_chip_gap"].values["measured_mm"] == pytest.approx(g.gap0_mm, abs=1e-4)
    # lying on its side, the only down-facing faces are the roofs: the pocket's, atan(1.2/1.05)
    # steep, and the insert slot's, a rise of 1.0 mm over half the 2 mm plate: 45 deg
    roofs = (math.degrees(math.atan(1.2 / 1.05)), math.degrees(math.atan(1.0 / 1.0)))
    assert g.has_insert and g.insert_plate.thickness_mm == 2.0 and g.insert_slot_roof_rise_mm == 1.0
    assert res["overhang"].values["min_inclination_deg"] == pytest.approx(min(roofs), abs=1e-3)
    assert res["magnet_pause"].values["roof_start_z_mm"] == pytest.approx(13.2, abs=1e-4)
    # the void shell is the magnet pocket, minus at most delta x curved area
    r = 3.1
    void = res["magnet_pocket"].values["volume_mm3"]
    assert pocket_volume_mm3(g) - 0.01 * pocket_curved_area_mm2(g) <= void <= pocket_volume_mm3(g) + 1e-3
    # its section at mid-depth: half disc + straight sides to y = 3.2 + the roof up to its apex
    area = res["magnet_pocket"].values["section_area_mm2"]
    assert math.pi * r * r / 2 - 0.01 * math.pi * r <= area - 2 * r * (3.2 + 1.2) <= math.pi * r * r / 2 + 1e-6


def test_a_missing_triangle_breaks_watertight_volume_and_manifold(exported):
    stl, manifest, _ = exported
    mesh = mesh_of(stl)
    holed = trimesh.Trimesh(mesh.vertices, mesh.faces[1:], process=False)
    bad = failed(checks.run_checks(holed, manifest))
    assert {"watertight", "is_volume", "manifold3d"} <= bad


def test_a_flipped_triangle_breaks_the_winding(exported):
    stl, manifest, _ = exported
    mesh = mesh_of(stl)
    faces = mesh.faces.copy()
    faces[0] = faces[0, ::-1]
    flipped = trimesh.Trimesh(mesh.vertices, faces, process=False)
    assert flipped.is_watertight  # still closed: only the orientation is wrong
    assert "is_volume" in failed(checks.run_checks(flipped, manifest))


def test_a_second_body_is_caught(exported):
    stl, manifest, _ = exported
    mesh = mesh_of(stl)
    twin = mesh.copy()
    twin.apply_translation((100.0, 0.0, 0.0))
    both = trimesh.util.concatenate([mesh, twin])
    res = by_name(checks.run_checks(both, manifest))
    assert res["one_body"].measured.startswith("2 body")
    assert {"one_body", "volume", "bbox"} <= failed(res.values())


def test_a_scaled_body_fails_volume_bbox_and_dimensions(exported):
    stl, manifest, _ = exported
    mesh = mesh_of(stl)
    mesh.apply_scale(1.01)
    bad = failed(checks.run_checks(mesh, manifest))
    assert {"volume", "bbox", "wall_thickness", "magnet_pocket", "board_slot", "magnet_chip_gap"} <= bad


@pytest.mark.parametrize(
    "edit, check",
    [
        (lambda m: m["body"].__setitem__("volume_mm3", m["body"]["volume_mm3"] + 1.0), "volume"),
        (lambda m: m["body"]["bbox_max_mm"].__setitem__(2, m["body"]["bbox_max_mm"][2] + 0.01), "bbox"),
        (lambda m: m["printer"].__setitem__("min_gap_mm", 0.75), "cavity_gap"),
        (lambda m: m["print"]["pause"].__setitem__("z_mm", 12.8), "magnet_pause"),
        (lambda m: m["print"]["pause"].__setitem__("after_layer", 65), "magnet_pause"),
        (lambda m: m["print"].__setitem__("layer_height_mm", 0.15), "layer_grid"),
        (lambda m: m["layers"][2].__setitem__("web_depth_mm", 19.8), "web_depth"),
        (lambda m: m.__setitem__("gap0_mm", m["gap0_mm"] + 0.01), "magnet_chip_gap"),
        (lambda m: m["magnet_pocket"].__setitem__("section_area_mm2", 42.5), "magnet_pocket"),
        (lambda m: m["magnet_pocket"].__setitem__("floor_z_mm", 17.9), "magnet_pocket"),
        (lambda m: m["board_slot"].__setitem__("x1_mm", 13.1), "board_slot"),
        (lambda m: m["board_slot"].__setitem__("floor_y_mm", -8.4), "board_slot"),
        (lambda m: m["board_slot"]["cable_windows"][0].__setitem__("floor_y_mm", -2.8), "board_slot"),
        (lambda m: m["layers"][1].__setitem__("t_mm", 1.05), "wall_thickness"),
        (lambda m: m["layers"][0].__setitem__("theta_deg", 26.0), "wall_thickness"),
        (lambda m: m["body"].__setitem__("internal_voids", 0), "one_body"),
    ],
)
def test_each_expectation_is_enforced(exported, edit, check):
    stl, manifest, _ = exported
    wrong = copy.deepcopy(manifest)
    edit(wrong)
    assert check in failed(checks.run_checks(mesh_of(stl), wrong))


def test_nozzle_wider_than_the_thinnest_wall_fails(exported):
    stl, manifest, _ = exported
    bad = failed(checks.run_checks(mesh_of(stl), manifest, nozzle_mm=0.8))
    assert bad == {"wall_thickness"}
    assert not failed(checks.run_checks(mesh_of(stl), manifest, nozzle_mm=0.6))


# --------------------------------------------------------------------------- measurements
def test_crossings_and_gaps_on_a_hollow_box():
    outer = trimesh.creation.box((10, 10, 10))
    inner = trimesh.creation.box((4, 4, 4))
    inner.invert()  # a cavity: inward-facing shell
    hollow = trimesh.util.concatenate([outer, inner])
    assert measure.shells(hollow)[:2] == (1, 1)
    assert hollow.volume == pytest.approx(1000 - 64)
    m, status = measure.to_manifold(hollow)
    assert status == "NoError"
    assert np.allclose(measure.vertical_gaps(m, 0.1, 0.2, 5.0, -5.0), [(-2.0, 2.0)])
    assert np.allclose(measure.air_gaps(m, (-8, 0.1, 0.2), (1, 0, 0), 16.0), [(6.0, 10.0)])
    assert measure.section_hole_area(m, 0.0, 0.0, 0.0) == pytest.approx(16.0)
    assert np.allclose(measure.section_boxes(m, 0.0), [(-5, -5, 5, 5)])


def test_a_part_tilted_off_its_side_fails_the_print_checks(exported):
    """Stood upright (the old orientation) the cavity roofs face down at 0 deg and the walls'
    undersides at theta: overhang and layer grid must catch it."""
    stl, manifest, _ = exported
    mesh = mesh_of(stl)
    mesh.apply_transform(trimesh.transformations.rotation_matrix(math.radians(10.0), [1, 0, 0]))
    mesh.apply_translation([0, 0, -mesh.bounds[0][2]])
    bad = failed(checks.run_checks(mesh, manifest))
    assert {"overhang"} <= bad
    res = by_name(checks.run_checks(mesh, manifest))
    assert res["overhang"].values["min_inclination_deg"] < 45.0


def test_unreadable_inputs_are_input_errors(tmp_path):
    from mst_cli.errors import InputError

    (tmp_path / "sensor.stl").write_bytes(b"not a mesh at all")
    (tmp_path / "export.json").write_text("{broken")
    with pytest.raises(InputError, match="export.json"):
        load_manifest(tmp_path / "export.json")
    with pytest.raises(InputError):
        checks.load_mesh(tmp_path / "sensor.stl")
    lonely = tmp_path / "lonely"
    lonely.mkdir()
    (lonely / "sensor.stl").write_bytes(b"")
    with pytest.raises(InputError, match="export.json not found"):
        checks.resolve_export(lonely / "sensor.stl")
    with pytest.raises(InputError, match="does not exist"):
        checks.resolve_export(tmp_path / "missing")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InputError, match="no such STL"):
        checks.resolve_export(empty)


def _random_geometries(n, seed=11):
    import sampling

    return sampling.random_valid_geometries(n, seed, max_offset_mm=3.0)


@pytest.mark.parametrize("g", _random_geometries(3), ids=lambda g: f"{g.board.key}")
def test_random_valid_designs_pass_every_check(g):
    """Seeded designs inside the bounds, random board and chip offset: the measurements find
    each layer's walls, cavity, the pocket and the off-centre slot where the design puts them."""
    from mst_cli.model.printer import Printer

    vertices, triangles = print_mesh(g, build_sensor(g).body, 0.02)
    manifest = export_manifest("random", g, Printer(), 0.02, ["sensor.stl"])
    res = by_name(checks.run_checks(mesh_of(mesh_io.stl_bytes(vertices, triangles)), manifest))
    assert not failed(res.values()), {k: (c.measured, c.expected, c.note) for k, c in res.items() if not c.passed}
    assert res["wall_thickness"].values["per_layer_mm"] == pytest.approx([c.t_mm for c in g.layers], abs=1e-3)
    assert res["overhang"].values["min_inclination_deg"] >= 45.0 - 1e-3


# --------------------------------------------------------------------------- structure
def test_the_mesh_is_measured_once_and_each_check_compares(exported, monkeypatch):
    stl, manifest, _ = exported
    typed = Manifest.from_dict(manifest)
    calls = []
    real = checks.measure
    monkeypatch.setattr(checks, "measure", lambda *a: calls.append(1) or real(*a))
    results = checks.run_checks(mesh_of(stl), typed)
    assert len(calls) == 1
    assert [c.name for c in results] == [f.__name__.removeprefix("check_") for f in checks.CHECKS]
    # a check is a pure comparison: the same measurements against another expectation
    measured = real(mesh_of(stl), typed)
    wider = checks.check_wall_thickness(
        measured, checks.replace(typed, printer=checks.replace(typed.printer, nozzle_mm=0.8))
    )
    assert not wider.passed and wider.values["nozzle_mm"] == 0.8


def test_the_manifest_is_typed_and_validated_on_load(exported, tmp_path):
    import json

    from mst_cli.errors import InputError

    _, manifest, g = exported
    typed = Manifest.from_dict(manifest)
    assert typed.print.pause.after_layer == g.pause_after_layer and isinstance(typed.print.pause.after_layer, int)
    assert typed.layers[0].t_mm == 0.6 and isinstance(typed.body.bbox_max_mm, tuple)
    assert typed.board_slot.cable_windows[0].floor_y_mm == manifest["board_slot"]["cable_windows"][0]["floor_y_mm"]
    (tmp_path / "export.json").write_text(json.dumps(manifest))
    assert load_manifest(tmp_path / "export.json") == typed
    for edit, field in [
        (lambda m: m["layers"][1].pop("t_mm"), "export.json.layers[1].t_mm"),
        (lambda m: m["body"].__setitem__("bodies", 1.5), "export.json.body.bodies"),
        (lambda m: m["print"]["translation_mm"].__setitem__(2, float("inf")), "export.json.print.translation_mm[2]"),
        (
            lambda m: m["print"].__setitem__("rotation", [[1, 0, 0], [0, 1, 0], [0, 0, -1]]),
            "export.json.print.rotation",
        ),
        (lambda m: m["board_slot"].__setitem__("board", 4022), "export.json.board_slot.board"),
    ]:
        wrong = copy.deepcopy(manifest)
        edit(wrong)
        with pytest.raises(InputError, match=re.escape(field)):
            Manifest.from_dict(wrong)


def test_a_bug_in_a_check_is_raised_as_it_is(exported, monkeypatch):
    """The manifest is valid: a KeyError inside a check is a bug and must not be turned into
    anything else."""
    stl, manifest, _ = exported

    def broken(m, x):
        return {}["a bug"]

    monkeypatch.setattr(checks, "CHECKS", checks.CHECKS + (broken,))
    with pytest.raises(KeyError, match="a bug"):
        checks.run_checks(mesh_of(stl), manifest)


# --------------------------------------------------------------------------- numpy mesh (no trimesh)
def test_numpy_mesh_reads_and_measures_as_trimesh_does(exported, tmp_path):
    """load_mesh reads a binary STL with numpy: the same welded mesh, volume, bounds, normals,
    areas and closedness trimesh gives, and the same shells as scipy's connected components."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    stl, manifest, _ = exported
    (tmp_path / "sensor.stl").write_bytes(stl)
    ours, theirs = checks.load_mesh(tmp_path / "sensor.stl"), mesh_of(stl)
    assert len(ours.vertices) == len(theirs.vertices) and len(ours.faces) == len(theirs.faces)
    assert ours.volume == pytest.approx(theirs.volume, rel=1e-12)
    assert np.allclose(ours.bounds, theirs.bounds, atol=0)
    assert np.allclose(np.sort(ours.area_faces), np.sort(theirs.area_faces), rtol=1e-9)
    assert (ours.is_watertight, ours.is_winding_consistent, ours.is_volume) == (True, True, True)
    faces = ours.faces[1:]
    holed = mesh_io.Mesh(ours.vertices, faces)
    assert not holed.is_watertight and not holed.is_volume
    # components of two copies side by side: each is the body, its pocket void and its insert's slot
    v = np.concatenate([ours.vertices, ours.vertices + 100.0])
    f = np.concatenate([ours.faces, ours.faces + len(ours.vertices)])
    edges = f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    labels = measure.vertex_components(len(v), edges)
    n, ref = connected_components(
        coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(len(v), len(v))), directed=False
    )
    assert len(np.unique(labels)) == n == 6
    assert np.array_equal(np.unique(ref, return_inverse=True)[1], np.unique(labels, return_inverse=True)[1])
    res = by_name(checks.run_checks(ours, manifest))
    assert not failed(res.values())


def test_mst_check_imports_neither_trimesh_nor_scipy(tmp_path):
    import subprocess
    import sys

    from mst_cli.cad import mesh_body

    doc, g = load_design_document(FORWARD)
    (tmp_path / "sensor.stl").write_bytes(mesh_io.stl_bytes(*mesh_body.print_mesh(g, 0.01)))
    (tmp_path / "export.json").write_text(
        __import__("json").dumps(export_manifest(doc.name, g, doc.printer, 0.01, ["sensor.stl"]))
    )
    code = (
        "import sys\nfrom mst_cli.cli.app import main\n"
        f"sys.argv = ['mst', 'check', {str(tmp_path)!r}]\n"
        "try:\n    main()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
        "print('loaded:' + ','.join(m for m in ('trimesh', 'scipy', 'build123d') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    assert out.stdout.strip().splitlines()[-1] == "loaded:"
