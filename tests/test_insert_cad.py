"""The insert plate (issue 44, docs/design.md section 10), one source of truth: the spec's
``insert`` section, its box in SensorGeometry, the slot the meshed body leaves for it (measured
with trimesh, an independent library), its pause in export.json and the 3MF, the closed form's
default, and the STEP's named part."""

import io
import math
import zipfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import trimesh
from mesh_rays import triangle_hits

from mst_cli.cad import mesh_io
from mst_cli.cad.expected_body import insert_slot_volume_mm3, insert_volume_mm3, to_print_frame
from mst_cli.cad.manifest import export_manifest
from mst_cli.cad.mesh_body import insert_mesh, print_mesh
from mst_cli.errors import InputError
from mst_cli.model import load_path as lp
from mst_cli.model.assembly import InsertPlate
from mst_cli.model.components import INSERT_MATERIALS
from mst_cli.model.housing_base import BEARING
from mst_cli.model.plate_joint import root_joint_mm_per_N
from mst_cli.sensor.document import load_design_document, parse_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"


@pytest.fixture(scope="module")
def forward():
    return load_design_document(FORWARD)


def test_the_plate_box_is_the_face_less_the_walls_and_clearance(forward):
    doc, g = forward
    # the bundled design: 30 x 20 mm face, side walls 1.2 mm, the default 2 mm PLA plate with
    # 0.2 mm clearance; its slot's top leaves 1.2 mm of wall over a 1 mm gable (half of 2 mm)
    assert (g.width_mm, g.depth_mm, g.housing.side_wall_mm) == (30.0, 20.0, 1.2)
    assert g.insert_plate == InsertPlate("pla", 2.0, 0.2)
    (x0, y0, z0), (x1, y1, z1) = g.insert_box_mm
    z_expected = g.z_stack_top_mm + 0.4 + 2.0 + 0.1 + 0.8  # pocket floor, magnet, clearance, wall
    assert (x0, x1) == pytest.approx((-13.6, 13.6))
    assert (y0, y1) == pytest.approx((-8.8, 7.6))  # floor 1.2 mm above the -y face, top 7.8 - 0.2
    assert (z0, z1) == pytest.approx((z_expected, z_expected + 2.0))
    assert insert_volume_mm3(g) == pytest.approx(27.2 * 16.4 * 2.0)
    # the cap: 0.8 mm of TPU over the plate, so the part grows by the plate and one wall
    bare = replace(g, insert_plate=None)
    assert g.total_height_mm - bare.total_height_mm == pytest.approx(2.0 + 0.8)


def test_the_slot_clears_the_plate_across_and_above_but_not_through(forward):
    _, g = forward
    slot, plate = np.asarray(g.insert_slot_box_mm), np.asarray(g.insert_box_mm)
    c = g.insert_plate.clearance_mm
    assert plate[0] - slot[0] == pytest.approx([c, 0.0, 0.0])  # rests on the slot's floor
    assert slot[1] - plate[1] == pytest.approx([c, c, 0.0])  # fills the slot's thickness
    # the slot's floor and top lie on the print layer grid (up-facing faces and the pause)
    for y in (slot[0][1], slot[1][1]):
        n = g.print_height_mm(y) / g.layer_height_mm
        assert n == pytest.approx(round(n), abs=1e-9)


