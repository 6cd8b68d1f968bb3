"""``mst slice``: slice an export with PrusaSlicer and judge whether it prints.

The slicer runs twice: as the profile says (the G-code that is written and measured), and
with automatic support switched on, to prove that none would be generated. The G-code kernels
are in :mod:`mst_cli.cad.gcode`; running PrusaSlicer is :mod:`mst_cli.cad.slicer`. matplotlib is
imported only to draw print.png.
"""

from __future__ import annotations

import contextlib
import json
import math
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

import click

from mst_cli.cli.common import EXIT_FAULT, EXIT_TARGETS, handles_input_errors, no_plot_option, one_line

if TYPE_CHECKING:
    from mst_cli.cad.gcode import GCode
    from mst_cli.cad.manifest import SliceManifest

DEFAULT_MAX_SPAN_MM = 5.0
MODEL_NAMES = ("sensor.3mf", "sensor.stl")


def _progress(t0: float, message: str) -> None:
    click.echo(f"[{time.perf_counter() - t0:5.2f} s] {message}", err=True)


def _fmt_time(seconds: float | None) -> str:
    if seconds is None:
        return "unknown"
    s = int(round(seconds))
    return f"{s // 3600}h {s % 3600 // 60:02d}m {s % 60:02d}s" if s >= 3600 else f"{s // 60}m {s % 60:02d}s"


def resolve_export(path: Path) -> tuple[Path, Path, Path | None, Path | None]:
    """(folder, export.json, sensor.3mf or None, sensor.stl or None) of an 'mst export' folder."""
    from mst_cli.errors import InputError
    folder = path if path.is_dir() else path.parent
    if not folder.is_dir():
        raise InputError("PATH", str(path), "no such folder: give the folder 'mst export' wrote")
    manifest = folder / "export.json"
    three_mf = folder / "sensor.3mf"
    stl = folder / "sensor.stl"
    if not (three_mf.is_file() or stl.is_file()):
        raise InputError("PATH", str(folder), "holds neither sensor.3mf nor sensor.stl: "
                                              "run 'mst export DESIGN.yaml --3mf --stl --out DIR' first")
    if not manifest.exists():
        raise InputError("PATH", str(folder), "holds no export.json: run 'mst export' again into this folder")
    return folder, manifest, three_mf if three_mf.is_file() else None, stl if stl.is_file() else None


def expected_pause(manifest: SliceManifest) -> dict:
    """The pause export.json asks for (print.pause {after_layer, z_mm}), else nothing."""
    pause = manifest.print.pause
    if pause is None:
        return {}
    return {"after_layer": pause.after_layer, "z_mm": pause.z_mm, "source": "print.pause"}


def judge_pause(pauses, expected: dict, layer_height_mm: float) -> tuple[dict, str | None]:
    """Report of the pauses found against the one asked for, and the broken limit (or None)."""
    found = [{"after_layer": p.after_layer, "z_mm": round(p.z_mm, 4), "command": p.command,
              "mid_layer": p.mid_layer, "gcode_line": p.line} for p in pauses]
    report = {"found": found, "expected": {k: v for k, v in expected.items()} if expected else "not given"}
    problem = None
    if not expected:
        problem = None if len(pauses) <= 1 else f"{len(pauses)} pauses in the G-code, export.json asks for none"
    elif not pauses:
        problem = (f"no pause in the G-code (export.json asks for one at z = {expected['z_mm']:.2f} mm"
                   + (f", after layer {expected['after_layer']}" if expected.get("after_layer") else "") + ")")
    elif len(pauses) > 1:
        problem = f"{len(pauses)} pauses in the G-code, export.json asks for one"
    else:
        p = pauses[0]
        z_ok = abs(p.z_mm - expected["z_mm"]) < 1e-3
        layer_ok = expected.get("after_layer") in (None, p.after_layer)
        boundary = abs(expected["z_mm"] / layer_height_mm - round(expected["z_mm"] / layer_height_mm)) < 1e-3
        if p.mid_layer:
            problem = f"the pause (G-code line {p.line}) falls in the middle of layer {p.after_layer + 1}"
        elif not (z_ok and layer_ok):
            problem = (f"pause after layer {p.after_layer} (z = {p.z_mm:.2f} mm), export.json asks for "
                       + (f"layer {expected['after_layer']}, " if expected.get("after_layer") else "")
                       + f"z = {expected['z_mm']:.2f} mm")
        elif not boundary:
            problem = f"pause height {expected['z_mm']:.2f} mm is not on a layer boundary"
    report["ok"] = problem is None
    return report, problem


