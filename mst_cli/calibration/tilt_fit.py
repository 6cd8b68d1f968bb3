"""The tilt of a printed sensor, from load-test rows pressed at known offsets (``mst calibrate``
with ``x_mm``, ``y_mm`` columns).

The centred rows (x = y = 0) calibrate the sensor as before; the others fix one more number,
the **lever factor**: every lever of the tilt rung (the chevrons' x_c and the pads' half width,
:mod:`mst_cli.model.mechanics.tilt`) times a common factor. It stands for what the rung leaves
out and a print changes: plates that bend (a lever shorter than rigid plates give), walls whose
roots print wider or narrower. It is fitted to all three field axes of the off-centre rows with
the calibrated model (least squares in units of the chip's noise), with its 1-sigma from the
curvature, and ``mst read --estimate-offset`` uses it.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar

from mst_cli.calibration.loadtest import Readings
from mst_cli.model.general_load import pose_field_T
from mst_cli.model.member_pose import MemberPose
from mst_cli.model.offcentre import section_members_pose
from mst_cli.model.stack_pose import tilt_laws
from mst_cli.sensor.document import Document

LEVER_FACTOR_BOUNDS = (0.3, 3.0)  # a lever a third or three times the rung's: beyond is not a tilt
LEVER_STEP = 1e-4  # finite-difference step of the 1-sigma


def field_residuals(
    doc: Document, mechanics: str, rd: Readings, sigma_T: float, lever_factor: float, members: MemberPose | None = None
) -> np.ndarray:
    """(model - reading) / sigma on every axis of every row (3 n,), rows grouped by their press
    and solved in ascending force; ``members``: what the whole-part rung adds (model.load_path:
    section, not scaled by the lever factor: it is the members', not the layers')."""
    geometry, material = doc.geometry(), doc.material
    layers = tilt_laws(geometry, material, mechanics, lever_factor, doc.whole_part)
    assert rd.offset_mm is not None and rd.force_N is not None
    B = np.empty_like(rd.B_T)
    presses = np.unique(rd.offset_mm, axis=0)
    for press in presses:
        rows = np.flatnonzero(np.all(rd.offset_mm == press, axis=1))
        order = rows[np.argsort(rd.force_N[rows], kind="stable")]
        B[order] = pose_field_T(
            geometry, layers, np.maximum(rd.force_N[order], 0.0), (float(press[0]), float(press[1])), members
        )
    return ((B - rd.B_T) / sigma_T).ravel()


def fit_lever_factor(doc: Document, mechanics: str, rd: Readings, sigma_T: float) -> dict:
    """calibration.json's ``tilt``: the lever factor with its 1-sigma, the rows and presses it
    came from, and the RMS field residual (uT) at the fit and at factor 1."""
    members = section_members_pose(doc.geometry(), doc.material, mechanics, doc.section_rung)

    def residuals(f: float) -> np.ndarray:
        return field_residuals(doc, mechanics, rd, sigma_T, f, members)

    def cost(f: float) -> float:
        return float(np.sum(residuals(f) ** 2))

    res = minimize_scalar(cost, bounds=LEVER_FACTOR_BOUNDS, method="bounded", options={"xatol": 1e-5})
    f = float(res.x)
    r = residuals(f)
    J = (residuals(f + LEVER_STEP) - r) / LEVER_STEP
    dof = max(r.size - 1, 1)
    chi2_red = float(np.sum(r**2)) / dof
    std = math.sqrt(max(chi2_red, 1.0) / float(J @ J)) if float(J @ J) > 0 else math.inf
    at_bound = min(abs(f - b) for b in LEVER_FACTOR_BOUNDS) < 1e-3
    r1 = residuals(1.0)
    assert rd.offset_mm is not None
    return {
        "lever_factor": f,
        "std": std,
        "at_bound": at_bound,
        "rows": int(len(rd)),
        "presses_mm": [[float(x), float(y)] for x, y in np.unique(rd.offset_mm, axis=0)],
        "rms_residual_uT": float(np.sqrt(np.mean(r**2))) * sigma_T * 1e6,
        "rms_residual_at_factor_1_uT": float(np.sqrt(np.mean(r1**2))) * sigma_T * 1e6,
        "what": "every lever of the tilt rung (chevrons' x_c, pads' half width) times this factor; "
        "mst read --estimate-offset uses it",
    }
