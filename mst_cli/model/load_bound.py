"""What the chips can tell apart: the field's Jacobian in the load's unknowns and the
Cramer-Rao bound of any unbiased estimate of them (issue 39).

The unknowns are the normal force Fz, the tangential force (Fx, Fy) and where the force presses
(x, y) (:data:`UNKNOWNS`); the data are the three axes of every chip, each with Gaussian noise
of the same sigma. The Fisher information is J^T J / sigma^2 (J the field's Jacobian), so the
1-sigma bound of estimate i is sigma_CRB,i = sigma sqrt((J^T J)^-1_ii): no unbiased estimator
does better at that noise. One chip gives three numbers: three unknowns at most (the centred
press's Fz, Fx, Fy); two chips give six, enough for all five. The Jacobian is the forward
model's (:func:`~mst_cli.model.general_load.field_jacobian_T`), a layout's grid of presses one batch.

Pure: no I/O.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mst_cli.model.general_load import LoadedStack, field_jacobian_T

UNKNOWNS = ("force_N", "shear_x_N", "shear_y_N", "x_mm", "y_mm")
CENTRED = (0, 1, 2)  # the unknowns of a centred press: Fz, Fx, Fy
ALL = (0, 1, 2, 3, 4)
MAX_CONDITION = 1e14  # of the scaled Fisher information: beyond, double precision cannot invert it


def field_jacobian(
    stack: LoadedStack,
    theta,
    chips_mm: Sequence[tuple[float, float]],
    free: Sequence[int] = ALL,
    at: np.ndarray | None = None,
) -> np.ndarray:
    """dB/dtheta (3 k, len(free)) in T per N or per mm at one load ``theta`` (5,): the forward
    model's Jacobian (:func:`~mst_cli.model.general_load.field_jacobian_T`) of a batch of one,
    central, or forward from ``at`` (the fields at ``theta``, already known)."""
    return field_jacobian_T(stack, theta, chips_mm, free, None if at is None else np.asarray(at)[None])[0]


def crb_sigma(J: np.ndarray, noise: float | np.ndarray) -> np.ndarray:
    """The 1-sigma Cramer-Rao bound noise sqrt(diag((J^T J)^-1)) of every unknown of ``J``'s
    columns: the one bound of every estimator (the exact solves, the tables, the two-chip reader,
    the layout bound). ``J`` is a batch of Jacobians (..., m, n) (one Jacobian (m, n) is a batch of
    one), ``noise`` the noise per axis in J's field unit, one or one per Jacobian (...); returns
    (..., n). Every unknown of a Jacobian is inf when the data cannot tell its unknowns apart: a
    column of zeros, or J^T J scaled to a unit diagonal (so that the units of the unknowns do not
    count) has a condition number above :data:`MAX_CONDITION`; one whose variance comes out <= 0 is
    inf too."""
    J = np.asarray(J, dtype=float)
    A = np.einsum("...ki,...kj->...ij", J, J)
    n = A.shape[-1]
    info = A.reshape(-1, n, n)
    per_axis = np.broadcast_to(np.asarray(noise, dtype=float), A.shape[:-2]).reshape(-1)
    out = np.full((len(info), n), np.inf)
    diag = np.diagonal(info, axis1=1, axis2=2)
    seen = np.all(diag > 0, axis=1)  # NaN too: no bound
    good = np.zeros(len(info), dtype=bool)
    if np.any(seen):
        s = 1.0 / np.sqrt(diag[seen])
        w = np.linalg.eigvalsh(info[seen] * s[:, :, None] * s[:, None, :])  # ascending
        good[seen] = (w[:, 0] > 0) & (w[:, -1] <= MAX_CONDITION * w[:, 0])
    if np.any(good):
        d = np.diagonal(np.linalg.inv(info[good]), axis1=1, axis2=2)
        out[good] = np.where(d > 0.0, per_axis[good, None] * np.sqrt(np.abs(d)), np.inf)
    return out.reshape(A.shape[:-1])


@dataclass
class LayoutBound:
    """The 1-sigma bounds of a chip layout over presses on a grid of the top face."""

    chips_mm: list[tuple[float, float]]
    free: tuple[int, ...]  # which of UNKNOWNS are estimated
    x_mm: np.ndarray  # (nx,)
    y_mm: np.ndarray  # (ny,)
    force_N: np.ndarray  # (nf,)
    shear_ratio: tuple[float, float]
    sigma_per_T: np.ndarray  # (nf, ny, nx, len(free)): the bound at a noise of 1 T (it scales with the noise)

    def summary(self, noise_uT: Sequence[float]) -> dict:
        """report.json's account: per noise, each estimate's median and worst 1-sigma bound."""
        out: dict = {
            "chips_mm": [list(c) for c in self.chips_mm],
            "estimates": [UNKNOWNS[i] for i in self.free],
            "region_mm": [float(self.x_mm.max()), float(self.y_mm.max())],
            "force_N": [float(f) for f in self.force_N],
            "shear_ratio": list(self.shear_ratio),
            "noise": [],
        }
        for n in noise_uT:
            s = self.sigma_per_T * n * 1e-6
            row: dict = {"noise_uT": float(n)}
            for k, i in enumerate(self.free):
                row[f"{UNKNOWNS[i]}_crb_median"] = float(np.median(s[..., k]))
                row[f"{UNKNOWNS[i]}_crb_worst"] = float(np.max(s[..., k]))
            out["noise"].append(row)
        return out


def layout_bound(
    stack: LoadedStack,
    chips_mm: Sequence[tuple[float, float]],
    force_N: Sequence[float],
    shear_ratio: tuple[float, float] = (0.0, 0.0),
    region_frac: float = 0.6,
    grid: tuple[int, int] = (5, 5),
) -> LayoutBound:
    """The bounds over a ``grid`` of presses spanning ``region_frac`` of the top face (centred
    presses only, Fz Fx Fy, for one chip; all five unknowns for two chips or more)."""
    g = stack.geometry
    free = CENTRED if len(chips_mm) == 1 else ALL
    xs = np.linspace(-1.0, 1.0, grid[0]) * 0.5 * region_frac * g.width_mm
    ys = np.linspace(-1.0, 1.0, grid[1]) * 0.5 * region_frac * g.depth_mm
    if free == CENTRED:
        xs, ys = np.zeros(1), np.zeros(1)
    F = np.asarray(force_N, dtype=float)
    f, y, x = (a.ravel() for a in np.meshgrid(F, ys, xs, indexing="ij"))
    theta = np.column_stack([f, shear_ratio[0] * f, shear_ratio[1] * f, x, y])
    sigma = crb_sigma(field_jacobian_T(stack, theta, chips_mm, free), 1.0).reshape(len(F), len(ys), len(xs), len(free))
    return LayoutBound([(float(c[0]), float(c[1])) for c in chips_mm], free, xs, ys, F, shear_ratio, sigma)


BOUND_NOISES_uT = (0.5, 2.0)  # the noises a layout's bound is stated at (with the design's own)
BOUND_FORCES = (0.25, 0.5, 0.75)  # of the range (the last lock)
DESIGN_SHEAR_RATIO = (0.2, 0.1)  # the tangential load `mst design` states a two-chip layout's bound at


def bound_report(stack: LoadedStack, chips_mm, shear_ratio: tuple[float, float], noise_uT: float) -> dict:
    """report.json's ``shear_bound``: :func:`layout_bound` at 25/50/75 % of the range over the
    middle 60 % of the face, stated at BOUND_NOISES_uT and ``noise_uT``."""
    top = max(t.lock_force_N for t in stack.tilt)
    bound = layout_bound(stack, chips_mm, [f * top for f in BOUND_FORCES], shear_ratio)
    noises = sorted({*BOUND_NOISES_uT, float(noise_uT)} - {0.0})
    return {**bound.summary(noises), "mechanics": stack.mechanics, "region_frac": 0.6}


def shear_bound_lines(s: dict) -> list[str]:
    """The terminal's account of report.json's shear_bound: each estimate's 1-sigma CRB."""
    chips = " and ".join(f"({x:g}, {y:g})" for x, y in s["chips_mm"])
    where = (
        "centred presses"
        if len(s["chips_mm"]) == 1
        else f"presses over +-{s['region_mm'][0]:g} x +-{s['region_mm'][1]:g} mm"
    )
    lines = [
        f"what the chip{'s' if len(s['chips_mm']) > 1 else ''} at {chips} mm can tell apart ({where}, "
        f"at {', '.join(f'{f:.3g}' for f in s['force_N'])} N, Fx/Fz {s['shear_ratio'][0]:g}, Fy/Fz "
        f"{s['shear_ratio'][1]:g}), median (worst) 1-sigma Cramer-Rao bound:"
    ]
    for row in s["noise"]:
        cells = []
        for name in s["estimates"]:
            what, unit = name.rsplit("_", 1)
            cells.append(f"{what} {row[name + '_crb_median']:.3g} ({row[name + '_crb_worst']:.3g}) {unit}")
        lines.append(f"  {row['noise_uT']:g} uT: " + ", ".join(cells))
    if len(s["chips_mm"]) == 1:
        lines.append("  one chip: 3 numbers, so Fz, Fx, Fy of a press taken as centred (a second chip tells position)")
    return lines