def test_the_stl_leaves_the_slot_export_json_declares(forward):
    """trimesh splits the written STL into its shells: the void around the declared plate is the
    slot, box plus a 45 deg gable; its bounds in the STL's frame are export.json's slot box
    (and the ridge), and its volume the analytic one."""
    doc, g = forward
    vertices, triangles = print_mesh(g, 0.01)
    mesh = trimesh.load(io.BytesIO(mesh_io.stl_bytes(vertices, triangles)), file_type="stl")
    part = next(p for p in export_manifest(doc.name, g, doc.printer, 0.01, [])["parts"] if p["name"] == "insert")
    centre = 0.5 * (np.asarray(part["box_min_mm"]) + np.asarray(part["box_max_mm"]))
    shells = [s for s in mesh.split(only_watertight=False) if np.all((s.bounds[0] <= centre) & (centre <= s.bounds[1]))]
    slot = min(shells, key=lambda s: abs(s.volume))  # the innermost: the slot, not the body
    assert slot.volume < 0 and abs(slot.volume) == pytest.approx(insert_slot_volume_mm3(g), rel=1e-6)
    lo, hi = slot.bounds
    rise = part["slot_roof_rise_mm"]
    assert lo == pytest.approx(part["slot_min_mm"], abs=1e-5)
    assert hi == pytest.approx(np.asarray(part["slot_max_mm"]) + [0.0, 0.0, rise], abs=1e-5)
    # the plate sits inside the slot, in the STL's frame
    assert np.all(np.asarray(part["box_min_mm"]) >= lo - 1e-5) and np.all(np.asarray(part["box_max_mm"]) <= hi + 1e-5)
    # its material as the table gives it
    pla = INSERT_MATERIALS["pla"]
    assert part["material"]["youngs_modulus_MPa"] == pla.youngs_modulus_MPa
    assert part["material"]["poisson_ratio"] == pla.poisson_ratio


def test_insert_stl_is_the_plate_flat(forward):
    _, g = forward
    v, t = insert_mesh(g)
    mesh = trimesh.Trimesh(v, t)
    assert mesh.is_volume and mesh.volume == pytest.approx(insert_volume_mm3(g))
    assert mesh.extents == pytest.approx([27.2, 16.4, 2.0])  # thickness up: it prints flat


def test_two_pauses_in_export_json_and_the_3mf(forward):
    doc, g = forward
    pauses = export_manifest(doc.name, g, doc.printer, 0.01, [])["print"]["pauses"]
    magnet, insert = pauses
    assert magnet["z_mm"] == pytest.approx(g.pause_height_mm)
    # the plate's slot top: half the depth + 7.8 mm; the plate's top is below it
    assert insert["z_mm"] == pytest.approx(17.8) and insert["after_layer"] == 89
    assert g.print_height_mm(g.insert_box_mm[1][1]) < insert["z_mm"]
    v, t = print_mesh(g, 0.05)
    data = mesh_io.three_mf_bytes(v, t, "x", pause_after_z_mm=[(p.z_mm, p.why) for p in g.pauses])
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        xml = zf.read(mesh_io.PRUSA_CUSTOM_GCODE_MEMBER).decode()
    # each event at the top of the layer after its pause
    assert xml.count('type="1"') == 2 and 'print_z="13.4"' in xml and 'print_z="18"' in xml


def test_the_closed_form_takes_the_geometry_insert_by_default(forward):
    doc, g = forward
    m = doc.material
    ins = g.insert
    # the plate's underside above the top pad's underside: pad, pocket floor, pocket, the wall
    assert ins.z_mm == pytest.approx(g.layers[-1].t_mm + 0.4 + 2.1 + 0.8)
    assert ins.depth_mm == pytest.approx(16.4)
    pla = INSERT_MATERIALS["pla"]
    assert ins.modulus_MPa == pytest.approx(pla.youngs_modulus_MPa / (1 - pla.poisson_ratio**2))
    assert lp.members(g, m) == lp.members(g, m, insert=ins)
    bare = lp.members(replace(g, insert_plate=None), m)
    assert lp.members(g, m).cap_mm_per_N < 0.1 * bare.cap_mm_per_N  # the plate carries the press


def test_an_insert_over_the_whole_depth_bends_as_its_section_says():
    """The plate's own depth enters its section: a plate over half the depth adds half the
    bending stiffness of one over all of it (the TPU's share is the same)."""
    E, G, D, T = 30.0, 10.0, 20.0, 4.0
    full = lp.Insert("p", 3000.0, 0.3, 1.0, 1.0)
    half = lp.Insert("p", 3000.0, 0.3, 1.0, 1.0, depth_mm=10.0)
    tpu = lp.section_EI_kGA(D, T, E, G)[0]
    ei_full, ei_half = lp.section_EI_kGA(D, T, E, G, insert=full)[0], lp.section_EI_kGA(D, T, E, G, insert=half)[0]
    # stiff plate off-centre: not exactly half (the neutral axis moves), but between a third and a half
    assert tpu < ei_half < ei_full and 0.3 < (ei_half - tpu) / (ei_full - tpu) < 0.55


