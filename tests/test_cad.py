"""The CAD of the printed body against geometry fixed by hand calculation.

Golden numbers of the reference design are worked out below from the housing defaults and the
Adafruit 4022 board (docs/design.md section 8), not read off the CAD.
"""

import io
import math
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import sampling
import trimesh
from build123d import Edge, import_step

from mst_cli.cad import mesh_io, parts
from mst_cli.cad.assembly import build_body, build_sensor
from mst_cli.cad.expected_body import (
    base_volume_mm3,
    body_bbox_mm,
    body_volume_mm3,
    cap_volume_mm3,
    plates_volume_mm3,
    pocket_curved_area_mm2,
)
from mst_cli.errors import InputError
from mst_cli.model.assembly import Housing, SensorGeometry
from mst_cli.model.cell import HexCell
from mst_cli.model.components import BOARDS
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
RAY_XY = (0.0123, 0.0071)  # off the symmetry lines, like mst check


@pytest.fixture(scope="module")
def reference():
    doc, geometry = load_design_document(FORWARD)
    return geometry, build_sensor(geometry)


def shoelace(points):
    x, y = np.array(points).T
    return 0.5 * abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def solid_intervals_z(solid, x, y, z_top):
    """z ranges of material along the vertical line (x, y): B-rep line/solid intersection."""
    edges = solid.intersect(Edge.make_line((x, y, -1.0), (x, y, z_top + 1.0))).edges()
    return sorted(tuple(sorted((e.vertices()[0].Z, e.vertices()[-1].Z))) for e in edges)


def common_volume(a, b):
    common = a.intersect(b)
    return 0.0 if common is None else sum(s.volume for s in common.solids())


def air_gaps_z(solid, x, y, z_top):
    iv = solid_intervals_z(solid, x, y, z_top)
    return [(a[1], b[0]) for a, b in zip(iv[:-1], iv[1:]) if b[0] - a[1] > 1e-9]


# --------------------------------------------------------------------------- golden reference
# Sensor frame. z: floor 0.8 + board 1.6 + tallest part 2.95 (JST SH sockets) + air 0.65 (the
#    config's) + cover 0.8 = 6.8; layers 2 + 2.8 + 3.5; 2 plates x 0.8; pocket floor 0.4 + pocket
#    2.1 + wall 0.8 + the default 2 mm insert plate + cap 0.8 -> 22.8
# y: the depth, +-10. Print heights are y + 10, on a 0.2 mm grid:
#    slot floor: chip at y = 0 puts the board's edge at -8.3 (print 1.7, half-way: up to 1.8)
#    -> y = -8.2; windows from 5.89 (socket edge) - 0.2 above the floor = -2.51 (print 7.49,
#    down to 7.4) -> y = -2.6; pocket sides up to r = 3.1 (print 13.1, up to 13.2) -> y = 3.2,
#    then a roof rising half the pocket depth, 1.05, up to whole layers: 1.2; windows up to the
#    socket's far edge 11.89 + 0.2 above the floor = 3.89 (print 13.89, up to 14.0) -> y = 4.0,
#    then a gable rising half the window's 3.6 mm (board top 2.4 to the cover 6.0), on the grid: 1.8; the insert's slot
#    from 1.2 above the -y face (y = -8.8) to 1.2 + a 1.0 mm gable under the +y face (y = 7.8)
# x: slot -12.8 .. 13.0, + side wall 1.2 = 14.2 < the cell's 15 -> +-15 mm
def test_reference_bbox_golden(reference):
    g, cad = reference
    bb = cad.body.bounding_box()
    assert (bb.min.X, bb.min.Y, bb.min.Z) == pytest.approx((-15.0, -10.0, 0.0), abs=1e-7)
    assert (bb.max.X, bb.max.Y, bb.max.Z) == pytest.approx((15.0, 10.0, 22.8), abs=1e-7)
    assert (g.slot_floor_y_mm, g.pocket_top_y_mm) == pytest.approx((-8.2, 3.2), abs=1e-9)
    assert [w[2] for w in g.cable_windows] == pytest.approx([-2.6, -2.6], abs=1e-9)
    assert g.board_slots[0].window_tops_y_mm == pytest.approx((4.0, 4.0), abs=1e-9)
    assert np.ravel(g.insert_slot_box_mm) == pytest.approx([-13.8, -8.8, 20.0, 13.8, 7.8, 22.0], abs=1e-9)
    assert (g.pause_height_mm, g.pause_after_layer) == (pytest.approx(13.2, abs=1e-9), 66)


