"""The one geometry object against plane geometry computed independently."""

import math

import numpy as np
import pytest

from mst_cli.geometry import HexCell, Printer, SensorGeometry


def shoelace(poly):
    x, y = np.array(poly).T
    return 0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


CELLS = [HexCell(25, 0.6, 2.0), HexCell(33, 1.0, 2.8), HexCell(37, 1.4, 3.5),
         HexCell(15, 0.4, 1.2), HexCell(60, 2.0, 6.0), HexCell(45, 0.8, 3.0, width_mm=24)]


@pytest.mark.parametrize("cell", CELLS)
def test_profile_area_equals_shoelace_of_the_two_polygons(cell):
    area = shoelace(cell.outer_profile_xz()) - shoelace(cell.inner_profile_xz())
    assert cell.profile_area_mm2 == pytest.approx(area, rel=1e-12)
    assert cell.volume_mm3 == pytest.approx(area * cell.b_mm * cell.struts_per_chevron)


@pytest.mark.parametrize("cell", CELLS)
def test_inner_edges_lie_at_distance_t_from_outer_edges(cell):
    outer, inner = np.array(cell.outer_profile_xz()), np.array(cell.inner_profile_xz())
    for i in range(6):
        a, b = outer[i], outer[(i + 1) % 6]
        n = np.array([-(b - a)[1], (b - a)[0]]) / np.linalg.norm(b - a)   # inward (CCW polygon)
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


def test_struts_are_evenly_spread_and_symmetric():
    cell = HexCell(30, 0.8, 3.0, struts_per_chevron=5)
    y = np.array(cell.strut_centres_y_mm)
    assert np.allclose(np.diff(y), 4.0) and y.sum() == pytest.approx(0.0, abs=1e-12)
    assert cell.strut_gap_mm == pytest.approx(4.0 - 0.8)


@pytest.mark.parametrize("rule,cell", [
    ("wall", HexCell(30, 0.3, 3.0)),
    ("cavity_gap", HexCell(30, 1.0, 2.3)),
    ("lock_stroke", HexCell(30, 1.0, 2.05)),
    ("pad_width", HexCell(15, 1.0, 7.9)),
    ("strut_spacing", HexCell(30, 1.0, 3.0, struts_per_chevron=15)),
])
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
    assert g.total_height_mm == pytest.approx(g.z_magnet_bottom_mm + g.magnet.thickness_mm
                                              + H.pocket_clearance_mm + H.cap_top_mm)
    # a thicker cover moves the magnet away by exactly that much
    from dataclasses import replace
    g2 = SensorGeometry(cells, housing=replace(H, cover_mm=H.cover_mm + 0.5))
    assert g2.gap0_mm - g.gap0_mm == pytest.approx(0.5)
