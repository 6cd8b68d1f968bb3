"""The one geometry object against plane geometry computed independently."""

import math

import numpy as np
import pytest

from mst_cli.cad.expected_body import body_bbox_mm, cell_volume_mm3, to_print_frame
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.cell import HexCell
from mst_cli.model.printer import Printer


def shoelace(poly):
    x, y = np.array(poly).T
    return 0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


CELLS = [
    HexCell(25, 0.6, 2.0),
    HexCell(33, 1.0, 2.8),
    HexCell(37, 1.4, 3.5),
    HexCell(15, 0.4, 1.2),
    HexCell(60, 2.0, 6.0),
    HexCell(45, 0.8, 3.0, width_mm=24),
]


@pytest.mark.parametrize("cell", CELLS)
def test_profile_area_equals_shoelace_of_the_two_polygons(cell):
    area = shoelace(cell.outer_profile_xz()) - shoelace(cell.inner_profile_xz())
    assert cell.profile_area_mm2 == pytest.approx(area, rel=1e-12)
    assert cell_volume_mm3(cell) == pytest.approx(area * cell.depth_mm)


@pytest.mark.parametrize("cell", CELLS)
def test_inner_edges_lie_at_distance_t_from_outer_edges(cell):
    outer, inner = np.array(cell.outer_profile_xz()), np.array(cell.inner_profile_xz())
    for i in range(6):
        a, b = outer[i], outer[(i + 1) % 6]
        n = np.array([-(b - a)[1], (b - a)[0]]) / np.linalg.norm(b - a)  # inward (CCW polygon)
        for p in (inner[i], inner[(i + 1) % 6]):
            assert np.dot(p - a, n) == pytest.approx(cell.t_mm, abs=1e-12)


@pytest.mark.parametrize("cell", CELLS)
def test_walls_are_inclined_at_theta_and_pad_formula(cell):
    (px, pz), (wx, wz) = cell.outer_profile_xz()[:2]
    assert math.degrees(math.atan2(wz - pz, wx - px)) == pytest.approx(cell.theta_deg)
    assert cell.p_mm == pytest.approx(cell.width_mm / 2 - cell.h_mm / 2 / math.tan(cell.theta_rad))
    # the centre line joins the mid-points of the outer and inner walls' ends
    assert cell.wall_length_mm == pytest.approx((cell.h_mm - cell.t_mm) / 2 / math.sin(cell.theta_rad))
    assert cell.cavity_height_mm == pytest.approx(cell.inner_profile_xz()[2][1] - cell.inner_profile_xz()[0][1])


@pytest.mark.parametrize(
    "rule,cell",
    [
        ("wall", HexCell(30, 0.3, 3.0)),
        ("cavity_gap", HexCell(30, 1.0, 2.3)),
        ("lock_stroke", HexCell(30, 1.0, 2.05)),
        ("pad_width", HexCell(15, 1.0, 7.9)),
    ],
)
def test_each_broken_rule_is_named(rule, cell):
    assert rule in {v.rule for v in cell.violations(Printer())}


def test_reference_cells_are_valid():
    for cell in CELLS[:3]:
        assert cell.violations() == []


def test_stack_heights_and_gap_follow_from_the_parts():
    cells = tuple(CELLS[:3])
    g = SensorGeometry(cells)
    H = g.housing
    assert g.layer_bottoms_mm[1] == pytest.approx(g.layer_bottoms_mm[0] + 2.0 + H.plate_mm)
    assert g.z_stack_top_mm == pytest.approx(g.z_base_top_mm + 2.0 + 2.8 + 3.5 + 2 * H.plate_mm)
    # two independent paths to the gap: z of the parts, and the vectorised kernel
    assert g.gap0_mm == pytest.approx(g.z_magnet_bottom_mm - g.z_hall_mm, abs=1e-12)
    assert g.total_height_mm == pytest.approx(
        g.z_magnet_bottom_mm + g.magnet.thickness_mm + H.pocket_clearance_mm + H.cap_top_mm
    )
    # a thicker cover moves the magnet away by exactly that much
    from dataclasses import replace

    g2 = SensorGeometry(cells, housing=replace(H, cover_mm=H.cover_mm + 0.5))
    assert g2.gap0_mm - g.gap0_mm == pytest.approx(0.5)


# --------------------------------------------------------------------------- print frame
def test_print_frame_is_a_rotation_that_puts_the_minus_y_face_on_the_bed():
    g = SensorGeometry(tuple(CELLS[:3]))
    lo, hi = body_bbox_mm(g)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    p = to_print_frame(g, corners)
    # distances are kept and the frame keeps its handedness: a proper rotation plus a shift
    a, b, c = p[1] - p[0], p[2] - p[0], p[4] - p[0]
    A, B, C = corners[1] - corners[0], corners[2] - corners[0], corners[4] - corners[0]
    assert np.dot(a, np.cross(b, c)) == pytest.approx(np.dot(A, np.cross(B, C)))
    assert np.linalg.norm(p[7] - p[0]) == pytest.approx(np.linalg.norm(corners[7] - corners[0]))
    # the -y face lies on the bed and the print is D high; the stack axis runs along -y
    assert p[:, 2].min() == pytest.approx(0.0) and p[:, 2].max() == pytest.approx(g.depth_mm)
    top = to_print_frame(g, [0.0, 0.0, g.total_height_mm])
    assert top[1] == pytest.approx(-g.total_height_mm) and top[2] == pytest.approx(0.5 * g.depth_mm)