def cavity_gap_report(g: GCode, manifest: SliceManifest, shift_xy: tuple[float, float],
                      z_shift: float) -> str | list[dict]:
    """Designed against as-sliced gaps along export.json's print.cavity_lines."""
    from mst_cli.cad.gcode import gap_at
    lines = manifest.print.cavity_lines
    if not lines:
        return "not given"
    rows = []
    for c in lines:
        layer = g.layer_at(c.z_mm + z_shift)
        row = {"layer": c.layer, "x_mm": c.x_mm, "z_mm": c.z_mm,
               "designed_gap_mm": c.gap_mm, "designed_y_mm": [c.y_low_mm, c.y_high_mm]}
        if layer is None:
            row.update(sliced_layer=None, sliced_gap_mm=None, sliced_y_mm=None)
        else:
            gap = gap_at(layer, "x", c.x_mm + shift_xy[0], c.y_low_mm + shift_xy[1], c.y_high_mm + shift_xy[1])
            row["sliced_layer"] = layer.index
            if gap is None:
                row.update(sliced_gap_mm=0.0, sliced_y_mm=None)
            else:
                row.update(sliced_gap_mm=round(gap[1] - gap[0], 4),
                           sliced_y_mm=[round(gap[0] - shift_xy[1], 4), round(gap[1] - shift_xy[1], 4)])
        if row.get("designed_gap_mm") is not None and row.get("sliced_gap_mm") is not None:
            row["difference_mm"] = round(row["sliced_gap_mm"] - float(row["designed_gap_mm"]), 4)
        rows.append(row)
    return rows


