"""What ``mst check`` measures on an exported mesh, measured once (:func:`measure`).

Numbers come from the mesh itself -- ray casts and plane sections (manifold3d), face normals,
shells and volume (numpy, :class:`~mst_cli.cad.mesh_io.Mesh`) -- at the places the design
(:class:`~mst_cli.cad.manifest.Manifest`) says a feature is; :mod:`mst_cli.cad.checks` compares
them with the design's values. The STL lies in print orientation; the manifest's ``print``
section turns it back to the sensor frame, where the design's dimensions live. A feature that
is not found measures NaN.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from mst_cli.cad.manifest import Manifest
from mst_cli.cad.mesh_io import Mesh

if TYPE_CHECKING:
    import manifold3d

# Mesh heights in print orientation are float32 values up to ~30 mm (~2e-6 mm steps) that went
# through one rotation: a face "on" a layer boundary (or on the bed) lies within this of it.
LAYER_GRID_TOL_MM = 1e-4
# Rays are cast slightly off the symmetry lines so they never run exactly along an edge of the
# triangulation (rectangles are split on their diagonals, which cross the axis).
_RAY_OFFSET_MM = (0.0123, 0.0071)


# --------------------------------------------------------------------------- primitives
def to_manifold(mesh: Mesh) -> tuple[manifold3d.Manifold, str]:
    """manifold3d view of the mesh and its status name ("NoError" when it is a manifold)."""
    import manifold3d as mf  # deferred: manifold3d's native library, only when a mesh is measured

    m = mf.Manifold(
        mf.Mesh(
            vert_properties=np.ascontiguousarray(mesh.vertices, dtype=np.float32),
            tri_verts=np.ascontiguousarray(mesh.faces, dtype=np.uint32),
        )
    )
    return m, m.status().name


def crossings(
    manifold: manifold3d.Manifold, origin: Sequence[float], direction: Sequence[float], length_mm: float
) -> list[tuple[float, bool]]:
    """Surface crossings along a ray: (distance from origin in mm, entering the solid?).

    A hit on a face whose outward normal opposes the ray enters the solid. Hits that repeat
    (a ray through a shared edge) are merged.
    """
    o = np.asarray(origin, dtype=float)
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    hits = manifold.ray_cast(tuple(o), tuple(o + length_mm * d))
    out: list[tuple[float, bool]] = []
    for hit in hits:
        s = hit.distance * length_mm
        entering = float(np.dot(hit.normal, d)) < 0.0
        if out and abs(out[-1][0] - s) < 1e-7 and out[-1][1] == entering:
            continue
        out.append((s, entering))
    return out


def air_gaps(
    manifold: manifold3d.Manifold, origin: Sequence[float], direction: Sequence[float], length_mm: float
) -> list[tuple[float, float]]:
    """Closed air intervals (start, end) along a ray that starts and ends outside the body:
    each runs from leaving the solid to entering it again (distances in mm)."""
    gaps, left = [], None
    for s, entering in crossings(manifold, origin, direction, length_mm):
        if entering and left is not None:
            gaps.append((left, s))
            left = None
        elif not entering:
            left = s
    return gaps


def vertical_gaps(
    manifold: manifold3d.Manifold, x: float, y: float, z_top: float, z_bottom: float = 0.0
) -> list[tuple[float, float]]:
    """Air intervals (z_low, z_high) in mm along the vertical line through (x, y), for a body
    between z_bottom and z_top."""
    start = z_bottom - 1.0
    return [(start + a, start + b) for a, b in air_gaps(manifold, (x, y, start), (0, 0, 1), z_top - z_bottom + 2.0)]


def section_boxes(manifold: manifold3d.Manifold, z_mm: float) -> list[tuple[float, float, float, float]]:
    """Bounds (x0, y0, x1, y1) of every connected region of the horizontal section at z."""
    return [tuple(part.bounds()) for part in manifold.slice(z_mm).decompose()]


def section_hole_area(manifold: manifold3d.Manifold, z_mm: float, x: float, y: float) -> float:
    """Area (mm^2) of the smallest hole of the horizontal section at z that encloses (x, y)."""
    best = math.inf
    for ring in manifold.slice(z_mm).to_polygons():
        rx, ry = ring[:, 0], ring[:, 1]
        area = 0.5 * float(np.sum(rx * np.roll(ry, -1) - np.roll(rx, -1) * ry))
        if area < 0.0 and rx.min() < x < rx.max() and ry.min() < y < ry.max():
            best = min(best, -area)
    return best if math.isfinite(best) else 0.0


def vertex_components(n_vertices: int, edges: np.ndarray) -> np.ndarray:
    """Component label of every vertex of a graph: the smallest vertex index it is joined to
    (hooking along every edge and pointer jumping, in numpy; a few passes per doubling)."""
    label = np.arange(n_vertices)
    a, b = edges[:, 0], edges[:, 1]
    while True:
        la, lb = label[a], label[b]
        low = np.minimum(la, lb)
        new = label.copy()
        np.minimum.at(new, la, low)  # hook both roots onto the smaller one
        np.minimum.at(new, lb, low)
        while not np.array_equal(new, new[new]):
            new = new[new]  # compress to the roots
        if np.array_equal(new, label):
            return label
        label = new


def shells(mesh: Mesh | Any) -> tuple[int, int, list[float]]:
    """(bodies, internal voids, signed shell volumes): a closed shell of negative volume is a
    cavity inside another shell.

    Shells are the connected components of the triangles (sharing vertices); each one's
    signed volume is the divergence-theorem sum of det(a, b, c) / 6 over its triangles.
    """
    volumes, _ = shell_volumes_and_boxes(mesh)
    return sum(v > 0 for v in volumes), sum(v < 0 for v in volumes), volumes


def shell_volumes_and_boxes(mesh: Mesh | Any) -> tuple[list[float], list[tuple[np.ndarray, np.ndarray]]]:
    """Each shell's signed volume and its bounding box (lo, hi), in the mesh's frame."""
    faces = np.asarray(mesh.faces)
    labels = vertex_components(len(mesh.vertices), faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2))
    face_label = np.unique(labels[faces[:, 0]], return_inverse=True)[1].reshape(-1)
    tri = np.asarray(mesh.vertices)[faces]
    signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
    volumes = np.bincount(face_label, weights=signed).tolist()
    boxes = [
        (tri[face_label == k].reshape(-1, 3).min(axis=0), tri[face_label == k].reshape(-1, 3).max(axis=0))
        for k in range(len(volumes))
    ]
    return volumes, boxes


def to_sensor_frame(mesh: Mesh, manifest: Manifest) -> Mesh:
    """The print-oriented mesh in the sensor frame (the manifest's rotation undone)."""
    rot = np.asarray(manifest.print.rotation, dtype=float)
    shift = np.asarray(manifest.print.translation_mm, dtype=float)
    return mesh.moved((mesh.vertices - shift) @ rot)  # R^T (p - T), row vectors


# --------------------------------------------------------------------------- measurements
@dataclass(frozen=True)
class LayerSection:
    """One layer, measured in a section through its two lower walls and along the axis."""

    wall_cuts: int  # regions the section cuts (the design has 2 walls)
    wall_mm: float  # wall normal thickness: x width x sin(design theta)
    web_depth_mm: float  # the walls' extent along y (the print height)
    cavity_mm: float  # the one air gap on the axis inside the layer's z range


@dataclass(frozen=True)
class PocketSize:
    section_area_mm2: float  # hole of the section at the design's mid-depth, around the axis
    floor_z_mm: float  # the topmost air gap on the axis: floor and top of the pocket
    top_z_mm: float
    void_volume_mm3: float  # minus the signed volume of the inward shell (0 without one)
    ridge_z_mm: float  # print height of the roof's ridge, along the build direction

    @property
    def depth_mm(self) -> float:
        return self.top_z_mm - self.floor_z_mm


@dataclass(frozen=True)
class SlotSize:
    floor_z_mm: float  # the lowest air gap above the chip: board floor ...
    top_z_mm: float  # ... and cover underside
    floor_y_mm: float  # where a ray up the depth first leaves the solid
    x0_mm: float  # the one air gap across the slot below the windows
    x1_mm: float
    window_floor_y_mm: tuple[float, ...]


@dataclass(frozen=True)
class InsertSlotSize:
    """The insert's slot as the mesh leaves it, sensor frame (mm); NaN where it is not found."""

    lo_mm: tuple[float, float, float]  # x across, y the floor (print height), z through the plate
    hi_mm: tuple[float, float, float]  # y: the gable's ridge


NO_SLOT = InsertSlotSize((math.nan,) * 3, (math.nan,) * 3)


def _measure_insert_slot(manifold, manifest: Manifest) -> InsertSlotSize:
    """Rays through the middle of the slot export.json declares: along z (its thickness), x
    (its width) and y (its floor and its roof's ridge); each takes the air gap around the
    declared middle."""
    part = manifest.insert
    if part is None or part.sensor_slot_min_mm is None or part.sensor_slot_max_mm is None:
        return NO_SLOT
    lo, hi = np.asarray(part.sensor_slot_min_mm), np.asarray(part.sensor_slot_max_mm)
    mid = 0.5 * (lo + hi) + np.array([0.0123, 0.0123, 0.0])  # off the mesh's vertices
    far = float(np.max(np.abs(manifest.body.bbox_max_mm))) + 1.0 + float(np.max(np.abs(manifest.body.bbox_min_mm)))
    found = []
    for axis in range(3):
        origin = mid.copy()
        origin[axis] = -far
        direction = np.eye(3)[axis]
        gaps = [(a - far, b - far) for a, b in air_gaps(manifold, origin, direction, 2.0 * far)]
        around = [g for g in gaps if g[0] < mid[axis] < g[1]]
        found.append(around[0] if len(around) == 1 else (math.nan, math.nan))
    return InsertSlotSize(tuple(f[0] for f in found), tuple(f[1] for f in found))  # type: ignore[arg-type]


@dataclass(frozen=True, eq=False)
class Measurements:
    """Everything :mod:`mst_cli.cad.checks` compares, measured once on one mesh (mm, deg)."""

    watertight: bool
    is_volume: bool
    manifold_status: str  # manifold3d's status name ("NoError")
    manifold_empty: bool
    bodies: int
    voids: int
    shell_volumes_mm3: list[float]
    volume_mm3: float
    bbox_min_mm: np.ndarray
    bbox_max_mm: np.ndarray
    layers: tuple[LayerSection, ...]
    pocket: PocketSize
    slots: tuple[SlotSize, ...]  # every chip's board slot, in the manifest's order
    # print orientation: down-facing faces off the bed, and heights of the horizontal faces
    down_inclination_deg: np.ndarray
    down_area_mm2: np.ndarray
    flat_heights_mm: np.ndarray
    insert_slot: InsertSlotSize = NO_SLOT

    @property
    def slot(self) -> SlotSize:
        """The first chip's slot (the only one of a one-chip sensor)."""
        return self.slots[0]


def measure(mesh: Mesh | Any, manifest: Manifest) -> Measurements:
    """Measure ``mesh`` (the STL as written, print orientation) where ``manifest`` puts each
    feature. Reads only its arguments; ``mesh`` may be a trimesh.Trimesh or a
    :class:`~mst_cli.cad.mesh_io.Mesh`."""
    mesh = Mesh.of(mesh)
    sensor = to_sensor_frame(mesh, manifest)
    manifold, status = to_manifold(sensor)
    bodies, voids, shell_volumes = shells(sensor)
    bbox_min, bbox_max = sensor.bounds
    # the axis line through cavities and pocket, cast once for the layers and the pocket
    axis_gaps = vertical_gaps(manifold, *_RAY_OFFSET_MM, manifest.body.bbox_max_mm[2])
    down_incl, down_area, flat_heights = _measure_faces(mesh, manifest)
    return Measurements(
        watertight=bool(sensor.is_watertight),
        is_volume=bool(sensor.is_volume),
        manifold_status=status,
        manifold_empty=manifold.is_empty(),
        bodies=bodies,
        voids=voids,
        shell_volumes_mm3=shell_volumes,
        volume_mm3=float(sensor.volume),
        bbox_min_mm=bbox_min,
        bbox_max_mm=bbox_max,
        layers=tuple(_measure_layer(manifold, layer, axis_gaps) for layer in manifest.layers),
        pocket=_measure_pocket(manifold, manifest, axis_gaps, _pocket_void_volumes(sensor, manifest)),
        slots=tuple(_measure_slot(manifold, manifest, i) for i in range(len(manifest.slots))),
        down_inclination_deg=down_incl,
        down_area_mm2=down_area,
        flat_heights_mm=flat_heights,
        insert_slot=_measure_insert_slot(manifold, manifest),
    )


def _measure_layer(manifold, layer, axis_gaps) -> LayerSection:
    zb, h, t = layer.z_bottom_mm, layer.h_mm, layer.t_mm
    # Section halfway between the bottom pad's top (z = t) and the side vertex (z = h/2):
    # it cuts only the two lower walls, each t / sin(theta) wide in x, D deep in y.
    boxes = section_boxes(manifold, zb + 0.5 * (t + 0.5 * h))
    wall = (
        float(min(x1 - x0 for x0, _, x1, _ in boxes) * math.sin(math.radians(layer.theta_deg))) if boxes else math.nan
    )
    depth = float(min(y1 - y0 for _, y0, _, y1 in boxes)) if boxes else math.nan
    gaps = [g for g in axis_gaps if zb < 0.5 * (g[0] + g[1]) < zb + h]
    cavity = gaps[0][1] - gaps[0][0] if len(gaps) == 1 else math.nan
    return LayerSection(wall_cuts=len(boxes), wall_mm=wall, web_depth_mm=depth, cavity_mm=cavity)


def _pocket_void_volumes(sensor: Mesh, manifest: Manifest) -> list[float]:
    """The signed volumes of the voids around the pocket's centre (on the axis, mid-depth): the
    pocket's own shell, not the insert's slot over it."""
    pocket = manifest.magnet_pocket
    centre = np.array([0.0, 0.0, pocket.floor_z_mm + 0.5 * pocket.depth_mm])
    volumes, boxes = shell_volumes_and_boxes(sensor)
    return [v for v, (lo, hi) in zip(volumes, boxes) if v < 0 and np.all(lo <= centre) and np.all(centre <= hi)]


def _measure_pocket(manifold, manifest: Manifest, axis_gaps, void_shell_volumes) -> PocketSize:
    pocket = manifest.magnet_pocket
    # the air gap on the axis around the pocket's mid-depth (the insert's slot lies above it)
    mid = pocket.floor_z_mm + 0.5 * pocket.depth_mm
    around = [g for g in axis_gaps if g[0] < mid < g[1]]
    floor, top = around[0] if around else (math.nan, math.nan)
    # along the build direction (sensor +y) through the pocket's mid-depth: from the U's bottom
    # up to the roof's ridge; the ray starts 1 mm below the bed (print z = sensor y + half)
    half = 0.5 * manifest.print.height_mm
    cols = air_gaps(
        manifold, (0.0123, -half - 1.0, pocket.floor_z_mm + 0.5 * pocket.depth_mm), (0, 1, 0), 2.0 * half + 2.0
    )
    return PocketSize(
        section_area_mm2=section_hole_area(manifold, pocket.section_z_mm, 0.0, 0.0),
        floor_z_mm=floor,
        top_z_mm=top,
        void_volume_mm3=-min(void_shell_volumes) if void_shell_volumes else 0.0,
        ridge_z_mm=cols[-1][1] - 1.0 if cols else math.nan,
    )


def _measure_slot(manifold, manifest: Manifest, index: int = 0) -> SlotSize:
    """The slot of chip ``index``: the air under its chip, its floor along the depth, its width
    across (below the windows: the one air gap, or with several slots the one around this
    chip, so that a filled slot does not hide the others) and its windows' floors."""
    slots, bbox_max = manifest.slots, manifest.body.bbox_max_mm
    slot = slots[index]
    x_far, y_far = bbox_max[0] + 1.0, bbox_max[1] + 1.0
    cx, cy = slot.chip_xy_mm
    chip_gaps = vertical_gaps(manifold, cx + _RAY_OFFSET_MM[0], cy + _RAY_OFFSET_MM[1], bbox_max[2])
    floor_z, top_z = chip_gaps[0] if chip_gaps else (math.nan, math.nan)
    z_s = 0.5 * (slot.floor_z_mm + slot.top_z_mm)

    def first_exit_y(x):
        """y where a ray up the depth first leaves the solid (the floor of an open slot)."""
        hits = crossings(manifold, (x, -y_far, z_s), (0, 1, 0), 2 * y_far)
        leave = [s for s, entering in hits if not entering]
        return leave[0] - y_far if leave else math.nan

    # across the slots below the windows: one closed air gap per slot is each one's width. With
    # several slots also below the windows in z (in the board's thickness): a link window may reach
    # below this slot's floor when the next slot's floor is lower
    windows = slot.cable_windows
    above = [w.floor_y_mm for w in windows if w.floor_y_mm > slot.floor_y_mm]
    y_across = 0.5 * (slot.floor_y_mm + min(above, default=slot.floor_y_mm + 2.0))
    z_across = z_s if len(slots) == 1 else slot.floor_z_mm + 0.5 * slot.board_thickness_mm
    x_gaps = [(a - x_far, b - x_far) for a, b in air_gaps(manifold, (-x_far, y_across, z_across), (1, 0, 0), 2 * x_far)]
    found = x_gaps if len(slots) == 1 else [g for g in x_gaps if g[0] < cx < g[1]]
    x0, x1 = found[0] if len(found) == 1 else (math.nan, math.nan)
    return SlotSize(
        floor_z_mm=floor_z,
        top_z_mm=top_z,
        floor_y_mm=first_exit_y(cx + _RAY_OFFSET_MM[0]),
        x0_mm=x0,
        x1_mm=x1,
        window_floor_y_mm=tuple(first_exit_y(0.5 * (w.x_inner_mm + w.x_outer_mm)) for w in windows),
    )


def _measure_faces(mesh, manifest: Manifest) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(inclination from horizontal in deg, area in mm^2) of every down-facing face off the bed,
    and the distinct heights of the horizontal faces, on the mesh as it lies on the bed."""
    pr, pocket = manifest.print, manifest.magnet_pocket
    z0 = float(mesh.bounds[0][2])
    nz = mesh.face_normals[:, 2]
    zc = mesh.triangles_center[:, 2] - z0
    # down-facing faces off the bed: material above air. Inclination from horizontal alpha has
    # n_z = -cos(alpha)
    down = (nz < -1e-9) & (zc > LAYER_GRID_TOL_MM)
    incl = np.degrees(np.arccos(np.clip(-nz[down], -1.0, 1.0)))
    # horizontal faces -- but for the chord of the pocket's round bottom, which the mesher may
    # leave flat (the slicer draws a curve as a staircase anyway)
    flat = np.abs(np.abs(nz) - 1.0) < 1e-9
    c = mesh.triangles_center
    r, floor_z = pocket.radius_mm, pocket.floor_z_mm
    in_round_bottom = (
        (np.abs(c[:, 0]) <= r + 1e-6)
        & (c[:, 1] <= -floor_z + 1e-6)
        & (c[:, 1] >= -(floor_z + pocket.depth_mm) - 1e-6)
        & (zc >= 0.5 * pr.height_mm - r - 1e-6)
        & (zc < 0.5 * pr.height_mm)
    )
    flat &= ~in_round_bottom
    return incl, mesh.area_faces[down], np.unique(np.round(zc[flat], 6))