def test_reference_volume_golden(reference):
    g, cad = reference
    window = 6.6 * 3.6 + 0.5 * 3.6 * 1.8  # box and gable, in the y-z plane
    base = 30 * 20 * 6.8 - 25.8 * 18.2 * 5.2 - (2.2 + 2.0) * window
    layers = sum((shoelace(c.outer_profile_xz()) - shoelace(c.inner_profile_xz())) * 20 for c in g.layers)
    plates = 2 * 30 * 20 * 0.8
    r, d = 3.1, 2.1
    pocket = (math.pi * r**2 / 2 + 2 * r * 3.2) * d + r * d * 1.2  # roof rises 1.2 mm
    # less two crush ribs at x = +-r/2: a triangle 0.8 mm wide, reaching 0.2 mm, from the round
    # bottom -sqrt(r^2 - x^2) up to the pause at y = 3.2 (scipy's quadrature, independent)
    from scipy.integrate import quad

    def rib_height(x):
        return 0.2 * max(0.0, 1.0 - abs(x - r / 2) / 0.4)

    rib = quad(lambda x: rib_height(x) * (3.2 + math.sqrt(r * r - x * x)), r / 2 - 0.4, r / 2 + 0.4, points=[r / 2])[0]
    pocket -= 2 * rib
    insert_slot = 27.6 * 2.0 * (16.6 + 0.5 * 1.0)  # box and a 1.0 mm gable
    cap = 30 * 20 * (3.3 + 0.8 + 2.0) - pocket - insert_slot
    expected = base + layers + plates + cap
    assert cad.body.volume == pytest.approx(expected, rel=1e-9)
    assert body_volume_mm3(g) == pytest.approx(expected, rel=1e-12)
    assert cad.body.is_valid


def test_layer_volume_is_profile_area_times_depth(reference):
    g, _ = reference
    for cell, zb in zip(g.layers, g.layer_bottoms_mm):
        area = shoelace(cell.outer_profile_xz()) - shoelace(cell.inner_profile_xz())
        assert parts.layer_web(cell, zb).volume == pytest.approx(area * cell.depth_mm, rel=1e-9)


def test_gap0_is_what_the_cad_builds(reference):
    g, cad = reference
    # pocket floor: the air gap on the axis under the insert's slot; slot floor: the lowest air gap at the chip
    pocket_floor = air_gaps_z(cad.body, *RAY_XY, g.total_height_mm)[-2][0]
    cx, cy = g.chip_xy_printed_mm
    slot_floor, slot_top = air_gaps_z(cad.body, RAY_XY[0] + cx, RAY_XY[1] + cy, g.total_height_mm)[0]
    hall = slot_floor + g.board.thickness_mm + 0.5 * g.board.chip_height_mm
    assert pocket_floor - hall == pytest.approx(g.gap0_mm, abs=1e-9)
    assert pocket_floor - hall == pytest.approx(14.2, abs=1e-9)  # 17.1 - (0.8 + 1.6 + 0.5)
    assert slot_top - slot_floor == pytest.approx(1.6 + 2.95 + 0.65, abs=1e-9)


@pytest.mark.parametrize("key", sorted(BOARDS))
def test_every_board_gives_the_model_gap_and_an_open_slot(key):
    """bd_warehouse style: every catalogue entry builds, the chip sits where the model says."""
    cells = (HexCell(30, 0.8, 2.4, depth_mm=30.0), HexCell(40, 1.2, 3.2, depth_mm=30.0))
    offset = (0.5, -0.7)  # off-centre, every board inside the 30 mm face with its side walls
    g = SensorGeometry(cells, board=BOARDS[key], chip_offset_mm=offset)
    assert g.housing_violations() == []
    body = build_body(g)
    assert body.is_valid and body.volume == pytest.approx(body_volume_mm3(g), rel=1e-9)
    pocket_floor = air_gaps_z(body, *RAY_XY, g.total_height_mm)[-1][0]
    cx, cy = g.chip_xy_printed_mm
    assert abs(cy - offset[1]) <= 0.5 * g.layer_height_mm + 1e-9
    slot_floor = air_gaps_z(body, cx + RAY_XY[0], cy + RAY_XY[1], g.total_height_mm)[0][0]
    gap = pocket_floor - (slot_floor + g.board.thickness_mm + 0.5 * g.board.chip_height_mm)
    assert gap == pytest.approx(g.gap0_mm, abs=1e-9)
    # the board (PCB, chip, sockets) fits in its slot: it does not intersect the body
    board = build_sensor(g).board
    assert sum(common_volume(s, body) for s in board.solids()) == pytest.approx(0.0, abs=1e-9)
    # side walls of at least housing.side_wall_mm beside and under the (off-centre) slot
    x0, x1 = g.slot_x_mm
    w = g.housing.side_wall_mm
    assert min(0.5 * g.base_length_mm - x1, x0 + 0.5 * g.base_length_mm) >= w - 1e-12
    assert g.slot_floor_y_mm + 0.5 * g.depth_mm >= w - 1e-12


