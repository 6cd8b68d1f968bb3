"""The printed body as a triangle mesh, built from the body's shapes with manifold3d (no CAD kernel).

``mst export --stl/--3mf`` writes meshes, and a mesh library builds and unions meshes in
milliseconds where the B-rep fuse and its tessellation take seconds. The shapes are those of
:func:`mst_cli.cad.shapes.body_plan`, the same the STEP's B-rep body is built from
(:mod:`mst_cli.cad.parts`): boxes and prisms are exact; the pocket's round bottom is a polygon
whose chord deviation is at most the export tolerance (and whose step is at most
:data:`ANGULAR_TOLERANCE_RAD`, as the CAD tessellation's), with vertices on the circle, one
on each axis.

The mesh comes out in a canonical order (vertices sorted by coordinate, each triangle starting
at its smallest vertex, triangles sorted), so the same design and tolerance always give the
same bytes, whatever order the boolean returns.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.cad import mesh_io, shapes
from mst_cli.cad.expected_body import to_print_frame
from mst_cli.cad.mesh_io import ANGULAR_TOLERANCE_RAD
from mst_cli.model.assembly import SensorGeometry

if TYPE_CHECKING:
    import manifold3d

# unit cube corners and its 12 outward triangles (counter-clockwise seen from outside)
_CUBE_CORNERS = np.array([[i >> 0 & 1, i >> 1 & 1, i >> 2 & 1] for i in range(8)], dtype=float)
_CUBE_TRIANGLES = np.array(
    [
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ],
    dtype=np.uint64,
)


def circle_segments(radius_mm: float, tolerance_mm: float) -> int:
    """Segments of the polygon that stands for a circle of ``radius_mm``: a multiple of four
    (a vertex on each axis), each step at most ANGULAR_TOLERANCE_RAD and with a chord
    deviation r (1 - cos(step / 2)) of at most ``tolerance_mm``."""
    step = ANGULAR_TOLERANCE_RAD
    if tolerance_mm < radius_mm:
        step = min(step, 2.0 * math.acos(1.0 - tolerance_mm / radius_mm))
    return 4 * math.ceil(2.0 * math.pi / step / 4.0 - 1e-9)


def _manifold(shape, tolerance_mm: float):
    import manifold3d as mf  # deferred: manifold3d's native library, only when a body is meshed

    if isinstance(shape, shapes.Box):
        lo, hi = np.asarray(shape.lo, float), np.asarray(shape.hi, float)
        # corners at the box's own coordinates (no lo + size rounding): faces that the design
        # puts on one plane are on one plane
        corners = np.where(_CUBE_CORNERS > 0, hi, lo)
        return mf.Manifold(mf.Mesh64(vert_properties=np.ascontiguousarray(corners), tri_verts=_CUBE_TRIANGLES))
    if isinstance(shape, shapes.Cylinder):
        n = circle_segments(shape.radius, tolerance_mm)
        return mf.Manifold.cylinder(shape.height, shape.radius, shape.radius, n).translate(shape.base)
    return _prism(shape)


def _ccw(loop, ccw: bool) -> np.ndarray:
    """The loop's points (k, 2), reversed if needed to run counter-clockwise (or clockwise)."""
    p = np.asarray(loop, dtype=float)
    area = 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
    return p if (area > 0) == ccw else p[::-1]


def _prism(shape: shapes.Prism):
    """A prism as an exact mesh: the profile's own coordinates at both ends (no rounding, so
    faces that touch another shape's fuse with it), caps triangulated by manifold3d."""
    import manifold3d as mf  # deferred: manifold3d's native library, only when a body is meshed

    loops = [_ccw(shape.outer, True)] + [_ccw(h, False) for h in shape.holes]
    profile = np.concatenate(loops)
    k = len(profile)
    caps = np.asarray(mf.triangulate(loops), dtype=np.int64)
    sides = []
    first = 0
    for loop in loops:  # material on the left of every loop: walls face out
        i = first + np.arange(len(loop))
        j = first + (np.arange(len(loop)) + 1) % len(loop)
        sides += [np.stack([i, j, j + k], axis=1), np.stack([i, j + k, i + k], axis=1)]
        first += len(loop)
    triangles = np.concatenate([caps[:, ::-1], caps + k, *sides])
    a_axis, b_axis = shapes.PROFILE_AXES[shape.axis]
    vertices = np.empty((2 * k, 3))
    for col, axis in enumerate("xyz"):
        if axis == shape.axis:
            vertices[:, col] = np.repeat([shape.start, shape.start + shape.length], k)
        else:
            vertices[:, col] = np.tile(profile[:, 0 if axis == a_axis else 1], 2)
    return mf.Manifold(mf.Mesh64(vert_properties=vertices, tri_verts=triangles.astype(np.uint64)))


