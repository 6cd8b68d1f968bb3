"""The section of the part as exported, at mid-depth (y = 0), as regions of material and a
triangle mesh of them: the input of the whole-part rung (:mod:`~mst_cli.model.mechanics.whole_part`,
docs/design.md section 4.7).

Every dimension comes from :class:`~mst_cli.model.assembly.SensorGeometry` and
:class:`~mst_cli.model.cell.HexCell`, the same objects the CAD extrudes (mst_cli/cad/shapes.py
``body_plan``): the base block less the board slot and the cable windows that reach y = 0, each
layer's hexagonal ring (its cavity filled when the layer is taken as locked, closed), the plates,
the cap less the magnet pocket (its crush ribs standing in it) and the insert's slot, the pocket
itself (the magnet, its clearance taken as magnet, or left empty) and a stiff insert when one is
given (the part's own plate in its slot, its side clearances open). The regions do not overlap, so the
section's exact area is the sum of theirs and the mesh is checked against it.

The mesh: Delaunay (scipy) of a triangular lattice at ``spacing_mm`` inside the solid, points
every ``spacing_mm`` along every region's edges and at the press's edges; the triangles whose
centroid lies in a region are kept and tagged with it. Numpy and scipy only, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import Delaunay

TAGS = ("base", "layer", "plate", "cap", "magnet", "insert", "rigid_plate")  # what each region is, for its modulus
# ("rigid_plate": a plate the attribution holds rigid, one plate at a time)


@dataclass(frozen=True)
class Region:
    """A polygon (x, z) with holes, of one member ``tag`` (:data:`TAGS`)."""

    tag: str
    outer: tuple[tuple[float, float], ...]
    holes: tuple[tuple[tuple[float, float], ...], ...] = ()

    @property
    def area_mm2(self) -> float:
        return polygon_area(np.array(self.outer)) - sum(polygon_area(np.array(h)) for h in self.holes)

    def contains(self, pts: np.ndarray) -> np.ndarray:
        inside = point_in_polygon(pts, np.array(self.outer))
        for h in self.holes:
            inside &= ~point_in_polygon(pts, np.array(h))
        return inside

    def edges(self) -> list[np.ndarray]:
        return [np.array(self.outer)] + [np.array(h) for h in self.holes]


def rect(x0: float, x1: float, z0: float, z1: float) -> tuple[tuple[float, float], ...]:
    """A counter-clockwise rectangle."""
    return ((x0, z0), (x1, z0), (x1, z1), (x0, z1))


def point_in_polygon(pts: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd test of points (n, 2) against a closed polygon (m, 2)."""
    x, z = pts[:, 0][:, None], pts[:, 1][:, None]
    x0, z0 = poly[:, 0][None, :], poly[:, 1][None, :]
    x1, z1 = np.roll(poly[:, 0], -1)[None, :], np.roll(poly[:, 1], -1)[None, :]
    crosses = ((z0 > z) != (z1 > z)) & (x < (x1 - x0) * (z - z0) / np.where(z1 != z0, z1 - z0, 1.0) + x0)
    return crosses.sum(axis=1) % 2 == 1


def polygon_area(poly: np.ndarray) -> float:
    x, z = poly[:, 0], poly[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(z, -1)) - np.dot(z, np.roll(x, -1))))