def test_the_insert_section_of_a_file():
    base = {"layers": [{"theta_deg": 45, "t_mm": 1.0, "h_mm": 3.0}]}
    doc = parse_document(base)
    assert doc.insert == InsertPlate()  # the default: a 2 mm PLA plate
    steel = parse_document({**base, "insert": {"material": "steel", "thickness_mm": 1.0}})
    g = steel.geometry()
    assert g.insert.modulus_MPa == pytest.approx(200e3 / (1 - 0.3**2))
    none = parse_document({**base, "insert": {"material": "none"}}).geometry()
    assert none.insert is None and not none.has_insert and len(none.pauses) == 1
    assert math.isclose(g.total_height_mm - none.total_height_mm, 1.0 + 0.8)
    with pytest.raises(InputError) as e:
        parse_document({**base, "insert": {"material": "wood"}})
    assert e.value.field == "insert.material"
    with pytest.raises(InputError) as e:
        parse_document({**base, "insert": {"thickness_mm": 0.0}})
    assert e.value.field == "insert.thickness_mm"


def test_the_bottom_is_one_flat_face_on_the_mount(forward):
    """The part's underside (sensor z = 0, print y = 0) is one full rectangle, base length x
    depth: nothing cuts it, so it sits flat on the mount."""
    _, g = forward
    v, t = print_mesh(g, 0.05)
    mesh = trimesh.Trimesh(v, t)
    on_bottom = (np.abs(mesh.triangles_center[:, 1]) < 1e-9) & (mesh.face_normals[:, 1] > 1 - 1e-9)
    assert mesh.area_faces[on_bottom].sum() == pytest.approx(g.base_length_mm * g.depth_mm, rel=1e-12)


def test_the_plate_must_stay_wider_than_the_pocket():
    base = {"family": {"depth_mm": 8.0}, "layers": [{"theta_deg": 45, "t_mm": 1.0, "h_mm": 3.0}]}
    with pytest.raises(InputError) as e:
        parse_document({**base, "insert": {"thickness_mm": 4.0}, "magnet": {"diameter_mm": 3.0}})
    assert e.value.field in ("insert.thickness_mm", "family.depth_mm")


def test_print_frame_of_the_insert_is_the_stls(forward):
    doc, g = forward
    part = next(p for p in export_manifest(doc.name, g, doc.printer, 0.01, [])["parts"] if p["name"] == "insert")
    corners = to_print_frame(g, g.insert_box_mm)
    assert part["box_min_mm"] == pytest.approx(corners.min(axis=0).tolist())
    assert part["box_max_mm"] == pytest.approx(corners.max(axis=0).tolist())


def test_the_side_walls_carry_the_cover_past_the_cable_windows(forward):
    """A section through the windows still joins the cover to the base: beside the slot, in the
    side wall, a column from the base's underside to the cover's top is solid everywhere but
    at the window itself (trimesh's inside test on the body in the sensor frame). Before issue 44
    the window ran out through the +y face, leaving the cover on a cantilever over the open slot."""
    from mst_cli.cad.mesh_body import body_mesh

    _, g = forward
    vertices, triangles = body_mesh(g, 0.05)
    tri = vertices[triangles]
    slot = g.board_slots[0]
    (_, _, y_floor, z0, z1), top = slot.windows[1], slot.window_tops_y_mm[1]
    assert top is not None  # the bundled design's windows close under the cover
    x_wall = 0.5 * (slot.x_mm[1] + 0.5 * g.width_mm)  # the +x side wall's middle
    z = np.linspace(0.05, g.z_base_top_mm - 0.05, 60)
    for y, solid in ((0.5 * g.depth_mm - 0.3, True), (0.5 * (y_floor + top), False), (y_floor - 0.5, True)):
        inside = np.array([crossings_along_x(tri, (x_wall, y, zi)) % 2 == 1 for zi in z])
        in_window = (z > z0) & (z < z1)
        assert inside[~in_window].all()
        assert inside[in_window].all() == solid  # the wall stands over the window, and under it


