"""The printed body as plain shapes: boxes, prisms and cylinders, read from the one geometry object.

This is the one place that turns :class:`mst_cli.model.assembly.SensorGeometry` into solids.
It imports no CAD or mesh library: :mod:`mst_cli.cad.parts` makes B-rep solids of these shapes
with build123d (the STEP assembly), :mod:`mst_cli.cad.mesh_body` makes meshes of the same
shapes with manifold3d (the STL and the 3MF). Both fuse the ``keep`` shapes of
:func:`body_plan` and cut its ``cut`` shapes, so the two bodies differ only where a mesh must
approximate the pocket's round bottom by a polygon.

Shapes are in the sensor frame (z up the stack, the magnet axis along z through x = y = 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.board_slots import slot_violations, window_roof_apex_y_mm
from mst_cli.model.cell import HexCell

# Cutting tools that end on an outer face of the part are extended past it by this much, so
# the boolean never has to resolve two coplanar faces (the result is the same solid).
OVERCUT_MM = 1.0

# the two in-plane axes of a prism's profile, by the axis it is swept along: a right-handed
# (cyclic) order, so that a profile counter-clockwise in (a, b) sweeps outward-facing
PROFILE_AXES = {"x": ("y", "z"), "y": ("z", "x"), "z": ("x", "y")}


@dataclass(frozen=True)
class Box:
    """Axis-aligned box between lo = (x0, y0, z0) and hi = (x1, y1, z1), mm."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]


@dataclass(frozen=True)
class Prism:
    """A polygon (with holes) in the plane across ``axis``, swept along it from ``start`` over
    ``length`` (mm). Profile points are (a, b) in the axes :data:`PROFILE_AXES` names."""

    axis: str
    outer: tuple[tuple[float, float], ...]
    holes: tuple[tuple[tuple[float, float], ...], ...]
    start: float
    length: float

    def point(self, a: float, b: float, s: float) -> tuple[float, float, float]:
        """The sensor-frame point at profile coordinates (a, b) and ``s`` along the axis."""
        coords = {self.axis: s, PROFILE_AXES[self.axis][0]: a, PROFILE_AXES[self.axis][1]: b}
        return (coords["x"], coords["y"], coords["z"])


@dataclass(frozen=True)
class Cylinder:
    """Round cylinder with its axis along z: radius, centre of the lower face, height (mm)."""

    radius: float
    base: tuple[float, float, float]
    height: float


def box(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float) -> Box:
    return Box((x0, y0, z0), (x1, y1, z1))


def check_fits(geometry: SensorGeometry) -> None:
    """Raise :class:`InputError` for the first broken housing rule (the pocket and the slots
    must fit inside the body, the depth must be whole print layers, several chips' slots side
    by side, a wall under and between them): see :meth:`SensorGeometry.housing_violations` and
    :func:`~mst_cli.model.board_slots.slot_violations`. The cell rules are checked by the caller."""
    for v in geometry.housing_violations() + slot_violations(geometry):
        raise v.input_error()


def _xz_to_prism_profile(points_xz) -> tuple[tuple[float, float], ...]:
    """Profile points (x, z) as (a, b) = (z, x) of a prism swept along y."""
    return tuple((z, x) for x, z in points_xz)


def layer_web(cell: HexCell, z_bottom_mm: float) -> Prism:
    """One collapsible layer: the hex profile (outer hexagon minus its inward offset by t,
    docs/design.md section 3) swept through the whole depth D along y, centred on y = 0.

    The bottom and top pads lie flat on z_bottom and z_bottom + h so that they fuse with the
    base/plate below and the plate/cap above.
    """
    outer = [(x, z + z_bottom_mm) for x, z in cell.outer_profile_xz()]
    inner = [(x, z + z_bottom_mm) for x, z in cell.inner_profile_xz()]
    d = cell.depth_mm
    return Prism("y", _xz_to_prism_profile(outer), (_xz_to_prism_profile(inner),), -0.5 * d, d)


def plates(geometry: SensorGeometry) -> list[Box]:
    """Solid plates (W x D x plate thickness) between consecutive layers."""
    w2, d2 = 0.5 * geometry.width_mm, 0.5 * geometry.depth_mm
    out = []
    for cell, z_bottom in zip(geometry.layers[:-1], geometry.layer_bottoms_mm[:-1]):
        z0 = z_bottom + cell.h_mm
        out.append(box(-w2, w2, -d2, d2, z0, z0 + geometry.housing.plate_mm))
    return out


