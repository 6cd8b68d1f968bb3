"""Parametric B-rep parts of the sensor, built with build123d from the one geometry object.

Every dimension is read from :class:`mst_cli.geometry.SensorGeometry` (and the
:class:`~mst_cli.geometry.HexCell` of each layer); nothing here stores a number of its own.
Parts are in print orientation: z up from the build plate, the magnet axis along z through
x = y = 0.

Each builder returns plain :class:`build123d.Solid` objects so that the body can be fused in
a single boolean operation (:func:`mst_cli.cad.assembly.build_body`).
"""

from __future__ import annotations

from build123d import Axis, Face, Location, Solid, Wire

from ..geometry import HexCell, SensorGeometry

# Cutting tools that end on an outer face of the part are extended past it by this much, so
# the boolean never has to resolve two coplanar faces (the result is the same solid).
_OVERCUT_MM = 1.0


def box(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float) -> Solid:
    """Axis-aligned box between the given coordinates (mm)."""
    return Solid.make_box(x1 - x0, y1 - y0, z1 - z0).moved(Location((x0, y0, z0)))


def _polygon_xz(points_xz, y_mm: float) -> Wire:
    return Wire.make_polygon([(x, y_mm, z) for x, z in points_xz], close=True)


def layer_struts(cell: HexCell, z_bottom_mm: float) -> list[Solid]:
    """One collapsible layer: the hex profile (outer hexagon minus its inward offset by t,
    DESIGN.md section 3) extruded by the strut width b along y, once per strut centre.

    The bottom and top pads lie flat on z_bottom and z_bottom + h so that they fuse with the
    base/plate below and the plate/cap above.
    """
    outer = [(x, z + z_bottom_mm) for x, z in cell.outer_profile_xz()]
    inner = [(x, z + z_bottom_mm) for x, z in cell.inner_profile_xz()]
    b = cell.b_mm
    # Profile face in the plane y = -b/2, extruded by +b: the strut is centred on y = 0.
    face = Face(_polygon_xz(outer, -0.5 * b), [_polygon_xz(inner, -0.5 * b)])
    strut = Solid.extrude(face, (0.0, b, 0.0))
    return [strut.moved(Location((0.0, y, 0.0))) for y in cell.strut_centres_y_mm]


def plates(geometry: SensorGeometry) -> list[Solid]:
    """Solid plates (W x D x plate thickness) between consecutive layers."""
    w2, d2 = 0.5 * geometry.width_mm, 0.5 * geometry.depth_mm
    out = []
    for cell, z_bottom in zip(geometry.layers[:-1], geometry.layer_bottoms_mm[:-1]):
        z0 = z_bottom + cell.h_mm
        out.append(box(-w2, w2, -d2, d2, z0, z0 + geometry.housing.plate_mm))
    return out


def magnet_pocket(geometry: SensorGeometry) -> Solid:
    """The closed pocket that receives the magnet: a cylinder of the pocket diameter from the
    pocket floor (z_magnet_bottom) up to the pause height, its top edge chamfered at 45 deg
    by ``housing.pocket_chamfer_mm``. Built as one solid of revolution about z."""
    r = 0.5 * geometry.pocket_diameter_mm
    c = geometry.housing.pocket_chamfer_mm
    z0, z1 = geometry.z_magnet_bottom_mm, geometry.z_pause_mm
    if c > 0.0:
        rz = [(0.0, z0), (r, z0), (r, z1 - c), (r + c, z1), (0.0, z1)]
    else:
        rz = [(0.0, z0), (r, z0), (r, z1), (0.0, z1)]
    section = Face(Wire.make_polygon([(x, 0.0, z) for x, z in rz], close=True))
    return Solid.revolve(section, 360.0, Axis.Z)


def cap_block(geometry: SensorGeometry) -> Solid:
    """The cap above the stack (W x D, up to the total height), without its pocket."""
    w2, d2 = 0.5 * geometry.width_mm, 0.5 * geometry.depth_mm
    return box(-w2, w2, -d2, d2, geometry.z_stack_top_mm, geometry.total_height_mm)


def base_block(geometry: SensorGeometry) -> Solid:
    """The base block (base_length x base_width, up to the top of the cover), without cuts."""
    L2, B2 = 0.5 * geometry.base_length_mm, 0.5 * geometry.base_width_mm
    return box(-L2, L2, -B2, B2, 0.0, geometry.z_base_top_mm)


def base_cuts(geometry: SensorGeometry) -> list[Solid]:
    """Board slot and cable exit, as cutting tools.

    The slot (board outline + clearance, from the base floor to the cover's underside) runs
    out through the -x face: the board slides in along +x until it stops at the slot's end,
    which puts the chip under the magnet axis (plus ``chip_offset_mm``). The cable exit is a
    notch of ``housing.cable_exit_width_mm`` through the +x wall, centred on the chip.
    """
    L2 = 0.5 * geometry.base_length_mm
    x0, x1, y0, y1 = geometry.slot_xy_mm
    z0, z1 = geometry.z_board_bottom_mm, geometry.z_cover_bottom_mm
    cuts = [box(-L2 - _OVERCUT_MM, x1, y0, y1, z0, z1)]
    e0, e1 = geometry.cable_exit_y_mm
    if e1 > e0:
        # starts inside the slot (already empty) so it never shares the slot's end face
        cuts.append(box(0.5 * (x0 + x1), L2 + _OVERCUT_MM, e0, e1, z0, z1))
    return cuts


def magnet_solid(geometry: SensorGeometry) -> Solid:
    """The magnet resting on the pocket floor (its lower pole face at z_magnet_bottom)."""
    m = geometry.magnet
    return Solid.make_cylinder(m.radius_mm, m.thickness_mm).moved(
        Location((0.0, 0.0, geometry.z_magnet_bottom_mm)))


def board_solids(geometry: SensorGeometry) -> list[Solid]:
    """The carrier board on the slot floor and the QFN package on it (Hall plates at the
    package centre, which is where the forward model puts the field point)."""
    bd = geometry.board
    bx, by = geometry.board_origin_xy_mm
    pcb = box(bx, bx + bd.length_mm, by, by + bd.width_mm,
              geometry.z_board_bottom_mm, geometry.z_board_top_mm)
    cx, cy = geometry.chip_offset_mm
    s2 = 0.5 * bd.chip_size_mm
    chip = box(cx - s2, cx + s2, cy - s2, cy + s2, geometry.z_board_top_mm, geometry.z_chip_top_mm)
    return [pcb, chip]
