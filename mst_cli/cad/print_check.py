"""Judging the sliced print: what ``mst slice`` measures in PrusaSlicer's G-code against what
export.json asks for, one :class:`~mst_cli.cad.checks.Check` per question as ``mst check``'s
mesh checks are:

* ``free_span``: no extrusion has more than ``max_span_mm`` of its centreline with nothing of
  the layer below under it;
* ``pause``: exactly the pauses export.json asks for (the magnet's, the insert's), each on its
  layer boundary (none when it asks for none);
* ``support``: the slicer, told to generate support automatically, generates none;
* ``cavity_gaps`` (report only): the designed cavity gaps against the gaps in the sliced layer.
* ``walls_as_sliced`` (report only): every inclined wall's designed thickness against the width
  of the extrusion the G-code lays across it.

Each Check's ``values`` is its section of slice.json; a failed one's ``note`` is the reason.
Pure: G-code and manifest in, Checks out (no slicer, no files).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mst_cli.cad.checks import Check
from mst_cli.cad.gcode import SUPPORT_TYPES, GCode, Pause
from mst_cli.cad.layer_measure import Span, SpanReport, gap_at, material_across
from mst_cli.cad.manifest import SliceManifest, WallLine

Shift = tuple[float, float]  # G-code = print frame + shift (x, y), mm


def expected_pauses(manifest: SliceManifest) -> list[dict]:
    """Every pause export.json asks for, lowest first (print.pauses; an older export's one
    print.pause), else none."""
    given = manifest.print.pauses or ((manifest.print.pause,) if manifest.print.pause is not None else ())
    return [{"after_layer": p.after_layer, "z_mm": p.z_mm, "source": "print.pauses"} for p in given]


def expected_pause(manifest: SliceManifest) -> dict:
    """The first pause export.json asks for (the magnet's), else nothing."""
    return next(iter(expected_pauses(manifest)), {})


def _one_pause_problem(p: Pause, expected: dict, layer_height_mm: float) -> str | None:
    z_ok = abs(p.z_mm - expected["z_mm"]) < 1e-3
    layer_ok = expected.get("after_layer") in (None, p.after_layer)
    boundary = abs(expected["z_mm"] / layer_height_mm - round(expected["z_mm"] / layer_height_mm)) < 1e-3
    if p.mid_layer:
        return f"the pause (G-code line {p.line}) falls in the middle of layer {p.after_layer + 1}"
    if not (z_ok and layer_ok):
        return (
            f"pause after layer {p.after_layer} (z = {p.z_mm:.2f} mm), export.json asks for "
            + (f"layer {expected['after_layer']}, " if expected.get("after_layer") else "")
            + f"z = {expected['z_mm']:.2f} mm"
        )
    if not boundary:
        return f"pause height {expected['z_mm']:.2f} mm is not on a layer boundary"
    return None


def _pause_problem(pauses: list[Pause], expected: list[dict], layer_height_mm: float) -> str | None:
    if not expected:
        return None if len(pauses) <= 1 else f"{len(pauses)} pauses in the G-code, export.json asks for none"
    if not pauses:
        first = expected[0]
        return (
            f"no pause in the G-code (export.json asks for {len(expected)}, the first at z = {first['z_mm']:.2f} mm"
            + (f", after layer {first['after_layer']}" if first.get("after_layer") else "")
            + ")"
        )
    if len(pauses) != len(expected):
        return f"{len(pauses)} pauses in the G-code, export.json asks for {len(expected)}"
    ordered = sorted(pauses, key=lambda p: p.z_mm)
    return next((why for p, e in zip(ordered, expected) if (why := _one_pause_problem(p, e, layer_height_mm))), None)


def check_pause(pauses: list[Pause], manifest: SliceManifest, layer_height_mm: float) -> Check:
    """The pauses found in the G-code against those export.json asks for."""
    expected = expected_pauses(manifest)
    found = [
        {
            "after_layer": p.after_layer,
            "z_mm": round(p.z_mm, 4),
            "command": p.command,
            "mid_layer": p.mid_layer,
            "gcode_line": p.line,
        }
        for p in pauses
    ]
    problem = _pause_problem(pauses, expected, layer_height_mm)
    found_text = (
        ", ".join(
            f"after layer {f['after_layer']} (z {f['z_mm']:.2f} mm"
            f"{', mid-layer' if f['mid_layer'] else ''}) {f['command']}"
            for f in found
        )
        or "none"
    )
    asked = ", ".join(pause_text(e) for e in expected) or "not given"
    return Check(
        "pause",
        problem is None,
        found_text,
        asked,
        problem or "",
        values={
            "found": found,
            "expected": dict(expected[0]) if expected else "not given",
            "expected_all": expected,
            "ok": problem is None,
        },
    )


def pause_text(expected: dict) -> str:
    """One expected pause as the terminal shows it."""
    layer = f"after layer {expected['after_layer']}, " if expected.get("after_layer") else ""
    return f"{layer}z {expected['z_mm']:.2f} mm"


def _span_dict(s: Span | None, shift: Shift) -> dict | None:
    if s is None:
        return None
    return {
        "length_mm": round(s.length_mm, 3),
        "layer": s.layer,
        "z_mm": round(s.z_mm, 4),
        "x_mm": round(s.x_mm - shift[0], 3),
        "y_mm": round(s.y_mm - shift[1], 3),
        "gcode_xy_mm": [round(s.x_mm, 3), round(s.y_mm, 3)],
        "type": s.type,
    }


def check_free_span(spans: SpanReport, joined: SpanReport, max_span_mm: float, shift: Shift) -> Check:
    """The longest free span (``joined``: with travel moves joined) against ``max_span_mm``."""
    s = spans.longest
    too_long = s is not None and s.length_mm > max_span_mm
    note = ""
    if s is not None and too_long:
        note = f"free span {s.length_mm:.1f} mm > {max_span_mm:g} mm (layer {s.layer}, z = {s.z_mm:.2f} mm, {s.type})"
    return Check(
        "free_span",
        not too_long,
        "none (one layer)" if s is None else f"{s.length_mm:.2f} mm",
        f"<= {max_span_mm:g} mm",
        note,
        values={
            "max_allowed_mm": max_span_mm,
            "longest": _span_dict(s, shift),
            "longest_joined_moves": _span_dict(joined.longest, shift),
            "per_layer": [
                {"layer": p.layer, "z_mm": round(p.z_mm, 4), "max_span_mm": round(p.length_mm, 3)}
                for p in spans.per_layer
            ],
        },
    )


def check_support(with_auto_support: GCode) -> Check:
    """The G-code of a second slice with automatic support on holds no support extrusion."""
    g = with_auto_support
    volume = g.type_volume_mm3(SUPPORT_TYPES)
    n = int(sum(np.isin(lay.types, SUPPORT_TYPES).sum() for lay in g.layers))
    layers = [lay.index for lay in g.layers if np.isin(lay.types, SUPPORT_TYPES).any()]
    note = f"the slicer generates {volume:.0f} mm3 of support (layers {layers[0]}-{layers[-1]})" if n else ""
    return Check(
        "support",
        not n,
        f"needed: {volume:.0f} mm3" if n else "none generated",
        "none",
        note,
        values={
            "needed": bool(n),
            "volume_mm3": round(volume, 2),
            "extrusions": n,
            "layers": [layers[0], layers[-1]] if layers else [],
        },
    )


def cavity_gaps(g: GCode, manifest: SliceManifest, shift: Shift, z_shift: float) -> Check:
    """Designed against as-sliced gaps along export.json's print.cavity_lines (report only:
    ``values["lines"]`` is a row per line, or "not given")."""
    lines = manifest.print.cavity_lines
    if not lines:
        return Check(
            "cavity_gaps", True, "-", "not given", "not given in export.json", info=True, values={"lines": "not given"}
        )
    rows = []
    for c in lines:
        layer = g.layer_at(c.z_mm + z_shift)
        row: dict[str, Any] = {
            "layer": c.layer,
            "x_mm": c.x_mm,
            "z_mm": c.z_mm,
            "designed_gap_mm": c.gap_mm,
            "designed_y_mm": [c.y_low_mm, c.y_high_mm],
        }
        if layer is None:
            row.update(sliced_layer=None, sliced_gap_mm=None, sliced_y_mm=None)
        else:
            gap = gap_at(layer, "x", c.x_mm + shift[0], c.y_low_mm + shift[1], c.y_high_mm + shift[1])
            row["sliced_layer"] = layer.index
            if gap is None:
                row.update(sliced_gap_mm=0.0, sliced_y_mm=None)
            else:
                row.update(
                    sliced_gap_mm=round(gap[1] - gap[0], 4),
                    sliced_y_mm=[round(gap[0] - shift[1], 4), round(gap[1] - shift[1], 4)],
                )
        if row.get("designed_gap_mm") is not None and row.get("sliced_gap_mm") is not None:
            row["difference_mm"] = round(row["sliced_gap_mm"] - float(row["designed_gap_mm"]), 4)
        rows.append(row)
    sliced = ", ".join("-" if r["sliced_gap_mm"] is None else f"{r['sliced_gap_mm']:.2f}" for r in rows)
    designed = ", ".join(f"{float(r['designed_gap_mm']):.2f}" for r in rows)
    return Check(
        "cavity_gaps",
        True,
        f"{sliced} mm",
        f"{designed} mm (designed)",
        "gaps along export.json's print.cavity_lines",
        info=True,
        values={"lines": rows},
    )


WALL_STATIONS = 5  # lines across each wall, evenly along the middle of its free stretch
# Extrusion within this of a wall's designed faces may be a neighbour's (the plate beyond a
# narrow notch); what reaches deeper into the wall is the wall.
WALL_FACE_MARGIN_MM = 0.05


def walls_as_sliced(g: GCode, manifest: SliceManifest, shift: Shift, z_shift: float) -> Check:
    """Designed against as-sliced wall thickness along export.json's print.wall_lines (report
    only: ``values["layers"]`` is a row per stack layer with its walls, or "not given").

    A wall's sliced width is the median, over :data:`WALL_STATIONS` lines across it in every
    print layer of its z range, of the run of extrusion that holds its centre line
    (:func:`~mst_cli.cad.layer_measure.material_across`); a layer's is the mean of its walls'."""
    lines = manifest.print.wall_lines
    if not lines:
        return Check(
            "walls_as_sliced",
            True,
            "-",
            "not given",
            "not given in export.json",
            info=True,
            values={"layers": "not given"},
        )
    walls: dict[int, list[dict]] = {}
    for w in lines:
        walls.setdefault(w.layer, []).append(_wall_row(g, w, shift, z_shift))
    rows = [_layer_row(layer, ws) for layer, ws in sorted(walls.items())]
    sliced_text = ", ".join("-" if r["sliced_t_mm"] is None else f"{r['sliced_t_mm']:.3f}" for r in rows)
    designed_text = ", ".join(f"{r['designed_t_mm']:.3f}" for r in rows)
    return Check(
        "walls_as_sliced",
        True,
        f"{sliced_text} mm",
        f"{designed_text} mm (designed)",
        "walls across export.json's print.wall_lines",
        info=True,
        values={"layers": rows},
    )


def _wall_row(g: GCode, w: WallLine, shift: Shift, z_shift: float) -> dict:
    """One wall as sliced: the material across its centre line in every print layer of its z range."""
    samples = []
    for layer in g.layers:
        if not w.z_low_mm < layer.z_mm - z_shift <= w.z_high_mm + 1e-6:
            continue
        samples += material_across(
            layer.segments[layer.of_part()],
            (w.x0_mm + shift[0], w.y0_mm + shift[1]),
            (w.x1_mm + shift[0], w.y1_mm + shift[1]),
            WALL_STATIONS,
            max(0.5 * w.t_mm - WALL_FACE_MARGIN_MM, 0.25 * w.t_mm),
        )
    width = np.array([a.width_mm for a in samples])
    n_lines = np.array([a.n_lines for a in samples], dtype=int)
    row = {"wall": w.wall, "designed_t_mm": w.t_mm, "samples": len(samples)}
    if samples:
        row.update(
            sliced_t_mm=round(float(np.median(width)), 4),
            sliced_t_min_mm=round(float(width.min()), 4),
            sliced_t_max_mm=round(float(width.max()), 4),
            n_lines=int(np.bincount(n_lines).argmax()),
            missing=int((width == 0).sum()),
        )
    else:
        row.update(sliced_t_mm=None, sliced_t_min_mm=None, sliced_t_max_mm=None, n_lines=None, missing=0)
    return row


def _layer_row(layer: int, ws: list[dict]) -> dict:
    """One stack layer: the mean of its walls as designed and as sliced (None if one is missing)."""
    sliced = [r["sliced_t_mm"] for r in ws]
    t = round(float(np.mean(sliced)), 4) if None not in sliced else None
    designed = float(np.mean([r["designed_t_mm"] for r in ws]))
    return {
        "layer": layer,
        "designed_t_mm": designed,
        "sliced_t_mm": t,
        "difference_mm": round(t - designed, 4) if t is not None else None,
        "n_lines": sorted({r["n_lines"] for r in ws if r["n_lines"] is not None}),
        "walls": ws,
    }