@pytest.mark.parametrize("layer_mm", [0.1, 0.15, 0.2, 0.3])
@pytest.mark.parametrize("diameter_mm", [3.0, 5.0, 6.0, 8.0])
def test_pause_is_a_layer_boundary_with_the_magnet_wholly_below_it(layer_mm, diameter_mm):
    from mst_cli.model.assembly import Magnet

    g = SensorGeometry(tuple(CELLS[:2]), magnet=Magnet(diameter_mm, 2.0), printer=Printer(layer_height_mm=layer_mm))
    n = g.pause_height_mm / layer_mm
    assert n == pytest.approx(round(n), abs=1e-9) and g.pause_after_layer == round(n)
    magnet_top = g.print_height_mm(g.magnet.radius_mm)
    assert magnet_top <= g.pause_height_mm < magnet_top + g.housing.pocket_clearance_mm + layer_mm + 1e-9
    # the roof rises at least at 45 deg (half the pocket depth), its ridge on a layer boundary
    rise = g.pocket_roof_apex_y_mm - g.pocket_top_y_mm
    assert 0.5 * g.pocket_depth_mm - 1e-9 <= rise < 0.5 * g.pocket_depth_mm + layer_mm
    ridge = g.print_height_mm(g.pocket_roof_apex_y_mm) / layer_mm
    assert ridge == pytest.approx(round(ridge), abs=1e-9)


def test_snapping_rounds_to_the_layer_grid_as_asked():
    from mst_cli.model.assembly import snap_to_layers_mm

    assert snap_to_layers_mm(1.7, 0.2, "down") == pytest.approx(1.6)
    assert snap_to_layers_mm(1.7, 0.2, "up") == pytest.approx(1.8)
    assert snap_to_layers_mm(1.75, 0.2, "nearest") == pytest.approx(1.8)
    assert snap_to_layers_mm(1.65, 0.2, "nearest") == pytest.approx(1.6)
    # a value on the grid up to float noise stays where it is, whatever the mode
    for mode in ("down", "up", "nearest"):
        assert snap_to_layers_mm(0.1 + 0.2 + 0.3, 0.2, mode) == pytest.approx(0.6)


def test_slot_floor_and_chip_as_printed():
    g = SensorGeometry(tuple(CELLS[:3]))
    b = g.board
    floor = g.print_height_mm(g.slot_floor_y_mm)
    assert floor / g.layer_height_mm == pytest.approx(round(floor / g.layer_height_mm), abs=1e-9)
    # the board rests on the floor: the chip is off its nominal place by at most half a layer
    assert abs(g.chip_xy_printed_mm[1] - g.chip_offset_mm[1]) <= 0.5 * g.layer_height_mm + 1e-9
    assert g.chip_xy_printed_mm[1] == pytest.approx(g.slot_floor_y_mm + b.chip_y_mm)
    # the headroom clears the tallest part on the board (STEMMA QT sockets, 2.95 mm)
    assert g.z_cover_bottom_mm - g.z_board_top_mm == pytest.approx(2.95 + g.housing.chip_clearance_mm)


def test_housing_rules_name_the_field():
    from mst_cli.model.components import BOARDS

    ok = SensorGeometry(tuple(CELLS[:3]))
    assert ok.housing_violations() == []
    odd = SensorGeometry((HexCell(30, 1.0, 3.0, depth_mm=20.1),))
    assert [v.field for v in odd.housing_violations()] == ["family.depth_mm"]
    big = SensorGeometry((HexCell(30, 1.0, 3.0),), board=BOARDS["sparkfun-14571"])
    assert "family.depth_mm" in [v.field for v in big.housing_violations()]
    assert (
        SensorGeometry((HexCell(30, 1.0, 3.0, depth_mm=30.0),), board=BOARDS["sparkfun-14571"]).housing_violations()
        == []
    )


def test_the_geometry_judges_walls_by_its_own_printer():
    # a 0.5 mm wall is printable on a 0.4 mm nozzle and not on a 0.6 mm one: the sensor's
    # own printer decides, unless another is asked for
    cell = HexCell(30, 0.5, 3.0)
    coarse = Printer(nozzle_mm=0.6, min_wall_mm=0.6, min_gap_mm=0.6)
    g = SensorGeometry((cell,), printer=coarse)
    assert [v.rule for v in g.violations()] == ["wall"]
    assert g.violations(Printer()) == []
    assert SensorGeometry((cell,)).violations() == []