def crossings_along_x(tri: np.ndarray, point) -> int:
    """How many triangles a ray from ``point`` along +x crosses: odd inside a closed mesh."""
    return len(ray_hits(tri, point, (1.0, 0.0, 0.0)))


def ray_hits(tri: np.ndarray, point, direction) -> np.ndarray:
    """Crossings of a ray from ``point`` nudged off every vertex and edge of these bodies (odd
    offsets across the ray) with the triangles (:func:`mesh_rays.triangle_hits`)."""
    nudge = np.array([3.21e-5, 1.234e-4, 2.345e-4]) * (1 - np.abs(np.asarray(direction, dtype=float)))
    return triangle_hits(tri, np.asarray(point, dtype=float) + nudge, direction)


def test_crush_ribs_hold_the_magnet_by_their_interference(forward):
    """Along the stack through a rib's ridge the pocket is the magnet's thickness less the
    interference; beside the ribs, the magnet and its clearance (numpy rays on the mesh)."""
    from mst_cli.cad.mesh_body import body_mesh
    from mst_cli.model.assembly import MAGNET_RIB_INTERFERENCE_MM

    _, g = forward
    vertices, triangles = body_mesh(g, 0.01)
    tri = vertices[triangles]
    z0 = g.z_magnet_bottom_mm

    def pocket_gap(x, y):
        hits = ray_hits(tri, (x, y, -1.0), (0.0, 0.0, 1.0)) - 1.0
        pairs = [(a, b) for a, b in zip(hits[1::2], hits[2::2]) if a < z0 + 1.0 < b]
        assert len(pairs) == 1
        return pairs[0]

    for x in g.magnet_rib_x_mm:
        lo, hi = pocket_gap(x, 1.0)
        assert lo == pytest.approx(z0, abs=1e-4)
        assert hi - lo == pytest.approx(g.magnet.thickness_mm - MAGNET_RIB_INTERFERENCE_MM, abs=1e-4)
    lo, hi = pocket_gap(0.0, 1.0)  # between the ribs: the magnet plus the axial clearance
    assert hi - lo == pytest.approx(g.magnet.thickness_mm + g.housing.pocket_clearance_mm, abs=1e-4)


def local_drop(g, E: float, D: float, outside_mm: float) -> float:
    """Layer 1's roots turning into the cover (a plate as thick as it) and its feet's bearing at
    the slot's edge, ``outside_mm`` from it (model.housing_base), mm/N."""
    cell, c = g.layers[0], g.housing.cover_mm
    roots = root_joint_mm_per_N(cell.theta_rad, cell.t_mm, cell.h_mm, c, D, E)
    return roots + 0.5 * math.exp(-((outside_mm / c) ** 2)) / (BEARING * E * D)