def body_manifold(geometry: SensorGeometry, tolerance_mm: float) -> manifold3d.Manifold:
    """The body as one manifold3d solid: the keep shapes fused, the cuts and the pocket cut."""
    import manifold3d as mf  # deferred: manifold3d's native library, only when a body is meshed

    plan = shapes.body_plan(geometry)
    keep = mf.Manifold.batch_boolean([_manifold(s, tolerance_mm) for s in plan.keep], mf.OpType.Add)
    voids = [
        mf.Manifold.batch_boolean([_manifold(s, tolerance_mm) for s in pieces], mf.OpType.Add)
        for pieces in (plan.pocket, plan.insert_slot)
        if pieces
    ]
    if plan.pocket_ribs:  # the crush ribs stay standing in the pocket
        ribs = [_manifold(s, tolerance_mm) for s in plan.pocket_ribs]
        voids[0] = mf.Manifold.batch_boolean([voids[0], *ribs], mf.OpType.Subtract)
    body = mf.Manifold.batch_boolean(
        [keep, *(_manifold(s, tolerance_mm) for s in plan.cut), *voids], mf.OpType.Subtract
    )
    # one solid around its closed voids (the pocket, the insert's slot): one shell of positive
    # volume and one of negative volume per void
    shells = sorted(part.volume() for part in body.decompose())
    if body.status().name != "NoError" or len(shells) != 1 + plan.voids or not shells[-2] < 0.0 < shells[-1]:
        raise RuntimeError("the meshed body is not one closed solid around its voids: please report this design")
    return body


def canonical(vertices: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The same mesh in a canonical order: vertices sorted by (x, y, z), each triangle rolled
    to start at its smallest index (its winding kept), triangles sorted."""
    order = np.lexsort(vertices.T[::-1])
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    t = rank[np.asarray(triangles, dtype=np.int64)]
    t = np.take_along_axis(t, (np.argmin(t, axis=1)[:, None] + np.arange(3)) % 3, axis=1)
    t = t[np.lexsort(t.T[::-1])]
    return vertices[order], t


def body_mesh(geometry: SensorGeometry, tolerance_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of the body in the sensor frame, closed and outward-oriented."""
    mesh = body_manifold(geometry, tolerance_mm).to_mesh64()
    vertices, triangles = canonical(
        np.asarray(mesh.vert_properties, dtype=float)[:, :3], np.asarray(mesh.tri_verts, dtype=np.int64)
    )
    if not mesh_io.is_closed_oriented(vertices, triangles):
        raise RuntimeError("the meshed body is not closed: please report this design")
    return vertices, triangles


def print_mesh(geometry: SensorGeometry, tolerance_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of the body as it lies on the bed (the STL/3MF frame)."""
    vertices, triangles = body_mesh(geometry, tolerance_mm)
    return to_print_frame(geometry, vertices), triangles  # a rotation: winding is kept


def insert_mesh(geometry: SensorGeometry) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, triangles) of the insert plate as it prints: flat on the bed, its thickness
    up, its corner at the origin (insert.stl)."""
    import manifold3d as mf  # deferred: manifold3d's native library, only when a body is meshed

    lo, hi = np.asarray(geometry.insert_box_mm, dtype=float)
    size = hi - lo  # x across the face, y the depth, z the thickness: already flat
    mesh = mf.Manifold.cube(tuple(size)).to_mesh64()
    return canonical(np.asarray(mesh.vert_properties, dtype=float)[:, :3], np.asarray(mesh.tri_verts, dtype=np.int64))