def magnet_pocket(geometry: SensorGeometry) -> list[Cylinder | Box | Prism]:
    """The closed pocket that receives the magnet, as shapes to fuse: a disc over the pocket's
    depth along z (the magnet axis), the straight sides and the roof.

    Its section across the axis is a U open towards +y (up in the print): a half disc of the
    pocket radius below y = 0 and straight sides up to ``pocket_top_y_mm`` (a layer boundary,
    where the print pauses). Above that a gable closes it, its ridge along x on a layer
    boundary, at least 45 deg steep: each layer after the pause overhangs less than a layer
    height, so nothing is bridged.
    """
    r = geometry.pocket_radius_mm
    z0, d = geometry.z_magnet_bottom_mm, geometry.pocket_depth_mm
    y_top = geometry.pocket_top_y_mm
    disc = Cylinder(r, (0.0, 0.0, z0), d)
    sides = box(-r, r, 0.0, y_top, z0, z0 + d)
    return [disc, sides, gable(y_top, geometry.pocket_roof_apex_y_mm, z0, z0 + d, -r, r)]


def magnet_ribs(geometry: SensorGeometry) -> list[Prism]:
    """The crush ribs left in the pocket on its face over the magnet (sensor +z): each a
    triangle in the x-z plane (base two lines wide on that face, apex
    :attr:`SensorGeometry.magnet_rib_reach_mm` towards the magnet) swept along y from below the
    pocket's round bottom up to the pause, so the magnet slides down them; it meets the round
    bottom, so no face of a rib hangs over air. Their base runs into the solid above the face
    (a boolean with no coplanar faces)."""
    z1 = geometry.z_magnet_bottom_mm + geometry.pocket_depth_mm
    w2, reach, r = 0.5 * geometry.magnet_rib_width_mm, geometry.magnet_rib_reach_mm, geometry.pocket_radius_mm
    y_top = geometry.pocket_top_y_mm
    out = []
    for x in geometry.magnet_rib_x_mm:
        profile = ((z1 + OVERCUT_MM, x - w2), (z1, x - w2), (z1 - reach, x), (z1, x + w2), (z1 + OVERCUT_MM, x + w2))
        out.append(Prism("y", profile, (), -r - OVERCUT_MM, y_top + r + OVERCUT_MM))
    return out


def gable(y_top: float, apex_y: float, z0: float, z1: float, x0: float, x1: float) -> Prism:
    """A cavity's roof in the print: a triangle in the y-z plane (its base on y = y_top from z0 to
    z1, its apex at apex_y over the middle) swept along x from x0 to x1. At 45 deg or steeper,
    every layer over the cavity overhangs less than a layer height: nothing is bridged."""
    tri = ((y_top, z0), (apex_y, 0.5 * (z0 + z1)), (y_top, z1))
    return Prism("x", tri, (), x0, x1 - x0)


def insert_slot(geometry: SensorGeometry) -> list[Box | Prism]:
    """The closed slot the insert plate drops into at its pause (none without an insert): the
    slot's box (:attr:`SensorGeometry.insert_slot_box_mm`, open upwards in the print until the
    pause) and the 45 deg gable that closes it over the plate's thickness."""
    if not geometry.has_insert:
        return []
    (x0, y0, z0), (x1, y1, z1) = geometry.insert_slot_box_mm
    roof = gable(y1, y1 + geometry.insert_slot_roof_rise_mm, z0, z1, x0, x1)
    return [box(x0, x1, y0, y1, z0, z1), roof]


def insert_plate(geometry: SensorGeometry) -> Box:
    """The insert plate as it sits in its slot (:attr:`SensorGeometry.insert_box_mm`)."""
    lo, hi = geometry.insert_box_mm
    return Box(lo, hi)


def cap_block(geometry: SensorGeometry) -> Box:
    """The cap above the stack (W x D, up to the total height), without its pocket."""
    w2, d2 = 0.5 * geometry.width_mm, 0.5 * geometry.depth_mm
    return box(-w2, w2, -d2, d2, geometry.z_stack_top_mm, geometry.total_height_mm)


def base_block(geometry: SensorGeometry) -> Box:
    """The base block (base_length x D, up to the top of the cover), without cuts."""
    L2, d2 = 0.5 * geometry.base_length_mm, 0.5 * geometry.depth_mm
    return box(-L2, L2, -d2, d2, 0.0, geometry.z_base_top_mm)