def test_the_cover_bends_only_where_layer_1_lands_inside_the_slot():
    """The closed form's cover member (model.housing_base: the slot walls are TPU columns w wide
    and H tall, their tops tied by the cover, E'I/H / (1 - (3/4) kappa/(1 + kappa)) against a
    turn, kappa = (E'cD/(L/2)) H^3/(3 E'I); P = F/2 a side). Layer 1's
    walls past the slot's edge stand on a column: the cover does not bend over the slot (nothing
    lands on the board), the foot squeezes the column and turns it by its lever a about the
    column's centre line, P H/(E' w D) + a phi with phi = P a / (k + 1/(B + 1/k_end)), B = (L/2)/E'I
    of the cover under layer 1's pad (which spans the narrow slot), k_end = pi/8 E'D c^2 its end's
    turn into the column's top; layer 1's roots turn into the cover
    and the feet bear on the slot's edge. Inside the slot, the cover bends, and only that part
    stops on the board; the columns then carry the squeeze, the roots and the bearing."""
    base = {"layers": [{"theta_deg": 20, "t_mm": 0.6, "h_mm": 3.0}]}
    narrow = parse_document({**base, "magnetometer": {"board": "bare-qfn"}})
    g, m = narrow.geometry(), narrow.material
    L2, head = 0.5 * (g.slot_x_mm[1] - g.slot_x_mm[0]), lp.wall_head_x_mm(g.layers[0])
    assert L2 < head < lp.pad_half_width_mm(g.layers[0].theta_rad, g.layers[0].h_mm, g.width_mm)
    E, D = m.youngs_modulus_MPa / (1 - m.poisson_ratio**2), g.depth_mm
    H = g.z_cover_bottom_mm - g.z_board_bottom_mm
    EI = E * D * (g.housing.cover_mm + g.layers[0].t_mm) ** 3 / 12
    P, drop = 0.5, []
    for w in (g.slot_x_mm[0] + 0.5 * g.base_length_mm, 0.5 * g.base_length_mm - g.slot_x_mm[1]):
        kappa = (E * g.housing.cover_mm * D / L2) * H**3 / (3 * E * D * w**3 / 12)  # the cover's tie
        k, a = E * D * w**3 / 12 / H / (1 - 0.75 * kappa / (1 + kappa)), L2 + 0.5 * w - head
        k_end = math.pi / 8 * E * D * g.housing.cover_mm**2
        drop.append(P * H / (E * w * D) + a * P * a / (k + 1 / (L2 / EI + 1 / k_end)))
    local = local_drop(g, E, D, head - L2)
    parts = lp.members(g, m)
    assert parts.cover_contact_mm_per_N == 0.0  # no bending over the slot: nothing lands
    assert parts.cover_mm_per_N == pytest.approx(0.5 * sum(drop) + local, rel=1e-12)
    wide = parse_document(base)
    g = wide.geometry()
    assert 0.5 * (g.slot_x_mm[1] - g.slot_x_mm[0]) > lp.wall_head_x_mm(g.layers[0])
    H = g.z_cover_bottom_mm - g.z_board_bottom_mm
    widths = (g.slot_x_mm[0] + 0.5 * g.base_length_mm, 0.5 * g.base_length_mm - g.slot_x_mm[1])
    squeeze = 0.5 * sum(P * H / (E * w * D) for w in widths)
    local = local_drop(g, E, D, 0.5 * (g.slot_x_mm[1] - g.slot_x_mm[0]) - lp.wall_head_x_mm(g.layers[0]))
    parts = lp.members(g, m)
    assert parts.cover_contact_mm_per_N > 10 * squeeze  # the bending over the slot, which lands
    assert parts.cover_mm_per_N - parts.cover_contact_mm_per_N == pytest.approx(squeeze + local, rel=1e-12)


@pytest.mark.slow
def test_the_step_carries_the_insert_as_its_own_named_solid(forward):
    """The STEP assembly: the body, the magnet, the insert and the board, each named; the
    insert's solid is the plate's box (OCCT's own volume and bounding box)."""
    from mst_cli.cad.assembly import build_sensor

    doc, g = forward
    cad = build_sensor(g)
    labels = [child.label for child in cad.assembly(doc.name).children]
    assert labels[:3] == ["sensor_body", "magnet", "insert_pla"]
    assert cad.insert.volume == pytest.approx(insert_volume_mm3(g), rel=1e-9)
    bb = cad.insert.bounding_box()
    lo, hi = g.insert_box_mm
    assert (bb.min.X, bb.min.Y, bb.min.Z, bb.max.X, bb.max.Y, bb.max.Z) == pytest.approx([*lo, *hi], abs=1e-7)
    step = mesh_io.step_bytes(cad.assembly(doc.name)).decode("latin-1")
    assert "'insert_pla'" in step and "'sensor_body'" in step and "'magnet'" in step
