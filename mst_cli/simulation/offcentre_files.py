"""What ``mst simulate --load-offset-mm`` and ``--offset-map`` write: offcentre.csv / .png, the
"off_centre" section of report.json, offset_map.csv / .png, and the terminal lines."""

from __future__ import annotations

import io
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mst_cli.model.member_pose import MEMBER_POSE_FIGURES
from mst_cli.model.offcentre import SMALL_ROTATION_DEG

if TYPE_CHECKING:
    from mst_cli.io.outputs import Staging
    from mst_cli.model.offcentre import OffCentreResponse, OffsetMap

OFFCENTRE_COLUMNS = (
    "force_N,Fx_N,Fy_N,Bx_mT,By_mT,Bz_mT,B_abs_mT,magnet_tilt_x_deg,magnet_tilt_y_deg,"
    "magnet_shift_x_mm,magnet_shift_y_mm,magnet_shift_z_mm,force_read_axial_N,read_error_N,in_range,"
    "axial_reading_flag,rotation_flag"
)
NO_AXIAL_READING = {
    "below_no_load": "|B| below the centred model's no-load |B|",
    "above_range": "|B| beyond the end of the centred model's curve",
}


def _cell(v: float) -> str:
    """A number's cell; empty where it has no value (nan, inf): the row's flag says why."""
    return f"{v:.9g}" if np.isfinite(v) else ""


def offcentre_csv(r: OffCentreResponse) -> str:
    """One row per force sample (the normal force force_N and the tangential Fx_N, Fy_N; field in
    mT, tilts toward +x and +y in degrees); the force read
    as axial and its error are empty where the centred model has no answer (axial_reading_flag);
    rotation_flag (:func:`~mst_cli.model.offcentre.rotation_flags`) says where the model stops."""
    rotation = _rotation(r)
    buf = io.StringIO()
    buf.write(OFFCENTRE_COLUMNS + "\n")
    B = r.B_T * 1e3
    for i, F in enumerate(r.force_N):
        row = [
            F,
            r.force_x_N[i],
            r.force_y_N[i],
            *B[i],
            r.B_abs_T[i] * 1e3,
            *r.magnet_tilt_deg[i],
            *r.magnet_shift_mm[i],
        ]
        row += [r.force_read_axial_N[i], r.read_error_N[i]]
        flags = f",{int(r.axial.in_range[i])},{r.axial_reading_flag[i]},{rotation[i]}\n"
        buf.write(",".join(map(_cell, row)) + flags)
    return buf.getvalue()


def offcentre_summary(r: OffCentreResponse) -> dict:
    """report.json's "off_centre": every layer's side locks and each regime's worst read error."""
    edges = np.concatenate([[0.0], r.axial.lock_forces_N])
    regimes = []
    for i in range(len(edges) - 1):
        inside = (r.force_N > edges[i]) & (r.force_N <= edges[i + 1])
        err = r.read_error_N[inside]
        rel = err / r.force_N[inside]
        worst = int(np.nanargmax(np.abs(rel))) if np.isfinite(rel).any() else None
        regimes.append(
            {
                "regime": i + 1,
                "force_from_N": float(edges[i]),
                "force_to_N": float(edges[i + 1]),
                "worst_read_error_rel": None if worst is None else float(rel[worst]),
                "worst_read_error_N": None if worst is None else float(err[worst]),
                "at_force_N": None if worst is None else float(r.force_N[inside][worst]),
            }
        )
    in_range = r.axial.in_range
    flags = [str(f) for f in r.axial_reading_flag]
    return {
        "load_offset_mm": list(r.offset_mm),
        "shear_ratio": list(r.shear_ratio),
        "mechanics": r.mechanics,
        "tilt_model": (
            "each chevron a depth-long line of the layer law (mst_cli.model.mechanics.tilt), "
            + (
                "each layer with the cap, plate or cover its walls load (mst_cli.model.part_laws)"
                if r.whole_part
                else "rigid plates (model.load_path: layers)"
            )
        ),
        "shear_model": "the tangential force at the top face adds its moment about every layer's pivot; each "
        "layer's plates slide with its lateral compliance along a press growing from zero "
        "(mst_cli.model.general_load)",
        "layers": [
            {
                "layer": j + 1,
                "lock_force_axial_N": float(R),
                "lock_force_minus_x_side_N": _finite(sides[0]),
                "lock_force_plus_x_side_N": _finite(sides[1]),
            }
            for j, (R, sides) in enumerate(zip(r.axial.lock_forces_N, r.side_lock_N))
        ],
        "side_lock_null_means": "the pads never close at that end: the plates pivot on the other side's pads",
        "regimes": regimes,
        "axial_reading": {k: flags.count(k) for k in ("ok", *NO_AXIAL_READING)},
        "rotation": _rotation_summary(r),
        "magnet_tilt_at_last_lock_deg": [float(v) for v in r.magnet_tilt_deg[in_range][-1]],
        "magnet_shift_at_last_lock_mm": [float(v) for v in r.magnet_shift_mm[in_range][-1]],
        "members_pose": _members_pose(r),
    }


