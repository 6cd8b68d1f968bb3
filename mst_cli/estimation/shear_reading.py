"""Reading the load's tangential part from the field (issue 39): ``--estimate shear``.

One 3-axis chip gives three numbers, so three unknowns: a press taken as centred gives (Fz,
Fx, Fy) from (Bx, By, Bz). Two chips give six numbers, enough for all five, (Fz, Fx, Fy, x, y).
Either way the estimate is the general-load model's (:func:`mst_cli.model.general_load.fields_T`,
each load's layers solved exactly) least squares fit to the reading, each axis weighted by the
chip's noise, by the estimators' one solver
(:func:`~mst_cli.estimation.least_squares.levenberg_marquardt`, the readings a batch), its
Jacobian by forward differences, started from the centred press that gives the first chip's |B|
(and, where that fit stalls beyond the noise, again from four other starts, the best kept). Each
estimate comes with its 1-sigma Cramer-Rao bound at the fit (:mod:`mst_cli.model.load_bound`) and
a flag: ``no_fit`` where the model cannot come within the noise of the reading (chi^2 past
:data:`CHI2_FLAG`: with one chip no residual is left for a reading the model reaches, so that is a
reading outside it; with two, one degree of freedom tests the assumption). A fit is judged by its
chi^2 alone: the layer laws are piecewise linear, so near a knot the steps can stall short of the
step tolerance on a fit already within the noise.

Pure: no I/O; works on arrays of readings (each fit independent, all fitted as one batch).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mst_cli.estimation.least_squares import levenberg_marquardt
from mst_cli.model.general_load import SHEAR_RATIO_MAX, LoadedStack, field_jacobian_T, fields_T, path_fields_T
from mst_cli.model.load_bound import ALL, CENTRED, UNKNOWNS, crb_sigma

CHI2_FLAG = {0: 9.0, 1: 10.83}  # the model more than 3 sigma off (no dof), p = 0.001 (one dof)
MAX_ITER = 40
STEP_TOL = 1e-4  # stop once a step is this fraction of the bound's sigma in every unknown
FLAGS = ("ok", "no_fit")


@dataclass
class ShearReading:
    """The estimates (m,) of every unknown of :data:`~mst_cli.model.load_bound.UNKNOWNS` (x, y
    are 0 where a centred press is assumed), their 1-sigma bounds and the fit's flag."""

    estimate: dict[str, np.ndarray]
    sigma: dict[str, np.ndarray]  # the CRB 1-sigma of the estimated unknowns (absent: assumed)
    chi2: np.ndarray  # (m,) the fit's weighted squared residual
    flag: np.ndarray  # (m,) FLAGS