# --------------------------------------------------------------------------- magnet pocket
@pytest.mark.parametrize("diameter_mm", [4.0, 6.0, 8.0])
def test_pocket_is_a_u_with_a_45_degree_roof(diameter_mm):
    from mst_cli.model.assembly import Magnet

    g = SensorGeometry((HexCell(30, 0.8, 2.4),), magnet=Magnet(diameter_mm, 2.0))
    r, d = 0.5 * diameter_mm + 0.1, 2.1
    y_top = math.ceil(round((10 + r) / 0.2, 6)) * 0.2 - 10
    pocket = parts.magnet_pocket(g)
    rise = 1.2  # d/2 = 1.05 up to whole 0.2 mm layers
    assert pocket.volume == pytest.approx((math.pi * r * r / 2 + 2 * r * y_top) * d + r * d * rise, rel=1e-9)
    bb = pocket.bounding_box()
    assert (bb.min.Y, bb.max.Y) == pytest.approx((-r, y_top + rise), abs=1e-9)
    # the roof: every down-facing face of the pocket's air is the gable, atan(1.2 / 1.05) steep
    for face in pocket.faces():
        n = face.normal_at(face.center())
        if n.Y > 1e-9:  # the pocket's outward normal up: the body's roof
            assert math.degrees(math.acos(n.Y)) == pytest.approx(math.degrees(math.atan(rise / 1.05)), abs=1e-9)
    # the magnet sits inside the pocket, its face on the floor
    magnet = parts.magnet_solid(g)
    assert common_volume(magnet, pocket) == pytest.approx(magnet.volume, rel=1e-9)
    assert magnet.bounding_box().min.Z == pytest.approx(g.z_magnet_bottom_mm)


def test_pocket_too_wide_for_the_cap_is_an_input_error():
    g = SensorGeometry((HexCell(30, 0.8, 2.4, width_mm=8, depth_mm=20),))
    with pytest.raises(InputError, match="magnet.diameter_mm"):
        build_body(g)


# --------------------------------------------------------------------------- random sweep
def random_valid_geometries(n, seed=4):
    return sampling.random_valid_geometries(n, seed, max_offset_mm=2.0)


@pytest.mark.parametrize("g", random_valid_geometries(6), ids=lambda g: f"{len(g.layers)}layers")
def test_random_valid_designs_build_watertight_bodies(g):
    body = build_body(g)
    assert body.is_valid
    v = body.volume
    # analytic envelope: more than the solid blocks without the layers' struts, less than the
    # bounding box; and the exact analytic sum of the parts
    (x0, y0, z0), (x1, y1, z1) = body_bbox_mm(g)
    floor = base_volume_mm3(g) + plates_volume_mm3(g) + cap_volume_mm3(g)
    assert floor < v < (x1 - x0) * (y1 - y0) * (z1 - z0)
    assert v == pytest.approx(body_volume_mm3(g), rel=1e-9)
    vertices, triangles = mesh_io.tessellate(body, 0.02)
    assert mesh_io.is_closed_oriented(vertices, triangles)
    mesh = trimesh.Trimesh(vertices, triangles, process=False)
    assert mesh.is_watertight and mesh.is_volume
    # chord deviation 0.02 mm only affects the pocket: volume within delta x curved area
    assert abs(mesh.volume - v) <= 0.02 * pocket_curved_area_mm2(g) + 1e-9 * v


# --------------------------------------------------------------------------- files
def test_step_round_trip_keeps_volume_and_names(reference, tmp_path):
    g, cad = reference
    path = tmp_path / "sensor.step"
    mesh_io.write_step(cad.assembly("ref"), path)
    back = import_step(str(path))
    labels = {}

    def walk(node):
        labels[node.label] = node
        for child in getattr(node, "children", ()):
            walk(child)

    walk(back)
    body = labels["sensor_body"]
    assert body.volume == pytest.approx(cad.body.volume, rel=1e-6)
    magnet = labels["magnet"]
    assert magnet.volume == pytest.approx(g.magnet.volume_mm3, rel=1e-6)
    assert labels["board_adafruit-4022"].volume == pytest.approx(
        25.4 * 17.78 * 1.6 + 3 * 3 * 1 + 2 * 6.0 * 4.25 * 2.95, rel=1e-6
    )
    assert {"pcb", "MLX90393", "connector_1", "connector_2"} <= set(labels)
    # deterministic: a second write is byte-identical (fixed header time stamp)
    path2 = tmp_path / "again.step"
    mesh_io.write_step(cad.assembly("ref"), path2)
    assert path.read_bytes() == path2.read_bytes()