def _members_pose(r: OffCentreResponse) -> dict | None:
    """report.json's off_centre.members_pose: with model.load_path: section, what the whole-part
    rung's members add per regime beyond their closed form (None: the closed form alone)."""
    pose = r.members_pose
    if pose is None:
        return None
    figures = [{k: float(getattr(pose, k)[i]) for k in MEMBER_POSE_FIGURES} for i in range(len(pose.edges_N))]
    return {
        "model": "per regime of the part, the whole-part rung's members (as printed less rigid) less the closed "
        "form's, integrated along the load's ray, in the x-z plane (mst_cli.model.section_pose)",
        "regimes": [
            {"regime": i + 1, "ends_at_lock_N": float(edge), **row}
            for i, (edge, row) in enumerate(zip(pose.edges_N, figures))
        ],
    }


def _rotation(r: OffCentreResponse) -> np.ndarray:
    return r.rotation_flag if r.rotation_flag is not None else np.full(len(r.force_N), "ok")


def _rotation_summary(r: OffCentreResponse) -> dict:
    """Where the model stops: how many samples leave small rotations or pass a layer's closure,
    and the first force at which one does (null: none in the curve)."""
    flags = _rotation(r)
    past = flags != "ok"
    return {
        "small_rotation_limit_deg": SMALL_ROTATION_DEG,
        "past_small_rotations": int((flags == "past_small_rotations").sum()),
        "past_closure": int((flags == "past_closure").sum()),
        "samples": len(flags),
        "first_force_N": float(r.force_N[past][0]) if past.any() else None,
    }


def _finite(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def _side(v: float | None) -> str:
    return "never (the plates pivot on the other side)" if v is None else f"{v:.4g} N"


def offcentre_lines(s: dict) -> list[str]:
    """The terminal's account of the off-centre load, from its :func:`offcentre_summary`."""
    x0, y0 = s["load_offset_mm"]
    rx, ry = s["shear_ratio"]
    shear = f", tangential Fx = {rx:g} F, Fy = {ry:g} F" if rx or ry else ""
    lines = [f"load at x = {x0:g} mm, y = {y0:g} mm{shear} (rigid-plate tilt model, {s['mechanics']} layers):"]
    for lay in s["layers"]:
        lines.append(
            f"  layer {lay['layer']}: locks at {lay['lock_force_axial_N']:.4g} N centred; here its -x side "
            f"{_side(lay['lock_force_minus_x_side_N'])}, its +x side {_side(lay['lock_force_plus_x_side_N'])}"
        )
    for reg in s["regimes"]:
        e = reg["worst_read_error_rel"]
        said = (
            "off the centred curve"
            if e is None
            else f"{100 * e:+.1f} % ({reg['worst_read_error_N']:+.3g} N at {reg['at_force_N']:.3g} N)"
        )
        lines.append(f"  regime {reg['regime']}: a reading taken as axial is off by up to {said}")
    counts = s["axial_reading"]
    for flag, why in NO_AXIAL_READING.items():
        if counts[flag]:
            lines.append(
                f"  {counts[flag]} of {sum(counts.values())} force samples have no axial reading ({why}): "
                f"offcentre.csv leaves their force_read_axial_N and read_error_N empty, axial_reading_flag {flag}"
            )
    rot = s["rotation"]
    if rot["past_small_rotations"] + rot["past_closure"]:
        lines.append(
            f"  the model stops from {rot['first_force_N']:.3g} N: {rot['past_small_rotations']} of {rot['samples']} "
            f"force samples turn past {rot['small_rotation_limit_deg']:g} deg (small rotations) and "
            f"{rot['past_closure']} turn a layer past its closure; offcentre.csv flags them (rotation_flag), "
            "their tilts and fields are not predictions"
        )
    tx, ty = (round(v, 2) + 0.0 for v in s["magnet_tilt_at_last_lock_deg"])  # no "-0.00"
    lines.append(f"  the magnet tilts {tx:.2f} deg toward +x and {ty:.2f} deg toward +y at the last lock")
    return lines


def offset_map_csv(m: OffsetMap) -> str:
    """One row per (force, x, y): the axial reading's relative error (empty where the centred
    model has no answer: axial_reading_flag says why)."""
    buf = io.StringIO()
    buf.write("force_N,regime,x_mm,y_mm,read_error_rel,axial_reading_flag\n")
    for k, F in enumerate(m.force_N):
        for iy, y in enumerate(m.y_mm):
            for ix, x in enumerate(m.x_mm):
                cells = f"{F:.9g},{m.regime[k]},{x:.6g},{y:.6g},{_cell(m.error_rel[k, iy, ix])}"
                buf.write(f"{cells},{m.flag[k, iy, ix]}\n")
    return buf.getvalue()


def plot_offcentre(r: OffCentreResponse, path: str | Path, title: str = "") -> None:
    """The field's three axes and |B| against force, off centre and centred; the read error."""
    from matplotlib.figure import Figure  # deferred: matplotlib only when a plot is asked for

    fig = Figure(figsize=(10, 4.2))
    ax1, ax2 = fig.subplots(1, 2)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.12, top=0.88, wspace=0.42)
    inr = r.axial.in_range & (r.force_N > 0)
    F = r.force_N[inr]
    ax1.plot(F, r.B_T[inr, 2] * 1e3, color="C2", label="Bz")
    ax1.plot(F, r.B_abs_T[inr] * 1e3, color="k", ls="--", label="|B|")
    ax1.plot(F, r.axial.B_abs_T[inr] * 1e3, color="k", ls=":", label="|B| centred")
    ax1.set_xlabel("force F [N]")
    ax1.set_ylabel("Bz, |B| at the chip [mT]")
    ax1.grid(alpha=0.3)
    ax1b = ax1.twinx()  # the transverse axes are a hundredth of Bz: their own scale
    ax1b.plot(F, r.B_T[inr, 0] * 1e6, color="C0", label="Bx")
    ax1b.plot(F, r.B_T[inr, 1] * 1e6, color="C1", label="By")
    ax1b.set_ylabel("Bx, By [uT]")
    handles = ax1.get_legend_handles_labels()[0] + ax1b.get_legend_handles_labels()[0]
    ax1.legend(handles=handles, fontsize=8, loc="lower right")
    ax2.plot(F, 100 * r.read_error_N[inr] / F, color="C3")
    ax2.set_xlabel("force F [N]")
    ax2.set_ylabel("force read as axial: error [%]")
    ax2.grid(alpha=0.3)
    x0, y0 = r.offset_mm
    fig.suptitle(title or f"load at ({x0:g}, {y0:g}) mm")
    fig.savefig(path, dpi=110, format="png")