def plot_print(path: Path, triangles, bed_xy, shift_xyz, g, spans, title: str) -> None:
    """print.png: the part on the bed (3D) and plan views of a mid layer's paths and of the
    layer with the longest free span, coloured by feature type."""
    import matplotlib
    matplotlib.use("Agg")
    import numpy as np
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    tri = triangles + np.asarray(shift_xyz)
    fig = Figure(figsize=(16, 5.6), dpi=110)
    ax = fig.add_subplot(1, 3, 1, projection="3d")
    coll = Poly3DCollection(tri, facecolor="#5fa8d3", edgecolor="none", alpha=1.0)
    # simple shading by the normal's z component
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    light = 0.45 + 0.55 * np.clip(n @ np.array([0.3, -0.5, 0.8]), 0, 1)
    coll.set_facecolor(np.c_[0.37 * light, 0.66 * light, 0.83 * light, np.ones_like(light)])
    ax.add_collection3d(coll)
    lo, hi = tri.reshape(-1, 3).min(0), tri.reshape(-1, 3).max(0)
    pad = 0.25 * max(hi[0] - lo[0], hi[1] - lo[1])
    bx = [lo[0] - pad, hi[0] + pad]
    by = [lo[1] - pad, hi[1] + pad]
    ax.plot([bx[0], bx[1], bx[1], bx[0], bx[0]], [by[0], by[0], by[1], by[1], by[0]], [0] * 5, color="0.4")
    ax.set_xlim(*bx)
    ax.set_ylim(*by)
    ax.set_zlim(0, max(hi[2], 1.0))
    with contextlib.suppress(AttributeError):       # matplotlib < 3.3 has no box aspect
        ax.set_box_aspect((bx[1] - bx[0], by[1] - by[0], max(hi[2], 1.0)))
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    ax.set_title(f"{title}\nas it sits on the bed (bed centre {bed_xy[0]:g}, {bed_xy[1]:g} mm)", fontsize=9)

    colours = {"External perimeter": "#d62728", "Perimeter": "#ff7f0e", "Overhang perimeter": "#1f77b4",
               "Internal infill": "#8c564b", "Solid infill": "#9467bd", "Top solid infill": "#e377c2",
               "Bridge infill": "#17becf", "Gap fill": "#2ca02c", "Skirt/Brim": "#7f7f7f",
               "Support material": "#bcbd22", "Support material interface": "#dbdb8d"}
    layers = [lay for lay in g.layers if len(lay.segments)]
    mid = layers[len(layers) // 2] if layers else None
    worst = spans.longest
    worst_layer = next((lay for lay in g.layers if worst is not None and lay.index == worst.layer), None)
    panels = [(mid, "mid layer")]
    if worst_layer is not None and worst_layer is not mid and worst.length_mm > 0:
        panels.append((worst_layer, "longest free span"))
    else:
        panels.append((None, ""))
    for k, (layer, what) in enumerate(panels):
        ax2 = fig.add_subplot(1, 3, 2 + k)
        if layer is None:
            ax2.axis("off")
            continue
        seen = set()
        for t in sorted(set(layer.types.tolist())):
            sel = layer.types == t
            segs = layer.segments[sel]
            lc = LineCollection(segs[:, :4].reshape(-1, 2, 2), colors=colours.get(t, "k"),
                                linewidths=1.2, label=t if t not in seen else None)
            seen.add(t)
            ax2.add_collection(lc)
        if worst is not None and worst.layer == layer.index and worst.length_mm > 0:
            (xa, ya), (xb, yb) = worst.start_xy_mm, worst.end_xy_mm
            ax2.plot([xa, xb], [ya, yb], color="k", lw=3, alpha=0.5,
                     label=f"free span {worst.length_mm:.1f} mm")
        part = layer.segments[layer.of_part()] if layer.of_part().any() else layer.segments
        ax2.set_xlim(part[:, [0, 2]].min() - 1, part[:, [0, 2]].max() + 1)
        ax2.set_ylim(part[:, [1, 3]].min() - 1, part[:, [1, 3]].max() + 1)
        ax2.set_aspect("equal")
        ax2.set_xlabel("bed x (mm)")
        ax2.set_ylabel("bed y (mm)")
        ax2.set_title(f"{what}: layer {layer.index}, z = {layer.z_mm:.2f} mm (G-code paths)", fontsize=9)
        ax2.legend(fontsize=6, loc="upper right")
    fig.tight_layout()
    fig.savefig(path)


@click.command("slice")
@click.argument("path", type=click.Path(path_type=Path))
@click.option("--profile", "profile", type=click.Path(path_type=Path), default=None,
              help="PrusaSlicer config (.ini) [default: configs/print/tpu85a-0.4mm.ini, TPU 85A].")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder [default: PATH].")
@click.option("--max-span", "max_span_mm", type=float, default=DEFAULT_MAX_SPAN_MM, show_default=True,
              help="Longest free span allowed (extrusion with nothing under it), mm.")
@click.option("--json", "as_json", is_flag=True, help="Print slice.json instead of the summary.")
@no_plot_option("print.png", "about 0.8 s: matplotlib and a 3D view of the part", has_json=True)
@handles_input_errors
def slice_(path: Path, profile: Path | None, out_dir: Path | None, max_span_mm: float, as_json: bool,
           no_plot: bool) -> None:
    """Slice the body 'mst export' wrote (PATH: its folder) with PrusaSlicer and judge it.

    Slices sensor.3mf (which carries the magnet pause; sensor.stl if there is no 3MF) with the
    profile and writes sensor.gcode, slice.json (print time, filament, layers, longest free
    span and where, the pause found against the one export.json asks for, support, designed
    against as-sliced cavity gaps) and print.png (not with --no-plot). Slices a
    second time with automatic support on to prove that none is needed. Exit 1 naming the
    broken limit (free span over --max-span, pause missing or misplaced, support needed);
    exit 2 when PrusaSlicer is not installed, the profile is not a PrusaSlicer config or
    export.json is malformed (checked before slicing, with mst check's rules); exit 1 when
    PrusaSlicer misbehaves (no G-code, an empty or truncated one). A profile's post_process
    scripts run as PrusaSlicer runs them; one line names them.
    """
    from mst_cli.cad import slicer as S
    try:
        _slice(path, profile, out_dir, max_span_mm, as_json, no_plot)
    except S.SlicerError as exc:
        click.echo(one_line(f"mst slice: {exc}; nothing was written"), err=True)
        sys.exit(EXIT_FAULT)


def _slice(path: Path, profile: Path | None, out_dir: Path | None, max_span_mm: float, as_json: bool,
           no_plot: bool) -> None:
    import numpy as np

    from mst_cli.cad import gcode as G
    from mst_cli.cad import slicer as S
    from mst_cli.cad.manifest import SliceManifest, load_manifest
    from mst_cli.errors import InputError
    from mst_cli.io.outputs import staged

    if not 0 < max_span_mm <= 1000:
        raise InputError("--max-span", max_span_mm, "must be a length from 0 to 1000 mm")
    t0 = time.perf_counter()
    exe = S.find_prusa_slicer()
    profile = Path(profile) if profile is not None else S.bundled_profile()
    settings = S.check_profile(profile, exe)
    folder, manifest_path, three_mf, stl = resolve_export(path)
    manifest = load_manifest(manifest_path, SliceManifest)    # before any slicing: exit 2 naming the key
    scripts = S.post_process_scripts(settings)
    if scripts:
        click.echo(one_line(f"mst slice: note: the profile's post_process runs {', '.join(map(repr, scripts))} "
                            "on each G-code (your script; what is measured is its output)"), err=True)
    model = three_mf or stl
    triangles = S.read_stl(stl) if stl is not None else S.read_3mf(three_mf)
    if len(triangles) == 0:
        raise InputError("PATH", str(model), "holds no triangles: run 'mst export' again")
    version = S.slicer_version(exe)
    _progress(t0, f"{version} at {exe}; profile {profile}")
    if three_mf is not None and not S.has_prusa_pause(three_mf):
        _progress(t0, f"note: {three_mf.name} carries no PrusaSlicer pause (an older export)")

    centre = S.bed_centre(settings)
    lo, hi = triangles.reshape(-1, 3).min(0), triangles.reshape(-1, 3).max(0)
    shift = (centre[0] - (lo[0] + hi[0]) / 2, centre[1] - (lo[1] + hi[1]) / 2)
    z_shift = -float(lo[2]) + 0.0
    out = out_dir or folder
    with tempfile.TemporaryDirectory(prefix="mst-slice-") as tmp:
        run1 = S.slice_model(exe, model, profile, Path(tmp) / "sensor.gcode", centre)
        _progress(t0, f"sliced {model.name} in {run1.seconds:.2f} s")
        run2 = S.slice_model(exe, model, profile, Path(tmp) / "support.gcode", centre,
                             ("--support-material", "--support-material-auto"))
        _progress(t0, f"sliced again with automatic support in {run2.seconds:.2f} s")
        gtext = S.read_gcode(run1.gcode_path)
        g = G.parse_gcode(gtext)
        gs = G.parse_gcode(S.read_gcode(run2.gcode_path))
    _progress(t0, f"read {len(g.layers)} layers")
    if not any(lay.of_part().any() for lay in g.layers):
        raise S.SlicerError("prusa-slicer wrote G-code without one extrusion of the part")
    spans = G.free_spans(g)
    joined = G.free_spans(g, join_moves=True)
    _progress(t0, "measured the free spans")

    layer_h = _num(settings.get("layer_height"), g.layers[min(1, len(g.layers) - 1)].height_mm)
    if not (isinstance(layer_h, float) and math.isfinite(layer_h) and layer_h > 0):
        raise S.SlicerError(f"prusa-slicer wrote G-code with a layer height of {layer_h} mm")
    pause_report, pause_problem = judge_pause(g.pauses, expected_pause(manifest), layer_h)
    pause_report["pause_print_gcode"] = g.config.get("pause_print_gcode", settings.get("pause_print_gcode"))
    pause_report["model_carries_pause"] = bool(three_mf is not None and S.has_prusa_pause(three_mf))
    support_mm3 = gs.type_volume_mm3(G.SUPPORT_TYPES)
    support_n = int(sum(np.isin(lay.types, G.SUPPORT_TYPES).sum() for lay in gs.layers))
    support_layers = [lay.index for lay in gs.layers if np.isin(lay.types, G.SUPPORT_TYPES).any()]

    # the frame: G-code = print frame + shift; check it with the extents of the part's paths
    part = np.concatenate([lay.segments[lay.of_part()] for lay in g.layers])
    gmin = np.minimum(part[:, [0, 1]].min(0), part[:, [2, 3]].min(0))
    gmax = np.maximum(part[:, [0, 1]].max(0), part[:, [2, 3]].max(0))
    residual = [float(gmin[0] - (lo[0] + shift[0])), float(gmin[1] - (lo[1] + shift[1])),
                float((hi[0] + shift[0]) - gmax[0]), float((hi[1] + shift[1]) - gmax[1])]

    longest = spans.longest
    failed, reasons = [], []
    if longest is not None and longest.length_mm > max_span_mm:
        failed.append("free_span")
        reasons.append(f"free span {longest.length_mm:.1f} mm > {max_span_mm:g} mm (layer {longest.layer}, "
                       f"z = {longest.z_mm:.2f} mm, {longest.type})")
    if pause_problem:
        failed.append("pause")
        reasons.append(pause_problem)
    if support_n:
        failed.append("support")
        reasons.append(f"the slicer generates {support_mm3:.0f} mm3 of support (layers "
                       f"{support_layers[0]}-{support_layers[-1]})")

    def span_dict(s):
        if s is None:
            return None
        return {"length_mm": round(s.length_mm, 3), "layer": s.layer, "z_mm": round(s.z_mm, 4),
                "x_mm": round(s.x_mm - shift[0], 3), "y_mm": round(s.y_mm - shift[1], 3),
                "gcode_xy_mm": [round(s.x_mm, 3), round(s.y_mm, 3)], "type": s.type}

    top_z = g.layers[-1].z_mm
    report = {
        "format": 1,
        "name": manifest.name,
        "slicer": version,
        "profile": str(profile),
        "post_process": scripts,
        "model_sliced": model.name,
        "slice_time_s": round(run1.seconds, 3),
        "print_time_s": g.print_time_s,
        "print_time": _fmt_time(g.print_time_s),
        "filament_mm": g.filament_mm,
        "filament_cm3": g.filament_cm3,
        "filament_g": g.filament_g,
        "layers": len(g.layers),
        "layer_height_mm": layer_h,
        "first_layer_height_mm": round(g.layers[0].height_mm, 4),
        "height_mm": round(top_z, 4),
        "frame": {"gcode_minus_print_xy_mm": [round(shift[0], 4), round(shift[1], 4)],
                  "gcode_minus_print_z_mm": round(z_shift, 4),
                  "bed_centre_mm": list(centre),
                  "path_inset_from_bbox_mm": [round(r, 3) for r in residual]},
        "free_span": {"max_allowed_mm": max_span_mm,
                      "longest": span_dict(longest),
                      "longest_joined_moves": span_dict(joined.longest),
                      "per_layer": [{"layer": s.layer, "z_mm": round(s.z_mm, 4),
                                     "max_span_mm": round(s.length_mm, 3)} for s in spans.per_layer]},
        "pause": pause_report,
        "support": {"needed": bool(support_n), "volume_mm3": round(support_mm3, 2),
                    "extrusions": support_n,
                    "layers": [support_layers[0], support_layers[-1]] if support_layers else []},
        "cavity_gaps": cavity_gap_report(g, manifest, shift, z_shift),
        "failed": failed,
        "reasons": reasons,
    }
    # unlike simulate and design, --json still draws here: tests/test_slice.py relies on it
    plot = not (no_plot or as_json)
    names = ["sensor.gcode", "slice.json"] + (["print.png"] if plot else [])
    from mst_cli.io.outputs import finite_or_none
    report = finite_or_none(report)       # nothing measured (NaN) is null: JSON holds no NaN
    with staged(out) as st:
        st.write_text("sensor.gcode", gtext)
        st.write_json("slice.json", report)
        if plot:
            plot_print(st.path("print.png"), triangles, centre, (shift[0], shift[1], z_shift), g, spans,
                       str(manifest.name or folder.name))
        else:
            st.remove("print.png")
    _progress(t0, f"wrote {out}/{', '.join(names)}")
    if as_json:
        click.echo(json.dumps(report, indent=2, allow_nan=False))
    else:
        click.echo(summary_table(report))
    if failed:
        click.echo(f"mst slice: failed: {'; '.join(reasons)}", err=True)
        sys.exit(EXIT_TARGETS)


def _num(text, default):
    try:
        return float(text)
    except (TypeError, ValueError):
        return default


def summary_table(r: dict) -> str:
    lines = [f"{r['slicer']}, profile {Path(r['profile']).name}, sliced {r['model_sliced']} "
             f"in {r['slice_time_s']:.2f} s"]
    fil = (f"{r['filament_mm']:.0f} mm, {r['filament_cm3']:.2f} cm3, {r['filament_g']:.2f} g"
           if r["filament_mm"] is not None else "unknown")
    lines.append(f"print time        {r['print_time']}; filament {fil}")
    lines.append(f"layers            {r['layers']} x {r['layer_height_mm']:g} mm (first "
                 f"{r['first_layer_height_mm']:g} mm), height {r['height_mm']:.2f} mm")
    s = r["free_span"]["longest"]
    ok = lambda name: "FAIL" if name in r["failed"] else "ok"     # noqa: E731
    if s is None:
        lines.append("free span         none (one layer)")
    else:
        lines.append(f"free span         {s['length_mm']:.2f} mm (max {r['free_span']['max_allowed_mm']:g}) "
                     f"at layer {s['layer']}, z {s['z_mm']:.2f} mm, x {s['x_mm']:.2f}, y {s['y_mm']:.2f} "
                     f"(print frame), {s['type']}  [{ok('free_span')}]")
    p = r["pause"]
    found = ", ".join(f"after layer {f['after_layer']} (z {f['z_mm']:.2f} mm{', mid-layer' if f['mid_layer'] else ''}) "
                      f"{f['command']}" for f in p["found"]) or "none"
    exp = p["expected"]
    exp_s = "not given" if exp == "not given" else (
        (f"after layer {exp['after_layer']}, " if exp.get("after_layer") else "") + f"z {exp['z_mm']:.2f} mm")
    lines.append(f"pause             found {found}; export.json asks {exp_s}  [{ok('pause')}]")
    sup = r["support"]
    support = f"needed: {sup['volume_mm3']:.0f} mm3" if sup["needed"] else "none generated"
    lines.append(f"support           {support}"
                 f"  [{ok('support')}]")
    gaps = r["cavity_gaps"]
    if gaps == "not given":
        lines.append("cavity gaps       not given in export.json")
    else:
        for c in gaps:
            sl = "-" if c.get("sliced_gap_mm") is None else f"{c['sliced_gap_mm']:.2f}"
            dg = c.get('designed_gap_mm')
            lines.append(f"cavity gap L{c.get('layer')}     designed {'-' if dg is None else f'{float(dg):.2f}'} mm, "
                         f"as sliced {sl} mm (x {c['x_mm']}, z {c['z_mm']})")
    return "\n".join(lines)