def base_cuts(geometry: SensorGeometry) -> list[Box | Prism]:
    """Board slots and cable windows, as cutting tools: one slot per chip, its windows after it.

    A slot (board outline + clearance, from the base floor to the cover's underside) runs
    from its floor at ``floor_y_mm`` out through the +y face, the face on top in the print:
    the board slides in along -y until it rests on the floor, which puts its chip where the
    design has it. Each connector's cable leaves through a window in the side wall beside it,
    out to the base's x face or into the next chip's slot (the two facing windows of
    neighbouring slots are one box, cut once), from just below the socket to just above it
    under a 45 deg gable, so the side wall carries the cover over the rest of the depth (open
    through the +y face only where that wall would be too thin); nothing in the base is
    bridged. See :mod:`mst_cli.model.board_slots`.
    """
    y_out = 0.5 * geometry.depth_mm + OVERCUT_MM
    z0, z1 = geometry.z_board_bottom_mm, geometry.z_cover_bottom_mm
    floor_at = {x: slot.floor_y_mm for slot in geometry.board_slots for x in slot.x_mm}  # slot wall x -> its floor

    def past(x_end: float, y_floor: float) -> float:
        """How far a window cuts past its end ``x_end``: into the air beyond (the outside, or a
        slot empty above this floor), not into a slot's solid under a higher floor."""
        return OVERCUT_MM if y_floor >= floor_at.get(x_end, -math.inf) - 1e-9 else 0.0

    cuts: list[Box | Prism] = []
    for slot in geometry.board_slots:
        x0, x1 = slot.x_mm
        cuts.append(box(x0, x1, slot.floor_y_mm, y_out, z0, z1))
        for (x_in, x_out, y_floor, wz0, wz1), top in zip(slot.windows, slot.window_tops_y_mm):
            lo, hi = sorted((x_in, x_out))
            lo, hi = lo - past(lo, y_floor), hi + past(hi, y_floor)
            window = box(lo, hi, y_floor, y_out if top is None else top, wz0, wz1)
            if window not in cuts:
                cuts.append(window)
                if top is not None:  # the wall stands over it, up to the +y face
                    cuts.append(gable(top, window_roof_apex_y_mm(geometry, top, wz0, wz1), wz0, wz1, lo, hi))
    return cuts


@dataclass(frozen=True)
class BodyPlan:
    """The printed body: fuse ``keep`` (bottom to top), then cut ``cut`` (the base's slot and
    windows), the union of ``pocket`` (the magnet pocket's pieces) less ``pocket_ribs`` (the
    crush ribs that hold the magnet) and the union of ``insert_slot`` (the insert's slot and
    roof; empty without an insert)."""

    keep: tuple[Box | Prism, ...]
    cut: tuple[Box | Prism, ...]
    pocket: tuple[Cylinder | Box | Prism, ...]
    insert_slot: tuple[Box | Prism, ...] = ()
    pocket_ribs: tuple[Prism, ...] = ()  # left standing in the pocket: cut from its union first

    @property
    def voids(self) -> int:
        """Closed cavities of the body: the pocket, and the insert's slot when there is one."""
        return 1 + bool(self.insert_slot)


def body_plan(geometry: SensorGeometry) -> BodyPlan:
    """The shapes of the one printed TPU body, after :func:`check_fits`."""
    check_fits(geometry)
    keep: list[Box | Prism] = [base_block(geometry)]
    keep += [layer_web(cell, z_bottom) for cell, z_bottom in zip(geometry.layers, geometry.layer_bottoms_mm)]
    keep += plates(geometry)
    keep.append(cap_block(geometry))
    return BodyPlan(
        tuple(keep),
        tuple(base_cuts(geometry)),
        tuple(magnet_pocket(geometry)),
        tuple(insert_slot(geometry)),
        tuple(magnet_ribs(geometry)),
    )


def magnet(geometry: SensorGeometry) -> Cylinder:
    """The magnet resting on the pocket floor (its lower pole face at z_magnet_bottom)."""
    m = geometry.magnet
    return Cylinder(m.radius_mm, (0.0, 0.0, geometry.z_magnet_bottom_mm), m.thickness_mm)


def board(geometry: SensorGeometry, chip: int = 0) -> list[Box]:
    """The carrier board of chip ``chip`` on its slot floor, the QFN package on it (Hall plates
    at the package centre, where the forward model puts the field point) and its connectors."""
    bd, slot = geometry.board, geometry.board_slots[chip]
    bx, by = slot.board_origin_xy_mm
    zb, zt = geometry.z_board_bottom_mm, geometry.z_board_top_mm
    pcb = box(bx, bx + bd.length_mm, by, by + bd.width_mm, zb, zt)
    cx, cy = slot.chip_xy_printed_mm
    s2 = 0.5 * bd.chip_size_mm
    chip_box = box(cx - s2, cx + s2, cy - s2, cy + s2, zt, geometry.z_chip_top_mm)
    sockets = [box(bx + c.x0_mm, bx + c.x1_mm, by + c.y0_mm, by + c.y1_mm, zt, zt + c.height_mm) for c in bd.connectors]
    return [pcb, chip_box] + sockets
