"""The tilt rung against L2 under tilted plates (``mst bench`` and studies/check_tilt_rung.py).

For one cell, L2 follows a chevron through its lock with the plates closing by d at the axis and
tilting by phi = tau d (:mod:`mst_cli.model.mechanics.continuum_tilt`), the loaded chevron with
+tau and the other with -tau. The tilt rung (:mod:`mst_cli.model.mechanics.tilt`) says, per chevron:
before the pads touch it is the untilted layer at the closure d (1 + tau x_c), x_c its fitted
lever (checked against L2's own untilted curve, so that only the tilt's assumptions are tested,
not L0's fits); the pads touch first at their loaded end, so the loaded chevron locks at
d = d_lock / (1 + tau a).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mst_cli.bench.sampling import sample_cells
from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics.continuum import PAD_LENGTH_IN_T, solve_continuum
from mst_cli.model.mechanics.continuum_tilt import linear_tilt_lever_mm, solve_tilted_chevron
from mst_cli.model.mechanics.tilt import chevron_lever_mm, root_midpoint_mm

DEFAULT_TAU = 0.03  # rad per mm of closure: about what a press 5 mm off centre gives
TILT_CELLS = 8  # mst bench checks the tilt rung on at most this many of its cells (4 L2 solves each)


def pad_half_width_mm(c: HexCell) -> float:
    return c.p_mm - c.t_mm * math.tan(0.5 * math.radians(c.theta_deg))


def cells_with_long_pads(n: int, seed: int) -> list[HexCell]:
    out: list[HexCell] = []
    s = seed
    while len(out) < n:
        out += [c for c in sample_cells(n, s) if pad_half_width_mm(c) > PAD_LENGTH_IN_T * c.t_mm]
        s += 1000
    return out[:n]


def check_tilt_cell(c: HexCell, mat: Material, tau: float = DEFAULT_TAU) -> dict:
    """Pre-lock deviation of both chevrons and the loaded side's lock stroke error, for the fitted
    lever and for the roots' midpoint."""
    base = solve_continuum(c, mat)
    d0, F0 = base.displacement_mm, base.force_N / base.mesh_scale  # the path's own mesh, unscaled
    a = pad_half_width_mm(c)
    theta = math.radians(c.theta_deg)
    levers = {
        "fit": chevron_lever_mm(theta, c.t_mm, c.h_mm, c.width_mm),
        "roots": root_midpoint_mm(theta, c.t_mm, c.p_mm),
    }
    loaded, other = solve_tilted_chevron(c, mat, tau), solve_tilted_chevron(c, mat, -tau)
    d_on = base.d_contact_mm / (1.0 + tau * a)  # the rung: the pads touch at x = +a
    # the other chevron's quarter has its pads from the cut x_cut = a - 4 t to a: they touch
    # first at the cut, where the closure d (1 - tau x_cut) passes the stroke
    d_off = base.d_contact_mm / (1.0 - tau * max(a - PAD_LENGTH_IN_T * c.t_mm, 0.0))
    row = {
        "cell": c,
        "lock_rel": loaded.d_contact_mm / d_on - 1.0,
        "far_lock_rel": other.d_contact_mm / d_off - 1.0,
        "contact_at": loaded.contact_at,
    }
    for name, x_c in levers.items():
        worst, half, far = 0.0, 0.0, 0.0
        for res, sign in ((loaded, 1.0), (other, -1.0)):
            d, F = res.displacement_mm, res.force_N
            # each chevron up to its own lock (its path's last point)
            keep = (d > 0) & (d * (1 + sign * tau * x_c) < d0[-1])
            pred = np.interp(d[keep] * (1 + sign * tau * x_c), d0, F0)
            dev = np.abs(F[keep] / pred - 1.0)
            before = d[keep] < d_on * (1 - 1e-6)
            worst = max(worst, float(np.max(dev[before], initial=0.0)))
            if sign < 0:  # the other side, from the loaded side's lock through its own
                far = float(np.max(dev[~before], initial=0.0))
            # halfway to the loaded side's lock: the walls' response before the zipping ramp
            d_half = 0.5 * min(d_on, d0[-1] / (1 + max(sign * tau * x_c, 0.0)))
            F_half = np.interp(d_half, d, F)
            half = max(half, abs(F_half / np.interp(d_half * (1 + sign * tau * x_c), d0, F0) - 1.0))
        row[name], row[name + "_half"], row[name + "_far"] = worst, half, far
    return row


def long_padded(cells: Sequence[HexCell]) -> list[HexCell]:
    """The cells whose pads are longer than PAD_LENGTH_IN_T t (the tilted L2 needs them)."""
    return [c for c in cells if pad_half_width_mm(c) > PAD_LENGTH_IN_T * c.t_mm]


def tilt_rows(cells: Sequence[HexCell], mat: Material, tau: float = DEFAULT_TAU) -> list[dict]:
    """:func:`check_tilt_cell` of every cell, JSON-ready, with the lever against L2's small-strain one."""
    rows = []
    for c in cells:
        r = check_tilt_cell(c, mat, tau)
        theta = math.radians(c.theta_deg)
        lever = chevron_lever_mm(theta, c.t_mm, c.h_mm, c.width_mm)
        rows.append(
            {
                "theta_deg": c.theta_deg,
                "t_mm": c.t_mm,
                "h_mm": c.h_mm,
                "l2_lock": r["contact_at"],
                "lever_rel_err": lever / linear_tilt_lever_mm(c, mat) - 1.0,
                "halfway_rel_err": r["fit_half"],
                "worst_prelock_rel_err": r["fit"],
                "lock_stroke_rel_err": r["lock_rel"],
                "other_side_rel_err": r["fit_far"],
            }
        )
    return rows


def tilt_lines(rows: Sequence[dict], tau: float = DEFAULT_TAU) -> list[str]:
    """bench.md's section: the tilt rung against L2 under tilted plates."""
    lines = [
        "",
        f"## Tilt rung against L2 under tilted plates (tau = {tau} rad per mm of closure)",
        "",
        "| theta [deg] | t [mm] | h [mm] | L2 lock | lever | halfway | worst before the lock | lock stroke "
        "| other side through its lock |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['theta_deg']:.1f} | {r['t_mm']:.2f} | {r['h_mm']:.2f} | {r['l2_lock']} "
            f"| {100 * r['lever_rel_err']:+.2f} % | {100 * r['halfway_rel_err']:.2f} % "
            f"| {100 * r['worst_prelock_rel_err']:.2f} % | {100 * r['lock_stroke_rel_err']:+.2f} % "
            f"| {100 * r['other_side_rel_err']:.2f} % |"
        )
    if rows:
        half = np.array([r["halfway_rel_err"] for r in rows])
        lines += ["", f"halfway to the loaded lock: median {100 * np.median(half):.2f} %, max {100 * half.max():.2f} %"]
    return lines
