"""Measuring sliced layers: pure kernels on the layers :func:`~mst_cli.cad.gcode.parse_gcode` reads.

* :func:`free_spans` finds, for every extrusion of layer n > 1, the longest stretch of its
  centreline with nothing of layer n - 1 under it (a strand held only at its ends).
* :func:`gaps_along_line` gives the air between extrusions along a line across one layer, to
  compare a designed cavity gap with the one that prints.
* :func:`material_across` gives the material along lines across a wall's centre line, to
  compare a designed wall thickness with the one that prints.

Conventions: the G-code frame (mm, bed coordinates); layers are numbered from 1.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mst_cli.cad.gcode import GCode, Layer


# --------------------------------------------------------------------------- free spans
@dataclass
class Span:
    """The longest unsupported stretch of one layer."""

    layer: int
    z_mm: float
    length_mm: float
    x_mm: float  # midpoint of the stretch
    y_mm: float
    start_xy_mm: tuple[float, float]
    end_xy_mm: tuple[float, float]
    type: str


@dataclass
class SpanReport:
    longest: Span | None  # over all layers (None: nothing above layer 1)
    per_layer: list[Span]  # one per analysed layer (layers 2..), in order


def rasterise(
    segments: np.ndarray, origin_xy: Sequence[float] | np.ndarray, shape: tuple[int, int], px_per_mm: float
) -> np.ndarray:
    """Boolean image (rows: y, cols: x) of the segments drawn as lines of their own width
    with round ends; pixel (r, c) covers [x0 + c/res, x0 + (c+1)/res) x [y0 + r/res, ...)."""
    from PIL import Image, ImageDraw  # deferred: PIL (via matplotlib) only for the span raster

    img = Image.new("1", (int(shape[1]), int(shape[0])), 0)
    draw = ImageDraw.Draw(img)
    ox, oy = origin_xy
    res = px_per_mm
    # pixel centres sit at (c + 0.5)/res: shift by -0.5 px so that geometry maps exactly
    # Edges that fall on a pixel centre are ambiguous: the stroke is drawn half a pixel wider
    # on each side, so material is found up to 1/(2 res) mm beyond the true edge (0.025 mm at
    # 20 px/mm) -- a 0.2 mm step under a 0.45 mm line (45 degrees) is safely supported.
    pts = (segments[:, :4] - np.array([ox, oy, ox, oy])) * res - 0.5
    radius = segments[:, 4] * res / 2 + 0.5
    for (a, b, c, d), r in zip(pts.tolist(), radius.tolist()):
        w = max(1, int(round(2 * r)))
        draw.line((a, b, c, d), fill=1, width=w)
        draw.ellipse((a - r, b - r, a + r, b + r), fill=1)
        draw.ellipse((c - r, d - r, c + r, d + r), fill=1)
    return np.array(img, dtype=bool)


def _samples(segments: np.ndarray, step: float):
    """Midpoints of equal pieces (at most ``step`` long) of every segment, with the piece
    length and the index of its segment, in segment order."""
    d = segments[:, 2:4] - segments[:, 0:2]
    length = np.hypot(d[:, 0], d[:, 1])
    n = np.maximum(1, np.ceil(length / step).astype(np.int64))
    seg_idx = np.repeat(np.arange(len(segments)), n)
    first = np.cumsum(n) - n
    k = np.arange(n.sum()) - np.repeat(first, n)
    t = (k + 0.5) / np.repeat(n, n)
    xy = segments[seg_idx, 0:2] + t[:, None] * d[seg_idx]
    ds = (length / n)[seg_idx]
    return xy, ds, seg_idx


def free_spans(
    gcode: GCode, px_per_mm: float = 20.0, step_mm: float | None = None, join_moves: bool = False
) -> SpanReport:
    """Longest free span of every layer above the first, and overall.

    A point of an extrusion's centreline is supported when the layer below has material
    there (its extrusions drawn at their own width): a 45-degree overhang (0.2 mm step, 0.45 mm
    lines) is supported, a bridge is not. A free span is a contiguous run of unsupported
    centreline within one extrusion move; with ``join_moves`` the run continues over the next
    move of the same path (consecutive extrusion moves with no travel between), so a strand
    that turns a corner in mid-air counts whole. Skirt, wipe tower and custom extrusions are
    ignored, support material counts as material.
    """
    step = step_mm or 1.0 / px_per_mm
    per_layer: list[Span] = []
    for below, layer in zip(gcode.layers[:-1], gcode.layers[1:]):
        keep = layer.of_part()
        segs = layer.segments[keep]
        if len(segs) == 0:
            continue
        xy, ds, si = _samples(segs, step)
        free = ~_supported(below, xy, px_per_mm)
        pid = layer.paths[keep][si] if join_moves else si
        per_layer.append(_longest_run(layer, layer.types[keep], xy, ds, si, free, pid))
    longest = max(per_layer, key=lambda s: s.length_mm) if per_layer else None
    return SpanReport(longest, per_layer)


def _supported(below: Layer, xy: np.ndarray, px_per_mm: float) -> np.ndarray:
    """(n,) True where a point ``xy`` (n, 2) has material of the layer ``below`` under it (its
    part's extrusions rasterised at their own width, ``px_per_mm``)."""
    bsegs = below.segments[below.of_part()]
    supported = np.zeros(len(xy), dtype=bool)
    if not len(bsegs):
        return supported
    margin = float(bsegs[:, 4].max()) + 2.0 / px_per_mm
    lo = np.minimum(bsegs[:, [0, 1]].min(0), bsegs[:, [2, 3]].min(0)) - margin
    hi = np.maximum(bsegs[:, [0, 1]].max(0), bsegs[:, [2, 3]].max(0)) + margin
    shape = (int(math.ceil((hi[1] - lo[1]) * px_per_mm)) + 1, int(math.ceil((hi[0] - lo[0]) * px_per_mm)) + 1)
    mask = rasterise(bsegs, lo, shape, px_per_mm)
    col = np.floor((xy[:, 0] - lo[0]) * px_per_mm).astype(np.int64)
    row = np.floor((xy[:, 1] - lo[1]) * px_per_mm).astype(np.int64)
    inside = (col >= 0) & (col < shape[1]) & (row >= 0) & (row < shape[0])
    supported[inside] = mask[row[inside], col[inside]]
    return supported


def _longest_run(
    layer: Layer,
    types: np.ndarray,
    xy: np.ndarray,
    ds: np.ndarray,
    si: np.ndarray,
    free: np.ndarray,
    pid: np.ndarray,
) -> Span:
    """The longest run of ``free`` samples (``xy`` (n, 2), each ``ds`` long, of segment ``si``)
    that stays on one ``pid`` (a move, or a path); a zero Span when nothing is free."""
    if not free.any():
        return Span(layer.index, layer.z_mm, 0.0, math.nan, math.nan, (math.nan, math.nan), (math.nan, math.nan), "")
    same_path_prev = np.r_[False, pid[1:] == pid[:-1]]
    prev_free = np.r_[False, free[:-1]]
    start = free & ~(prev_free & same_path_prev)
    run_id = np.cumsum(start) - 1
    lengths = np.bincount(run_id[free], weights=ds[free])
    best = int(np.argmax(lengths))
    idx = np.flatnonzero(free & (run_id == best))
    a, b = idx[0], idx[-1]
    # the run's ends: half a piece beyond the first and last sample
    pa = xy[a] - (xy[min(a + 1, b)] - xy[a]) * 0.5 if b > a else xy[a]
    pb = xy[b] + (xy[b] - xy[max(b - 1, a)]) * 0.5 if b > a else xy[b]
    mid = xy[idx[len(idx) // 2]]
    return Span(
        layer.index,
        layer.z_mm,
        float(lengths[best]),
        float(mid[0]),
        float(mid[1]),
        (float(pa[0]), float(pa[1])),
        (float(pb[0]), float(pb[1])),
        str(types[si[a]]),
    )


# --------------------------------------------------------------------------- gaps on a line
def _stroke_spans(segments: np.ndarray, axis: str, value: float) -> tuple[np.ndarray, np.ndarray]:
    """Where the line {axis = value} crosses each extrusion (centreline +- width/2, round ends):
    per segment (lo, hi) of the other coordinate, lo > hi where it misses."""
    if axis not in ("x", "y"):
        raise ValueError("axis must be 'x' or 'y'")
    s = segments.astype(float)
    if axis == "y":  # swap roles: the line y = value, measure along x
        s = s[:, [1, 0, 3, 2, 4]]
    p0, p1, r = s[:, 0:2], s[:, 2:4], s[:, 4] / 2
    lo = np.full(len(s), np.inf)
    hi = np.full(len(s), -np.inf)
    # the two end discs
    for p in (p0, p1):
        dx = value - p[:, 0]
        h2 = r**2 - dx**2
        ok = h2 >= 0
        h = np.sqrt(np.where(ok, h2, 0))
        lo = np.where(ok, np.minimum(lo, p[:, 1] - h), lo)
        hi = np.where(ok, np.maximum(hi, p[:, 1] + h), hi)
    # the body: rectangle p0 -> p1 of half-width r
    d = p1 - p0
    length = np.hypot(d[:, 0], d[:, 1])
    nz = length > 0
    n = np.zeros_like(d)
    n[nz] = np.stack([-d[nz, 1], d[nz, 0]], axis=1) / length[nz, None]
    corners = np.stack(
        [p0 + n * r[:, None], p1 + n * r[:, None], p1 - n * r[:, None], p0 - n * r[:, None]], axis=1
    )  # (k, 4, 2)
    a = corners
    b = np.roll(corners, -1, axis=1)
    xa, ya, xb, yb = a[..., 0], a[..., 1], b[..., 0], b[..., 1]
    cross = ((xa - value) * (xb - value) <= 0) & (xa != xb)
    t = np.where(cross, (value - xa) / np.where(xa != xb, xb - xa, 1.0), 0.0)
    yc = ya + t * (yb - ya)
    ylo = np.where(cross, yc, np.inf).min(axis=1)
    yhi = np.where(cross, yc, -np.inf).max(axis=1)
    body = nz & np.isfinite(ylo)
    lo = np.where(body, np.minimum(lo, ylo), lo)
    hi = np.where(body, np.maximum(hi, yhi), hi)
    return lo, hi


def _merge(iv: np.ndarray) -> np.ndarray:
    """Sorted, merged (m, 2) intervals of (k, 2) ones."""
    if len(iv) == 0:
        return iv.reshape(0, 2)
    iv = iv[np.argsort(iv[:, 0])]
    merged = [list(iv[0])]
    for l, h in iv[1:]:
        if l <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], h)
        else:
            merged.append([l, h])
    return np.array(merged)


def covered_intervals(segments: np.ndarray, axis: str, value: float) -> np.ndarray:
    """Where the line {axis = value} crosses the extrusions (centreline +- width/2, round
    ends): (m, 2) sorted, merged intervals of the other coordinate."""
    if axis not in ("x", "y"):
        raise ValueError("axis must be 'x' or 'y'")
    if len(segments) == 0:
        return np.zeros((0, 2))
    lo, hi = _stroke_spans(segments, axis, value)
    hit = hi >= lo
    return _merge(np.stack([lo[hit], hi[hit]], axis=1))


@dataclass
class Across:
    """The material a line across a wall meets: the runs of extrusion inside the wall, from the
    first one's outer edge to the last one's (``offset_mm``, signed distance from the centre
    line), and how many extrusion centrelines cross the line between them."""

    width_mm: float  # 0.0: no extrusion reaches into the wall's core
    n_lines: int
    offset_mm: tuple[float, float] | None


def material_across(
    segments: np.ndarray, start_xy: tuple[float, float], end_xy: tuple[float, float], stations: int, core_mm: float
) -> list[Across]:
    """At ``stations`` points evenly along the centre line start -> end (one at its midpoint
    when the two coincide), the wall along the line perpendicular to it: the merged extrusion
    strokes (each its own width, round ends) that reach into its core, within ``core_mm`` of
    the centre line, measured from the outer edge of the first to that of the last.

    That is the wall as the slicer lays it down: one line of width w gives w, overlapping
    perimeters their outer edges' distance (not the sum of their widths, which counts the overlap
    twice), and the small voids a zig-zag infill leaves at its turns stay inside the wall.
    Material beyond air outside the core (a plate, the pad) is not the wall."""
    a, b = np.asarray(start_xy, dtype=float), np.asarray(end_xy, dtype=float)
    length = float(np.hypot(*(b - a)))
    u = (b - a) / length if length > 0 else np.array([1.0, 0.0])
    n = np.array([-u[1], u[0]])
    s = np.asarray(segments, dtype=float).reshape(-1, 5)
    rel0, rel1 = s[:, 0:2] - a, s[:, 2:4] - a
    # the segments in (along, across) coordinates: the line across at 'along = station'
    sr = np.column_stack([rel0 @ u, rel0 @ n, rel1 @ u, rel1 @ n, s[:, 4]])
    out = []
    for station in np.linspace(0.0, length, stations) if length > 0 and stations > 1 else [0.5 * length]:
        lo, hi = _stroke_spans(sr, "x", float(station)) if len(sr) else (np.zeros(0), np.zeros(0))
        hit = hi >= lo
        runs = _merge(np.stack([lo[hit], hi[hit]], axis=1))
        wall = runs[(runs[:, 1] > -core_mm) & (runs[:, 0] < core_mm)] if len(runs) else runs
        if not len(wall):
            out.append(Across(0.0, 0, None))
            continue
        r0, r1 = float(wall[0, 0]), float(wall[-1, 1])
        # centrelines crossing the line inside the wall (half-open along: a shared vertex counts once)
        s0, s1 = sr[:, 0], sr[:, 2]
        crosses = (np.minimum(s0, s1) <= station) & (station < np.maximum(s0, s1))
        f = np.where(crosses, (station - s0) / np.where(s1 != s0, s1 - s0, 1.0), 0.0)
        r_at = sr[:, 1] + f * (sr[:, 3] - sr[:, 1])
        n_lines = int(np.sum(crosses & (r_at >= r0) & (r_at <= r1)))
        out.append(Across(r1 - r0, n_lines, (r0, r1)))
    return out


def gaps_along_line(
    layer: Layer, axis: str, value: float, lo: float | None = None, hi: float | None = None
) -> list[tuple[float, float]]:
    """Air intervals between the part's extrusions of ``layer`` along the line {axis = value}
    (e.g. axis 'x', value 3.0: the line x = 3 and intervals in y), optionally only inside
    [lo, hi]. Only gaps bounded by material on both sides are returned."""
    iv = covered_intervals(layer.segments[layer.of_part()], axis, value)
    gaps = [(float(a), float(b)) for (_, a), (b, _) in zip(iv[:-1], iv[1:])]
    if lo is not None:
        gaps = [(max(a, lo), b) for a, b in gaps if b > lo]
    if hi is not None:
        gaps = [(a, min(b, hi)) for a, b in gaps if a < hi]
    return [(a, b) for a, b in gaps if b > a]


def gap_at(layer: Layer, axis: str, value: float, low: float, high: float) -> tuple[float, float] | None:
    """The as-sliced air interval along the line that best matches the designed gap
    [low, high]: the one overlapping it most (None when no air overlaps it)."""
    best, best_overlap = None, 0.0
    for a, b in gaps_along_line(layer, axis, value):
        overlap = min(b, high) - max(a, low)
        if overlap > best_overlap:
            best, best_overlap = (a, b), overlap
    return best
