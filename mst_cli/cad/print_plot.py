"""``print.png`` of ``mst slice``: the part on the bed (3D) and plan views of a mid layer's
paths and of the layer with the longest free span, coloured by feature type. matplotlib is
imported inside (about 0.8 s with the 3D view): ``--no-plot`` never pays for it."""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.cad.gcode import GCode, Layer
from mst_cli.cad.layer_measure import Span, SpanReport

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

COLOURS = {
    "External perimeter": "#d62728",
    "Perimeter": "#ff7f0e",
    "Overhang perimeter": "#1f77b4",
    "Internal infill": "#8c564b",
    "Solid infill": "#9467bd",
    "Top solid infill": "#e377c2",
    "Bridge infill": "#17becf",
    "Gap fill": "#2ca02c",
    "Skirt/Brim": "#7f7f7f",
    "Support material": "#bcbd22",
    "Support material interface": "#dbdb8d",
}


def plot_print(
    path: Path,
    triangles: np.ndarray,
    bed_xy: tuple[float, float],
    shift_xyz: tuple[float, float, float],
    g: GCode,
    spans: SpanReport,
    title: str,
) -> None:
    """Draw print.png at ``path``: ``triangles`` (n, 3, 3) in the print frame, moved by
    ``shift_xyz`` onto the bed; the G-code's layers and its free spans."""
    import matplotlib  # deferred: matplotlib is 0.45 s; only a picture needs it

    matplotlib.use("Agg")
    from matplotlib.figure import Figure  # deferred: as matplotlib

    fig = Figure(figsize=(16, 5.6), dpi=110)
    _draw_on_bed(fig, triangles + np.asarray(shift_xyz), bed_xy, title)
    for k, (layer, what) in enumerate(_layer_panels(g, spans)):
        ax2 = fig.add_subplot(1, 3, 2 + k)
        if layer is None:
            ax2.axis("off")
            continue
        _draw_layer(ax2, layer, what, spans.longest)
    fig.tight_layout()
    fig.savefig(path)


def _draw_on_bed(fig: Figure, tri: np.ndarray, bed_xy: tuple[float, float], title: str) -> None:
    """The first panel: the mesh ``tri`` (n, 3, 3, bed frame, mm), shaded, on its patch of bed."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # deferred: as matplotlib

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
    with contextlib.suppress(AttributeError):  # matplotlib < 3.3 has no box aspect
        ax.set_box_aspect((bx[1] - bx[0], by[1] - by[0], max(hi[2], 1.0)))
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    ax.set_title(f"{title}\nas it sits on the bed (bed centre {bed_xy[0]:g}, {bed_xy[1]:g} mm)", fontsize=9)


def _layer_panels(g: GCode, spans: SpanReport) -> list[tuple[Layer | None, str]]:
    """The two layers drawn: the middle one, and the one with the longest free span (if another)."""
    layers = [lay for lay in g.layers if len(lay.segments)]
    mid = layers[len(layers) // 2] if layers else None
    worst = spans.longest
    worst_layer = next((lay for lay in g.layers if worst is not None and lay.index == worst.layer), None)
    panels: list[tuple[Layer | None, str]] = [(mid, "mid layer")]
    if worst is not None and worst_layer is not None and worst_layer is not mid and worst.length_mm > 0:
        panels.append((worst_layer, "longest free span"))
    else:
        panels.append((None, ""))
    return panels


def _draw_layer(ax2: Axes, layer: Layer, what: str, worst: Span | None) -> None:
    """One layer's G-code paths, coloured by feature type, and the longest free span if on it."""
    from matplotlib.collections import LineCollection  # deferred: as matplotlib

    seen = set()
    for t in sorted(set(layer.types.tolist())):
        sel = layer.types == t
        segs = layer.segments[sel]
        lc = LineCollection(
            segs[:, :4].reshape(-1, 2, 2),
            colors=COLOURS.get(t, "k"),
            linewidths=1.2,
            label=t if t not in seen else None,
        )
        seen.add(t)
        ax2.add_collection(lc)
    if worst is not None and worst.layer == layer.index and worst.length_mm > 0:
        (xa, ya), (xb, yb) = worst.start_xy_mm, worst.end_xy_mm
        ax2.plot([xa, xb], [ya, yb], color="k", lw=3, alpha=0.5, label=f"free span {worst.length_mm:.1f} mm")
    part = layer.segments[layer.of_part()] if layer.of_part().any() else layer.segments
    ax2.set_xlim(part[:, [0, 2]].min() - 1, part[:, [0, 2]].max() + 1)
    ax2.set_ylim(part[:, [1, 3]].min() - 1, part[:, [1, 3]].max() + 1)
    ax2.set_aspect("equal")
    ax2.set_xlabel("bed x (mm)")
    ax2.set_ylabel("bed y (mm)")
    ax2.set_title(f"{what}: layer {layer.index}, z = {layer.z_mm:.2f} mm (G-code paths)", fontsize=9)
    ax2.legend(fontsize=6, loc="upper right")
