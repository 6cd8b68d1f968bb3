"""What the printed body is expected to measure: the numbers ``cad/`` checks an exported mesh
against (volumes, areas, the bounding box, the wall centre lines a slice is read across) and
the sensor-to-print frame, as plain functions of a cell
(:class:`~mst_cli.model.cell.HexCell`) or of a sensor
(:class:`~mst_cli.model.assembly.SensorGeometry`).

No model computation reads them: the model holds the dimensions, this module derives from
them what the body made of those dimensions should measure. Their readers are ``cad/``
(``manifest``, ``mesh_body``, ``assembly``), ``cli/export.py`` and the tests.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.board_slots import window_roof_apex_y_mm

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from mst_cli.model.assembly import SensorGeometry
    from mst_cli.model.cell import HexCell


# --------------------------------------------------------------------------- a cell


def wall_horizontal_width_mm(cell: HexCell) -> float:
    """Width of an inclined wall in a horizontal section of the sensor: t / sin(theta)."""
    return cell.t_mm / math.sin(cell.theta_rad)


def cell_volume_mm3(cell: HexCell) -> float:
    """Material volume of the layer: profile area x web width D."""
    return cell.profile_area_mm2 * cell.b_mm


def wall_centrelines_xz(cell: HexCell, keep: float = 0.5) -> list[tuple[str, tuple[float, float], tuple[float, float]]]:
    """The four inclined walls as (name, start, end) of the middle ``keep`` of each wall's
    centre line where both its faces are free (cavity inside, air outside), so a line across
    the wall there crosses the wall alone, not the pad, plate or tip it joins (mm).

    A wall shorter than it is thick has no such stretch: its centre line's midpoint, twice."""
    outer, inner = cell.outer_profile_xz(), cell.inner_profile_xz()
    out = []
    for name, (k0, k1) in (
        ("lower right", (0, 1)),
        ("upper right", (1, 2)),
        ("upper left", (3, 4)),
        ("lower left", (4, 5)),
    ):
        o0, o1, i0, i1 = (np.asarray(v, dtype=float) for v in (outer[k0], outer[k1], inner[k0], inner[k1]))
        u = (o1 - o0) / np.hypot(*(o1 - o0))
        m0 = 0.5 * (o0 + i0)  # on the centre line: midway between parallel faces
        s_lo = max(float((o0 - m0) @ u), float((i0 - m0) @ u))
        s_hi = min(float((o1 - m0) @ u), float((i1 - m0) @ u))
        mid, half = 0.5 * (s_lo + s_hi), max(0.0, 0.5 * keep * (s_hi - s_lo))
        a, b = m0 + (mid - half) * u, m0 + (mid + half) * u
        out.append((name, (float(a[0]), float(a[1])), (float(b[0]), float(b[1]))))
    return out


# --------------------------------------------------------------------------- the sensor


