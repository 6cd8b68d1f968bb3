"""Parametric B-rep parts of the sensor, built with build123d from the one geometry object.

Every dimension is read from :class:`mst_cli.model.geometry.SensorGeometry` (and the
:class:`~mst_cli.model.geometry.HexCell` of each layer); nothing here stores a number of its own.
Parts are built in the sensor frame (z up the stack, the magnet axis along z through x = y = 0);
the mesh files are turned into the print frame (lying on the -y face) when they are written.

Each builder returns plain :class:`build123d.Solid` objects so that the body can be fused in
a single boolean operation (:func:`mst_cli.cad.assembly.build_body`).
"""

from __future__ import annotations

from build123d import Face, Location, Solid, Wire

from mst_cli.model.geometry import HexCell, SensorGeometry

# Cutting tools that end on an outer face of the part are extended past it by this much, so
# the boolean never has to resolve two coplanar faces (the result is the same solid).
_OVERCUT_MM = 1.0


def box(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float) -> Solid:
    """Axis-aligned box between the given coordinates (mm)."""
    return Solid.make_box(x1 - x0, y1 - y0, z1 - z0).moved(Location((x0, y0, z0)))


def _polygon_xz(points_xz, y_mm: float) -> Wire:
    return Wire.make_polygon([(x, y_mm, z) for x, z in points_xz], close=True)


def layer_web(cell: HexCell, z_bottom_mm: float) -> Solid:
    """One collapsible layer: the hex profile (outer hexagon minus its inward offset by t,
    docs/design.md section 3) extruded through the whole depth D along y, centred on y = 0.

    The bottom and top pads lie flat on z_bottom and z_bottom + h so that they fuse with the
    base/plate below and the plate/cap above.
    """
    outer = [(x, z + z_bottom_mm) for x, z in cell.outer_profile_xz()]
    inner = [(x, z + z_bottom_mm) for x, z in cell.inner_profile_xz()]
    d = cell.depth_mm
    face = Face(_polygon_xz(outer, -0.5 * d), [_polygon_xz(inner, -0.5 * d)])
    return Solid.extrude(face, (0.0, d, 0.0))


def plates(geometry: SensorGeometry) -> list[Solid]:
    """Solid plates (W x D x plate thickness) between consecutive layers."""
    w2, d2 = 0.5 * geometry.width_mm, 0.5 * geometry.depth_mm
    out = []
    for cell, z_bottom in zip(geometry.layers[:-1], geometry.layer_bottoms_mm[:-1]):
        z0 = z_bottom + cell.h_mm
        out.append(box(-w2, w2, -d2, d2, z0, z0 + geometry.housing.plate_mm))
    return out


def magnet_pocket(geometry: SensorGeometry) -> Solid:
    """The closed pocket that receives the magnet, as one prism along z (the magnet axis)
    over the pocket's depth, plus its roof.

    Its section across the axis is a U open towards +y (up in the print): a half disc of the
    pocket radius below y = 0 and straight sides up to ``pocket_top_y_mm`` (a layer boundary,
    where the print pauses). Above that a gable closes it, its ridge along x on a layer
    boundary, at least 45 deg steep: each layer after the pause overhangs less than a layer
    height, so nothing is bridged.
    """
    r = geometry.pocket_radius_mm
    z0, d = geometry.z_magnet_bottom_mm, geometry.pocket_depth_mm
    y_top = geometry.pocket_top_y_mm
    disc = Solid.make_cylinder(r, d).moved(Location((0.0, 0.0, z0)))
    sides = box(-r, r, 0.0, y_top, z0, z0 + d)
    # gable: triangle in the y-z plane (base on y = y_top across the depth, apex at the
    # ridge), extruded along x over the pocket's width
    tri = [(y_top, z0), (geometry.pocket_roof_apex_y_mm, z0 + 0.5 * d), (y_top, z0 + d)]
    roof = Solid.extrude(Face(Wire.make_polygon([(-r, y, z) for y, z in tri], close=True)),
                         (2.0 * r, 0.0, 0.0))
    return disc.fuse(sides, roof).clean()


def cap_block(geometry: SensorGeometry) -> Solid:
    """The cap above the stack (W x D, up to the total height), without its pocket."""
    w2, d2 = 0.5 * geometry.width_mm, 0.5 * geometry.depth_mm
    return box(-w2, w2, -d2, d2, geometry.z_stack_top_mm, geometry.total_height_mm)


def base_block(geometry: SensorGeometry) -> Solid:
    """The base block (base_length x D, up to the top of the cover), without cuts."""
    L2, d2 = 0.5 * geometry.base_length_mm, 0.5 * geometry.depth_mm
    return box(-L2, L2, -d2, d2, 0.0, geometry.z_base_top_mm)


def base_cuts(geometry: SensorGeometry) -> list[Solid]:
    """Board slot and cable windows, as cutting tools.

    The slot (board outline + clearance, from the base floor to the cover's underside) runs
    from its floor at ``slot_floor_y_mm`` out through the +y face, the face on top in the
    print: the board slides in along -y until it rests on the floor, which puts the chip
    under the magnet axis. Each connector's cable leaves through a window in the side wall
    beside it, open through the same face; so nothing in the base is bridged.
    """
    x0, x1 = geometry.slot_x_mm
    y_out = 0.5 * geometry.depth_mm + _OVERCUT_MM
    z0, z1 = geometry.z_board_bottom_mm, geometry.z_cover_bottom_mm
    cuts = [box(x0, x1, geometry.slot_floor_y_mm, y_out, z0, z1)]
    for x_in, x_out, y_floor, wz0, wz1 in geometry.cable_windows:
        # from just inside the slot (already empty) to past the outer face
        a, b = (x_out - _OVERCUT_MM, x_in + _OVERCUT_MM) if x_out < x_in else (x_in - _OVERCUT_MM, x_out + _OVERCUT_MM)
        cuts.append(box(a, b, y_floor, y_out, wz0, wz1))
    return cuts


def magnet_solid(geometry: SensorGeometry) -> Solid:
    """The magnet resting on the pocket floor (its lower pole face at z_magnet_bottom)."""
    m = geometry.magnet
    return Solid.make_cylinder(m.radius_mm, m.thickness_mm).moved(
        Location((0.0, 0.0, geometry.z_magnet_bottom_mm)))


def board_solids(geometry: SensorGeometry) -> list[Solid]:
    """The carrier board on the slot floor, the QFN package on it (Hall plates at the package
    centre, where the forward model puts the field point) and its connectors."""
    bd = geometry.board
    bx, by = geometry.board_origin_xy_mm
    zb, zt = geometry.z_board_bottom_mm, geometry.z_board_top_mm
    pcb = box(bx, bx + bd.length_mm, by, by + bd.width_mm, zb, zt)
    cx, cy = geometry.chip_xy_printed_mm
    s2 = 0.5 * bd.chip_size_mm
    chip = box(cx - s2, cx + s2, cy - s2, cy + s2, zt, geometry.z_chip_top_mm)
    sockets = [box(bx + c.x0_mm, bx + c.x1_mm, by + c.y0_mm, by + c.y1_mm, zt, zt + c.height_mm)
               for c in bd.connectors]
    return [pcb, chip] + sockets