def plot_offset_map(m: OffsetMap, path: str | Path, title: str = "") -> None:
    """One heat map per force: the axial reading's error (%) over the top face."""
    from matplotlib.figure import Figure  # deferred: as plot_offcentre

    n = len(m.force_N)
    cols = min(n, 3)
    rows = -(-n // cols)
    fig = Figure(figsize=(3.8 * cols + 1.0, 2.9 * rows))
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    fig.subplots_adjust(left=0.07, right=0.86, bottom=0.08, top=0.9, wspace=0.3, hspace=0.45)
    lim = float(np.nanmax(np.abs(m.error_rel))) * 100 if np.isfinite(m.error_rel).any() else 1.0
    im: Any = None
    for k, ax in enumerate(axes):
        if k >= n:
            ax.set_visible(False)
            continue
        im = ax.pcolormesh(m.x_mm, m.y_mm, 100 * m.error_rel[k], cmap="RdBu_r", vmin=-lim, vmax=lim, shading="nearest")
        ax.set_title(f"regime {m.regime[k]}: F = {m.force_N[k]:.3g} N", fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.set_ylabel("y [mm]", fontsize=8)
    fig.colorbar(im, cax=fig.add_axes((0.89, 0.15, 0.02, 0.7)), label="force read as axial: error [%]")
    fig.suptitle(title or "force read as axial: error over the top face")
    fig.savefig(path, dpi=100, format="png")


def write_offcentre(st: Staging, r: OffCentreResponse | None, m: OffsetMap | None, plot: bool) -> None:
    """offcentre.csv (+ .png) and offset_map.csv (+ .png) into a staging folder; old ones go."""
    _write_pair(
        st,
        "offcentre",
        None if r is None else offcentre_csv(r),
        None if r is None else partial(plot_offcentre, r),
        plot,
    )
    _write_pair(
        st,
        "offset_map",
        None if m is None else offset_map_csv(m),
        None if m is None else partial(plot_offset_map, m),
        plot,
    )


def _write_pair(st: Staging, stem: str, csv: str | None, draw: Callable[[Path], None] | None, plot: bool) -> None:
    """stem.csv and, when plotting, stem.png; a file this run does not write is removed."""
    if csv is None:
        st.remove(f"{stem}.csv")
    else:
        st.write_text(f"{stem}.csv", csv)
    if plot and draw is not None:
        draw(st.path(f"{stem}.png"))
    else:
        st.remove(f"{stem}.png")