def edge_distance(pts: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Distance of points (n, 2) to the edges of a closed polygon (m, 2)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    ab = b - a
    out = np.full(len(pts), np.inf)
    for i in range(0, len(pts), 4096):  # chunks: (n, m, 2) temporaries stay small
        rel = pts[i : i + 4096, None, :] - a[None, :, :]
        s = np.clip((rel * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
        out[i : i + 4096] = np.hypot(*(rel - s[..., None] * ab).transpose(2, 0, 1)).min(axis=1)
    return out


def edge_points(poly: np.ndarray, spacing: float, segments: np.ndarray) -> np.ndarray:
    """Points along a closed polygon's edges, its corners among them, ``spacing`` apart or
    closer: at most 0.7 times the distance to the nearest of ``segments`` (k, 2, 2: every
    region's edges) that is not collinear with the edge, and no closer than spacing / 16. A
    narrow wedge (a shallow wall meeting its plate) or a cavity's tip is then resolved,
    geometrically graded, and Delaunay keeps to the edges."""
    out = []
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        ab = b - a
        length = float(np.hypot(*ab))
        normal = np.array([-ab[1], ab[0]]) / length
        off = np.abs((segments - a) @ normal)  # (k, 2): both ends' distance to the edge's line
        others = segments[~((off[:, 0] < 1e-9) & (off[:, 1] < 1e-9))]
        s_list, s = [0.0], 0.0
        while True:
            d = _point_segments_distance(a + s * ab, others)
            s += float(np.clip(0.7 * d, spacing / 16.0, spacing)) / length
            if s > 1.0 - 0.3 * spacing / 16.0 / length:
                break
            s_list.append(s)
        out.append(a + np.array(s_list)[:, None] * ab)
    return np.concatenate(out)


def _point_segments_distance(p: np.ndarray, segments: np.ndarray) -> float:
    a, b = segments[:, 0], segments[:, 1]
    ab = b - a
    t = np.clip(((p - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0.0, 1.0)
    return float(np.hypot(*(p - a - t[:, None] * ab).T).min()) if len(segments) else np.inf


def polygon_segments(polys: list[np.ndarray]) -> np.ndarray:
    """(k, 2, 2): every edge of the closed polygons."""
    return np.concatenate([np.stack([p, np.roll(p, -1, axis=0)], axis=1) for p in polys])


def section_regions(
    geometry,
    locked: tuple[int, ...] = (),
    magnet: bool = True,
    insert=None,
    windows: bool = False,
    rigid_plates: tuple[int, ...] = (),
) -> list[Region]:
    """The part's section at y = 0 (module docstring), bottom to top. ``locked``: indices of the
    layers taken as closed (their cavity filled); ``magnet``: the pocket filled by the magnet
    (else left empty); ``insert``: a :class:`~mst_cli.model.load_path.Insert` over the face's
    width, its underside ``insert.z_mm`` above the top layer's top pad's underside (replacing TPU);
    ``windows``: cut the cable windows that reach y = 0 too. They cut the side walls over part
    of the depth only, and in the section they would leave the cover with no support at all (a
    plane-strain model cannot carry it): off by default, their 3D tipping is the 3D check's.
    ``rigid_plates``: indices of plates (bottom first) tagged "rigid_plate" (the attribution's)."""
    g, w2 = geometry, 0.5 * geometry.width_mm
    L2 = 0.5 * g.base_length_mm
    cuts = []
    for slot in g.board_slots:
        if slot.floor_y_mm <= 0.0:  # the slot runs from its floor out through +y
            cuts.append(rect(slot.x_mm[0], slot.x_mm[1], g.z_board_bottom_mm, g.z_cover_bottom_mm))
        for x_in, x_out, y_floor, z0, z1 in slot.windows:
            lo, hi = sorted((x_in, x_out))
            if windows and y_floor <= 0.0:
                cuts.append(rect(max(lo, -L2), min(hi, L2), z0, z1))
    regions = [_base(L2, g.z_base_top_mm, cuts)]
    for i, (cell, zb) in enumerate(zip(g.layers, g.layer_bottoms_mm)):
        outer = tuple((x, z + zb) for x, z in cell.outer_profile_xz())
        inner = tuple((x, z + zb) for x, z in cell.inner_profile_xz())
        regions.append(Region("layer", outer) if i in locked else Region("layer", outer, (inner,)))
    for j, (cell, zb) in enumerate(zip(g.layers[:-1], g.layer_bottoms_mm[:-1])):
        tag = "rigid_plate" if j in rigid_plates else "plate"
        regions.append(Region(tag, rect(-w2, w2, zb + cell.h_mm, zb + cell.h_mm + g.housing.plate_mm)))
    regions += _cap(g, magnet, insert)
    return regions


def _base(half_length: float, top: float, cuts: list) -> Region:
    """The base block less its cuts; a cut reaching the block's side opens it, so the block's
    outline is traced around those (a hole must lie inside)."""
    outline = rect(-half_length, half_length, 0.0, top)
    inner = [c for c in cuts if c[0][0] > -half_length + 1e-9 and c[1][0] < half_length - 1e-9]
    open_cuts = [c for c in cuts if c not in inner]
    if open_cuts:
        outline = _notched(outline, open_cuts)
    return Region("base", outline, tuple(inner))


def _notched(outline, cuts) -> tuple[tuple[float, float], ...]:
    """A rectangle's outline with rectangular notches cut into its left and right sides."""
    (x0, z0), (x1, _), (_, z1), _ = outline
    right = sorted((c for c in cuts if c[1][0] >= x1 - 1e-9), key=lambda c: c[0][1])
    left = sorted((c for c in cuts if c[0][0] <= x0 + 1e-9), key=lambda c: -c[0][1])
    pts = [(x0, z0), (x1, z0)]
    for c in right:
        pts += [(x1, c[0][1]), (c[0][0], c[0][1]), (c[0][0], c[2][1]), (x1, c[2][1])]
    pts += [(x1, z1), (x0, z1)]
    for c in left:
        pts += [(x0, c[2][1]), (c[1][0], c[2][1]), (c[1][0], c[0][1]), (x0, c[0][1])]
    return tuple(pts)


def _cap(g, magnet: bool, insert) -> list[Region]:
    """The cap above the stack less the pocket and, when the part has one, the insert's slot (as
    exported: TPU side walls beside it); the pocket as the magnet; the insert. The geometry's own
    plate sits in its slot with its side clearances left open; another insert spans the face."""
    w2 = 0.5 * g.width_mm
    z0, z1 = g.z_stack_top_mm, g.total_height_mm
    pocket = _pocket(g)
    holes = [pocket]
    if getattr(g, "has_insert", False):
        (sx0, _, sz0), (sx1, _, sz1) = g.insert_slot_box_mm
        holes.append(rect(sx0, sx1, sz0, sz1))
    out, pieces = [], [rect(-w2, w2, z0, z1)]
    if insert is not None:
        zi = g.z_stack_top_mm - g.layers[-1].t_mm + insert.z_mm
        zi0, zi1 = max(zi, z0), zi + insert.thickness_mm
        if len(holes) > 1 and abs(zi0 - holes[1][0][1]) < 1e-9 and abs(zi1 - holes[1][2][1]) < 1e-9:
            (px0, _, _), (px1, _, _) = g.insert_box_mm  # the part's own plate, in its slot
            out.append(Region("insert", rect(px0, px1, zi0, zi1)))
        else:
            if any(zi0 < h[2][1] and zi1 > h[0][1] for h in holes):
                raise ValueError("the insert overlaps the magnet pocket or the insert's slot")
            out.append(Region("insert", rect(-w2, w2, zi0, zi1)))
            pieces = [rect(-w2, w2, z0, zi0), rect(-w2, w2, zi1, z1)]
    for piece in pieces:
        if piece[2][1] - piece[0][1] > 1e-9:
            inside = tuple(h for h in holes if piece[0][1] <= h[0][1] and h[2][1] <= piece[2][1])
            out.append(Region("cap", piece, inside))
    if magnet:
        out.append(Region("magnet", pocket))
    return out


def _pocket(g) -> tuple[tuple[float, float], ...]:
    """The magnet pocket's section less the crush ribs on its face over the magnet (as exported:
    cad/shapes.magnet_ribs, triangles two lines wide reaching clearance + interference down)."""
    r, zb = g.pocket_radius_mm, g.z_magnet_bottom_mm
    zt = zb + g.pocket_depth_mm
    top = [(r, zt)]
    w2, reach = 0.5 * g.magnet_rib_width_mm, g.magnet_rib_reach_mm
    for xc in sorted(g.magnet_rib_x_mm, reverse=True):  # along the face from +x to -x
        top += [(xc + w2, zt), (xc, zt - reach), (xc - w2, zt)]
    return ((-r, zb), (r, zb), *top, (-r, zt))


def section_area_mm2(regions: list[Region]) -> float:
    return sum(r.area_mm2 for r in regions)


def mesh_section(
    regions: list[Region], spacing_mm: float, extra_points: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points (2, n), triangles (3, m), tag index per triangle (m,)) of the regions (module
    docstring); raises ValueError when the kept triangles miss the regions' area."""
    pts, tri, tag = triangulate(regions, spacing_mm, extra_points)
    want = section_area_mm2(regions)
    got = float(triangle_areas(pts, tri).sum())
    if abs(got - want) > 1e-6 * want:
        raise ValueError(f"section mesh covers {got:.9g} mm^2 of {want:.9g}")
    used, inverse = np.unique(tri, return_inverse=True)
    return pts[used].T.copy(), inverse.reshape(tri.shape).T.copy(), tag


def triangle_areas(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    e1, e2 = pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]]
    return 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def triangulate(
    regions: list[Region], spacing_mm: float, extra_points: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points (n, 2), kept triangles (m, 3), their tags): the lattice, the edges' points,
    Delaunay, the triangles whose centroid lies in a region."""
    all_edges = [e for r in regions for e in r.edges()]
    pts_all = np.concatenate(all_edges)
    lo, hi = pts_all.min(axis=0), pts_all.max(axis=0)
    dz = spacing_mm * np.sqrt(3.0) / 2.0
    rows = np.arange(lo[1], hi[1] + dz, dz)
    lattice = np.concatenate(
        [
            np.stack([xs, np.full_like(xs, z)], 1)
            for i, z in enumerate(rows)
            for xs in [np.arange(lo[0] + (i % 2) * 0.5 * spacing_mm, hi[0], spacing_mm)]
        ]
    )
    solid = np.zeros(len(lattice), bool)
    for r in regions:
        solid |= r.contains(lattice)
    lattice = lattice[solid]
    far = np.ones(len(lattice), bool)
    for e in all_edges:
        far &= edge_distance(lattice, e) > 0.45 * spacing_mm
    segments = polygon_segments(all_edges)
    boundary = [edge_points(e, spacing_mm, segments) for e in all_edges]
    parts = [lattice[far], *boundary] + ([extra_points] if extra_points is not None else [])
    pts = np.unique(np.round(np.concatenate(parts), 9), axis=0)
    tri = Delaunay(pts).simplices
    mid = pts[tri].mean(axis=1)
    tag = np.full(len(tri), -1)
    for r in regions[::-1]:  # the first region that holds a centroid names it
        tag[r.contains(mid)] = TAGS.index(r.tag)
    keep = (tag >= 0) & (triangle_areas(pts, tri) > 1e-9 * spacing_mm**2)
    return pts, tri[keep], tag[keep]
