"""The finite depth of the web: the plane-strain rungs corrected for the web's free faces.

Every rung models the web as plane strain (the walls cannot stretch along the depth D). The
web's faces at y = +-D/2 are free, and within a boundary layer of width l next to each face the
walls are in plane stress instead, softer by nu^2 (E against E / (1 - nu^2)). The layer is
softer by

    k_3D / k_2D = 1 - 2 nu^2 l / D,       l = t * lam(theta, y),   y = t / (h - t),

l independent of D, and proportional to t at a fixed profile shape (both measured on a 3D
model, tools/fit_depth_correction.py, docs/design.md section 4.1). lam is a mix of t and h - t with
quadratic weights in theta - 45 deg, fitted there and stored in mst_cli/model/data/depth_correction.json. The
lock force moves with k (3D against plane strain along the path to the lock: R within 1.5 % of
k's ratio on the four path cells of studies/bench_3d.py), and the lock stroke does not
(< 0.25 %), so the correction scales a layer's force at every compression, on every rung.

Pure and vectorised.
"""

from __future__ import annotations

import functools
import json
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.arrays import stacked_terms

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from mst_cli.model.cell import HexCell
    from mst_cli.model.material import Material

TERMS = ("1", "s", "s^2", "1/y", "s/y", "s^2/y")
DATA = Path(__file__).resolve().parent.parent / "data" / "depth_correction.json"
# y = t / (h - t) > 0 for every cell; this floor only keeps 1/y finite for degenerate input
Y_MIN = 1e-3


def design_matrix(theta_rad: ArrayLike, y: ArrayLike) -> np.ndarray:
    """The terms of lam (TERMS) at (theta, y = t / (h - t)), stacked on a last axis.

    t lam = t (c0 + c1 s + c2 s^2) + (h - t) (c3 + c4 s + c5 s^2): the boundary layer's width
    is a mix of the wall's thickness and the layer's height, weighted by the wall angle."""
    s = np.asarray(theta_rad, dtype=float) - np.pi / 4
    inv_y = 1.0 / np.maximum(np.asarray(y, dtype=float), Y_MIN)
    return stacked_terms(np.ones_like(s), s, s**2, inv_y, s * inv_y, s**2 * inv_y)


@functools.lru_cache(maxsize=1)
def _coefficients() -> np.ndarray:
    """The stored fit; a missing file is an installation error, never a silent 'no correction'."""
    return np.asarray(json.loads(DATA.read_text())["coefficients"], dtype=float)


def finite_depth_factor(
    theta_rad: ArrayLike,
    t_mm: ArrayLike,
    h_mm: ArrayLike,
    depth_mm: ArrayLike,
    nu: ArrayLike,
    coefficients: ArrayLike | None = None,
) -> np.ndarray:
    """k of the web D deep with free faces over k of plane strain (dimensionless, in (1 - nu^2, 1]).

    Parameters
    ----------
    theta_rad, t_mm, h_mm : wall angle (rad), wall thickness and layer height (mm), any shape
    depth_mm : the web's depth D (mm); nu : Poisson's ratio
    coefficients : lam's coefficients (default: the stored fit)
    """
    t = np.asarray(t_mm, dtype=float)
    h = np.asarray(h_mm, dtype=float)
    c = _coefficients() if coefficients is None else np.asarray(coefficients, dtype=float)
    y = t / np.maximum(h - t, 1e-9)
    lam = np.maximum(design_matrix(theta_rad, y) @ c, 0.0)
    ell = np.minimum(t * lam, 0.5 * np.asarray(depth_mm, dtype=float))
    return 1.0 - 2.0 * np.asarray(nu, dtype=float) ** 2 * ell / np.asarray(depth_mm, dtype=float)


def web_modulus_MPa(
    theta_rad: ArrayLike,
    t_mm: ArrayLike,
    h_mm: ArrayLike,
    depth_mm: ArrayLike,
    youngs_modulus_MPa: ArrayLike,
    nu: ArrayLike,
) -> np.ndarray:
    """The modulus a plane-strain rung takes so that its layer is as stiff as the web D deep.

    Every rung's force is linear in E at fixed nu, so scaling E by :func:`finite_depth_factor`
    scales the layer's force at every compression by it (MPa, the broadcast shape)."""
    return np.asarray(youngs_modulus_MPa, dtype=float) * finite_depth_factor(theta_rad, t_mm, h_mm, depth_mm, nu)


def in_web(cell: HexCell, material: Material) -> Material:
    """The material with which a plane-strain rung gives the layer of ``cell`` as printed, D deep
    with free faces (:func:`web_modulus_MPa`; same name and nu)."""
    E = float(
        web_modulus_MPa(
            cell.theta_rad, cell.t_mm, cell.h_mm, cell.b_mm, material.youngs_modulus_MPa, material.poisson_ratio
        )
    )
    return replace(material, youngs_modulus_MPa=E)
