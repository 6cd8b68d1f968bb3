"""Reading PrusaSlicer G-code and judging what it would print: pure kernels, no CLI, no slicer.

* :func:`parse_gcode` turns G-code text into layers of extrusion segments
  ``(x0, y0, x1, y1, width_mm)`` with their feature type (``;TYPE:``), the filament each one
  pushes, the path each belongs to, the pause commands and the footer (print time, filament).
* :func:`free_spans` finds, for every extrusion of layer n > 1, the longest stretch of its
  centreline with nothing of layer n - 1 under it (a strand held only at its ends).
* :func:`gaps_along_line` gives the air between extrusions along a line across one layer, to
  compare a designed cavity gap with the one that prints.
* :func:`material_across` gives the material along lines across a wall's centre line, to
  compare a designed wall thickness with the one that prints.

Conventions: the G-code frame (mm, bed coordinates); layers are numbered from 1 and carry the
height of their top (``;Z:``). A pause found at the start of layer k is reported as "after
layer k - 1 whose top is at z".
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

DEFAULT_PAUSE_GCODE = "M601"
FILAMENT_DIAMETER_MM = 1.75

# Feature types that are not part of the part (never need support, never give support).
NOT_PART = ("Skirt/Brim", "Wipe tower", "Custom")
SUPPORT_TYPES = ("Support material", "Support material interface")


@dataclass
class Layer:
    """One printed layer: its index from 1, the height of its top and its extrusions."""

    index: int
    z_mm: float
    height_mm: float
    segments: np.ndarray  # (n, 5): x0, y0, x1, y1, width_mm
    types: np.ndarray  # (n,) feature type strings
    e_mm: np.ndarray  # (n,) filament length pushed by each segment
    paths: np.ndarray  # (n,) path id: consecutive segments with no travel between

    @property
    def z_bottom_mm(self) -> float:
        return self.z_mm - self.height_mm

    def of_part(self) -> np.ndarray:
        """Boolean mask of the segments that belong to the part (no skirt, wipe tower, custom)."""
        return ~np.isin(self.types, NOT_PART)


@dataclass
class Pause:
    """A pause command: the line it is on, the command, and where it falls."""

    line: int  # 1-based line number in the G-code
    command: str
    after_layer: int  # layers wholly printed before the pause (0: before layer 1)
    z_mm: float  # top of that layer (0.0 for the bed)
    mid_layer: bool  # True when part of the layer being printed precedes it


@dataclass
class GCode:
    layers: list[Layer]
    pauses: list[Pause]
    print_time_s: float | None = None
    filament_mm: float | None = None
    filament_cm3: float | None = None
    filament_g: float | None = None
    config: dict[str, str] = field(default_factory=dict)

    def layer_at(self, z_mm: float) -> Layer | None:
        """The layer that prints height z_mm: z_bottom < z <= z_top (to 1e-6 mm)."""
        for layer in self.layers:
            if layer.z_bottom_mm + 1e-6 < z_mm <= layer.z_mm + 1e-6:
                return layer
        return None

    def type_volume_mm3(self, types: Iterable[str]) -> float:
        """Volume of filament pushed by extrusions of the given feature types, mm3."""
        diameter = _float_or(self.config.get("filament_diameter", "").split(",")[0], FILAMENT_DIAMETER_MM)
        area = math.pi * diameter**2 / 4
        return float(sum(lay.e_mm[np.isin(lay.types, list(types))].sum() for lay in self.layers) * area)


def _float_or(text: str, default):
    try:
        return float(text)
    except (TypeError, ValueError):
        return default


# Commands that may be part of a pause_print_gcode macro but are no pause by themselves.
_NOT_PAUSE = {
    "G0",
    "G1",
    "G2",
    "G3",
    "G4",
    "G90",
    "G91",
    "G92",
    "M82",
    "M83",
    "M117",
    "M400",
    "M104",
    "M109",
    "M140",
    "M190",
    "M106",
    "M107",
}

_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")
_TIME_PART = re.compile(r"(\d+)\s*([dhms])")


def parse_duration_s(text: str) -> float | None:
    """'1h 14m 15s' (PrusaSlicer's format, also with d) -> seconds."""
    parts = _TIME_PART.findall(text)
    if not parts:
        return None
    scale = {"d": 86400, "h": 3600, "m": 60, "s": 1}
    return float(sum(int(n) * scale[u] for n, u in parts))


def pause_commands(config: dict[str, str], extra: Iterable[str] = ()) -> set[str]:
    """The commands (first word, upper case) that pause the print under this config."""
    commands = {DEFAULT_PAUSE_GCODE}
    text = config.get("pause_print_gcode")
    if text is not None:
        commands = set()
        for line in text.replace("\\n", "\n").splitlines():
            word = line.split(";", 1)[0].strip().split()
            if word:
                commands.add(word[0].upper())
    commands.update(c.upper() for c in extra)
    return commands


def _footer_config(lines: list[str]) -> dict[str, str]:
    """The ``; key = value`` settings PrusaSlicer writes at the end of the G-code."""
    config: dict[str, str] = {}
    start = 0
    for i in range(len(lines) - 1, -1, -1):
        if lines[i].startswith("; prusaslicer_config = begin"):
            start = i + 1
            break
    else:
        # older files: the settings follow the last 'estimated printing time' line
        for i in range(len(lines) - 1, -1, -1):
            if lines[i].startswith("; estimated printing time"):
                start = i + 1
                break
        else:
            return config
    for line in lines[start:]:
        if line.startswith("; ") and " = " in line:
            key, value = line[2:].split(" = ", 1)
            if key == "prusaslicer_config":
                continue
            config[key.strip()] = value
    return config


def parse_gcode(text: str, pause_gcode: str | None = None) -> GCode:
    """Layers, extrusion segments, pauses and footer of PrusaSlicer G-code.

    Understands G0/G1 with X Y Z E F, G90/G91 (positions; also E unless M82/M83 follow),
    M82/M83 (absolute/relative E), G92 (set positions, usually E0), and PrusaSlicer's comments
    ``;LAYER_CHANGE``, ``;Z:``, ``;HEIGHT:``, ``;TYPE:``, ``;WIDTH:``, ``;PAUSE_PRINT``.
    A move extrudes when E increases and X/Y change. Extrusions before the first
    ``;LAYER_CHANGE`` (start G-code) are ignored. ``pause_gcode``: the pause_print_gcode
    to look for [default: the file's own setting, else M601].
    """
    lines = text.splitlines()
    config = _footer_config(lines)
    config_for_pause = {"pause_print_gcode": pause_gcode} if pause_gcode is not None else config
    reader = _GCodeReader(pause_commands(config_for_pause) - _NOT_PAUSE)
    for lineno, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        if line[0] == ";":
            reader.comment(lineno, line[1:])
            continue
        code = line.split(";", 1)[0].strip()
        if code:
            reader.command(lineno, code)
    layers = _layers(reader.layers_raw)
    for pause in reader.pauses:
        pause.z_mm = layers[pause.after_layer - 1].z_mm if pause.after_layer >= 1 else 0.0
    footer = reader.footer
    return GCode(layers, reader.pauses, footer.time_s, footer.fil_mm, footer.fil_cm3, footer.fil_g, config)


@dataclass
class _RawLayer:
    """A layer as read: its ``;Z:`` and ``;HEIGHT:`` (None until given) and its extrusions."""

    z: float | None = None
    h: float | None = None
    seg: list[tuple[float, float, float, float, float]] = field(default_factory=list)
    type: list[str] = field(default_factory=list)
    e: list[float] = field(default_factory=list)
    path: list[int] = field(default_factory=list)


@dataclass
class _Footer:
    """The print time and filament PrusaSlicer states in its closing comments."""

    time_s: float | None = None
    fil_mm: float | None = None
    fil_cm3: float | None = None
    fil_g: float | None = None

    def read(self, c: str) -> None:
        """Take the value of one comment (``c``: the text after ';') if it states one."""
        if c.startswith(" estimated printing time (normal mode)"):
            self.time_s = parse_duration_s(c.split("=", 1)[1])
        elif c.startswith(" filament used [mm]"):
            self.fil_mm = _float_or(c.split("=", 1)[1].split(",")[0], None)
        elif c.startswith(" filament used [cm3]"):
            self.fil_cm3 = _float_or(c.split("=", 1)[1].split(",")[0], None)
        elif c.startswith(" total filament used [g]"):
            self.fil_g = _float_or(c.split("=", 1)[1], None)
        elif c.startswith(" filament used [g]") and self.fil_g is None:
            self.fil_g = _float_or(c.split("=", 1)[1].split(",")[0], None)


def _words(code: str, head: str) -> dict[str, float]:
    """The letter -> number words of a G-code command after its head (``X1.5 E.2`` -> X, E)."""
    return {k.upper(): float(v) for k, v in _WORD.findall(code[len(head) :])}


class _GCodeReader:
    """The state of the print head line by line: position, E, modes, the layer being printed."""

    def __init__(self, pause_words: set[str]):
        self.pause_words = pause_words
        self.x = self.y = self.z = 0.0
        self.e = 0.0
        self.abs_xyz = True
        self.abs_e = True
        self.width = 0.45
        self.ftype = ""
        self.path = 0
        self.last_was_extrusion = False
        self.layers_raw: list[_RawLayer] = []
        self.cur: _RawLayer | None = None
        self.pauses: list[Pause] = []
        self.footer = _Footer()

    def _pause_here(self, lineno: int, command: str) -> Pause:
        started = self.cur is not None and bool(self.cur.seg)
        done = len(self.layers_raw) - 1 if self.cur is not None else 0
        return Pause(lineno, command, done, 0.0, started)

    def comment(self, lineno: int, c: str) -> None:
        """One comment line (``c``: the text after ';')."""
        cur = self.cur
        if c.startswith("LAYER_CHANGE"):
            self.cur = _RawLayer()
            self.layers_raw.append(self.cur)
            self.last_was_extrusion = False
            self.path += 1
        elif c.startswith("Z:") and cur is not None and cur.z is None:
            cur.z = _float_or(c[2:], None)
        elif c.startswith("HEIGHT:") and cur is not None and cur.h is None:
            cur.h = _float_or(c[7:], None)
        elif c.startswith("TYPE:"):
            self.ftype = c[5:].strip()
        elif c.startswith("WIDTH:"):
            self.width = _float_or(c[6:], self.width)
        elif c.startswith("PAUSE_PRINT"):
            self.pauses.append(self._pause_here(lineno, ";PAUSE_PRINT"))
        else:
            self.footer.read(c)

    def command(self, lineno: int, code: str) -> None:
        """One G-code command (comment stripped)."""
        head = code.split(None, 1)[0].upper()
        if head in ("G1", "G0"):
            self._move(_words(code, head))
        elif head in ("G90", "G91"):
            self.abs_xyz = self.abs_e = head == "G90"
        elif head in ("M82", "M83"):
            self.abs_e = head == "M82"
        elif head == "G92":
            words = _words(code, head)
            self.e = words.get("E", self.e if words else 0.0)
            self.x = words.get("X", self.x)
            self.y = words.get("Y", self.y)
            self.z = words.get("Z", self.z)
        if head in self.pause_words:
            recent = self.pauses[-1] if self.pauses else None
            if recent is not None and recent.command == ";PAUSE_PRINT" and lineno - recent.line <= 10:
                recent.command = head  # the command PrusaSlicer wrote for it
            else:
                self.pauses.append(self._pause_here(lineno, head))
            self.last_was_extrusion = False

    def _axis(self, words: dict[str, float], key: str, now: float) -> float:
        if key not in words:
            return now
        return words[key] if self.abs_xyz else now + words[key]

    def _move(self, words: dict[str, float]) -> None:
        """G0/G1: the new position; an extrusion segment when E increases and X/Y change."""
        x, y = self.x, self.y
        nx, ny, nz = self._axis(words, "X", x), self._axis(words, "Y", y), self._axis(words, "Z", self.z)
        de = 0.0
        if "E" in words:
            de = words["E"] - self.e if self.abs_e else words["E"]
            self.e = words["E"] if self.abs_e else self.e + words["E"]
        moved_xy = nx != x or ny != y
        cur = self.cur
        if moved_xy and de > 0 and cur is not None:
            if not self.last_was_extrusion:
                self.path += 1
            cur.seg.append((x, y, nx, ny, self.width))
            cur.type.append(self.ftype)
            cur.e.append(de)
            cur.path.append(self.path)
            self.last_was_extrusion = True
        elif moved_xy:
            self.last_was_extrusion = False
        self.x, self.y, self.z = nx, ny, nz


def _layers(layers_raw: list[_RawLayer]) -> list[Layer]:
    """The layers read, numbered from 1, a missing ``;Z:``/``;HEIGHT:`` taken from the other."""
    layers: list[Layer] = []
    prev_z = 0.0
    for i, raw in enumerate(layers_raw, start=1):
        zt = raw.z if raw.z is not None else prev_z + (raw.h or 0.0)
        h = raw.h if raw.h is not None else zt - prev_z
        seg = np.array(raw.seg, dtype=float).reshape(-1, 5)
        layers.append(
            Layer(
                i,
                float(zt),
                float(h),
                seg,
                np.array(raw.type, dtype=object),
                np.array(raw.e, dtype=float),
                np.array(raw.path, dtype=np.int64),
            )
        )
        prev_z = zt
    return layers


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