def body_bbox_mm(geometry: SensorGeometry) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Bounding box (min, max) of the body in the sensor frame: base or cells, whichever
    is wider."""
    x = 0.5 * max(geometry.base_length_mm, geometry.width_mm)
    y = 0.5 * geometry.depth_mm
    return (-x, -y, 0.0), (x, y, geometry.total_height_mm)


def pocket_section_area_mm2(geometry: SensorGeometry, z_mm: float) -> float:
    """Area of the pocket in the x-y plane at height z (inside the pocket's z range): the
    lower half disc, the straight-sided part up to the pocket top and the strip of the
    45 deg roof, which reaches its apex at the pocket's mid height."""
    g = geometry
    r, d = g.pocket_radius_mm, g.pocket_depth_mm
    roof = g.pocket_roof_rise_mm * max(1.0 - abs(z_mm - (g.z_magnet_bottom_mm + 0.5 * d)) / (0.5 * d), 0.0)
    return 0.5 * math.pi * r * r + 2 * r * (g.pocket_top_y_mm + roof)


def pocket_volume_mm3(geometry: SensorGeometry) -> float:
    """The U-shaped pocket (its x-y section times the depth) plus the roof: a triangular
    prism of base ``pocket_depth`` and height ``pocket_roof_rise_mm``, 2 r long; less the crush
    ribs (:func:`magnet_ribs_volume_mm3`)."""
    g = geometry
    r, d = g.pocket_radius_mm, g.pocket_depth_mm
    u = (0.5 * math.pi * r * r + 2 * r * g.pocket_top_y_mm) * d + r * d * g.pocket_roof_rise_mm
    return u - magnet_ribs_volume_mm3(g)


def magnet_ribs_volume_mm3(geometry: SensorGeometry) -> float:
    """The crush ribs inside the pocket: each triangle's height h(x) (reach at its centre, 0 at
    its base's ends) times the pocket's extent along y at x, from the round bottom
    -sqrt(r^2 - x^2) to the pause y_top, integrated over x by Gauss-Legendre on each half (a
    smooth integrand there: exact to rounding with 24 points)."""
    g = geometry
    r, w2, reach, y_top = g.pocket_radius_mm, 0.5 * g.magnet_rib_width_mm, g.magnet_rib_reach_mm, g.pocket_top_y_mm
    s, wts = np.polynomial.legendre.leggauss(24)
    total = 0.0
    for xc in g.magnet_rib_x_mm:
        for a, b in ((xc - w2, xc), (xc, xc + w2)):
            x = 0.5 * (b - a) * s + 0.5 * (a + b)
            h = reach * (1.0 - np.abs(x - xc) / w2)
            total += 0.5 * (b - a) * float(np.sum(wts * h * (y_top + np.sqrt(r * r - x * x))))
    return total


def pocket_curved_area_mm2(geometry: SensorGeometry) -> float:
    """Curved surface of the pocket (the half cylinder): a mesh of chord deflection delta
    changes the pocket volume by at most delta times this area."""
    return math.pi * geometry.pocket_radius_mm * geometry.pocket_depth_mm


def overlap_volume_mm3(boxes: Sequence[tuple[Sequence[float], Sequence[float]]]) -> float:
    """Volume that axis-aligned boxes (lo, hi) cover more than once, counted once per extra
    cover: their summed volumes minus this is the volume of their union. Exact on the grid of
    the boxes' own coordinates; 0.0 when no two overlap (boxes that only touch do not)."""
    if len(boxes) < 2:
        return 0.0
    lo, hi = np.asarray([b[0] for b in boxes]), np.asarray([b[1] for b in boxes])
    grids = [np.unique(np.concatenate([lo[:, k], hi[:, k]])) for k in range(3)]
    centres = np.meshgrid(*[0.5 * (g[1:] + g[:-1]) for g in grids], indexing="ij")
    cells = np.einsum("i,j,k->ijk", *[np.diff(g) for g in grids])
    count = sum(
        np.all([(lo[b, k] < centres[k]) & (centres[k] < hi[b, k]) for k in range(3)], axis=0) for b in range(len(boxes))
    )
    return float(np.sum(cells * np.maximum(count - 1, 0)))


def base_volume_mm3(geometry: SensorGeometry) -> float:
    """Base block minus the board slots (open through the +y face) and the cable windows, each
    a box from its floor to its top (or through the +y face) and a 45 deg gable over a closed
    one; a window between two slots is one window, removed once."""
    g = geometry
    L, D = g.base_length_mm, g.depth_mm
    y_top = 0.5 * D
    z0, z1 = g.z_board_bottom_mm, g.z_cover_bottom_mm
    boxes = [((s.x_mm[0], s.floor_y_mm, z0), (s.x_mm[1], y_top, z1)) for s in g.board_slots]
    slot = sum((s.x_mm[1] - s.x_mm[0]) * (y_top - s.floor_y_mm) * g.slot_height_mm for s in g.board_slots)
    distinct = {
        (min(a, b), max(a, b), yf, wz0, wz1, top)
        for s in g.board_slots
        for (a, b, yf, wz0, wz1), top in zip(s.windows, s.window_tops_y_mm)
    }
    windows = 0.0
    for lo, hi, yf, wz0, wz1, top in sorted(distinct, key=str):
        end = y_top if top is None else top
        boxes.append(((lo, yf, wz0), (hi, end, wz1)))
        windows += (hi - lo) * (end - yf) * (wz1 - wz0)
        if top is not None:  # the gable: a triangle of base wz1 - wz0 and height its rise
            windows += (hi - lo) * 0.5 * (wz1 - wz0) * (window_roof_apex_y_mm(g, top, wz0, wz1) - top)
    return L * D * g.z_base_top_mm - slot - windows + overlap_volume_mm3(boxes)


def plates_volume_mm3(geometry: SensorGeometry) -> float:
    """Solid plates between layers, each W x D x plate thickness."""
    g = geometry
    return (len(g.layers) - 1) * g.width_mm * g.depth_mm * g.housing.plate_mm


def insert_slot_volume_mm3(geometry: SensorGeometry) -> float:
    """The insert's slot: its box plus the gable over it, a triangular prism of base the plate's
    thickness and height its rise, the slot's width long (0 without an insert)."""
    g = geometry
    if not g.has_insert:
        return 0.0
    (x0, y0, z0), (x1, y1, z1) = g.insert_slot_box_mm
    return (x1 - x0) * (z1 - z0) * ((y1 - y0) + 0.5 * g.insert_slot_roof_rise_mm)


def insert_volume_mm3(geometry: SensorGeometry) -> float:
    """The insert plate's volume, its box (0 without an insert)."""
    if not geometry.has_insert:
        return 0.0
    lo, hi = geometry.insert_box_mm
    return float(np.prod(np.subtract(hi, lo)))


def cap_volume_mm3(geometry: SensorGeometry) -> float:
    """Cap (W x D, from the stack top to the total height) minus the magnet pocket and the
    insert's slot."""
    g = geometry
    block = g.width_mm * g.depth_mm * (g.total_height_mm - g.z_stack_top_mm)
    return block - pocket_volume_mm3(g) - insert_slot_volume_mm3(g)


def body_volume_mm3(geometry: SensorGeometry) -> float:
    """Volume of the one printed TPU body: analytic sum of its parts."""
    g = geometry
    return base_volume_mm3(g) + sum(cell_volume_mm3(c) for c in g.layers) + plates_volume_mm3(g) + cap_volume_mm3(g)


def to_print_frame(geometry: SensorGeometry, points_mm: ArrayLike) -> np.ndarray:
    """Sensor-frame points (..., 3) to the print frame: (x, -z, y + D/2)."""
    p = np.asarray(points_mm, dtype=float)
    return np.stack([p[..., 0], -p[..., 2], p[..., 1] + 0.5 * geometry.depth_mm], axis=-1)