class ShearReader:
    """The estimator of one sensor: its loaded stack and its chips (one: a centred press's Fz,
    Fx, Fy; two or more: all five unknowns)."""

    def __init__(self, stack: LoadedStack, chips_mm: Sequence[tuple[float, float]] | None = None):
        self.stack = stack
        self.chips_mm = [(float(c[0]), float(c[1])) for c in (chips_mm or [stack.geometry.chip_offset_mm])]
        self.free = CENTRED if len(self.chips_mm) == 1 else ALL
        top = max(t.lock_force_N for t in stack.tilt)
        self.table_F = np.linspace(0.0, 1.5 * top, 301)
        B0 = path_fields_T(stack, self.table_F, (0.0, 0.0), chips_mm=self.chips_mm[:1])
        self.table_B = np.linalg.norm(B0, axis=-1)  # |B| at the first chip, centred presses

    def read(self, B_T: np.ndarray, noise_T: float) -> ShearReading:
        """The estimates from readings ``B_T`` (m, k, 3) or, one chip, (m, 3), in T."""
        B = np.asarray(B_T, dtype=float).reshape(len(B_T), len(self.chips_mm) * 3)
        dof = B.shape[1] - len(self.free)
        limit = CHI2_FLAG.get(dof, 3.0 * dof + 10.0)
        est, sig, chi2 = self.fit(B, noise_T, np.array([self._start(b) for b in B]).reshape(len(B), 5))
        again = np.flatnonzero(~(chi2 <= limit))
        if len(again):  # four more starts each; the first of the lowest chi^2 kept
            starts = np.array([s for i in again for s in self._restarts(B[i])])
            more = self.fit(np.repeat(B[again], 4, axis=0), noise_T, starts)
            for i, rows in zip(again, np.arange(len(again) * 4).reshape(-1, 4)):
                k = int(np.argmin(np.r_[chi2[i], more[2][rows]]))
                if k:
                    est[i], sig[i], chi2[i] = more[0][rows[k - 1]], more[1][rows[k - 1]], more[2][rows[k - 1]]
        flag = np.where(chi2 <= limit, "ok", "no_fit").astype(object)  # a stall at the cone's edge too
        return ShearReading(
            {name: est[:, j] for j, name in enumerate(UNKNOWNS)},
            {UNKNOWNS[j]: sig[:, k] for k, j in enumerate(self.free)},
            chi2,
            flag,
        )

    def _start(self, B: np.ndarray) -> np.ndarray:
        """The centred press whose |B| at the first chip is the reading's."""
        F0 = float(np.interp(np.linalg.norm(B[:3]), self.table_B, self.table_F))
        return np.array([max(F0, 1e-2), 0.0, 0.0, 0.0, 0.0])

    def _restarts(self, B: np.ndarray) -> list[np.ndarray]:
        """Where a fit that stalls far from the reading starts again: the press a quarter of the
        face out toward each corner (positions free), else pushed a quarter of the cone each way."""
        g, s = self.stack.geometry, self._start(B)
        if len(self.free) == 5:
            corners = [(sx * 0.25 * g.width_mm, sy * 0.25 * g.depth_mm) for sx in (-1, 1) for sy in (-1, 1)]
            return [np.array([s[0], 0.0, 0.0, x, y]) for x, y in corners]
        push = 0.25 * SHEAR_RATIO_MAX * s[0]
        return [np.array([s[0], sx * push, sy * push, 0.0, 0.0]) for sx in (-1, 1) for sy in (-1, 1)]

    def _clip(self, theta: np.ndarray) -> np.ndarray:
        """Loads (m, 5) kept inside what the model takes: Fz > 0, the friction cone, the top face."""
        g = self.stack.geometry
        t = theta.copy()
        t[:, 0] = np.maximum(t[:, 0], 1e-3)
        lim = SHEAR_RATIO_MAX * t[:, 0]
        t[:, 1], t[:, 2] = np.clip(t[:, 1], -lim, lim), np.clip(t[:, 2], -lim, lim)
        t[:, 3] = np.clip(t[:, 3], -0.5 * g.width_mm, 0.5 * g.width_mm)
        t[:, 4] = np.clip(t[:, 4], -0.5 * g.depth_mm, 0.5 * g.depth_mm)
        return t

    def _fields(self, theta: np.ndarray, warm: None = None) -> tuple[np.ndarray, None]:
        """(the chips' fields (m, 3 k) at the loads ``theta`` (m, 5), NaN where the model has no
        answer; None: each load solved afresh)."""
        return fields_T(self.stack, theta, self.chips_mm, unsolved_nan=True), None

    def _jacobian(self, theta: np.ndarray, at: np.ndarray, warm: None = None) -> np.ndarray:
        """(m, 3 k, free) dB/dtheta by forward differences from the fields ``at``."""
        return field_jacobian_T(self.stack, theta, self.chips_mm, self.free, at)

    def fit(self, B_T: np.ndarray, noise_T: float, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Readings ``B_T`` (m, 3 k) fitted from the loads ``theta`` (m, 5) by the estimators' one
        solver (:func:`~mst_cli.estimation.least_squares.levenberg_marquardt`), each row on its
        own: (the loads (m, 5), their CRB 1-sigma (m, free) by central differences, chi^2 (m,))."""
        B = np.asarray(B_T, dtype=float).reshape(len(theta), 3 * len(self.chips_mm))
        fit = levenberg_marquardt(
            self._fields, self._jacobian, B, theta, noise_T, self._clip, MAX_ITER, STEP_TOL, self.free
        )
        J = field_jacobian_T(self.stack, fit.theta, self.chips_mm, self.free)
        return fit.theta, crb_sigma(J, noise_T), fit.chi2
