"""Where a reading was pressed, from all three field axes (``mst read --estimate-offset``).

A press at (x0, y0) tilts the stack and moves the magnet sideways (:mod:`mst_cli.model.offcentre`),
so one reading (Bx, By, Bz) holds three numbers for three unknowns: the force and the two
offsets. :class:`OffsetEstimator` finds them by Gauss-Newton on the model's field, each reading
started from the centred model's force and the previous reading's offset (a stream of presses
moves little between samples). The chip's field noise sigma gives their covariance,
sigma^2 (J^T J)^-1; a reading whose offset's 1-sigma exceeds a bound is *not identifiable*
(under a light press the stack hardly tilts, so Bx and By say nothing): it keeps the centred
model's force and is flagged.

This is the rung's own inverse: it corrects what the tilt rung predicts, and is as good as
that rung (docs/design.md section 4.2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mst_cli.model.geometry import SensorGeometry
from mst_cli.model.material import Material
from mst_cli.model.offcentre import magnet_field_T, magnet_pose, stack_path, tilt_laws

DEFAULT_MAX_SIGMA_MM = 1.0  # an offset less certain than this is not identifiable
GAUSS_NEWTON_ITERATIONS = 30
STEP_FORCE_REL = 1e-5  # finite-difference steps: of the largest force ...
STEP_OFFSET_MM = 1e-3  # ... and in mm


@dataclass
class OffsetReadings:
    """Per reading: the corrected force, the offset and their 1-sigma (NaN where not estimated)."""

    force_N: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    sigma_x_mm: np.ndarray
    sigma_y_mm: np.ndarray
    sigma_force_N: np.ndarray
    flag: np.ndarray  # "ok", "not_identifiable", or "" (the reading itself is flagged)

    def summary(self) -> str:
        ok = self.flag == "ok"
        n_un = int(np.sum(self.flag == "not_identifiable"))
        if not ok.any():
            return f"offset: identifiable on no reading ({n_un} not identifiable: the centred force kept)"
        x, y = self.x_mm[ok], self.y_mm[ok]
        return (
            f"offset: estimated on {int(ok.sum())} readings (median 1-sigma "
            f"{np.median(self.sigma_x_mm[ok]):.2g} mm in x, {np.median(self.sigma_y_mm[ok]):.2g} mm in y; "
            f"x {x.min():.3g}..{x.max():.3g} mm, y {y.min():.3g}..{y.max():.3g} mm); "
            f"{n_un} not identifiable (the centred force kept)"
        )


class OffsetEstimator:
    """(force, x0, y0) of readings, from the tilt rung of one sensor model."""

    def __init__(
        self,
        geometry: SensorGeometry,
        material: Material,
        mechanics: str,
        field_sigma_T: float,
        force_max_N: float,
        max_sigma_mm: float = DEFAULT_MAX_SIGMA_MM,
        lever_factor: float = 1.0,
    ):
        self.geometry = geometry
        self.layers = tilt_laws(geometry, material, mechanics, lever_factor)
        self.sigma_T = float(field_sigma_T)
        self.force_max_N = float(force_max_N)
        self.max_sigma_mm = float(max_sigma_mm)
        self.half_face_mm = np.array([0.5 * geometry.width_mm, 0.5 * geometry.depth_mm])
        self._start: np.ndarray | None = None  # the layers' last (d, phi_y, phi_x)

    def field_T(self, p: np.ndarray) -> np.ndarray:
        """The model's field (3,) at p = (force N, x0 mm, y0 mm); each layer's solve starts from
        the last call's answer (the estimate moves by small steps)."""
        F = max(float(p[0]), 0.0)
        if F == 0.0:
            return magnet_field_T(self.geometry, np.zeros((1, 3)), np.zeros((1, 3)))[0]
        d, tilt = stack_path(self.layers, np.array([F]), (float(p[1]), float(p[2])), self._start)
        self._start = np.column_stack([d[0], tilt[0]])
        return magnet_field_T(self.geometry, *magnet_pose(self.geometry, d, tilt))[0]

    def _jacobian(self, p: np.ndarray, B0: np.ndarray) -> np.ndarray:
        steps = np.array([STEP_FORCE_REL * self.force_max_N, STEP_OFFSET_MM, STEP_OFFSET_MM])
        cols = []
        for k in range(3):
            q = p.copy()
            q[k] += steps[k]
            cols.append((self.field_T(q) - B0) / steps[k])
        return np.stack(cols, axis=1)

    def estimate(self, B_T: np.ndarray, force_guess_N: float, offset_guess_mm=(0.0, 0.0)) -> tuple:
        """(force, x, y, sigma_x, sigma_y, sigma_force, identifiable) of one reading (T)."""
        p = np.array([force_guess_N, *offset_guess_mm], dtype=float)
        lo = np.array([0.0, -self.half_face_mm[0], -self.half_face_mm[1]])
        hi = np.array([self.force_max_N, self.half_face_mm[0], self.half_face_mm[1]])
        for _ in range(GAUSS_NEWTON_ITERATIONS):
            B0 = self.field_T(p)
            J = self._jacobian(p, B0)
            dp, *_ = np.linalg.lstsq(J, B_T - B0, rcond=None)
            p_new = np.clip(p + dp, lo, hi)
            # converged when the step moves the model's field by a thousandth of the noise
            done = float(np.linalg.norm(J @ (p_new - p))) <= 1e-3 * self.sigma_T
            p = p_new
            if done:
                break
        J = self._jacobian(p, self.field_T(p))
        try:
            cov = self.sigma_T**2 * np.linalg.inv(J.T @ J)
            sig = np.sqrt(np.maximum(np.diag(cov), 0.0))
        except np.linalg.LinAlgError:
            sig = np.full(3, math.inf)
        ok = bool(np.all(np.isfinite(sig)) and max(sig[1], sig[2]) <= self.max_sigma_mm)
        return float(p[0]), float(p[1]), float(p[2]), float(sig[1]), float(sig[2]), float(sig[0]), ok

    def estimate_all(self, B_T: np.ndarray, force_axial_N: np.ndarray) -> OffsetReadings:
        """Every reading with a finite centred force (the others stay flagged as they are)."""
        n = len(force_axial_N)
        out = {k: np.full(n, np.nan) for k in ("F", "x", "y", "sx", "sy", "sF")}
        flag = np.full(n, "", dtype=object)
        guess = (0.0, 0.0)
        for i in range(n):
            if not np.isfinite(force_axial_N[i]):
                continue
            F, x, y, sx, sy, sF, ok = self.estimate(B_T[i], float(force_axial_N[i]), guess)
            if ok:
                guess = (x, y)
                for k, v in zip(("F", "x", "y", "sx", "sy", "sF"), (F, x, y, sx, sy, sF)):
                    out[k][i] = v
                flag[i] = "ok"
            else:
                out["F"][i] = force_axial_N[i]
                flag[i] = "not_identifiable"
        return OffsetReadings(out["F"], out["x"], out["y"], out["sx"], out["sy"], out["sF"], flag)


def offset_columns(forces_csv_text: str, est: OffsetReadings, centred_force_N: np.ndarray) -> str:
    """forces.csv with the offset's columns appended: the centred model's force, x and y with
    their 1-sigma (mm), and offset_flag (ok, not_identifiable, or empty for a flagged reading)."""
    lines = forces_csv_text.splitlines()
    out = [lines[0] + ",force_centred_N,x_mm,y_mm,sigma_x_mm,sigma_y_mm,offset_flag"]
    for i, line in enumerate(lines[1:]):
        vals = [centred_force_N[i], est.x_mm[i], est.y_mm[i], est.sigma_x_mm[i], est.sigma_y_mm[i]]
        cells = ["" if not np.isfinite(v) else f"{v:.6g}" for v in vals]
        out.append(line + "," + ",".join(cells) + "," + str(est.flag[i]))
    return "\n".join(out) + "\n"