def test_stl_and_3mf_hold_the_same_closed_mesh(reference):
    g, cad = reference
    vertices, triangles = mesh_io.tessellate(cad.body, 0.01)
    stl = mesh_io.stl_bytes(vertices, triangles)
    assert len(stl) == 84 + 50 * len(triangles)
    assert stl == mesh_io.stl_bytes(*mesh_io.tessellate(cad.body, 0.01))
    mesh = trimesh.load(io.BytesIO(stl), file_type="stl")
    assert mesh.is_watertight and mesh.is_volume
    assert abs(mesh.volume - body_volume_mm3(g)) <= 0.01 * pocket_curved_area_mm2(g) + 1e-5 * mesh.volume
    # 3MF: parse the XML independently and compare the enclosed volume (divergence theorem)
    with zipfile.ZipFile(io.BytesIO(mesh_io.three_mf_bytes(vertices, triangles, "ref"))) as zf:
        assert {"[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"} <= set(zf.namelist())
        root = ET.fromstring(zf.read("3D/3dmodel.model"))
    ns = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}
    assert root.get("unit") == "millimeter"
    v = np.array([[float(e.get(k)) for k in "xyz"] for e in root.iterfind(".//m:vertex", ns)])
    t = np.array([[int(e.get(k)) for k in ("v1", "v2", "v3")] for e in root.iterfind(".//m:triangle", ns)])
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    assert volume == pytest.approx(mesh.volume, rel=1e-5)


def test_merge_vertices_welds_duplicates_in_first_seen_order():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 0], [0, 0, 1]], float)
    t = np.array([[0, 1, 2], [3, 4, 5], [0, 3, 1]])
    nv, nt = mesh_io.merge_vertices(v, t)
    assert nv.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    assert nt.tolist() == [[0, 1, 2], [1, 0, 3]]  # the degenerate third triangle is dropped


def test_closed_oriented_catches_a_hole_and_a_flipped_triangle():
    box = trimesh.creation.box((1, 2, 3))
    v, t = np.asarray(box.vertices), np.asarray(box.faces)
    assert mesh_io.is_closed_oriented(v, t)
    assert not mesh_io.is_closed_oriented(v, t[1:])
    flipped = t.copy()
    flipped[0] = flipped[0, ::-1]
    assert not mesh_io.is_closed_oriented(v, flipped)


def test_tessellation_keeps_the_corner_order_of_earlier_exports(reference):
    """STL and 3MF store each triangle's corners in order: the mesh read through build123d must
    list them as mst's own face-by-face readout of the OCCT triangulation did (reversed faces
    (n3, n2, n1)), so that exports stay byte-identical. The readout is redone here by hand."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_REVERSED
    from OCP.TopLoc import TopLoc_Location

    _, cad = reference
    vertices, triangles = mesh_io.tessellate(cad.body, 0.01)
    points, tris, offset = [], [], 0
    for face in (f.wrapped for f in cad.body.faces()):
        loc = TopLoc_Location()
        poly = BRep_Tool.Triangulation_s(face, loc)
        trsf = loc.Transformation()
        nodes = (poly.Node(i).Transformed(trsf) for i in range(1, poly.NbNodes() + 1))
        points += [(p.X(), p.Y(), p.Z()) for p in nodes]
        t = np.array([poly.Triangle(i).Get() for i in range(1, poly.NbTriangles() + 1)]) - 1
        tris.append((t[:, ::-1] if face.Orientation() == TopAbs_REVERSED else t) + offset)
        offset += poly.NbNodes()
    key = np.round(np.array(points), 9)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    rank = np.argsort(np.argsort(first))  # welded in first-seen order
    assert np.array_equal(vertices, np.array(points)[np.sort(first)])
    assert np.array_equal(triangles, rank[inverse.reshape(-1)][np.concatenate(tris)])


def test_cover_moves_the_magnet_but_not_the_pause():
    cells = (HexCell(30, 0.8, 2.4),)
    a = SensorGeometry(cells)
    b = replace(a, housing=Housing(cover_mm=1.6))
    # the pause is a print height (along the depth): the stack's height does not move it
    assert b.pause_height_mm == a.pause_height_mm
    assert b.gap0_mm - a.gap0_mm == pytest.approx(0.8)
    body = build_body(b)
    assert air_gaps_z(body, *RAY_XY, b.total_height_mm)[-1][0] == pytest.approx(b.z_magnet_bottom_mm, abs=1e-9)
