"""B-rep solids of the body's shapes (:mod:`mst_cli.cad.shapes`), built with build123d.

:mod:`mst_cli.cad.shapes` reads every dimension from the geometry object; this module only
turns its boxes, prisms and cylinders into :class:`build123d.Solid` objects (the STEP
assembly). The STL and the 3MF are meshed from the same shapes by :mod:`mst_cli.cad.mesh_body`.
Each builder returns plain solids so that the body can be fused in a single boolean
operation (:func:`mst_cli.cad.assembly.build_body`).
"""

from __future__ import annotations

from collections.abc import Iterable

from build123d import Face, Location, Solid, Wire

from mst_cli.cad import shapes
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.cell import HexCell


def solid(shape: shapes.Box | shapes.Prism | shapes.Cylinder) -> Solid:
    """The B-rep solid of one shape."""
    if isinstance(shape, shapes.Box):
        (x0, y0, z0), (x1, y1, z1) = shape.lo, shape.hi
        return Solid.make_box(x1 - x0, y1 - y0, z1 - z0).moved(Location((x0, y0, z0)))
    if isinstance(shape, shapes.Cylinder):
        return Solid.make_cylinder(shape.radius, shape.height).moved(Location(shape.base))

    def wire(points):
        return Wire.make_polygon([shape.point(a, b, shape.start) for a, b in points], close=True)

    face = Face(wire(shape.outer), [wire(h) for h in shape.holes])
    sweep = tuple(shape.length if axis == shape.axis else 0.0 for axis in "xyz")
    return Solid.extrude(face, sweep)


def layer_web(cell: HexCell, z_bottom_mm: float) -> Solid:
    """One collapsible layer (:func:`mst_cli.cad.shapes.layer_web`)."""
    return solid(shapes.layer_web(cell, z_bottom_mm))


def fused(pieces: Iterable[shapes.Box | shapes.Prism | shapes.Cylinder]) -> Solid:
    """The union of shapes as one solid (one boolean)."""
    first, *rest = (solid(s) for s in pieces)
    return first.fuse(*rest).clean()


def magnet_pocket(geometry: SensorGeometry) -> Solid:
    """The closed magnet pocket, one solid (:func:`mst_cli.cad.shapes.magnet_pocket`)."""
    return fused(shapes.magnet_pocket(geometry))


def magnet_solid(geometry: SensorGeometry) -> Solid:
    """The magnet resting on the pocket floor."""
    return solid(shapes.magnet(geometry))


def board_solids(geometry: SensorGeometry, chip: int = 0) -> list[Solid]:
    """The carrier board of chip ``chip``, the QFN package on it and its connectors."""
    return [solid(s) for s in shapes.board(geometry, chip)]
